"""The engine: releases, the choice of the next job, the job itself, idle work, on either clock.

One loop serves both clocks: on virtual time (`run_virtual`: tests, simulation) the clock
jumps from event to event; on real time (`run_realtime`) it sleeps to absolute deadlines on
CLOCK_MONOTONIC. The policy (`scheduler.py`) orders the released jobs; each job latches the
process image's inputs, runs its task's program instances and publishes the outputs. The PLC
clock that timers read is the job's release time, so a run is deterministic whether it is
paced or not. This is the hot path: it reads the PLC's state directly, one function per job.
"""

from __future__ import annotations

import gc
import math
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .access import apply_forced
from .clock import RealClock, VirtualClock
from .faults import PLCFaultError, fault_from_exception
from .lifecycle import FAULT, RUN, enter_fault, fault_error
from .retained import commit_retained
from .scheduler import Task
from .values import parse_duration_arg

if TYPE_CHECKING:
    from .plc import PLC


def run_virtual(plc: PLC, t_end: int) -> None:
    """Run on virtual time until PLC time t_end."""
    if plc.state == FAULT:
        raise fault_error(plc)
    if not isinstance(plc.clock, VirtualClock):
        plc.clock = VirtualClock(plc._time)
    if plc.clock.now() < plc._time:
        plc.clock.t = plc._time
    run(plc, t_end)


def run_realtime(
    plc: PLC,
    scans: int | None = None,
    duration: Any = None,
    on_idle: Callable[[PLC], None] | None = None,
    phase: Any = "500us",
    gc_control: bool = True,
    stop: threading.Event | None = None,
) -> None:
    """See PLC.run_realtime."""
    if plc.state == FAULT:
        raise fault_error(plc)
    end: float = math.inf
    if scans is not None:
        end = plc._time + scans * plc.tick
    if duration is not None:
        end = min(end, plc._time + parse_duration_arg(duration))
    gc_was = gc.isenabled()
    if gc_control:
        gc.collect()
        gc.freeze()
        gc.disable()
    plc.clock = RealClock(plc._time, parse_duration_arg(phase) if phase else 0)
    plc._on_idle = on_idle
    plc._stop_event = stop
    try:
        run(plc, end)
    finally:
        plc._on_idle = None
        plc._stop_event = None
        if gc_control:
            gc.unfreeze()
            if gc_was:
                gc.enable()
        plc.clock = VirtualClock(plc._time)


def request_stop(plc: PLC, reason: str) -> None:
    """See PLC.request_stop."""
    if plc._stop_requested and plc._wd.running:
        plc._wd.abort(f"the job was ended by a second stop request ({reason})")
    plc._stop_requested = True
    if isinstance(plc.clock, RealClock):
        plc.clock.wake = True


def run(plc: PLC, t_end: Any) -> None:
    """Release and run jobs until PLC time t_end (exclusive for releases): ns, or math.inf for no end."""
    clock = plc.clock
    eager = plc.policy.eager
    key = plc.policy.key
    tasks = plc.tasks
    idle_jobs = 0
    # idle work only where there is some: retained data to commit, or real time (GC, the hook)
    idle_work = clock.real or plc.retain_store is not None
    for t in tasks:
        t.wd_budget = _default_budget(plc, t)
    while True:
        if plc._stop_requested or (plc._stop_event is not None and plc._stop_event.is_set()):
            plc._stop_requested = False
            plc._time = max(plc._time, min(plc._next_tick, t_end))
            return
        now = clock.now()
        if now >= t_end:  # overloaded on virtual time: the clock passed the end; stop here
            plc._time = max(plc._time, t_end)
            plc.scans = plc._time // plc.tick
            return
        if eager:
            _release_until(plc, min(now, t_end - 1))
            ready = [t for t in tasks if t.pending is not None]
            if ready and plc.state == RUN:
                task = min(ready, key=lambda t: key(t, t.pending))  # type: ignore[arg-type]
                release: int = task.pending  # type: ignore[assignment]      # ready: it is set
                task.pending = None
                _job(plc, task, release)
                idle_jobs += 1
                continue
            for t in ready:  # STOP or FAULT: releases lapse
                t.pending = None
            nxt = min(
                [t.next_release for t in tasks if t.interval > 0]
                + ([plc._next_tick] if plc._event_tasks else [])
                + [math.inf]
            )
        else:
            nxt = plc._next_tick
            if nxt < t_end and nxt <= now:
                _openplc_tick(plc, nxt)
                idle_jobs += 1
                if clock.real or plc._stop_requested or plc._stop_event is not None:
                    continue
                # virtual time: straight on to the wait for the next tick (what the next pass would do)
                nxt = plc._next_tick
                now = clock.t
                if nxt <= now or now >= t_end:
                    continue
        tick = plc._next_tick
        if tick > plc._time:  # the PLC time: the next base tick, within the run
            plc._time = tick if tick < t_end else max(plc._time, t_end)
        if nxt >= t_end:
            if t_end != math.inf:
                _idle(plc, t_end, idle_jobs)
                clock.sleep_until(t_end)
                plc._time = t_end
                plc.scans = t_end // plc.tick
            return
        if idle_work:
            _idle(plc, nxt, idle_jobs)
        idle_jobs = 0
        clock.sleep_until(nxt)


