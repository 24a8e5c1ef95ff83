"""The SFC engine: one evolution of a sequential function chart per call.

Per scan: (1) transitions whose source steps are all active and whose
condition is TRUE fire (in declaration order; a step consumed by an earlier
transition cannot fire another one), (2) their sources deactivate and their
targets activate, (3) action qualifiers are evaluated for every step and the
active actions run (ACTION bodies in declaration order; a BOOL variable used as
an action gets the action's state).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass
class SfcDesc:
    """Static description, generated per POU."""

    n_steps: int
    initial: int
    transitions: list[tuple[tuple[int, ...], tuple[int, ...], str]]  # [(sources, targets, method name)]
    steps: list[list[tuple[int, str, str]]]  # per step: [(action index, qualifier, time method name or "")]
    actions: list[tuple[str, str]]  # per action: ("act", method name) or ("var", attribute name)


class SfcState:
    __slots__ = ("desc", "x", "start", "last", "stored", "timers", "prev_x", "started", "act_prev")

    def __init__(self, desc: SfcDesc):
        self.desc = desc
        self.x = [False] * desc.n_steps
        self.x[desc.initial] = True
        self.start = [0] * desc.n_steps
        self.last = [0] * desc.n_steps
        self.prev_x = [False] * desc.n_steps
        self.stored = [False] * len(desc.actions)
        self.timers: dict[tuple[int, str], int] = {}  # (action, kind) → start time for SD/DS/SL
        self.started = False
        self.act_prev = [False] * len(desc.actions)

    def elapsed(self, i: int) -> int:
        return self._now - self.start[i] if self.x[i] else self.last[i]

    _now = 0

    def run(self, inst: Any, now: int) -> None:
        d = self.desc
        x = self.x
        SfcState._now = now
        if not self.started:
            self.started = True
            self.start[d.initial] = now
        # 1-2: transitions
        consumed: set[int] = set()
        fire = []
        for srcs, dsts, meth in d.transitions:
            if all(x[s] for s in srcs) and not any(s in consumed for s in srcs):
                if getattr(inst, meth)():
                    consumed.update(srcs)
                    fire.append(dsts)
        if fire:
            for s in consumed:
                x[s] = False
                self.last[s] = now - self.start[s]
            for dsts in fire:
                for t in dsts:
                    if not x[t]:
                        x[t] = True
                        self.start[t] = now
        # 3: action control
        n_act = len(d.actions)
        q = [False] * n_act
        stored = self.stored
        timers = self.timers
        for i, assoc in enumerate(d.steps):
            active = x[i]
            rising = active and not self.prev_x[i]
            el = now - self.start[i]
            for a, qual, tmeth in assoc:
                if qual == "N":
                    if active:
                        q[a] = True
                elif qual == "S":
                    if active:
                        stored[a] = True
                elif qual == "R":
                    if active:
                        stored[a] = False
                        for k in [k for k in timers if k[0] == a]:
                            del timers[k]
                elif qual in ("P", "P1"):
                    if rising:
                        q[a] = True
                elif qual == "P0":
                    if not active and self.prev_x[i]:
                        q[a] = True
                elif qual == "L":
                    if active and el < getattr(inst, tmeth)():
                        q[a] = True
                elif qual == "D":
                    if active and el >= getattr(inst, tmeth)():
                        q[a] = True
                elif qual == "SD":
                    if active and (a, "SD") not in timers:
                        timers[(a, "SD")] = now
                elif qual == "DS":
                    if active and el >= getattr(inst, tmeth)():
                        stored[a] = True
                elif qual == "SL":
                    if rising:
                        timers[(a, "SL")] = now
        for (a, kind), t0 in list(timers.items()):
            if kind == "SD":
                dur = self._duration(inst, a, "SD")
                if now - t0 >= dur:
                    q[a] = True
            elif kind == "SL":
                dur = self._duration(inst, a, "SL")
                if now - t0 < dur:
                    q[a] = True
                else:
                    del timers[(a, kind)]
        for a in range(n_act):
            if stored[a]:
                q[a] = True
        self.prev_x = list(x)
        # run the active actions
        for a, (kind, name) in enumerate(d.actions):
            if kind == "var":
                setattr(inst, name, q[a])
            elif q[a]:
                getattr(inst, name)()
        self.act_prev = q

    def _duration(self, inst: Any, a: int, qual: str) -> int:
        for assoc in self.desc.steps:
            for act, q, tmeth in assoc:
                if act == a and q == qual and tmeth:
                    d: int = getattr(inst, tmeth)()
                    return d
        return 0
