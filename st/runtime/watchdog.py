"""The task watchdog: ends a job that runs too long (an endless loop) or that a stop must end.

Every loop of generated code tests one global flag per iteration (`if _wd_armed: _wd_check()`,
the LoopGuard that compiler/lower/loops.py puts first in every ST loop), which costs a few nanoseconds while the flag is down.
A single daemon thread polls every 5 ms and raises the flag of a namespace whose running job
passed its deadline; the loop then calls `_wd_check`, which raises the WATCHDOG fault at the
loop's ST line. `abort()` raises the flag at once (a forced stop: a second Ctrl-C). The same
watchdog guards start-up and online change: module code, declared initial values and FB_init
run under a budget too.
"""

from __future__ import annotations

import threading
import time
import weakref
from typing import Any

from .faults import PLCFault

_POLL_S = 0.005
POLL_NS = int(_POLL_S * 1e9)


class Watchdog:
    def __init__(self, ns: dict[str, Any]):
        self.ns = ns
        self.deadline = 0  # monotonic ns; 0 = not running
        self.budget = 0
        self.what = "the job"
        self.abort_reason = ""
        ns["_wd_armed"] = False
        ns["_wd_check"] = self.check
        _Monitor.get().register(self)

    def start(self, budget_ns: int, what: str = "the job") -> None:
        self.abort_reason = ""
        self.budget = budget_ns
        self.what = what
        self.deadline = time.monotonic_ns() + budget_ns

    def arm(self, budget_ns: int) -> None:
        """start() for a task's job, on the engine's hot path: `what` is already "the job" (stop()
        puts it back) and no abort is pending (one is cleared by stop() or raised by check())."""
        self.budget = budget_ns
        self.deadline = time.monotonic_ns() + budget_ns

    def stop(self) -> None:
        self.deadline = 0
        self.abort_reason = ""
        self.what = "the job"
        if self.ns["_wd_armed"]:
            self.ns["_wd_armed"] = False

    @property
    def running(self) -> bool:
        return self.deadline != 0

    def abort(self, reason: str) -> None:
        """End the running job at its next loop iteration (safe to call from a signal handler)."""
        if self.deadline:
            self.abort_reason = reason
            self.ns["_wd_armed"] = True

    def check(self) -> None:
        if self.abort_reason:
            reason, self.abort_reason = self.abort_reason, ""
            self.deadline = 0
            self.ns["_wd_armed"] = False
            raise PLCFault(reason, "WATCHDOG")
        if self.deadline and time.monotonic_ns() >= self.deadline:
            self.ns["_wd_armed"] = False
            self.deadline = 0
            raise PLCFault(f"{self.what} did not finish within {_ms(self.budget)} (endless loop?)", "WATCHDOG")
        self.ns["_wd_armed"] = False

    def poll(self, now: int) -> None:
        if self.deadline and now >= self.deadline:
            self.ns["_wd_armed"] = True


def _ms(ns: int) -> str:
    return f"{ns / 1e9:g} s" if ns >= 1_000_000_000 else f"{ns / 1e6:g} ms"


class _Monitor:
    _instance = None
    _lock = threading.Lock()

    def __init__(self) -> None:
        self.dogs: weakref.WeakSet[Watchdog] = weakref.WeakSet()
        t = threading.Thread(target=self._run, name="st-watchdog", daemon=True)
        t.start()

    @classmethod
    def get(cls) -> _Monitor:
        with cls._lock:
            if cls._instance is None:
                cls._instance = _Monitor()
            return cls._instance

    def register(self, dog: Watchdog) -> None:
        self.dogs.add(dog)

    def _run(self) -> None:
        while True:
            time.sleep(_POLL_S)
            now = time.monotonic_ns()
            for dog in list(self.dogs):
                dog.poll(now)
