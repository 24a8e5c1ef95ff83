"""Two declarations of one variable agree on its type: a VAR_EXTERNAL and the VAR_GLOBAL it names,
a VAR_CONFIG entry and the variable of the program instance it configures, a VAR_ACCESS path and
the variable it reaches. Under every preset.

Codes: E060.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..common import same_type
from ..context import CheckContext


def check_external(ctx: CheckContext, sym: T.VarSym, g: T.VarSym) -> None:
    """The VAR_EXTERNAL `sym` bound to the VAR_GLOBAL `g`."""
    if not same_type(g.type, sym.type):
        ctx.err(
            Code.DECLARATION_MISMATCH,
            sym.span,
            f"VAR_EXTERNAL '{sym.name}' is declared {sym.type} but the VAR_GLOBAL is {g.type}",
        )


def check_config_entry(ctx: CheckContext, d: A.VarDecl, path: list, declared: T.Type, t: T.Type) -> bool:
    """The VAR_CONFIG entry `d` for the variable at `path`, of type `t`, declared `declared`:
    reported (False) when they differ."""
    if same_type(declared, t):
        return True
    ctx.err(Code.DECLARATION_MISMATCH, d.type.span, f"VAR_CONFIG: {'.'.join(path)} is {t}, not {declared}")
    return False


def check_access_entry(ctx: CheckContext, d: A.AccessDecl, declared: T.Type, t: T.Type) -> bool:
    """The VAR_ACCESS entry `d`, declared `declared`, for a variable of type `t`: reported (False)
    when they differ."""
    if same_type(declared, t):
        return True
    ctx.err(
        Code.DECLARATION_MISMATCH,
        d.type.span,
        f"VAR_ACCESS: {'.'.join(d.path)} is {t}, not {declared}",
    )
    return False
