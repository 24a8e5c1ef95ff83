"""Operating-system knobs for a real-time scan, each tried and reported: granted or why not.

SCHED_FIFO (priority 30 like OpenPLC v3 by default), mlockall, CPU affinity, holding
/dev/cpu_dma_latency at 0 (no deep C-states) and a 1 ns timer slack. Measured on these
machines (../shared/notes/realtime.md): SCHED_FIFO and cpu_dma_latency matter most.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import struct

_MCL_CURRENT, _MCL_FUTURE = 1, 2
_PR_SET_TIMERSLACK = 29


class RealtimeSetup:
    def __init__(self) -> None:
        self.granted: dict[str, str] = {}
        self._dma_fd: int | None = None

    def apply(self, priority: int = 30, cpu: int | None = None) -> dict[str, str]:
        libc = _libc()
        try:
            # every thread of the process, not only the scan's: a helper thread (the watchdog monitor)
            # left at SCHED_OTHER can be preempted by ordinary load while it holds the interpreter
            # lock, and the scan then waits for it (priority inversion, measured: p99 10 ms under
            # stress-ng). Threads started later inherit the policy.
            for tid in _threads():
                os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
            self.granted["SCHED_FIFO"] = f"priority {priority}"
        except (OSError, AttributeError) as e:
            self.granted["SCHED_FIFO"] = f"refused ({_why(e)})"
        if libc is not None and libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) == 0:
            self.granted["mlockall"] = "locked"
        else:
            self.granted["mlockall"] = f"refused ({os.strerror(ctypes.get_errno()) if libc else 'no libc'})"
        if cpu is not None:
            try:
                os.sched_setaffinity(0, {int(cpu)})
                self.granted["affinity"] = f"CPU {cpu}"
            except OSError as e:
                self.granted["affinity"] = f"refused ({_why(e)})"
        try:
            self._dma_fd = os.open("/dev/cpu_dma_latency", os.O_WRONLY)
            os.write(self._dma_fd, struct.pack("i", 0))
            self.granted["cpu_dma_latency"] = "held at 0"
        except OSError as e:
            self.granted["cpu_dma_latency"] = f"refused ({_why(e)})"
        if libc is not None and libc.prctl(_PR_SET_TIMERSLACK, 1, 0, 0, 0) == 0:
            self.granted["timerslack"] = "1 ns"
        else:
            self.granted["timerslack"] = "refused"
        return self.granted

    def release(self) -> None:
        if self._dma_fd is not None:
            os.close(self._dma_fd)
            self._dma_fd = None
        try:
            for tid in _threads():
                os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
        except (OSError, AttributeError):
            pass
        libc = _libc()
        if libc is not None:
            libc.munlockall()


def _threads() -> list[int]:
    try:
        return [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:
        return [0]


def _libc() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("c")
    if not name:
        return None
    try:
        return ctypes.CDLL(name, use_errno=True)
    except OSError:
        return None


def _why(e: OSError | AttributeError) -> str:
    return getattr(e, "strerror", None) or type(e).__name__
