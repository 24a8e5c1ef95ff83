"""Names that only name a variable: `GVL_Main.x` (a named global variable list's variable,
TwinCAT) is the global `x` itself, and `%QW2` where a variable is declared AT %QW2 is that
variable (named, or declared `AT %QW2 : INT;` without a name); code generation prints a name."""

from __future__ import annotations

from .. import ast as A


def plain_name(e):
    """The rewrite of one expression (lower/__init__.py applies it with the others in one walk)."""
    sym = getattr(e, "sym", None)
    if isinstance(e, A.Direct) and sym is not None:  # %QW2 where a variable is declared AT %QW2
        out = A.Name(e.span, sym.name, sym)
        out.ty = e.ty
        return out
    if isinstance(e, A.Field) and sym is not None and getattr(sym, "is_global", False) and isinstance(e.base, A.Name):
        out = A.Name(e.span, sym.name, sym)
        out.ty = e.ty
        return out
    return e
