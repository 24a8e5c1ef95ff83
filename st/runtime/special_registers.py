"""OpenPLC v3's special function registers: %ML1024 and up, filled by the runtime before each scan.

OpenPLC's runtime writes them into the located variables at every cycle, before the program
runs (a program's own writes are overwritten at the next cycle):

| register | value |
|---|---|
| %ML1024 | local time, seconds since 1970-01-01 (as if the local clock were UTC) |
| %ML1025 | the number of the current cycle (base tick), 1 in the first |
| %ML1026 | Modbus master communication errors: st has no Modbus master; left to the program |
| %ML1027 | UTC time, seconds since 1970-01-01 |
| %ML1028 | the previous job's execution time of this task, µs |
| %ML1029 | the previous job's wake-up latency of this task, µs |

%ML1030-%ML2047 are plain memory the runtime does not touch. On virtual time the clock is the
PLC's own (seconds of PLC time since the start, local = UTC), so tests stay reproducible.
"""

from __future__ import annotations

import calendar
import time
from typing import TYPE_CHECKING

from ..model.addresses import SPECIAL_BASE
from .iodriver import IODriverBase
from .scheduler import Task

if TYPE_CHECKING:
    from .plc import PLC

LOCAL_TIME, CYCLES, UTC_TIME, CYCLE_TIME, LATENCY = (SPECIAL_BASE + k for k in (0, 1, 3, 4, 5))


class SpecialRegisters(IODriverBase):
    """Joins `PLC.io` when the program binds a special register (runtime/build.py)."""

    def __init__(self, plc: PLC):
        self.plc = plc
        self.table = plc.image.tables[("M", "L")]

    def before_job(self, task: Task | None = None) -> None:
        if task is None:
            return
        plc, table = self.plc, self.table
        now = plc.clock.now()
        if plc.clock.real:
            utc = int(time.time())
            local = calendar.timegm(time.localtime(utc))
        else:
            utc = local = now // 1_000_000_000
        table[LOCAL_TIME] = local
        table[UTC_TIME] = utc
        table[CYCLES] = now // plc.tick + 1
        stats = task.stats
        table[CYCLE_TIME] = stats.last_exec // 1000
        table[LATENCY] = stats.latencies[-1] // 1000 if stats.latencies else 0
