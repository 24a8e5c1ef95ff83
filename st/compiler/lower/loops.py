"""Loops: FOR decided into a counted form, and the watchdog's guard in every loop.

Every WHILE, REPEAT and FOR of the program, the library's ST and the unit tests gets one
`LoopGuard` first in its body, so no statement kind and no CONTINUE can skip it: any of them
can run for longer than a job's budget (a FOR's bounds are values too). A FOR becomes a
`CountedFor` whose form says how the counter runs; a FOR whose body writes its own counter
(directly, through a nested FOR or as an output argument) is a "while" form that re-tests the
counter each round, and is guarded like the others.
"""

from __future__ import annotations

from .. import ast as A
from ..check import CallTarget
from .walk import inner_bodies, walk_stmts


def guard_loops(body: list) -> None:
    """Put a `LoopGuard` first in the body of every loop in `body` (nested ones included)."""
    for s in walk_stmts(body):
        if isinstance(s, (A.CountedFor, A.While, A.Repeat)) and not (s.body and isinstance(s.body[0], A.LoopGuard)):
            s.body.insert(0, A.LoopGuard(s.span))


def count_fors(body: list) -> None:
    """Replace every FOR in `body` (nested ones included) by its `CountedFor`."""
    for i, s in enumerate(body):
        if isinstance(s, A.For):
            body[i] = s = counted(s)
        for inner in inner_bodies(s):
            count_fors(inner)


def counted(s: A.For) -> A.CountedFor:
    step_value: int | None = 1
    if s.step is not None:
        c = s.step.const if s.step.const is not None else (s.step.value if isinstance(s.step, A.Literal) else None)
        step_value = c if isinstance(c, int) else None
    form = "while" if assigns_counter(s.body, s.var) else "range"
    return A.CountedFor(s.span, s.var, s.start, s.end, s.step, step_value, form, s.body)


def assigns_counter(body: list, var) -> bool:
    """Whether `body` may write the loop variable `var` (anything but a plain name may be)."""
    if not isinstance(var, A.Name):
        return True
    key = var.name.lower()
    for s in walk_stmts(body):
        if isinstance(s, A.Assign) and isinstance(s.target, A.Name) and s.target.name.lower() == key:
            return True
        if isinstance(s, (A.For, A.CountedFor)) and isinstance(s.var, A.Name) and s.var.name.lower() == key:
            return True
        if isinstance(s, A.CallStmt):
            for a in s.call.args:
                if (
                    (a.output or isinstance(s.call.target, CallTarget))
                    and isinstance(a.value, A.Name)
                    and a.value.name.lower() == key
                    and a.output
                ):
                    return True
    return False
