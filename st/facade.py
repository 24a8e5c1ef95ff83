"""`st.PLC`: the runtime's PLC with constructors that compile first (and the axes' view). Kept
apart from st/api.py so that compiling (`st check`, the compile API) loads no runtime."""

from __future__ import annotations

import os
from collections.abc import Sequence

from .api import compile_paths, compile_text
from .runtime import plc as runtime_plc
from .stdlib.plcopen import AxisView, axis_view


class PLC(runtime_plc.PLC):
    """The runtime's PLC, made from ST source text or files: the compile options among `kw`
    (f_trig_first_scan, time_unit, use_cache, coverage, native, dialect; lib_path for files) go to the
    compiler, the rest to the PLC."""

    @classmethod
    def from_source(cls, text: str, cycle=None, *, name: str = "<source>.st", **kw) -> PLC:
        return cls(compile_text(text, name, **_compile_kw(kw)), cycle, **kw)

    @classmethod
    def from_files(cls, *paths: str, cycle=None, lib_path: Sequence[str | os.PathLike] = (), **kw) -> PLC:
        """The PLC of ST files; `lib_path`: where a .plcproj's referenced libraries are (see compile_paths)."""
        return cls(compile_paths(list(paths), lib_path=lib_path, **_compile_kw(kw)), cycle, **kw)

    def axis(self, name: str | int) -> AxisView:
        """A PLCopen axis as the blocks saw it in the last scan (st.stdlib.plcopen.AxisView): by
        its configured name, its AxisNo or the path of an AXIS_REF variable."""
        return axis_view(self, name)


def _compile_kw(kw: dict) -> dict:
    out = {}
    for k in ("f_trig_first_scan", "time_unit", "use_cache", "coverage", "native", "dialect"):
        if k in kw:
            out[k] = kw.pop(k)
    return out
