"""The PLC's two clocks: virtual (jumps to the next event) and real (CLOCK_MONOTONIC, absolute deadlines).

Both count nanoseconds of PLC time from the start of the run. The real clock sleeps to a
little before a deadline, then spins on `time.monotonic_ns()` for the last stretch (a sleep
alone wakes up to a scheduler tick late); the grid of deadlines is offset by a phase so it
does not coincide with the kernel's tick (measured here: aligned deadlines lose ~44 µs).
"""

from __future__ import annotations

import time

SPIN_NS = 200_000  # sleep until deadline − 200 µs, then spin
SLICE_NS = 50_000_000  # the longest single sleep


class VirtualClock:
    real = False

    def __init__(self, start: int = 0):
        self.t = start

    def now(self) -> int:
        return self.t

    def sleep_until(self, t: int) -> None:
        if t > self.t:
            self.t = t

    def spend(self, ns: int) -> None:
        """Execution time on virtual time (a task's simulated cost)."""
        self.t += ns


class RealClock:
    real = True

    def __init__(self, start: int = 0, phase_ns: int = 0, spin_ns: int = SPIN_NS):
        self.base = time.monotonic_ns() - start + phase_ns
        self.spin = spin_ns
        self.wake = False  # set by a stop request: a long sleep ends early

    def now(self) -> int:
        return time.monotonic_ns() - self.base

    def sleep_until(self, t: int) -> None:
        deadline = self.base + t
        mono = time.monotonic_ns
        # long sleeps in slices, so that a stop request (a signal) is seen within one slice
        while not self.wake:
            rest = deadline - mono() - self.spin
            if rest <= 0:
                break
            time.sleep(min(rest, SLICE_NS) / 1e9)
        if self.wake:
            return
        while mono() < deadline:
            pass

    def spend(self, ns: int) -> None:
        pass
