"""Tasks and the scheduling policies that decide which task's job runs next.

All policies run jobs to completion in one thread (the generated code is not preemptible
and Python has one interpreter lock): a policy only decides the order in which released jobs
start, and what happens to a release that finds the previous job still waiting.

- `openplc`: OpenPLC v3. A base tick (the GCD of the intervals); at tick k every task due at
  k runs, in declaration order. A late tick is not skipped: the next ticks run back to back
  until the schedule has caught up, so every release runs, late.
- `priority`: fixed priority, non-preemptive. The released job with the best PRIORITY runs
  first (IEC: 0 is the highest); equal priorities fall back to rate monotonic (shorter
  interval first). A release that finds the task's previous job not yet started replaces it
  (one skip, counted as an overrun): under overload, long-period tasks starve.
- `edf`: earliest deadline first (deadline = release + interval), otherwise as `priority`.
- `frame`: the semaphore-based scheduler of the thesis (ch. 4.3): every interval must be a
  multiple of the shortest (the minor frame); at each frame the due tasks are released and
  take the semaphore that guards the process image in order of release, then period; a stale
  unstarted job is replaced as above. Releases stay on the frame grid (no drift), and older
  releases go first, so under overload a long-period task is delayed rather than starved.

An overrun (a job that ends after its next release) never starts a second copy of a task: see
`TaskStats` for how overruns and skipped releases are counted.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .stats import TaskStats

POLICIES = ("openplc", "priority", "edf", "frame")


@dataclass(eq=False)
class Task:
    name: str
    interval: int  # ns (0: event task)
    priority: int
    instances: list[tuple[str, Any, Any]]  # [(name, object, InstanceModel)]
    single: str = ""  # event task: the BOOL global whose rising edge releases it
    index: int = 0  # declaration order
    prev_single: bool = False
    runs: int = 0
    calls: list[tuple[str, Any, Callable[[Any], None] | None, Callable[[Any], None] | None]] = field(
        default_factory=list
    )  # [(name, object, copy-in fn, copy-out fn)]
    cost: Any = 0  # simulated execution time on virtual time (ns), or a callable giving it
    stats: TaskStats = None  # type: ignore[assignment]     # set when the program is installed
    next_release: int = 0
    pending: int | None = None  # release time of a released job not yet started
    ins: list[Any] = field(default_factory=list)  # process image bindings latched before the job
    outs: list[Any] = field(default_factory=list)  # … published after it
    wd_budget: int = 0  # the watchdog's default budget for this run's clock (engine.run sets it)


class Policy:
    name = ""
    eager = True  # releases happen at their time (False: OpenPLC's tick catch-up)

    def __init__(self, tasks: list[Task], tick: int):
        self.tasks = tasks
        self.tick = tick

    def key(self, task: Task, release: int) -> tuple[Any, ...]:
        raise NotImplementedError


class OpenPLCPolicy(Policy):
    name = "openplc"
    eager = False

    def key(self, task: Task, release: int) -> tuple[Any, ...]:
        return (release, task.index)


class PriorityPolicy(Policy):
    name = "priority"

    def key(self, task: Task, release: int) -> tuple[Any, ...]:
        return (task.priority, task.interval or math.inf, task.index, release)


class EDFPolicy(Policy):
    name = "edf"

    def key(self, task: Task, release: int) -> tuple[Any, ...]:
        return (release + (task.interval or self.tick), task.index)


class FramePolicy(Policy):
    name = "frame"

    def __init__(self, tasks: list[Task], tick: int):
        super().__init__(tasks, tick)
        periodic = [t.interval for t in tasks if t.interval > 0]
        self.frame = min(periodic) if periodic else tick
        for t in tasks:
            if t.interval and t.interval % self.frame:
                raise ValueError(
                    f"policy frame: task {t.name}'s interval {t.interval / 1e6:g} ms is not a multiple "
                    f"of the minor frame {self.frame / 1e6:g} ms (the shortest interval)"
                )

    def key(self, task: Task, release: int) -> tuple[Any, ...]:
        return (release, task.interval or self.frame, task.index)


def make_policy(name: str, tasks: list[Task], tick: int) -> Policy:
    policies: dict[str, type[Policy]] = {
        "openplc": OpenPLCPolicy,
        "priority": PriorityPolicy,
        "edf": EDFPolicy,
        "frame": FramePolicy,
    }
    cls = policies.get(name)
    if cls is None:
        raise ValueError(f"unknown scheduling policy {name!r} (one of {', '.join(POLICIES)})")
    return cls(tasks, tick)


def reset_releases(tasks: list[Task], tick: int, now: int) -> int:
    """Every periodic task's next release is its next multiple of its interval from `now`, nothing is
    pending; returns the next base tick (start-up, start, a reload, a reset fault)."""
    for t in tasks:
        t.pending = None
        if t.interval > 0:
            t.next_release = -(-now // t.interval) * t.interval
    return -(-now // tick) * tick
