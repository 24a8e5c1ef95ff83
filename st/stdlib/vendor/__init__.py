"""The vendor compatibility library: what TwinCAT's Tc2_System / Tc2_Utilities and CODESYS's
system libraries give that real code uses most (T_MaxString, F_LTrim, DWORD_TO_HEXSTR, MEMCPY,
ADSLOGSTR, DRAND, GETCPUCOUNTER, …, and SysFile / SysDir: sysfile.st, sysfile.py). Loaded under
the codesys and twincat presets and by default (none of its names is IEC's; a user declaration
of the same name wins); docs/semantics.md lists it."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from ...compiler.library import Library
from . import sysfile
from .natives import HELPERS, signatures

SOURCES = (
    Path(__file__).with_name("vendor.st"),
    Path(__file__).with_name("sysinfo.st"),
    Path(__file__).with_name("sysfile.st"),
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
)


@lru_cache(maxsize=1)
def library() -> Library:
    lib = Library("vendor", namespaces=NAMESPACES)
    lib.sources.extend((str(p), p.read_text()) for p in SOURCES)
    for sig in (*signatures(), *sysfile.signatures()):
        lib.add(sig)
    lib.helpers.update(HELPERS)
    lib.helpers.update(sysfile.HELPERS)
    return lib
