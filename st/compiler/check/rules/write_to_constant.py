"""What is not a variable's storage is not written: a CONSTANT (or a VAR_EXTERNAL of a global
CONSTANT), a property without SET, an enumeration value, under every preset.

Codes: E018.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_property_write(ctx: CheckContext, e: A.Expr, prop: T.PropSym) -> None:
    """The property `prop` (used as `e`) is written."""
    if prop.set is None:
        ctx.err(Code.WRITE_TO_CONSTANT, e.span, f"property {prop.name} has no SET: it cannot be written")


def check_constant_write(ctx: CheckContext, e: A.Expr, sym: T.VarSym) -> bool:
    """The variable `sym` (under `e`) is written: reported (True) if it is a CONSTANT."""
    g = sym.global_ref or sym
    if g.constant or sym.constant:
        ctx.err(Code.WRITE_TO_CONSTANT, e.span, f"'{sym.name}' is a CONSTANT")
        return True
    return False


def check_enum_value_write(ctx: CheckContext, e: A.Expr) -> None:
    """`e` is written: an enumeration value is not a variable."""
    if isinstance(e, A.Name) and isinstance(e.sym, T.EnumType):
        ctx.err(
            Code.WRITE_TO_CONSTANT, e.span, f"'{e.name}' is a value of the enumeration {e.sym.name}, not a variable"
        )
