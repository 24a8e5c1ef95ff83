"""What the code generator knows about each function it prints, for the native tier.

The generated Python is all the Python tier needs. The native tier (st/compiler/native) compiles
the same Python and needs, besides, what the printer decided while printing it: which Python
locals hold which ST variables (and their IEC types), where it put the loop guards, which runtime
helpers it called and what for, which calls run a block's body or a user FUNCTION, and the
intervals it proved. A `BodyFacts` per generated function (a block's `_body` or action, a user
FUNCTION, a METHOD or property accessor) holds them, kept on that function's node (`attach`,
`facts_of`): a side structure that never changes the generated code and is not part of the
compiled artefact (the native build reads it in the same compile).

A fact about a statement or an expression holds that node of the function's tree (identity, not
shape). A reader that copies the tree maps the nodes through `copy.deepcopy`'s memo.

Recording: the generator of a body opens `recording(facts)`; the two builders every helper call
and every wrap go through (pyast._call, expressions.wrap, which libraries use too through
codegen/emit.py) note theirs in it, and the generators add the rest (`current()`).
"""

from __future__ import annotations

import ast as py
import copy
import enum
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import NamedTuple

from ...model import types as T
from ..intervals import Interval

# the loop guard's names: `if _wd_armed: _wd_check()` (the runtime's watchdog, st/runtime/watchdog.py)
WATCHDOG_ARMED = "_wd_armed"
WATCHDOG_CHECK = "_wd_check"


class Helper(enum.Enum):
    """What a runtime helper (st/runtime/helpers.py) that generated code calls computes."""

    INDEX = "an array index checked against its bounds"  # (i, lo, hi) → i - lo; an INDEX fault outside
    DIV = "IEC DIV of integers"  # (a, b): toward zero; a DIV0 fault for b = 0
    MOD = "IEC MOD of integers"  # (a, b): with the dividend's sign; 0 for b = 0
    UMOD = "MOD of unsigned integers"  # (a, b): a % b; 0 for b = 0
    REAL_DIV = "REAL division"  # (a, b): a / b, ±INF or NaN for b = 0
    ROUND = "REAL rounding"  # (x): x rounded to single precision
    TO_REAL = "an integer as LREAL"  # (i): float(i)
    TO_INT = "a BOOL as an integer"  # (b): int(b)
    ABS = "ABS"  # Python's abs
    MIN = "MIN"  # Python's min
    MAX = "MAX"  # Python's max
    RANGE = "a FOR loop's values"  # Python's range


# the names generated code calls them by
RUNTIME_HELPERS: dict[str, Helper] = {
    "_ix": Helper.INDEX,
    "_idiv": Helper.DIV,
    "_imod": Helper.MOD,
    "_umod": Helper.UMOD,
    "_fdiv": Helper.REAL_DIV,
    "_f32": Helper.ROUND,
    "_float": Helper.TO_REAL,
    "_int": Helper.TO_INT,
    "_abs": Helper.ABS,
    "_min": Helper.MIN,
    "_max": Helper.MAX,
    "_range": Helper.RANGE,
}


class Local(NamedTuple):
    """An ST variable held in a Python local of the same name while the function runs."""

    type: T.Type
    section: str  # VAR, VAR_TEMP, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, or RESULT (a function's own)


class Loop(NamedTuple):
    """A FOR loop printed as `for counter in _range(…)`: its body does not write the counter, a
    Python local, whose values in the body are `values`."""

    node: py.For
    counter: str
    values: Interval


class Ranged(NamedTuple):
    """An integer expression whose values codegen proved to lie in `values` (a value stored
    without a wrap, an index without a check, or the result of a wrap to a type)."""

    node: py.expr
    values: Interval


class BodyCall(NamedTuple):
    """`inst._body()`: the call of the body of a block whose class is `cls` (or one derived from it)."""

    node: py.Call
    cls: str


class UserFunctionCall(NamedTuple):
    """The call of the user FUNCTION printed as the module-level function `name`."""

    node: py.Call
    name: str


@dataclass(eq=False)
class BodyFacts:
    """The facts of one generated function (see the module's docstring)."""

    kind: str  # "body" (a block's `_body` or action), "function" or "method"
    locals: dict[str, Local] = field(default_factory=dict)
    # a FUNCTION's or METHOD's parameters in order (without `self`): the IEC type of one that
    # receives a value, None for one that receives a reference or a box
    params: list[tuple[str, T.Type | None]] = field(default_factory=list)
    guards: list[py.stmt] = field(default_factory=list)  # the loop guards, first in each loop
    helpers: dict[str, Helper] = field(default_factory=dict)  # the runtime helpers called, by name
    loops: list[Loop] = field(default_factory=list)
    ranges: list[Ranged] = field(default_factory=list)
    body_calls: list[BodyCall] = field(default_factory=list)
    function_calls: list[UserFunctionCall] = field(default_factory=list)

    def add_inlined(self, other: BodyFacts, memo: dict[int, object], prefix: str) -> None:
        """The facts of a block's body copied into this one (codegen/inline.py): its locals renamed
        with `prefix`, its nodes mapped through the copy's `memo`."""

        def mapped(node):
            return memo.get(id(node))

        for name, local in other.locals.items():
            self.locals[prefix + name] = local
        self.helpers.update(other.helpers)
        self.guards += [g for g in map(mapped, other.guards) if g is not None]
        self.loops += [Loop(n, prefix + f.counter, f.values) for f in other.loops if (n := mapped(f.node)) is not None]
        self.ranges += [Ranged(n, f.values) for f in other.ranges if (n := mapped(f.node)) is not None]
        self.body_calls += [BodyCall(n, f.cls) for f in other.body_calls if (n := mapped(f.node)) is not None]
        self.function_calls += [
            UserFunctionCall(n, f.name) for f in other.function_calls if (n := mapped(f.node)) is not None
        ]


_ATTR = "st_facts"


def attach(fn: py.FunctionDef, facts: BodyFacts) -> py.FunctionDef:
    setattr(fn, _ATTR, facts)
    return fn


def facts_of(fn: py.AST) -> BodyFacts | None:
    """The facts the code generator kept with a function it printed, else None."""
    facts = getattr(fn, _ATTR, None)
    return facts if isinstance(facts, BodyFacts) else None


def deepcopy_with(node, facts: BodyFacts | None, memo: dict[int, object]):
    """A deep copy of `node` (or list of nodes) that leaves `facts` (kept on a function node) shared,
    not copied; `memo` maps each copied node's id to its copy."""
    if facts is not None:
        memo[id(facts)] = facts
    return copy.deepcopy(node, memo)


_recording: ContextVar[BodyFacts | None] = ContextVar("st_codegen_facts", default=None)


@contextmanager
def recording(facts: BodyFacts) -> Iterator[BodyFacts]:
    """The facts of the function being generated, for the builders below and `current()`."""
    token = _recording.set(facts)
    try:
        yield facts
    finally:
        _recording.reset(token)


def current() -> BodyFacts | None:
    """The facts of the function being generated (None outside one: initial values, tests, glue)."""
    return _recording.get()


def note_helper(name: str) -> None:
    """A call of the runtime helper `name` was printed."""
    facts = _recording.get()
    if facts is not None:
        helper = RUNTIME_HELPERS.get(name)
        if helper is not None:
            facts.helpers[name] = helper


def note_range(node: py.expr, values: Interval) -> None:
    facts = _recording.get()
    if facts is not None:
        facts.ranges.append(Ranged(node, values))
