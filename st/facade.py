"""`st.PLC`: the runtime's PLC with constructors that compile first (and the axes' view). Kept
apart from st/api.py so that compiling (`st check`, the compile API) loads no runtime."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Sequence
from typing import Any

from .api import compile_paths, compile_text
from .runtime import plc as runtime_plc
from .stdlib.plcopen import AxisView, axis_view


class PLC(runtime_plc.PLC):
    """The runtime's PLC, made from ST source text or files: the compile options among `kw`
    (f_trig_first_scan, time_unit, use_cache, coverage, native, dialect; lib_path for files) go to the
    compiler, the rest to the PLC.

    `opcua`: serve the program over OPC UA (st/opcua, docs/opcua.md) while this PLC lives: a dict of
    `OpcUaServer`'s keywords with "endpoint" ("[HOST:]PORT", default 127.0.0.1:4840), e.g.
    `{"endpoint": "127.0.0.1:4840", "users": "users.txt", "map_file": "opcua.toml"}`; the server is
    `plc.opcua`, polled between scans by scan(), advance() and run_realtime(), stopped by close()."""

    opcua: Any = None

    def __init__(self, compiled, cycle=None, *, opcua: dict[str, Any] | None = None, **kw):
        super().__init__(compiled, cycle, **kw)
        if opcua is not None:
            from .io.modbus import parse_endpoint
            from .opcua import OpcUaServer

            options = dict(opcua)
            host, port = parse_endpoint(options.pop("endpoint", "127.0.0.1:4840"))
            self.opcua = OpcUaServer(self, host, port, **options).start()

    def scan(self, n: int = 1) -> None:
        super().scan(n)
        if self.opcua is not None:
            self.opcua.poll()

    def advance(self, duration: Any) -> None:
        super().advance(duration)
        if self.opcua is not None:
            self.opcua.poll()

    def run_realtime(
        self,
        scans: int | None = None,
        duration: Any = None,
        on_idle: Callable[[runtime_plc.PLC], None] | None = None,
        phase: Any = "500us",
        gc_control: bool = True,
        stop: threading.Event | None = None,
    ) -> None:
        server, hook = self.opcua, on_idle
        if server is not None:

            def both(p: runtime_plc.PLC) -> None:
                server.poll()
                if hook is not None:
                    hook(p)

            hook = both
        super().run_realtime(scans, duration, hook, phase, gc_control, stop)

    def close(self) -> None:
        if self.opcua is not None:
            self.opcua.stop()
            self.opcua = None
        super().close()

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
