"""The PLC: program instances of a configuration, tasks, the scan engine, states and variable access.

One engine serves both clocks: on virtual time (`scan`, `advance`: tests, simulation) the
clock jumps from event to event; on real time (`run_realtime`) it sleeps to absolute
deadlines on CLOCK_MONOTONIC. The policy (`scheduler.py`) orders the released jobs; each job
latches the process image's inputs, runs its task's program instances and publishes the
outputs. The PLC clock that timers read is the job's release time, so a run is deterministic
whether it is paced or not. States: STOP, RUN, FAULT.
"""
from __future__ import annotations

import gc
import math
import threading
from typing import Callable, Optional

from ..compiler import types as T
from ..compiler.driver import CompiledProgram
from .clock import RealClock, VirtualClock
from .faults import FaultInfo, fault_from_exception
from .iodriver import IODriver
from .namespace import build_namespace
from .paths import Holder, norm_addr, read, resolve, write
from .process_image import AddressError, Binding, ProcessImage, from_raw, parse_address, to_raw
from . import refnames
from .relink import relink
from .retain import RetainStore
from .scheduler import Task, make_policy
from .stats import TaskStats
from .varref import VarRef
from .watchdog import Watchdog
from .values import ValueError_, from_python, parse_duration_arg, to_json, to_python

DEFAULT_CYCLE = 10_000_000

STOP, RUN, FAULT = "STOP", "RUN", "FAULT"


class PLCFaultError(RuntimeError):
    """A scan ended in a PLC fault; `.fault` says where and why."""

    def __init__(self, fault: FaultInfo):
        super().__init__(str(fault))
        self.fault = fault


class PLCStartError(ValueError):
    """The program cannot start: a located address outside the process image, a VAR_CONFIG value
    that does not fit, or a fault while creating the instances (FB_init, an initial value): then
    `.fault` names it and its ST line, as for a fault in a scan."""

    def __init__(self, message: str, fault: Optional[FaultInfo] = None):
        super().__init__(message)
        self.fault = fault


class OnlineChangeRefused(ValueError):
    """An online change that cannot be applied; the running program and its state are untouched."""

    def __init__(self, reasons: list):
        super().__init__("online change refused, the old program keeps running:\n  " + "\n  ".join(reasons))
        self.reasons = list(reasons)


# start-up, warm restart and online change run initial values and FB_init under the watchdog too,
# with the task budget (--watchdog) but at least this much
STARTUP_BUDGET = 1_000_000_000


