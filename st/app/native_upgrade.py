"""The native tier by default (issue 36): `st run` starts at once on the Python tier, builds the
same program (the very texts it runs) compiled to C in a process of its own (native_build.py:
Cython and the C compiler never hold this process's interpreter), reads the build from st's
cache beside the scan, and swaps it in at a scan boundary through the online-change path, its
state carried over. `--native` waits for the build before starting instead; `--python` stays on
the Python tier. Where Cython or a C compiler is missing, or a body cannot be compiled, the
Python tier goes on and one line says why. Not under `--virtual` (a run on virtual time is a
test: the same program throughout) nor `--web` (its line marks need the Python tier's probes:
`--native` there). With `--watch` an edit is swapped in on the Python tier at once, then built
natively in its turn.
"""

from __future__ import annotations

import pickle
import subprocess
import sys
import threading
import time
from typing import Any

from ..api import compile_sources_again, own_sources
from ..diagnostics import Code
from ..runtime.online_change import STALE, OnlineChangeRefused, beside_the_scan
from .options import RunOptions
from .output import err


class NativeUpgrade:
    """The background build and the swap (`poll()`, between two jobs)."""

    def __init__(self, plc: Any, o: RunOptions):
        self.plc, self.o = plc, o
        self.prepared: Any = None
        self.done = False
        self.started = time.monotonic()
        self.built_in = 0.0
        self.note = ""
        self.attempts = 0
        self.current = plc.compiled  # the program this build is for
        self.proc: subprocess.Popen[bytes] | None = None
        self.closed = False
        self._start()

    def close(self) -> None:
        """The run ends: a build still going is stopped (no compiler left running after st)."""
        self.closed = True
        proc = self.proc
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()

    def _start(self) -> None:
        self.attempts += 1
        threading.Thread(target=self._build, name="st-native-build", daemon=True).start()

    def _again_for(self, program: Any) -> None:
        """An edit came in on the Python tier (--watch swaps it in at once): build it natively too."""
        self.current, self.done, self.note, self.attempts, self.started = program, False, "", 0, time.monotonic()
        self._start()

    def _build(self) -> None:
        base = self.plc.compiled  # what runs now: its own texts are built (an edit since is --watch's)
        options = {
            "time_unit": self.o.time_unit,
            "f_trig_first_scan": self.o.f_trig_first_scan,
            "native": True,
            "dialect": self.o.dialect,
        }
        sources = own_sources(base)
        # Cython and the C compiler in a process of their own (native_build.py: into st's cache),
        # then the build read from the cache here, beside the scan
        payload = pickle.dumps(([(s.path, s.text) for s in sources], options))
        if self.closed:
            return
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "st.app.native_build"],
                stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            self.proc.communicate(payload)
        except OSError:
            pass  # (then built here, below)
        if self.closed:
            return
        with beside_the_scan():
            try:
                compiled = compile_sources_again(sources, **options)
                self.built_in = time.monotonic() - self.started
                if not compiled.native:
                    why = next((d.message for d in compiled.diagnostics if d.code == Code.NATIVE_UNAVAILABLE.value), "")
                    self.note = f"native: staying on the Python tier ({why or 'no block body could be compiled to C'})"
                    return
                change = self.plc.prepare_change(compiled)
                change.base = base  # it replaces the program it was built from, not one swapped in since
                self.prepared = change
            except Exception as e:  # noqa: BLE001 - the Python tier goes on whatever happens here
                self.note = f"native: staying on the Python tier ({type(e).__name__}: {e})"

    def poll(self) -> None:
        """At a scan boundary: the native program in, once it is built (or the reason it is not)."""
        if self.done:
            program = self.plc.compiled
            if program is not self.current and not program.native:
                self._again_for(program)
            return
        if self.note:
            self.done = True
            err(self.note)
            return
        if self.prepared is None:
            return
        prepared, self.prepared = self.prepared, None
        try:
            self.plc.apply_change(prepared)
        except OnlineChangeRefused as e:
            if e.reasons == [STALE] and self.attempts < 3:  # an edit came in (--watch): build the new one
                self._start()
                return
            self.done = True
            err(f"native: staying on the Python tier (the swap was refused: {'; '.join(e.reasons)})")
            return
        except Exception as e:  # noqa: BLE001 - refused: the Python tier goes on
            self.done = True
            err(f"native: staying on the Python tier (the swap was refused: {e})")
            return
        self.done = True
        bodies = sum(len(m.functions) + len(m.classes) for m in self.plc.compiled.native)
        err(
            f"native: built in {self.built_in:.1f} s; {bodies} block bodies now run compiled to C "
            "(swapped in at a scan boundary, the state carried over)"
        )
        self.current = self.plc.compiled


def start_native_upgrade(stack: Any, plc: Any, o: RunOptions) -> NativeUpgrade | None:
    """The background build (stopped by `stack` when the run ends), unless the run is native
    already, opted out, or cannot use it."""
    if o.native or o.python or o.virtual or o.web:
        return None
    upgrade = NativeUpgrade(plc, o)
    stack.callback(upgrade.close)
    return upgrade
