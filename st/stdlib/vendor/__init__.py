"""The vendor compatibility library: what TwinCAT's Tc2_System / Tc2_Utilities and CODESYS's
system libraries give that real code uses most (T_MaxString, F_LTrim, DWORD_TO_HEXSTR, MEMCPY,
ADSLOGSTR, DRAND, GETCPUCOUNTER, TestAndSet, __SYSTEM.ExceptionCode, …; FB_MemRingBuffer and
FB_FormatString: utilities.st, formatting.py; T_FILETIME, FB_LocalSystemTime and the date
conversions: datetime.st, filetime.py; SysFile / SysDir: sysfile.st, sysfile.py; TwinCAT's file
blocks and FB_EnumFindFileList: files.st, findfile.py; Tc3_DynamicMemory: dynmem.st). Loaded under the codesys and twincat
presets and by default (none of its names is IEC's; a user declaration of the same name wins);
docs/semantics.md lists it."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from ...compiler.library import Library
from . import filetime, findfile, formatting, sysfile
from .natives import HELPERS, signatures

SOURCES = tuple(
    Path(__file__).with_name(name)
    for name in ("vendor.st", "sysinfo.st", "utilities.st", "datetime.st", "sysfile.st", "files.st", "dynmem.st")
)
NAMESPACES = (
    "Tc2_System",
    "Tc2_Utilities",
    "Util",
    "__SYSTEM",
    "IBaseLibrary",
    "SysFile",
    "SysDir",
    "SysTypes",
    "CmpErrors",
    "Tc3_DynamicMemory",
)


@lru_cache(maxsize=1)
def library() -> Library:
    lib = Library("vendor", namespaces=NAMESPACES)
    lib.sources.extend((str(p), p.read_text()) for p in SOURCES)
    for module in (filetime, findfile, formatting, sysfile):
        for sig in module.signatures():
            lib.add(sig)
        lib.helpers.update(module.HELPERS)
    for sig in signatures():
        lib.add(sig)
    lib.helpers.update(HELPERS)
    return lib