class _Build:
    """A program made ready to run (namespace, instances, tasks, image bindings) but not running yet.
    Its attribute names are the PLC's, so path resolution works on either."""

    def __init__(self, compiled: CompiledProgram):
        self.compiled = compiled
        self.project = compiled.project
        self.ns: dict = {}
        self.wd: Optional[Watchdog] = None
        self.config = None
        self.instances: dict = {}           # lower name → (display name, object, POUType)
        self.tasks: list = []
        self.tick = DEFAULT_CYCLE
        self.policy = None
        self.bindings: dict = {}            # normalised address → [Binding]
        self.binding_of: dict = {}          # (id(container), key) → Binding


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

    def __init__(self, compiled: CompiledProgram, cycle=None, *, watchdog=None, policy: str = "openplc",
                 retain: Optional[str] = None, retain_interval="1s", cold: bool = False,
                 safe_outputs: Optional[dict] = None):
        self.cycle = parse_duration_arg(cycle) if cycle is not None else None
        self.watchdog = parse_duration_arg(watchdog) if watchdog is not None else None
        self.policy_name = policy
        self.safe_outputs = dict(safe_outputs or {})
        for addr in self.safe_outputs:
            if parse_address(addr)[0] != "Q":
                raise ValueError(f"safe output {addr}: only outputs (%Q…) have safe values")
        self.image = ProcessImage()
        self.image_lock = threading.Lock()      # held by a job under the frame policy (the thesis's semaphore)
        self.state = RUN
        self.fault: Optional[FaultInfo] = None
        self.faults: list = []
        self._time = 0
        self.scans = 0
        self.clock = VirtualClock()
        self._stats: dict = {}
        self.io: list[IODriver] = []            # see iodriver.py
        self._forced: dict = {}                 # (path, id(container), key) → (container, key, value, binding)
        self._force_spec: dict = {}             # path → the value asked for (re-applied after a reload)
        self._stop_requested = False
        self._install(self._build(compiled))
        self.retain_store = RetainStore(retain) if retain else None
        self.retain_interval = parse_duration_arg(retain_interval)
        self._next_retain = self.retain_interval
        self.retain_restored = 0
        if self.retain_store is not None:
            if cold:
                self.retain_store.clear()
            else:
                self.retain_restored = self._restore_retained(self.retain_store.load())

    # ------------------------------------------------------------------ construction
    # A program is made ready in two steps. `_build` executes the generated modules into a new
    # namespace, creates the program instances (declared values, FB_init), applies VAR_CONFIG and
    # checks every located address, all under the watchdog and without touching the running PLC;
    # any failure raises PLCStartError. `_install` then makes it the running program, and cannot
    # fail for reasons of the program. Start-up, warm restart and online change all go this way,
    # so a change is all or nothing.
    def _build(self, compiled: CompiledProgram, what: str = "start-up") -> "_Build":
        b = _Build(compiled)
        budget = max(self.watchdog or 0, STARTUP_BUDGET)

        def install(ns):
            b.wd = Watchdog(ns)
            b.wd.start(budget, f"the {what} (initial values, FB_init)")
        try:
            b.ns = build_namespace(compiled, install)
            cfg = b.config = b.project.configs[0] if b.project.configs else None
            cyc = self.cycle
            if cfg is not None:
                for tm in cfg.tasks:
                    interval = tm.interval
                    if cfg.implicit or (interval == 0 and not tm.single):
                        interval = cyc or DEFAULT_CYCLE
                    b.tasks.append(Task(tm.name, interval, tm.priority, [], tm.single, index=len(b.tasks)))
                by_task = {t.name.lower(): t for t in b.tasks}
                for im in cfg.instances:
                    obj = b.ns[im.type.pyname]()
                    b.instances[im.name.lower()] = (im.name, obj, im.type)
                    task = by_task.get(im.task.lower()) if im.task else None
                    if task is None:
                        if not b.tasks:
                            b.tasks.append(Task("main", cyc or DEFAULT_CYCLE, 0, []))
                        task = b.tasks[0]
                    task.instances.append((im.name, obj, im))
                self._apply_var_config(cfg, b)
            for t in b.tasks:
                t.calls = [(name, obj, b.ns.get("_cfg_in_" + name.lower()), b.ns.get("_cfg_out_" + name.lower()))
                           for name, obj, im in t.instances]
            intervals = [t.interval for t in b.tasks if t.interval > 0]
            b.tick = math.gcd(*intervals) if intervals else (cyc or DEFAULT_CYCLE)
            b.policy = make_policy(self.policy_name, b.tasks, b.tick)
            self._bind_image(b)
        except PLCStartError:
            raise
        except (AddressError, KeyError, ValueError_, ValueError) as e:
            raise PLCStartError(str(e)) from None
        except Exception as exc:  # noqa: BLE001 - a fault of ST code (FB_init, an initial value) or a limit
            info = fault_from_exception(exc)
            raise PLCStartError(str(info), info) from None
        finally:
            if b.wd is not None:
                b.wd.stop()
        return b

    def _install(self, b: "_Build") -> None:
        """Make a built program the running one (at a scan boundary)."""
        old_ns = getattr(self, "ns", None)
        self.compiled, self.project, self.ns, self._wd = b.compiled, b.project, b.ns, b.wd
        self.config, self.instances, self.tasks = b.config, b.instances, b.tasks
        self.tick, self.policy = b.tick, b.policy
        self.bindings, self._binding_of = b.bindings, b.binding_of
        # drivers that live in the namespace (the motion kernel) follow it; the old ones hand over
        old_drivers = {type(d): d for d in self.io if d.per_namespace}
        self.io = [d for d in self.io if not d.per_namespace]
        for d in b.ns.get("_io_drivers", []):
            prev = old_drivers.get(type(d))
            if prev is not None and old_ns is not None:
                d.adopt(prev)
            self.io.insert(0, d)
        for t in self.tasks:
            old = self._stats.get(t.name)
            t.stats = old if old is not None and old.period == t.interval else TaskStats(t.name, t.interval)
            self._stats[t.name] = t.stats
        for binds in self.bindings.values():
            for bd in binds:
                bd.publish() if bd.area in "QM" else bd.latch_in()
        self._event_tasks = [t for t in self.tasks if t.single]
        self._reset_releases(self._time)
        if getattr(self, "_force_spec", None):
            spec, self._forced = dict(self._force_spec), {}
            for path, value in spec.items():
                try:
                    self.force(path, value)
                except (KeyError, ValueError, TypeError):
                    self._force_spec.pop(path, None)       # the variable is gone or changed its type
        for d in self.io:
            d.rebind()

    def _reset_releases(self, now: int) -> None:
        for t in self.tasks:
            t.pending = None
            if t.interval > 0:
                t.next_release = -(-now // t.interval) * t.interval     # the next multiple of the interval
        self._next_tick = -(-now // self.tick) * self.tick

    def _apply_var_config(self, cfg, b: "_Build") -> None:
        """VAR_CONFIG initial values (literals) for variables inside program instances."""
        for path, location, init, ty, span in cfg.var_config:
            if init is None or not path or not hasattr(init, "value"):
                continue
            try:
                container, key, t = resolve(b, ".".join(path))
                write(container, key, from_python(init.value, t, ".".join(path)))
            except (KeyError, ValueError_) as e:
                raise PLCStartError(f"{span.file}:{span.line}: VAR_CONFIG {'.'.join(path)}: {e}") from None

    # ------------------------------------------------------------------ process image
    def _located(self, b: "_Build"):
        """(address, container, key, type, owning instance name or None) of every located variable."""
        for lname, (name, obj, pou) in b.instances.items():
            for sym in pou.vars.values():
                if sym.location and "*" not in sym.location:
                    yield sym.location, obj, sym.pyname, sym.type, lname
        for g in b.project.globals.values():
            if g.location and "*" not in g.location:
                yield g.location, b.ns, g.pyname, g.type, None
        for addr, (pyname, t) in b.project.direct_vars.items():
            yield addr, b.ns, pyname, t, None
        if b.config is not None:
            for path, location, init, ty, span in b.config.var_config:
                if location and "*" not in location:
                    try:
                        container, key, t = resolve(b, ".".join(path))
                    except KeyError:
                        continue
                    yield location, container, key, t, path[0].lower()

    def _bind_image(self, b: "_Build") -> None:
        """Each task latches the inputs of its own instances (and located globals) and publishes its outputs."""
        owner_task = {}
        for t in b.tasks:
            t.ins, t.outs = [], []
            for name, obj, im in t.instances:
                owner_task[name.lower()] = t
        for addr, container, key, t, inst in self._located(b):
            try:
                bd = Binding(addr, container, key, t, self.image)
            except AddressError as e:
                raise PLCStartError(f"{addr}: {e}") from None
            b.bindings.setdefault(norm_addr(addr), []).append(bd)
            b.binding_of[(id(container), key)] = bd
            targets = [owner_task[inst]] if inst in owner_task else b.tasks
            for task in targets:
                if bd.area in "IM":
                    task.ins.append(bd)
                if bd.area in "QM":
                    task.outs.append(bd)

    # ------------------------------------------------------------------ time and the engine
    @property
    def time(self) -> int:
        """The PLC time (ns) at which the next scan runs."""
        return self._time

    def set_cost(self, task: str, cost) -> None:
        """Simulated execution time of a task's job on virtual time (to study overload): a duration,
        or a callable returning ns for each job (e.g. random execution times)."""
        for t in self.tasks:
            if t.name.lower() == task.lower():
                t.cost = cost if callable(cost) else parse_duration_arg(cost)
                return
        raise KeyError(f"no task named {task!r}")

    def scan(self, n: int = 1) -> None:
        """Run n base ticks on virtual time."""
        self._run_virtual(self._time + n * self.tick)

    def advance(self, duration) -> None:
        """Run on virtual time until `duration` more PLC time has passed (whole base ticks)."""
        d = parse_duration_arg(duration)
        self._run_virtual(self._time + -(-d // self.tick) * self.tick)

    def _run_virtual(self, t_end: int) -> None:
        if self.state == FAULT:
            raise PLCFaultError(self.fault)
        if not isinstance(self.clock, VirtualClock):
            self.clock = VirtualClock(self._time)
        if self.clock.now() < self._time:
            self.clock.t = self._time
        self._engine(t_end)

    def run_realtime(self, scans: Optional[int] = None, duration=None, on_idle: Optional[Callable] = None,
                     phase="500us", gc_control: bool = True, stop: Optional[threading.Event] = None) -> None:
        """Pace the engine by CLOCK_MONOTONIC with absolute deadlines (no drift) until `scans` base ticks
        or `duration` have passed, `stop` is set, or Ctrl-C. `on_idle(plc)` runs between jobs when there
        is slack (status line, file watching). A fault ends the run with PLCFaultError."""
        if self.state == FAULT:
            raise PLCFaultError(self.fault)
        end = math.inf
        if scans is not None:
            end = self._time + scans * self.tick
        if duration is not None:
            end = min(end, self._time + parse_duration_arg(duration))
        gc_was = gc.isenabled()
        if gc_control:
            gc.collect()
            gc.freeze()
            gc.disable()
        self.clock = RealClock(self._time, parse_duration_arg(phase) if phase else 0)
        self._on_idle = on_idle
        self._stop_event = stop
        try:
            self._engine(end)
        finally:
            self._on_idle = None
            self._stop_event = None
            if gc_control:
                gc.unfreeze()
                if gc_was:
                    gc.enable()
            self.clock = VirtualClock(self._time)

    _on_idle = None
    _stop_event = None

    def request_stop(self, reason: str = "stop requested") -> None:
        """Stop the engine at the next scan boundary; safe from a signal handler or another thread.
        A job still running finishes, or is ended by its watchdog budget; asked again while that job
        runs, the job is ended at once (at its next loop iteration) as a WATCHDOG fault."""
        if self._stop_requested and self._wd.running:
            self._wd.abort(f"the job was ended by a second stop request ({reason})")
        self._stop_requested = True
        if isinstance(self.clock, RealClock):
            self.clock.wake = True
    idle_slack = 0              # ns until the next release, as seen by an `on_idle` hook

    def _engine(self, t_end) -> None:
        """Release and run jobs until PLC time t_end (exclusive for releases)."""
        clock = self.clock
        eager = self.policy.eager
        key = self.policy.key
        tasks = self.tasks
        idle_jobs = 0
        while True:
            if self._stop_requested or (self._stop_event is not None and self._stop_event.is_set()):
                self._stop_requested = False
                self._time = max(self._time, min(self._next_tick, t_end))
                return
            now = clock.now()
            if now >= t_end:            # overloaded on virtual time: the clock passed the end; stop here
                self._time = max(self._time, t_end)
                self.scans = self._time // self.tick
                return
            if eager:
                self._release_until(min(now, t_end - 1))
                ready = [t for t in tasks if t.pending is not None]
                if ready and self.state == RUN:
                    task = min(ready, key=lambda t: key(t, t.pending))
                    release = task.pending
                    task.pending = None
                    self._job(task, release)
                    idle_jobs += 1
                    continue
                for t in ready:         # STOP or FAULT: releases lapse
                    t.pending = None
                nxt = min([t.next_release for t in tasks if t.interval > 0] +
                          ([self._next_tick] if self._event_tasks else []) + [math.inf])
            else:
                nxt = self._next_tick
                if nxt < t_end and nxt <= now:
                    self._openplc_tick(nxt)
                    idle_jobs += 1
                    continue
            self._time = max(self._time, min(t_end, max(self._next_tick, 0)))
            if nxt >= t_end:
                if t_end != math.inf:
                    self._idle(t_end, idle_jobs)
                    clock.sleep_until(t_end)
                    self._time = t_end
                    self.scans = t_end // self.tick
                return
            self._idle(nxt, idle_jobs)
            idle_jobs = 0
            clock.sleep_until(nxt)

    def _idle(self, next_event: int, jobs_since: int) -> None:
        """Slack before the next event: retained data, a young-generation GC, the caller's hook."""
        if self.retain_store is not None and self.clock.now() >= self._next_retain:
            self.commit_retained()
            self._next_retain = self.clock.now() + self.retain_interval
        if self.clock.real:
            if jobs_since and next_event - self.clock.now() > 2_000_000:
                gc.collect(0)
            if self._on_idle is not None:
                self.idle_slack = next_event - self.clock.now()
                self._on_idle(self)

    def _release_until(self, now: int) -> None:
        """Eager policies: every periodic release up to `now` (a stale unstarted job is replaced), and
        event tasks at the base ticks."""
        for t in self.tasks:
            if t.interval <= 0:
                continue
            while t.next_release <= now:
                if t.pending is not None:
                    t.stats.record_skip()
                t.pending = t.next_release
                t.next_release += t.interval
        if self._event_tasks:
            while self._next_tick <= now:
                for t in self._event_tasks:
                    if self._edge(t):
                        if t.pending is not None:
                            t.stats.record_skip()
                        t.pending = self._next_tick
                self._next_tick += self.tick
        elif self._next_tick <= now:
            self._next_tick = (now // self.tick + 1) * self.tick

    def _edge(self, t: Task) -> bool:
        cur = bool(self.ns.get(t.single, False))
        rising = cur and not t.prev_single
        t.prev_single = cur
        return rising

    def _openplc_tick(self, tick_time: int) -> None:
        """OpenPLC v3: at base tick k, every due task runs, in declaration order (late ticks catch up)."""
        for t in self.tasks:
            if t.single:
                due = self._edge(t)
            else:
                due = t.interval > 0 and tick_time % t.interval == 0
            if due and self.state == RUN:
                self._job(t, tick_time)
        self._next_tick = tick_time + self.tick

    def _job(self, task: Task, release: int) -> None:
        """One execution of a task: latch inputs, run its instances, publish outputs, record statistics."""
        clock = self.clock
        start = clock.now()
        ns = self.ns
        lock = self.image_lock if self.policy.name == "frame" else None
        if lock is not None:
            lock.acquire()
        io = self.io
        try:
            if io:
                for d in io:
                    d.before_job(task)
            for b in task.ins:
                b.latch_in()
            if self._forced:
                self._apply_forced()
            ns["_now"] = release
            self._wd.start(self.watchdog or (10 * (task.interval or self.tick) if clock.real else
                                             max(10 * (task.interval or self.tick), 1_000_000_000)))
            try:
                for name, obj, cin, cout in task.calls:
                    if cin is not None:
                        cin(obj)
                    obj._body()
                    if cout is not None:
                        cout(obj)
            finally:
                self._wd.stop()
            if self._forced:
                self._apply_forced()
            for b in task.outs:
                b.publish()
            if io:
                for d in io:
                    d.after_job(task)
        except Exception as exc:  # noqa: BLE001 - every fault of user code lands here
            info = fault_from_exception(exc, task.name)
            # the faulting job consumes its base tick: a restart resumes with the next one
            self._time = max(self._time, (clock.now() // self.tick + 1) * self.tick)
            self._enter_fault(info)
            raise PLCFaultError(info) from None
        finally:
            if lock is not None:
                lock.release()
        cost = task.cost
        clock.spend(cost() if callable(cost) else cost)
        task.stats.record(release, start, clock.now())
        task.runs += 1

    # ------------------------------------------------------------------ states and faults
    def _enter_fault(self, info: FaultInfo) -> None:
        self.state = FAULT
        self.fault = info
        self.faults.append(info)
        self._safe_outputs()
        if self.retain_store is not None:
            # as a PLC's retain memory: the values as the faulting scan left them, nothing lost
            self.commit_retained()

    def _safe_outputs(self) -> None:
        """Outputs to their safe values: FALSE/0, or what `safe_outputs` configures."""
        self.image.clear("Q")
        for addr, v in self.safe_outputs.items():
            area, size, i = parse_address(addr)
            self.image.tables[(area, size)][i] = v if size == "X" else int(v)
        for d in self.io:
            d.after_job()

    def stop(self) -> None:
        """RUN → STOP: no task runs, outputs safe, retained data committed."""
        if self.state == RUN:
            self.state = STOP
        self._safe_outputs()
        if self.retain_store is not None:
            self.commit_retained()

    def start(self) -> None:
        if self.state == FAULT:
            raise PLCFaultError(self.fault)
        self.state = RUN
        self._reset_releases(self._time)
        for t in self.tasks:
            for b in t.outs:
                b.publish()

    def reset_fault(self) -> None:
        """FAULT → RUN with the program's state as the fault left it."""
        self.state = RUN
        self.fault = None
        self._reset_releases(self._time)

    def restart(self) -> None:
        """Warm restart after a fault (--on-fault restart): fresh instances, retained values restored."""
        snapshot = self._retained_values() if self.retain_store is None else None
        committed = self.retain_store.load() if self.retain_store is not None else snapshot
        try:
            b = self._build(self.compiled, "restart")
        except PLCStartError as e:             # FB_init faults again: stay in FAULT, say why
            self._enter_fault(e.fault or FaultInfo("START", str(e)))
            raise PLCFaultError(self.fault) from None
        self.fault = None
        self.state = RUN
        self._install(b)
        if committed:
            self._restore_retained(committed)

    def close(self) -> None:
        """Clean shutdown: outputs safe, retained data committed and the store closed."""
        self.stop()
        if self.retain_store is not None:
            self.retain_store.close()
            self.retain_store = None

    # ------------------------------------------------------------------ retained data
    def _retained_paths(self):
        """(path, container, key, type) of every RETAIN/PERSISTENT variable of the instances and globals."""
        for lname, (name, obj, pou) in self.instances.items():
            yield from _retained_in(name, obj, pou)
        for g in self.project.globals.values():
            if g.retain or g.persistent:
                yield g.name, self.ns, g.pyname, g.type
            else:
                yield from _retained_inside(g.name, self.ns[g.pyname], g.type)

    def _retained_values(self) -> dict:
        out = {}
        for path, c, k, t in self._retained_paths():
            out[path] = (str(t), to_python(c[k] if isinstance(c, dict) else getattr(c, k), t))
        return out

    def commit_retained(self) -> None:
        if self.retain_store is not None:
            self.retain_store.save(self._retained_values(), self._time)

    def _restore_retained(self, saved: dict) -> int:
        n = 0
        for path, c, k, t in self._retained_paths():
            got = saved.get(path)
            if got is None or got[0] != str(t):
                continue
            try:
                _restore_into(c, k, t, got[1])
                n += 1
            except (ValueError, KeyError, TypeError, IndexError):
                continue
        return n

    # ------------------------------------------------------------------ online change
    def online_change(self, compiled: CompiledProgram) -> str:
        """Swap in a new build of the program at this scan boundary, carrying every variable over by
        name and type. All or nothing: raises OnlineChangeRefused (a ValueError) and leaves the running
        program and its state untouched when the configuration or a variable's type changed, when the
        new program cannot start (an address outside the image, a fault in FB_init), or when a value
        cannot be carried over."""
        return self.apply_change(self.prepare_change(compiled))

    def prepare_change(self, compiled: CompiledProgram) -> "_Build":
        """The part of an online change that may run in another thread while the old program scans:
        the checks, and the new namespace and instances with their FB_init."""
        problems = self._change_problems(compiled)
        if problems:
            raise OnlineChangeRefused(problems)
        try:
            return self._build(compiled, "online change")
        except PLCStartError as e:
            raise OnlineChangeRefused([f"the new program cannot start: {e}"]) from None

    def apply_change(self, b: "_Build") -> str:
        """The part of an online change done at a scan boundary: carry the old state over, swap."""
        try:
            self._carry_over(b)
        except Exception as exc:  # noqa: BLE001 - whatever fails, the old program keeps running
            reason = exc.args[0] if isinstance(exc, (ValueError, KeyError)) and exc.args else \
                str(fault_from_exception(exc))
            raise OnlineChangeRefused([f"the state cannot be carried over: {reason}"]) from None
        old_now = self.ns.get("_now", 0)
        self._install(b)
        self.ns["_now"] = old_now
        for t in self.tasks:
            for bd in t.outs:
                bd.publish()
        return f"online change: {len(b.instances)} instance(s) carried over"

    def _carry_over(self, b: "_Build") -> None:
        """Copy every variable whose path and type are unchanged from the running program into the
        built one, and re-aim interfaces and references at the new objects. Reads the old program only."""
        for key, (name, obj, pou) in b.instances.items():
            old = self.instances.get(key)
            if old is not None:
                _restore_into(Holder(obj), "v", pou, to_python(old[1], old[2]))
        old_globals = {g.pyname: g for g in self.project.globals.values()}
        for g in b.project.globals.values():
            og = old_globals.get(g.pyname)
            if og is not None and str(og.type) == str(g.type):
                _restore_into(b.ns, g.pyname, g.type, to_python(self.ns[og.pyname], og.type))
        # interface variables and references still point into the old objects: re-aim them
        relink([(self.instances[k][1], obj, self.instances[k][2], pou)
                for k, (name, obj, pou) in b.instances.items() if k in self.instances],
               [(g.pyname, g.pyname, old_globals[g.pyname].type, g.type)
                for g in b.project.globals.values() if g.pyname in old_globals],
               self.ns, b.ns)

    def _change_problems(self, compiled: CompiledProgram) -> list:
        new_cfg = compiled.project.configs[0] if compiled.project.configs else None
        out = []

        def shape(cfg):
            if cfg is None:
                return set(), set()
            return ({(t.name.lower(), t.interval, t.priority, t.single) for t in cfg.tasks},
                    {(i.name.lower(), i.type.name.lower(), i.task.lower()) for i in cfg.instances})
        if shape(self.config) != shape(new_cfg):
            out.append("the configuration's tasks or program instances changed (restart the PLC to apply it)")
        new_pous = {i.name.lower(): i.type for i in (new_cfg.instances if new_cfg else [])}
        for key, (name, obj, pou) in self.instances.items():
            if key in new_pous:
                _type_changes(pou, new_pous[key], name, out)
        new_globals = {g.pyname: g for g in compiled.project.globals.values()}
        for g in self.project.globals.values():
            ng = new_globals.get(g.pyname)
            if ng is not None:
                _type_changes(g.type, ng.type, g.name, out)
        return out

    # ------------------------------------------------------------------ statistics
    def stats(self) -> list:
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
    def __getitem__(self, path: str):
        if path.strip().startswith("%"):
            return self._image_read(path)
        container, key, t = resolve(self, path)
        return to_python(read(container, key), t, refnames.namer(self))

    def force(self, path: str, value) -> None:
        """Force a variable (or a located variable by its %address): it holds `value` when every job
        starts and ends, whatever the program, the inputs or an HMI write it, until unforce()."""
        if path.strip().startswith("%"):
            binds = self.bindings.get(norm_addr(path))
            if not binds:
                raise KeyError(f"{path}: no located variable at this address")
            targets = [(b.container, b.key, b.type) for b in binds]
        else:
            targets = [resolve(self, path)]
        self._force_spec[path] = value
        for container, key, t in targets:
            v = from_python(value, t, path)
            write(container, key, v)
            self._forced[(path.strip().lower(), id(container), key)] = (container, key, v,
                                                                       self._binding_of.get((id(container), key)))
        self._apply_forced()

    def unforce(self, path: Optional[str] = None) -> None:
        """Release one forced variable, or all of them."""
        if path is None:
            self._forced.clear()
            self._force_spec.clear()
            return
        self._force_spec.pop(path, None)
        p = path.strip().lower()
        for k in [k for k in self._forced if k[0] == p]:
            del self._forced[k]

    @property
    def forced(self) -> list:
        return sorted({k[0] for k in self._forced})

    def _apply_forced(self) -> None:
        for container, key, v, b in self._forced.values():
            write(container, key, v)
            if b is not None:
                b.table[b.index] = b.conv_out(v)

    def __setitem__(self, path: str, value) -> None:
        if path.strip().startswith("%"):
            self._image_write(path, value)
            return
        container, key, t = resolve(self, path)
        v = from_python(value, t, path)
        write(container, key, v)
        b = self._binding_of.get((id(container), key))
        if b is not None:                   # keep the image in step, or the next latch would undo the write
            b.table[b.index] = to_raw(v, t, b.size)

    def _image_read(self, addr: str):
        """%I, %Q, %M read from the process image (what I/O and the HMI see), typed by the bound variable."""
        try:
            area, size, i = parse_address(addr)
        except AddressError as e:
            raise KeyError(str(e)) from None
        raw = self.image.tables[(area, size)][i]
        binds = self.bindings.get(norm_addr(addr))
        if binds:
            return to_python(from_raw(raw, binds[0].type, size), binds[0].type)
        return raw

    def _image_write(self, addr: str, value) -> None:
        """Write an image cell; %Q and %M also write their variables (the program would overwrite them)."""
        try:
            area, size, i = parse_address(addr)
        except AddressError as e:
            raise KeyError(str(e)) from None
        binds = self.bindings.get(norm_addr(addr), [])
        if binds:
            t = binds[0].type
            v = from_python(value, t, addr)
            raw = to_raw(v, t, size)
            if area in "QM":
                for b in binds:
                    b.write_var(from_python(value, b.type, addr))
        else:
            if isinstance(value, bool) and size != "X" or not isinstance(value, (bool, int)):
                raise ValueError_(f"{addr}: expected {'a BOOL' if size == 'X' else 'an integer'}, got {value!r}")
            raw = value
        self.image.set(addr, raw)

    def ref(self, path: str) -> VarRef:
        """A reference to the variable at `path` ("main.fb.x", "g_arr[2]", "main.w.3"); KeyError
        saying what is wrong with the path. Valid until the program is reloaded."""
        container, key, t = resolve(self, path)
        return VarRef(path, container, key, t, self._binding_of.get((id(container), key)))

    def variables(self) -> dict:
        """Every variable of every program instance, as JSON values keyed "instance.var"."""
        out = {}
        ref = refnames.namer(self)
        for lname, (name, obj, pou) in self.instances.items():
            for sym in pou.vars.values():
                if sym.section == "VAR_TEMP":
                    continue
                if sym.section == "VAR_EXTERNAL":
                    if sym.global_ref is not None:
                        out[f"{name}.{sym.name}"] = to_json(self.ns[sym.global_ref.pyname], sym.global_ref.type, ref)
                    continue
                out[f"{name}.{sym.name}"] = to_json(getattr(obj, sym.pyname), sym.type, ref)
        return out

    def globals(self) -> dict:
        """Global variables, and static ones (VAR_STAT) as 'POU.name' or 'FB.Method.name'."""
        def name(g):
            if g.section != "VAR_STAT" or g.owner is None:
                return g.name
            fb = getattr(g.owner, "owner_fb", None)
            return f"{fb.name + '.' if fb is not None else ''}{g.owner.name}.{g.name}"
        ref = refnames.namer(self)
        return {name(g): to_json(self.ns[g.pyname], g.type, ref) for g in self.project.globals.values()}


def _retained_in(path: str, obj, pou: T.POUType):
    """(path, container, key, type) of the RETAIN/PERSISTENT variables of one program or block
    instance, and of the block instances inside it (a RETAIN in a block is kept wherever the
    block is instantiated, as in CODESYS)."""
    for sym in pou.vars.values():
        if sym.section in ("VAR_EXTERNAL", "VAR_TEMP", "VAR_IN_OUT", "VAR_STAT"):
            continue
        if sym.retain or sym.persistent:
            yield f"{path}.{sym.name}", obj, sym.pyname, sym.type
        else:
            yield from _retained_inside(f"{path}.{sym.name}", getattr(obj, sym.pyname), sym.type)


def _retained_inside(path: str, value, t):
    """The retained variables inside a value that is not retained as a whole: block instances and
    arrays of them."""
    ut = T.unalias(t)
    if isinstance(ut, T.POUType) and ut.pou_kind == "FUNCTION_BLOCK" and value is not None:
        yield from _retained_in(path, value, ut)
    elif isinstance(ut, T.ArrayType) and isinstance(T.unalias(ut.element), (T.POUType, T.ArrayType)):
        for i, index in enumerate(_array_indices(ut.dims)):
            yield from _retained_inside(f"{path}[{index}]", value[i], ut.element)


def _array_indices(dims):
    """'1', '2', … or '0,1', … : the ST indices of a flat array's elements, in storage order."""
    out = [""]
    for lo, hi in dims:
        out = [f"{a},{i}" if a else str(i) for a in out for i in range(lo, hi + 1)]
    return out


def _restore_into(container, key, t, value) -> None:
    """Write a to_python-form value back into a variable, aggregates element by element."""
    ut = T.unalias(t)
    if isinstance(ut, T.ArrayType):
        arr = read(container, key)
        flat = _flatten(value, len(ut.dims))
        if len(flat) != len(arr):
            raise ValueError("array size changed")
        for i, v in enumerate(flat):
            _restore_into(arr, i, ut.element, v)
    elif isinstance(ut, T.RefType) or (isinstance(ut, T.POUType) and ut.pou_kind == "INTERFACE"):
        return                                   # references: re-aimed by relink()
    elif isinstance(ut, (T.StructType, T.POUType)):
        obj = read(container, key)
        members = ut.members if isinstance(ut, T.StructType) else ut.vars
        for m in members.values():
            if m.name in value and getattr(m, "section", "") not in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                _restore_into(obj, m.pyname, m.type, value[m.name])
    else:
        write(container, key, from_python(value, t, ""))


def _type_changes(old: T.Type, new: T.Type, path: str, out: list) -> None:
    """Variables that keep their name but change their type (their values cannot be carried over)."""
    uo, un = T.unalias(old), T.unalias(new)
    if isinstance(uo, (T.POUType, T.StructType)) and isinstance(un, (T.POUType, T.StructType)) \
            and type(uo) is type(un) and uo.name.lower() == un.name.lower():
        om = uo.members if isinstance(uo, T.StructType) else uo.vars
        nm = un.members if isinstance(un, T.StructType) else un.vars
        for k, m in om.items():
            if k in nm and getattr(m, "section", "") not in ("VAR_TEMP", "VAR_EXTERNAL", "VAR_IN_OUT"):
                _type_changes(m.type, nm[k].type, f"{path}.{m.name}", out)
        return
    if str(old) != str(new):
        out.append(f"{path} changed its type from {old} to {new}")


def _flatten(v, depth: int) -> list:
    if depth <= 1:
        return list(v)
    return [x for row in v for x in _flatten(row, depth - 1)]
