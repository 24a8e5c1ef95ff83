"""The PLC: program instances of a configuration, tasks, the scan engine, states and variable access.

This is the façade; each job lives in its own module and works on the PLC's state:
build.py (loading a program: build, install), engine.py (releases, jobs, both clocks),
lifecycle.py (STOP/RUN/FAULT, safe outputs, warm restart), retained.py (RETAIN/PERSISTENT
values), online_change.py, access.py (variables by path or %address, forcing, dumps) over
paths.py (path resolution) and varref.py (`ref`).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from ..model.compiled import CompiledProgram
from . import access, engine, lifecycle, online_change
from .build import build, install
from .clock import VirtualClock
from .faults import FaultInfo
from .iodriver import IODriver
from .lifecycle import RUN
from .messages import MessageLog
from .online_change import Change
from .process_image import Binding, ProcessImage, parse_address
from .retain import RetainStore
from .retained import commit_retained, restore_retained
from .scheduler import Policy, Task
from .stats import TaskStats
from .values import parse_duration_arg
from .varref import VarRef
from .watchdog import Watchdog


class PLC:
    """A PLC for one compiled program (its first CONFIGURATION).

    policy: openplc | priority | edf | frame.  watchdog: a budget per task (default 10 ×
    its interval on real time, at least 1 s on virtual time).  retain: a SQLite file for
    RETAIN/PERSISTENT variables (restored here unless cold=True).  safe_outputs: {"%QX0.1":
    True, …} written to the image on a fault or stop instead of FALSE/0.

    For drivers: `image` (the process image), `bindings` (normalised address → [Binding] of the
    located variables), `tasks`, `ns` (the program's namespace), `io` (the I/O drivers, see
    iodriver.py), `clock`; `ref(path)` gives a VarRef to one variable.
    """

    # set by install() (build.py) for every program made the running one
    compiled: CompiledProgram
    project: Any
    ns: dict[str, Any]
    config: Any
    instances: dict[str, tuple[str, Any, Any]]  # lower name → (display name, object, POUType)
    tasks: list[Task]
    tick: int
    policy: Policy
    job_lock: threading.Lock | None  # what a job holds: the image lock under the frame policy
    job_task: Task | None = None  # the task whose job is running (None between jobs)
    bindings: dict[str, list[Binding]]
    _binding_of: dict[tuple[int, Any], Binding]
    _wd: Watchdog
    _event_tasks: list[Task]
    _next_tick: int

    _on_idle: Callable[[PLC], None] | None = None
    _stop_event: threading.Event | None = None
    idle_slack: float = 0  # ns until the next release, as seen by an `on_idle` hook

    def __init__(
        self,
        compiled: CompiledProgram,
        cycle: Any = None,
        *,
        watchdog: Any = None,
        policy: str = "openplc",
        retain: str | None = None,
        retain_interval: Any = "1s",
        cold: bool = False,
        safe_outputs: dict[str, Any] | None = None,
    ):
        self.cycle = parse_duration_arg(cycle) if cycle is not None else None
        self.watchdog = parse_duration_arg(watchdog) if watchdog is not None else None
        self.policy_name = policy
        self.safe_outputs = dict(safe_outputs or {})
        for addr in self.safe_outputs:
            if parse_address(addr)[0] != "Q":
                raise ValueError(f"safe output {addr}: only outputs (%Q…) have safe values")
        self.image = ProcessImage()
        self.image_lock = threading.Lock()  # held by a job under the frame policy (the thesis's semaphore)
        self.state = RUN
        self.fault: FaultInfo | None = None
        self.faults: list[FaultInfo] = []
        self._time = 0
        self.scans = 0
        self.clock: Any = VirtualClock()
        self._stats: dict[str, TaskStats] = {}
        self.io: list[IODriver] = []  # see iodriver.py
        self.log = MessageLog()  # the program's messages (ADSLOGSTR, …), kept across online changes
        # (path, id(container), key) → (container, key, value, binding)
        self._forced: dict[tuple[str, int, Any], tuple[Any, Any, Any, Binding | None]] = {}
        self._force_spec: dict[str, Any] = {}  # path → the value asked for (re-applied after a reload)
        self._stop_requested = False
        self.retain_store: RetainStore | None = None
        install(self, build(compiled, self.image, cycle=self.cycle, watchdog=self.watchdog, policy=policy), first=True)
        self.retain_store = RetainStore(retain) if retain else None
        self.retain_interval = parse_duration_arg(retain_interval)
        self._next_retain = self.retain_interval
        self.retain_restored = 0
        if self.retain_store is not None:
            if cold:
                self.retain_store.clear()
            else:
                self.retain_restored = restore_retained(self, self.retain_store.load())

    # ------------------------------------------------------------------ time and the engine
    @property
    def time(self) -> int:
        """The PLC time (ns) at which the next scan runs."""
        return self._time

    def set_cost(self, task: str, cost: Any) -> None:
        """Simulated execution time of a task's job on virtual time (to study overload): a duration,
        or a callable returning ns for each job (e.g. random execution times)."""
        for t in self.tasks:
            if t.name.lower() == task.lower():
                t.cost = cost if callable(cost) else parse_duration_arg(cost)
                return
        raise KeyError(f"no task named {task!r}")

    def scan(self, n: int = 1) -> None:
        """Run n base ticks on virtual time."""
        engine.run_virtual(self, self._time + n * self.tick)

    def advance(self, duration: Any) -> None:
        """Run on virtual time until `duration` more PLC time has passed (whole base ticks)."""
        d = parse_duration_arg(duration)
        engine.run_virtual(self, self._time + -(-d // self.tick) * self.tick)

    def run_realtime(
        self,
        scans: int | None = None,
        duration: Any = None,
        on_idle: Callable[[PLC], None] | None = None,
        phase: Any = "500us",
        gc_control: bool = True,
        stop: threading.Event | None = None,
    ) -> None:
        """Pace the engine by CLOCK_MONOTONIC with absolute deadlines (no drift) until `scans` base ticks
        or `duration` have passed, `stop` is set, or Ctrl-C. `on_idle(plc)` runs between jobs when there
        is slack (status line, file watching). A fault ends the run with PLCFaultError."""
        engine.run_realtime(self, scans, duration, on_idle, phase, gc_control, stop)

    def request_stop(self, reason: str = "stop requested") -> None:
        """Stop the engine at the next scan boundary; safe from a signal handler or another thread.
        A job still running finishes, or is ended by its watchdog budget; asked again while that job
        runs, the job is ended at once (at its next loop iteration) as a WATCHDOG fault."""
        engine.request_stop(self, reason)

    # ------------------------------------------------------------------ states and faults
    def stop(self) -> None:
        """RUN → STOP: no task runs, outputs safe, retained data committed."""
        lifecycle.stop(self)

    def start(self) -> None:
        lifecycle.start(self)

    def reset_fault(self) -> None:
        """FAULT → RUN with the program's state as the fault left it."""
        lifecycle.reset_fault(self)

    def restart(self, cold: bool = False) -> None:
        """Warm restart (after a fault, --on-fault restart): fresh instances, retained values restored.
        Cold: every variable, retained ones too, starts from its initial value."""
        lifecycle.restart(self, cold)

    def close(self) -> None:
        """Clean shutdown: outputs safe, retained data committed and the store closed."""
        lifecycle.close(self)

    # ------------------------------------------------------------------ retained data
    def commit_retained(self) -> None:
        commit_retained(self)

    # ------------------------------------------------------------------ online change
    def online_change(self, compiled: CompiledProgram) -> str:
        """Swap in a new build of the program at this scan boundary, carrying every variable over by
        name and type. All or nothing: raises OnlineChangeRefused (a ValueError) and leaves the running
        program and its state untouched when the configuration or a variable's type changed, when the
        new program cannot start (an address outside the image, a fault in FB_init), or when a value
        cannot be carried over."""
        return self.apply_change(self.prepare_change(compiled))

    def prepare_change(self, compiled: CompiledProgram) -> Change:
        """The part of an online change that runs in another thread while the old program scans:
        the checks, the new namespace and instances with their FB_init, and the plan that carries
        the state over (from the types: it reads no value)."""
        return online_change.prepare_change(self, compiled)

    def apply_change(self, change: Change) -> str:
        """The part of an online change done at a scan boundary: carry the state over by the plan
        (per variable; an unchanged array of elementary values is moved, not copied), swap."""
        return online_change.apply_change(self, change)

    # ------------------------------------------------------------------ statistics
    def stats(self) -> list[dict[str, Any]]:
        """Per-task statistics summaries (see runtime/stats.py)."""
        return [t.stats.summary() for t in self.tasks]

    def use_stats(self, task: str, stats: TaskStats) -> None:
        """Record a task's jobs in `stats` (a TaskStats, or a subclass that records more) from now on,
        also after a reload while the task keeps its interval."""
        for t in self.tasks:
            if t.name.lower() == task.lower():
                t.stats = self._stats[t.name] = stats
                return
        raise KeyError(f"no task named {task!r}")

    # ------------------------------------------------------------------ variables
    def __getitem__(self, path: str) -> Any:
        return access.get(self, path)

    def __setitem__(self, path: str, value: Any) -> None:
        access.set_(self, path, value)

    def ref(self, path: str) -> VarRef:
        """A reference to the variable at `path` ("main.fb.x", "g_arr[2]", "main.w.3"); KeyError
        saying what is wrong with the path. Valid until the program is reloaded."""
        return access.ref(self, path)

    def force(self, path: str, value: Any) -> None:
        """Force a variable (or a located variable by its %address): it holds `value` when every job
        starts and ends, whatever the program, the inputs or an HMI write it, until unforce()."""
        access.force(self, path, value)

    def unforce(self, path: str | None = None) -> None:
        """Release one forced variable, or all of them."""
        access.unforce(self, path)

    @property
    def forced(self) -> list[str]:
        return sorted({k[0] for k in self._forced})

    def variables(self, all: bool = False) -> dict[str, Any]:
        """Every variable of every program instance, as JSON values keyed "instance.var"; a function
        block instance by its interface (inputs, outputs, in-outs) unless all=True."""
        return access.variables(self, all=all)

    def globals(self) -> dict[str, Any]:
        """Global variables, and static ones (VAR_STAT) as 'POU.name' or 'FB.Method.name'."""
        return access.globals_(self)
