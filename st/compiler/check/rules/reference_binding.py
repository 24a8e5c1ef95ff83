"""A reference is bound to a variable of the type it refers to (or of a block that extends it):
REF= (whose left side must be a REFERENCE TO variable), a REFERENCE TO variable's initial value,
a REFERENCE TO input's argument. Under every preset that has references (REF= and REFERENCE TO
are vendor extensions: E044 elsewhere).

Codes: E054.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..common import same_type
from ..context import CheckContext


def check_ref_target(ctx: CheckContext, target: A.Expr, sym) -> T.VarSym | None:
    """The left side of REF=, whose symbol is `sym`: a REFERENCE TO variable (else reported: None)."""
    if isinstance(sym, T.VarSym) and T.is_reference(sym.type):
        return sym
    ctx.err(Code.REFERENCE_MISMATCH, target.span, "REF= binds a REFERENCE TO variable; this is not one")
    return None


def check_ref_source(ctx: CheckContext, value: A.Expr, want: T.Type | None, got: T.Type | None) -> None:
    """REF= binds a reference to `want` to `value`, a variable (or a call's REFERENCE TO result) of type `got`."""
    if want is not None and got is not None and not same_type(got, want) and not T.extends(got, want):
        ctx.err(Code.REFERENCE_MISMATCH, value.span, f"REF= needs a {want} variable, not {got}")


def check_initial_reference(ctx: CheckContext, init: A.Expr, want: T.Type | None, got: T.Type | None) -> None:
    """A REFERENCE TO `want` declared with the variable `init` (of type `got`) as its initial value."""
    if got is not None and want is not None and not same_type(got, want) and not T.extends(got, want):
        ctx.err(Code.REFERENCE_MISMATCH, init.span, f"a REFERENCE TO {want} needs a {want} variable, not {got}")


def check_reference_argument(ctx: CheckContext, a: A.Arg, p: T.VarSym, want: T.Type, got: T.Type | None) -> None:
    """The input `p`, a REFERENCE TO `want`, bound to the argument `a` (a variable of type `got`)."""
    if got is not None and not same_type(got, want) and not T.extends(got, want):
        ctx.err(
            Code.REFERENCE_MISMATCH, a.value.span, f"'{p.name}' is a REFERENCE TO {want}; {got} cannot be bound to it"
        )
