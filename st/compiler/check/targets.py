"""What a call resolved to, kept on `Call.target` for the lowering and code generation.

One frozen dataclass per kind of call, each with exactly the fields that kind has, so that a
reader dispatches with `match` (or isinstance) and mypy checks every field it reads. A stage that
changes a target (the lowering decides which body a SUPER^ call runs) makes a new one with
`dataclasses.replace`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypedDict

from ...model import types as T
from .. import ast as A

if TYPE_CHECKING:
    from ...model.program import AssertInfo
    from ..library import FuncSig


class Binding(TypedDict):
    """A call's arguments matched to the callee's parameters."""

    params: dict[str, A.Arg]  # lower-case parameter name → argument
    en: A.Arg | None
    eno: A.Arg | None


@dataclass(frozen=True, eq=False)
class CallTarget:
    """The base of every kind of call target."""


@dataclass(frozen=True, eq=False)
class FbCall(CallTarget):
    """An instance of a function block called: `inst(...)`; `nonvirtual`, after lowering: the body
    to run non-virtually (SUPER^())."""

    pou: T.POUType
    bind: Binding
    nonvirtual: T.POUType | None = None


@dataclass(frozen=True, eq=False)
class FunctionCall(CallTarget):
    """A user (or library ST) FUNCTION."""

    pou: T.POUType
    bind: Binding


@dataclass(frozen=True, eq=False)
class MethodCall(CallTarget):
    """A METHOD: `obj.M(...)`, or of this instance (`obj` None); `nonvirtual`, after lowering: the
    block whose method runs non-virtually (SUPER^.M())."""

    pou: T.POUType
    bind: Binding
    obj: A.Expr | None
    nonvirtual: T.POUType | None = None


@dataclass(frozen=True, eq=False)
class ActionCall(CallTarget):
    """An ACTION of this instance (`inst` None) or of another one; TwinCAT's `inst.A(in := …)`
    passes the block's inputs and reads its outputs as an instance call does (`block`, `bind`)."""

    name: str  # lower case
    inst: A.Expr | None = None
    block: T.POUType | None = None
    bind: Binding | None = None


@dataclass(frozen=True, eq=False)
class NativeCall(CallTarget):
    """A function implemented in Python (the standard library's and the vendor libraries')."""

    sig: FuncSig
    args: list[A.Arg]
    arg_types: list[T.Type | None]
    en: A.Arg | None = None
    eno: A.Arg | None = None


@dataclass(frozen=True, eq=False)
class BoundCall(CallTarget):
    """LOWER_BOUND / UPPER_BOUND of an array; `value` the constant, None for ARRAY[*]."""

    arg: A.Expr
    dim: int
    upper: bool
    value: Any


@dataclass(frozen=True, eq=False)
class NewCall(CallTarget):
    """__NEW(T) or __NEW(T, n) (`count`: n, or None); __NEW(FB(a := v)) (`init`: FB_init's arguments)."""

    type: T.Type
    count: A.Expr | None
    init: A.CtorInit | None = None


@dataclass(frozen=True, eq=False)
class DeleteCall(CallTarget):
    """__DELETE(p); `itself`: __DELETE(THIS), a method's instance releasing itself."""

    arg: A.Expr
    itself: bool = False


@dataclass(frozen=True, eq=False)
class RefCall(CallTarget):
    """REF(x): a reference to a variable."""

    arg: A.Expr


@dataclass(frozen=True, eq=False)
class IsValidRefCall(CallTarget):
    """__ISVALIDREF(r)."""

    arg: A.Expr


@dataclass(frozen=True, eq=False)
class SizeofCall(CallTarget):
    """SIZEOF(x): its size in bytes, a constant."""

    value: Any


@dataclass(frozen=True, eq=False)
class QueryItfCall(CallTarget):
    """__QUERYINTERFACE(src, dst): is `src` an instance that provides `itf`, then `dst` refers to it."""

    src: A.Expr
    dst: A.Expr
    itf: T.POUType


@dataclass(frozen=True, eq=False)
class TestCall(CallTarget):
    """A unit-test statement (ASSERT_EQ, …): `op` its name."""

    op: str
    info: AssertInfo
    operands: list[A.Expr]
    msg: A.Expr | None


BODY_CALLS = (FbCall, FunctionCall, MethodCall)  # the kinds that bind arguments to a POU's parameters
