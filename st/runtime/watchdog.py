"""The task watchdog: ends a scan that runs too long (an endless loop).

Generated loops test one global flag per iteration (`if _wd_armed: _wd_check()`),
which costs a few nanoseconds while the flag is down. A single daemon thread
raises the flag of a PLC whose running task passed its deadline; the loop then
calls `_wd_check`, which raises the WATCHDOG fault at the loop's ST line.
"""
from __future__ import annotations

import threading
import time
import weakref

from .faults import PLCFault

_POLL_S = 0.005


class Watchdog:
    def __init__(self, ns: dict):
        self.ns = ns
        self.deadline = 0           # monotonic ns; 0 = not running
        ns["_wd_armed"] = False
        ns["_wd_check"] = self.check
        _Monitor.get().register(self)

    def start(self, budget_ns: int) -> None:
        self.deadline = time.monotonic_ns() + budget_ns

    def stop(self) -> None:
        self.deadline = 0
        if self.ns["_wd_armed"]:
            self.ns["_wd_armed"] = False

    def check(self) -> None:
        if self.deadline and time.monotonic_ns() >= self.deadline:
            self.ns["_wd_armed"] = False
            self.deadline = 0
            raise PLCFault("watchdog: the task did not finish in time (endless loop?)", "WATCHDOG")
        self.ns["_wd_armed"] = False

    def poll(self, now: int) -> None:
        if self.deadline and now >= self.deadline:
            self.ns["_wd_armed"] = True


class _Monitor:
    _instance = None
    _lock = threading.Lock()

    def __init__(self):
        self.dogs: "weakref.WeakSet[Watchdog]" = weakref.WeakSet()
        t = threading.Thread(target=self._run, name="st-watchdog", daemon=True)
        t.start()

    @classmethod
    def get(cls) -> "_Monitor":
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
