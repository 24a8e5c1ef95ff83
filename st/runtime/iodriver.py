"""What the PLC asks of an I/O driver (the Modbus slave, EtherCAT, the motion kernel).

A driver joins `PLC.io`. The engine calls `before_job(task)` before a job latches its inputs
and `after_job(task)` after it published its outputs; `after_job()` without a task when the
outputs went to their safe values (stop, fault). `rebind()` follows every reload of the
program (warm restart, online change). Work done there must be a few memory operations: a
driver keeps its own threads or processes off the scan's path.

The optional parts have defaults in `IODriverBase`, which drivers extend: a `name`, `stats()`
for the end-of-run report, `status()`, a JSON-able view of the driver's state that the online
mode asks of each driver on `plc.io` by its name between two jobs (the motion kernel's axes,
EtherCAT's counters and slaves, the Modbus slave's clients), and for a driver that lives in the
program's namespace (`per_namespace`, listed in its `_io_drivers`, made again with every reload)
`adopt(old)` to take over the state of the one it replaces, and `join(plc)`, which puts it into
`PLC.io` (a driver with nothing to do yet may wait, as the motion kernel waits for its first
axis: the engine then pays nothing for it).
"""

from __future__ import annotations

from typing import Any, Protocol

from .scheduler import Task


class IODriver(Protocol):
    name: str
    per_namespace: bool

    def before_job(self, task: Task | None = None) -> None: ...

    def after_job(self, task: Task | None = None) -> None: ...

    def rebind(self) -> None: ...

    def join(self, plc: Any) -> None: ...

    def adopt(self, old: IODriver) -> None: ...

    def stats(self) -> dict[str, Any] | None: ...

    def status(self) -> dict[str, Any] | None: ...


class IODriverBase:
    """Defaults for the optional parts of IODriver: nothing to do, nothing to report."""

    name = ""  # shown in reports and the online mode ("" and stats() / status() None: not shown)
    per_namespace = False  # True: made by the program's namespace, replaced on every reload

    def before_job(self, task: Task | None = None) -> None:
        pass

    def after_job(self, task: Task | None = None) -> None:
        pass

    def rebind(self) -> None:
        pass

    def join(self, plc: Any) -> None:
        """A per-namespace driver joins the PLC's drivers after a (re)load: first in `plc.io`, so that
        it runs before the drivers that carry its results to the field."""
        plc.io.insert(0, self)

    def adopt(self, old: IODriver) -> None:
        """A per-namespace driver replacing `old` after a reload takes over what must survive it."""

    def stats(self) -> dict[str, Any] | None:
        """Counters for the end-of-run report, or None."""
        return None

    def status(self) -> dict[str, Any] | None:
        """The driver's state as JSON-able values for the online mode (called between two jobs), or
        None: nothing to show."""
        return None
