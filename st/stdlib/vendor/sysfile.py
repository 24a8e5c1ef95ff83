"""CODESYS's SysFile and SysDir for the vendor compatibility library: the native functions
(signatures and the Python generated code calls). Types, ACCESS_MODE and CmpErrors.Errors are ST
(sysfile.st).

Files are the host's. A relative file name is taken from the file root: `FILE_ROOT` when set (a
path; tests set it), else the process's current directory at the time of the call. An absolute
name is used as it is. On a POSIX host a backslash separates directories too (TwinCAT code writes
Windows paths), and a drive letter is a directory under the file root (`C:\\Logs\\a.txt` is
`<root>/C/Logs/a.txt`). An open file is a small handle number (1, 2, …, the lowest free one); the files
stay open until SysFileClose (or the end of the process), across PLCs. No OS error leaves a native
as a Python exception: it becomes the CmpErrors code the function returns or writes to *pResult
(a NULL pResult is allowed: nothing is written). A NULL buffer with a size above 0, or a size
beyond the variable the buffer points into, is a PLC fault (NULL, MEMORY).
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any

from ...compiler.library import FuncSig, Param
from ...model import types as T
from ...runtime.faults import PLCFault
from ...runtime.pointers import byte_view

FILE_ROOT: str | os.PathLike[str] | None = None  # None: the process's current directory

# CmpErrors.Errors (sysfile.st)
ERR_OK = 0
ERR_FAILED = 1
ERR_PARAMETER = 2
ERR_NO_OBJECT = 0x10
ERR_DUPLICATE = 0x12
ERR_INVALID_HANDLE = 0x14
ERR_NO_ACCESS_RIGHTS = 0x19
ERR_DISK_FULL = 0x29
ERR_FILE_ERROR = 0x32

RTS_INVALID_HANDLE = 0xFFFFFFFFFFFFFFFF

# ACCESS_MODE → the host's open mode
_MODES = {0: "rb", 1: "wb", 2: "ab", 3: "r+b", 4: "w+b", 5: "a+b"}

_files: dict[int, Any] = {}  # handle → an open unbuffered binary file


def close_all() -> None:
    """Close every file a program left open (tests; a host embedding st)."""
    for f in _files.values():
        try:
            f.close()
        except OSError:
            pass
    _files.clear()


def _path(name: str) -> Path:
    if os.sep == "/":
        name = name.replace("\\", "/")
        if len(name) >= 2 and name[1] == ":" and name[0].isalpha():
            name = name[0].upper() + "/" + name[2:].lstrip("/")  # C:\Logs\a.txt: C/Logs/a.txt under the root
    p = Path(name)
    if p.is_absolute():
        return p
    return Path(FILE_ROOT if FILE_ROOT is not None else os.getcwd()) / p


def _code(exc: BaseException) -> int:
    """The CmpErrors code of a failed file operation."""
    if isinstance(exc, FileNotFoundError):
        return ERR_NO_OBJECT
    if isinstance(exc, FileExistsError):
        return ERR_DUPLICATE
    if isinstance(exc, PermissionError):
        return ERR_NO_ACCESS_RIGHTS
    if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)):
        return ERR_DISK_FULL
    return ERR_FILE_ERROR


def _report(p: Any, code: int) -> None:
    """*pResult := code, unless pResult is NULL (or the literal 0)."""
    if p is None or (isinstance(p, int) and p == 0):
        return
    if isinstance(p, int):
        raise PLCFault(f"pResult is the number {p}, not a pointer", "NULL")
    p.set(code)


def _buffer(p: Any, spec: tuple | None, size: int, what: str) -> Any:
    """The byte view of the buffer `size` bytes are read into or written from."""
    if p is None or isinstance(p, int):
        raise PLCFault(f"{what} was given a NULL buffer for {size} byte(s)", "NULL")
    view = byte_view(p, spec, what)
    room = view.room()
    if size > room:
        raise PLCFault(f"{what} of {size} byte(s) beyond the {room} byte(s) of the buffer's variable", "MEMORY")
    return view


# ------------------------------------------------------------------ SysFile


def _sf_open(name: str, mode: int, p_result: Any) -> int:
    how = _MODES.get(int(mode))
    if how is None or not name:
        _report(p_result, ERR_PARAMETER)
        return RTS_INVALID_HANDLE
    try:
        f = open(_path(name), how, buffering=0)  # noqa: SIM115 (kept open until SysFileClose)
    except (OSError, ValueError) as exc:
        _report(p_result, _code(exc))
        return RTS_INVALID_HANDLE
    handle = 1
    while handle in _files:
        handle += 1
    _files[handle] = f
    _report(p_result, ERR_OK)
    return handle


def _sf_close(handle: int) -> int:
    f = _files.pop(handle, None)
    if f is None:
        return ERR_INVALID_HANDLE
    try:
        f.close()
    except OSError as exc:
        return _code(exc)
    return ERR_OK


def _sf_read(handle: int, buf: Any, size: int, p_result: Any, spec: tuple | None) -> int:
    f = _files.get(handle)
    if f is None:
        _report(p_result, ERR_INVALID_HANDLE)
        return 0
    if size <= 0:
        _report(p_result, ERR_OK)
        return 0
    view = _buffer(buf, spec, size, "SysFileRead")
    data = b""
    try:
        while len(data) < size:
            part = f.read(size - len(data))
            if not part:
                break
            data += part
    except (OSError, ValueError) as exc:
        _report(p_result, _code(exc))
        return 0
    if data:
        view.write_image(data)
    _report(p_result, ERR_OK)
    return len(data)


def _sf_write(handle: int, buf: Any, size: int, p_result: Any, spec: tuple | None) -> int:
    f = _files.get(handle)
    if f is None:
        _report(p_result, ERR_INVALID_HANDLE)
        return 0
    if size <= 0:
        _report(p_result, ERR_OK)
        return 0
    data = _buffer(buf, spec, size, "SysFileWrite").image(size)
    done = 0
    try:
        while done < size:
            n = f.write(data[done:])
            if not n:
                break
            done += n
    except (OSError, ValueError) as exc:
        _report(p_result, _code(exc))
        return done
    _report(p_result, ERR_OK if done == size else ERR_FAILED)
    return done


def _sf_delete(name: str) -> int:
    if not name:
        return ERR_PARAMETER
    try:
        os.remove(_path(name))
    except (OSError, ValueError) as exc:
        return _code(exc)
    return ERR_OK


def _sf_get_size(name: str, p_result: Any) -> int:
    if not name:
        _report(p_result, ERR_PARAMETER)
        return 0
    try:
        size = os.stat(_path(name)).st_size
    except (OSError, ValueError) as exc:
        _report(p_result, _code(exc))
        return 0
    _report(p_result, ERR_OK)
    return size


def _sf_rename(old: str, new: str) -> int:
    if not old or not new:
        return ERR_PARAMETER
    src, dst = _path(old), _path(new)
    try:
        if not src.exists():
            return ERR_NO_OBJECT
        if dst.exists():
            return ERR_DUPLICATE
        os.rename(src, dst)
    except (OSError, ValueError) as exc:
        return _code(exc)
    return ERR_OK


def _sf_eof(handle: int, p_result: Any) -> int:
    f = _files.get(handle)
    if f is None:
        _report(p_result, ERR_INVALID_HANDLE)
        return ERR_INVALID_HANDLE
    try:
        at_end = f.tell() >= os.fstat(f.fileno()).st_size
    except (OSError, ValueError) as exc:
        _report(p_result, _code(exc))
        return _code(exc)
    _report(p_result, ERR_OK)
    return ERR_OK if at_end else ERR_FAILED


def _sf_get_pos(handle: int, p_result: Any) -> int:
    f = _files.get(handle)
    if f is None:
        _report(p_result, ERR_INVALID_HANDLE)
        return 0
    try:
        pos = f.tell()
    except (OSError, ValueError) as exc:
        _report(p_result, _code(exc))
        return 0
    _report(p_result, ERR_OK)
    return pos


def _sf_set_pos(handle: int, offset: int, p_result: Any) -> int:
    f = _files.get(handle)
    code = ERR_INVALID_HANDLE
    if f is not None:
        try:
            f.seek(offset)
            code = ERR_OK
        except (OSError, ValueError, OverflowError) as exc:
            code = _code(exc)
    _report(p_result, code)
    return code


# ------------------------------------------------------------------ SysDir


def _sd_create(name: str) -> int:
    if not name:
        return ERR_PARAMETER
    try:
        os.mkdir(_path(name))
    except (OSError, ValueError) as exc:
        return _code(exc)
    return ERR_OK


def _sd_delete(name: str) -> int:
    if not name:
        return ERR_PARAMETER
    try:
        os.rmdir(_path(name))
    except (OSError, ValueError) as exc:
        return _code(exc)
    return ERR_OK


# ------------------------------------------------------------------ signatures

_RESULT = T.ELEMENTARY["UDINT"]  # RTS_IEC_RESULT
_SIZE = T.ELEMENTARY["ULINT"]  # RTS_IEC_SIZE, RTS_IEC_HANDLE


def _target(t: Any) -> T.Type | None:
    u = T.unalias(t)
    return u.target if isinstance(u, T.RefType) else None


def _is_null(t: Any) -> bool:
    """A NULL pointer argument: the literal 0 (CODESYS's usual NULL) or NULL."""
    return T.base_of(t) is T.LIT_INT or getattr(t, "kind", "") == "null"


def _shown(t: Any) -> str:
    """A type as the message names it (ADR(x) is a POINTER TO, as CODESYS says)."""
    target = _target(t)
    return str(t) if target is None else f"POINTER TO {target}"


def _mode_error(t: Any) -> str:
    b = T.base_of(t)
    if isinstance(b, T.EnumType):
        return "" if b.name.lower() == "access_mode" else f"'am' must be ACCESS_MODE, not {_shown(t)}"
    if b is T.LIT_INT or (isinstance(b, T.ElemType) and b.kind in ("int", "bit")):
        return ""
    return f"'am' must be ACCESS_MODE, not {_shown(t)}"


def _result_ptr_error(t: Any) -> str:
    if _is_null(t):
        return ""
    target = _target(t)
    if target is not None and (T.byte_layout(target) or ("",))[:2] == ("i", 4):
        return ""
    return f"'pResult' must be a POINTER TO RTS_IEC_RESULT (ADR of a UDINT) or 0, not {_shown(t)}"


def _buffer_error(t: Any) -> str:
    if _is_null(t):
        return ""
    target = _target(t)
    if target is not None and T.byte_layout(target) is not None:
        return ""
    return f"'pbyBuffer' must be a pointer to a variable with bytes (ADR of an array, a string, ...), not {_shown(t)}"


def _checked(result: T.Type, checks: dict[int, Any]):
    """The result-type callable: `result`, or the message of an argument of the wrong kind (E013)."""

    def res(types: list) -> T.Type | str:
        for i, check in checks.items():
            msg = check(types[i]) if i < len(types) else ""
            if msg:
                return msg
        return result

    return res


def _buffer_spec(types: list, _rt: Any) -> list:
    """The byte image spec of what the buffer pointer points to (None for a literal NULL)."""
    target = _target(types[1])
    return [None if target is None else T.byte_layout(target)]


def _handle() -> Param:
    return Param("hFile", "ULINT")


def _p_result() -> Param:
    return Param("pResult", "ANY")


def _name(name: str) -> Param:
    return Param(name, "ANY_STRING")


def signatures() -> list[FuncSig]:
    io_checks = {1: _buffer_error, 3: _result_ptr_error}  # (hFile, pbyBuffer, ulSize, pResult)
    second = {1: _result_ptr_error}  # pResult after one parameter
    return [
        FuncSig(
            "SysFileOpen",
            [_name("szFile"), Param("am", "ANY"), _p_result()],
            _checked(_SIZE, {1: _mode_error, 2: _result_ptr_error}),
            helper="_sf_open",
            doc="opens a file: its handle, or RTS_INVALID_HANDLE",
        ),
        FuncSig("SysFileClose", [_handle()], "UDINT", helper="_sf_close", doc="closes a file"),
        FuncSig(
            "SysFileRead",
            [_handle(), Param("pbyBuffer", "ANY"), Param("ulSize", "ULINT"), _p_result()],
            _checked(_SIZE, io_checks),
            helper="_sf_read",
            extra=_buffer_spec,
            doc="reads up to ulSize bytes into the buffer: how many it read",
        ),
        FuncSig(
            "SysFileWrite",
            [_handle(), Param("pbyBuffer", "ANY"), Param("ulSize", "ULINT"), _p_result()],
            _checked(_SIZE, io_checks),
            helper="_sf_write",
            extra=_buffer_spec,
            doc="writes the buffer's first ulSize bytes: how many it wrote",
        ),
        FuncSig("SysFileDelete", [_name("szFileName")], "UDINT", helper="_sf_delete", doc="deletes a file"),
        FuncSig(
            "SysFileGetSize",
            [_name("szFileName"), _p_result()],
            _checked(_SIZE, second),
            helper="_sf_get_size",
            doc="the size of a file in bytes",
        ),
        FuncSig(
            "SysFileRename",
            [_name("szOldFileName"), _name("szNewFileName")],
            "UDINT",
            helper="_sf_rename",
            doc="renames a file",
        ),
        FuncSig(
            "SysFileEOF",
            [_handle(), _p_result()],
            _checked(_RESULT, second),
            helper="_sf_eof",
            doc="ERR_OK at the end of the file, ERR_FAILED before it",
        ),
        FuncSig(
            "SysFileGetPos",
            [_handle(), _p_result()],
            _checked(_SIZE, second),
            helper="_sf_get_pos",
            doc="the position in the file",
        ),
        FuncSig(
            "SysFileSetPos",
            [_handle(), Param("ulOffset", "ULINT"), _p_result()],
            _checked(_RESULT, {2: _result_ptr_error}),
            helper="_sf_set_pos",
            doc="moves to a position from the file's start",
        ),
        FuncSig("SysDirCreate", [_name("szDir")], "UDINT", helper="_sd_create", doc="creates a directory"),
        FuncSig("SysDirDelete", [_name("szDir")], "UDINT", helper="_sd_delete", doc="deletes an empty directory"),
    ]


HELPERS = {
    "_sf_open": _sf_open,
    "_sf_close": _sf_close,
    "_sf_read": _sf_read,
    "_sf_write": _sf_write,
    "_sf_delete": _sf_delete,
    "_sf_get_size": _sf_get_size,
    "_sf_rename": _sf_rename,
    "_sf_eof": _sf_eof,
    "_sf_get_pos": _sf_get_pos,
    "_sf_set_pos": _sf_set_pos,
    "_sd_create": _sd_create,
    "_sd_delete": _sd_delete,
}
