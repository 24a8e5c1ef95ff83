"""Names that only name a variable: `GVL_Main.x` (a named global variable list's variable,
TwinCAT) is the global `x` itself, and `%QW2` where a variable is declared AT %QW2 is that
variable (named, or declared `AT %QW2 : INT;` without a name); code generation prints a name."""

from __future__ import annotations

from .. import ast as A
from .walk import rewrite_exprs, rewrite_outside_bodies


def global_names(body: list) -> None:
    rewrite_exprs(body, _plain)


def global_names_outside_bodies(project) -> None:
    rewrite_outside_bodies(project, _plain)


def _plain(e):
    sym = getattr(e, "sym", None)
    if isinstance(e, A.Direct) and sym is not None:  # %QW2 where a variable is declared AT %QW2
        out = A.Name(e.span, sym.name, sym)
        out.ty = e.ty
        return out
    if isinstance(e, A.Field) and getattr(sym, "is_global", False) and isinstance(e.base, A.Name):
        out = A.Name(e.span, sym.name, sym)
        out.ty = e.ty
        return out
    return e