def _idle(plc: PLC, next_event: float, jobs_since: int) -> None:
    """Slack before the next event: retained data, a young-generation GC, the caller's hook."""
    if plc.retain_store is not None and plc.clock.now() >= plc._next_retain:
        commit_retained(plc)
        plc._next_retain = plc.clock.now() + plc.retain_interval
    if plc.clock.real:
        if jobs_since and next_event - plc.clock.now() > 2_000_000:
            gc.collect(0)
        if plc._on_idle is not None:
            plc.idle_slack = next_event - plc.clock.now()
            plc._on_idle(plc)


def _release_until(plc: PLC, now: int) -> None:
    """Eager policies: every periodic release up to `now` (a stale unstarted job is replaced), and
    event tasks at the base ticks."""
    for t in plc.tasks:
        if t.interval <= 0:
            continue
        while t.next_release <= now:
            if t.pending is not None:
                t.stats.record_skip()
            t.pending = t.next_release
            t.next_release += t.interval
    if plc._event_tasks:
        while plc._next_tick <= now:
            for t in plc._event_tasks:
                if _edge(plc, t):
                    if t.pending is not None:
                        t.stats.record_skip()
                    t.pending = plc._next_tick
            plc._next_tick += plc.tick
    elif plc._next_tick <= now:
        plc._next_tick = (now // plc.tick + 1) * plc.tick


def _edge(plc: PLC, t: Task) -> bool:
    cur = bool(plc.ns.get(t.single, False))
    rising = cur and not t.prev_single
    t.prev_single = cur
    return rising


def _openplc_tick(plc: PLC, tick_time: int) -> None:
    """OpenPLC v3: at base tick k, every due task runs, in declaration order (late ticks catch up)."""
    for t in plc.tasks:
        if t.single:
            if _edge(plc, t) and plc.state == RUN:
                _job(plc, t, tick_time)
        elif t.interval > 0 and not tick_time % t.interval and plc.state == RUN:
            _job(plc, t, tick_time)
    plc._next_tick = tick_time + plc.tick


def _job(plc: PLC, task: Task, release: int) -> None:
    """One execution of a task: latch inputs, run its instances, publish outputs, record statistics.

    The hot path of every scan: locals instead of repeated attribute loads, the watchdog armed
    and disarmed inline (see Watchdog.start/stop), nothing evaluated that a run fixes once."""
    clock = plc.clock
    real = clock.real
    start = clock.now() if real else clock.t  # (a virtual clock's time is its `t`: no call)
    ns = plc.ns
    lock = plc.job_lock
    if lock is not None:
        lock.acquire()
    io = plc.io
    wd = plc._wd
    plc.job_task = task
    try:
        if io:
            for d in io:
                d.before_job(task)
        for b in task.ins:
            b.latch_in()
        if plc._forced:
            apply_forced(plc)
        ns["_now"] = release
        wd.arm(plc.watchdog or task.wd_budget or _default_budget(plc, task))
        try:
            for _name, obj, cin, cout in task.calls:
                if cin is not None:
                    cin(obj)
                obj._body()
                if cout is not None:
                    cout(obj)
        finally:
            wd.deadline = 0
            if wd.abort_reason or ns["_wd_armed"]:
                wd.stop()
        if plc._forced:
            apply_forced(plc)
        for b in task.outs:
            b.publish()
        if io:
            for d in io:
                d.after_job(task)
    except Exception as exc:  # noqa: BLE001 - every fault of user code lands here
        info = fault_from_exception(exc, task.name)
        # the faulting job consumes its base tick: a restart resumes with the next one
        plc._time = max(plc._time, (clock.now() // plc.tick + 1) * plc.tick)
        enter_fault(plc, info)
        raise PLCFaultError(info) from None
    finally:
        plc.job_task = None
        if lock is not None:
            lock.release()
    cost = task.cost
    if cost:
        clock.spend(cost() if callable(cost) else cost)
    task.stats.record(release, start, clock.now() if real else clock.t)
    task.runs += 1


def _default_budget(plc: PLC, task: Task) -> int:
    """The watchdog's budget when none is configured: 10 intervals (at least 1 s on virtual time,
    where a job's wall time says nothing about the PLC's)."""
    budget = 10 * (task.interval or plc.tick)
    return budget if plc.clock.real or budget >= 1_000_000_000 else 1_000_000_000
