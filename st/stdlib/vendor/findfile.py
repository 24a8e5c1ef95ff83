"""The directory listing behind TwinCAT's FB_EnumFindFileList (files.st): native functions that
take a snapshot of the entries a pattern matches (`C:\\Logs\\*.txt`, `Logs\\TcLog_*`, a directory
name alone: its entries), sorted by name, and read one field of one entry; the block copies them
into the caller's ST_FindFileEntry array. Paths are sysfile.py's (the file root, backslashes,
drive letters). Errors are TwinCAT's ADS codes, returned negated: 16#70C (1804) where the
directory does not exist, 16#704 (1796) where it may not be read.
"""

from __future__ import annotations

import fnmatch
import os
import stat
import time
from typing import Any

from ...compiler.library import FuncSig, Param
from ...model import types as T
from .sysfile import _path

ADS_NOT_FOUND = 0x70C
ADS_NOT_PERMITTED = 0x704

# Windows' FILE_ATTRIBUTE_* bits, as ST_FindFileEntry's fileAttributes spells them out
_READONLY, _HIDDEN, _DIRECTORY, _ARCHIVE, _NORMAL = 0x1, 0x2, 0x10, 0x20, 0x80

_listings: dict[int, list[tuple[str, os.stat_result]]] = {}  # id → the entries of one enumeration


def _vd_find(pattern: str) -> int:
    """A snapshot of the entries `pattern` matches: its id (1, 2, …), or an ADS error, negated."""
    path = _path(pattern)
    if any(c in path.name for c in "*?"):
        folder, mask = path.parent, path.name
    else:
        folder, mask = path, "*"
    try:
        names = sorted(os.listdir(folder), key=str.lower)
    except FileNotFoundError:
        return -ADS_NOT_FOUND
    except NotADirectoryError:
        folder, names, mask = path.parent, [path.name], path.name
    except OSError:
        return -ADS_NOT_PERMITTED
    entries = []
    for name in names:
        if not fnmatch.fnmatch(name.lower(), mask.lower()):  # Windows matches regardless of case
            continue
        try:
            entries.append((name, os.stat(folder / name)))
        except OSError:
            continue  # gone since the listing
    key = next(i for i in range(1, len(_listings) + 2) if i not in _listings)
    _listings[key] = entries
    return key


def _vd_found_count(key: int) -> int:
    return len(_listings.get(key, ()))


def _vd_found_name(key: int, index: int) -> str:
    entries = _listings.get(key, [])
    return entries[index][0] if 0 <= index < len(entries) else ""


def _vd_found_info(key: int, index: int, field: int, now: int) -> int:
    """One number of entry `index`: 0 its size, 1 its attribute bits, 2 creation, 3 last access,
    4 last write (FILETIME ticks on the PLC's calendar, whose now is `now`: a file's time is as
    long before the PLC's now as it is before the host's, so an age computed from it holds on
    virtual time too)."""
    entries = _listings.get(key, [])
    if not 0 <= index < len(entries):
        return 0
    name, st = entries[index]
    if field == 0:
        return 0 if stat.S_ISDIR(st.st_mode) else st.st_size
    if field == 1:
        bits = _DIRECTORY if stat.S_ISDIR(st.st_mode) else _ARCHIVE
        if not st.st_mode & 0o222:
            bits |= _READONLY
        if name.startswith("."):
            bits |= _HIDDEN
        return bits
    seconds = (getattr(st, "st_birthtime", st.st_ctime), st.st_atime, st.st_mtime)[field - 2]
    return max(0, now - int((time.time() - seconds) * 10_000_000))


def _vd_find_end(key: int) -> bool:
    return _listings.pop(key, None) is not None


def signatures() -> list[FuncSig]:
    key, index = Param("id", "DINT"), Param("index", "UDINT")
    return [
        FuncSig("__VD_FIND", [Param("pattern", "ANY_STRING")], "DINT", helper="_vd_find"),
        FuncSig("__VD_FOUND_COUNT", [key], "UDINT", helper="_vd_found_count"),
        FuncSig("__VD_FOUND_NAME", [key, index], lambda _t: T.StringType(255, False), helper="_vd_found_name"),
        FuncSig(
            "__VD_FOUND_INFO",
            [key, index, Param("field", "ANY_INT"), Param("now", "ULINT")],
            "ULINT",
            helper="_vd_found_info",
        ),
        FuncSig("__VD_FIND_END", [key], "BOOL", helper="_vd_find_end"),
    ]


HELPERS: dict[str, Any] = {
    "_vd_find": _vd_find,
    "_vd_found_count": _vd_found_count,
    "_vd_found_name": _vd_found_name,
    "_vd_found_info": _vd_found_info,
    "_vd_find_end": _vd_find_end,
}
