"""--watch: online change when a source file is edited."""

from __future__ import annotations

import os
import threading
import time

from ..api import compile_paths
from ..diagnostics import CompileError
from ..runtime.online_change import STALE, Change, OnlineChangeRefused, beside_the_scan
from ..runtime.plc import PLC
from .options import RunOptions
from .output import err


def source_mtimes(files) -> dict[str, int | None]:
    """Modification times of the source files; an edit made while the PLC starts is not missed when
    these are taken before compiling."""
    out: dict[str, int | None] = {}
    for f in files:
        try:
            out[f] = os.stat(f).st_mtime_ns
        except OSError:
            out[f] = None
    return out


class Watcher:
    """--watch: when a source changes, compile it, build the new program (namespace, instances,
    FB_init) and plan how its state is carried over, in a background thread while the old one keeps
    scanning; carry the state over and swap at a scan boundary (runtime/online_change.py). Whatever
    fails leaves the old program running and says why."""

    def __init__(self, plc: PLC, o: RunOptions):
        self.plc = plc
        self.o = o
        self.mtimes = o.compiled_mtimes if o.compiled_mtimes is not None else source_mtimes(o.files)
        self.last_poll = 0.0
        self.result: Change | None = None  # a change built by the background thread, swapped in by poll()
        self.busy = False

    def poll(self) -> None:
        if self.result is not None:
            prepared, self.result = self.result, None
            self._swap(prepared)
        now = time.monotonic()
        if self.busy or now - self.last_poll < 0.5:
            return
        self.last_poll = now
        m = source_mtimes(self.o.files)
        if m != self.mtimes:
            self.mtimes = m
            self.busy = True
            threading.Thread(target=self._prepare, daemon=True).start()

    def _prepare(self) -> None:
        with beside_the_scan():
            self._prepare_change()

    def _prepare_change(self) -> None:
        try:
            compiled = compile_paths(
                self.o.files,
                time_unit=self.o.time_unit,
                f_trig_first_scan=self.o.f_trig_first_scan,
                native=self.o.native,
                coverage=bool(self.o.web) and not self.o.native,  # --web's line marks (cli.run)
                dialect=self.o.dialect,
                lib_path=self.o.lib_path,
            )
            self.result = self.plc.prepare_change(compiled)
        except CompileError as e:
            err("\nonline change refused, the old program keeps running:\n" + e.render())
        except OnlineChangeRefused as e:
            err(f"\n{e}")
        except Exception as e:  # noqa: BLE001 - an edit must never take the PLC down
            err(f"\nonline change refused, the old program keeps running:\n  {type(e).__name__}: {e}")
        finally:
            self.busy = False

    def _swap(self, prepared) -> None:
        try:
            err("\n" + self.plc.apply_change(prepared))
        except OnlineChangeRefused as e:
            if e.reasons == [STALE]:
                self.mtimes = {}  # (the native build came in meanwhile) the edit is built again
                return
            err(f"\n{e}")
