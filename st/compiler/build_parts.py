"""What the AST builder's callbacks (build.py) hand one another: the result of a grammar rule that
is not a node of the AST (ast.py) but a piece its parent rule takes apart, read with `isinstance`
or `match`. Private to the builder: none of these reaches the AST.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Literal

from ..source import Span
from . import ast as A

# the AST's own shapes, built by one callback and stored as they are by another
FieldValue = tuple[str, Span, Any]  # `name := initializer` (StructInit.fields, NamedType.ctor_args)
Range = tuple[A.Expr, A.Expr]  # `lo..hi` of an ARRAY or a subrange type (None for `*`)
CaseLabelValue = tuple[A.Expr, A.Expr | None]  # a CASE label: a value (hi None) or a range


class Chain(list[A.Assign]):
    """Several statements from one piece of text (a chained assignment), spliced into the
    statement list around it by `flat`."""


@dataclass(frozen=True, slots=True)
class AssignCondition:
    """`b := f()` where a condition stands (IF, ELSIF, WHILE, UNTIL): the builder makes it the
    assignment, before the test of `b` (AstBuilder._conditional)."""

    span: Span
    target: A.Expr
    value: A.Expr

    def assign(self) -> A.Assign:
        out = A.Assign(self.span, self.target, self.value)
        out.in_condition = True
        return out

    def test(self) -> A.Expr:
        """The target again, as the condition (a node of its own)."""
        return copy.deepcopy(self.target)


def flat(items: Iterable[Any]) -> Iterator[Any]:
    """The items, each Chain replaced by its statements."""
    for x in items:
        if isinstance(x, Chain):
            yield from x
        else:
            yield x


# ------------------------------------------------------------------ declarations


@dataclass(frozen=True, slots=True)
class Modifier:
    """A POU, method, property or accessor modifier (PUBLIC, ABSTRACT, OVERRIDE, ...), upper case."""

    name: str


@dataclass(frozen=True, slots=True)
class Extends:
    """`EXTENDS base` of a function block or class."""

    base: str


@dataclass(frozen=True, slots=True)
class Implements:
    """`IMPLEMENTS I1, I2` of a function block or class."""

    names: list[str]


@dataclass(frozen=True, slots=True)
class Accessor:
    """A property's GET or SET: where it starts and what is between the keyword and its END_*
    (modifiers, VAR blocks, statements)."""

    kind: Literal["GET", "SET"]
    span: Span
    parts: list[Any]


@dataclass(frozen=True, slots=True)
class TypeBody:
    """What follows `TYPE name :`, the type and its initial value (None without one)."""

    spec: A.TypeSpec
    init: Any


@dataclass(frozen=True, slots=True)
class Location:
    """`AT %IX0.0`: the address, upper case."""

    address: str


@dataclass(frozen=True, slots=True)
class ArrayCtor:
    """`ARRAY[1..2] OF FB(a := 1)` (every element's FB_init arguments: `each`) or
    `ARRAY[1..2] OF FB[(a := 1), (a := 2)]` (element by element: `elements`)."""

    spec: A.ArrayType
    each: list | None
    elements: list | None


@dataclass(frozen=True, slots=True)
class CtorArgs:
    """`(a := 1, b := 2)`: one element's FB_init arguments in `ARRAY[..] OF FB[...]`."""

    args: list


@dataclass(frozen=True, slots=True)
class Edge:
    """R_EDGE or F_EDGE after a VAR_INPUT's type, upper case."""

    kind: str


@dataclass(frozen=True, slots=True)
class TaskParam:
    """`INTERVAL := T#10ms` in a TASK declaration (the name as written)."""

    name: str
    value: A.Expr


# ------------------------------------------------------------------ statements


@dataclass(frozen=True, slots=True)
class ElsIf:
    """`ELSIF cond THEN body` of an IF."""

    cond: A.Expr
    body: list[A.Stmt]


@dataclass(frozen=True, slots=True)
class Else:
    """`ELSE body` of an IF or a CASE."""

    body: list[A.Stmt]


@dataclass(frozen=True, slots=True)
class CaseLabel:
    """One CASE label: a value (hi None) or a range lo..hi."""

    lo: A.Expr
    hi: A.Expr | None


@dataclass(frozen=True, slots=True)
class CaseLabels:
    """`label, label, ... :` that starts a CASE branch."""

    labels: list[CaseLabelValue]


@dataclass(frozen=True, slots=True)
class Catch:
    """`__CATCH(var) statements` of a __TRY."""

    var: A.Expr
    body: list[A.Stmt]


@dataclass(frozen=True, slots=True)
class Finally:
    """`__FINALLY statements` of a __TRY."""

    body: list[A.Stmt]


# ------------------------------------------------------------------ SFC


@dataclass(frozen=True, slots=True)
class TransitionCond:
    """`:= expression;` of a transition."""

    cond: A.Expr


@dataclass(frozen=True, slots=True)
class TransitionBody:
    """`: statements` of a transition (assigning the transition's name)."""

    body: list[A.Stmt]
