"""Loops: FOR decided into a counted form, and the watchdog's guard in every loop.

Every WHILE, REPEAT and FOR of the program, the library's ST and the unit tests gets one
`LoopGuard` first in its body, so no statement kind and no CONTINUE can skip it: any of them
can run for longer than a job's budget (a FOR's bounds are values too). A FOR becomes a
`CountedFor` whose form says how the counter runs; a FOR whose counter may be written while its
body runs (by the body: an assignment, a nested FOR, an output, VAR_IN_OUT or reference argument;
or by code the body calls that reaches it: writes.py) is a "while" form that re-tests the counter
each round, as CODESYS and TwinCAT do, and is guarded like the others.
"""

from __future__ import annotations

from ...model import types as T
from .. import ast as A
from ..check.rules.for_counter import counter_writes, root_sym
from .walk import inner_bodies, walk_stmts
from .writes import Writes


def guard_loops(body: list) -> None:
    """Put a `LoopGuard` first in the body of every loop in `body` (nested ones included)."""
    for s in walk_stmts(body):
        if isinstance(s, (A.CountedFor, A.While, A.Repeat)) and not (s.body and isinstance(s.body[0], A.LoopGuard)):
            s.body.insert(0, A.LoopGuard(s.span))


def count_fors(body: list, writes: Writes | None = None, block: T.POUType | None = None) -> None:
    """Replace every FOR in `body` (nested ones included) by its `CountedFor`; `block`: the
    function block or program whose instance the body runs on (None: a FUNCTION, a test)."""
    for i, s in enumerate(body):
        if isinstance(s, A.For):
            body[i] = s = counted(s, writes, block)
        for inner in inner_bodies(s):
            count_fors(inner, writes, block)


def counted(s: A.For, writes: Writes | None = None, block: T.POUType | None = None) -> A.CountedFor:
    step_value: int | None = 1
    if s.step is not None:
        c = s.step.const if s.step.const is not None else (s.step.value if isinstance(s.step, A.Literal) else None)
        step_value = c if isinstance(c, int) else None
    form = "while" if may_write_counter(s.body, s.var, writes, block) else "range"
    return A.CountedFor(s.span, s.var, s.start, s.end, s.step, step_value, form, s.body)


def may_write_counter(body: list, var, writes: Writes | None, block: T.POUType | None) -> bool:
    """Whether anything may write the loop variable `var` while `body` runs: the body itself
    (check/rules/for_counter.py), or, for a variable other code can reach (a global, a VAR_IN_OUT, a
    reference, one whose address is taken anywhere, an instance variable of a block whose instance
    other code may reach), the code the body calls (writes.py). Without `writes` (a body lowered
    on its own) only what the body shows is known, and any call is assumed to write."""
    sym = root_sym(var)
    if sym is None or not isinstance(var, A.Name):
        return True
    if counter_writes(body, sym):
        return True
    if sym.is_global or sym.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_STAT") or sym.address_taken:
        return True
    if T.is_reference(sym.type):
        return True
    local = sym.section == "VAR_TEMP" or (
        isinstance(sym.owner, T.POUType) and sym.owner.pou_kind == "FUNCTION" and sym.section != "VAR_INST"
    )
    if local:  # a Python local of the call: nothing but the body reaches it
        return False
    if writes is None:
        return any(isinstance(n, (A.Call, A.AccessorCall)) for n in A.walk_nodes(body))
    return writes.shared(body, block)
