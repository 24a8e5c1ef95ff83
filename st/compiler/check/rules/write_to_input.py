"""A POU does not write its own VAR_INPUT under the presets whose `writable_inputs` is off (iec):
IEC 61131-3 makes inputs read-only inside the POU. openplc, codesys, twincat and the default
allow it (MatIEC, CODESYS and TwinCAT do: the POU writes its copy).

Codes: E048.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..common import Scope
from ..context import CheckContext


def check_write_to_input(ctx: CheckContext, e: A.Expr, sym: T.VarSym, scope: Scope) -> bool:
    """`e`, the variable `sym` itself, is written in `scope`: reported (True) if it is an input of
    that POU the dialect keeps read-only. A block instance, a reference or a part of the input
    (x.f, x[i]) is not the input's own value."""
    pou = scope.pou
    if not (
        sym.section == "VAR_INPUT"
        and pou is not None
        and sym.owner is pou
        and not isinstance(T.unalias(sym.type), (T.POUType,))
        and isinstance(e, A.Name)
        and not T.is_reference(sym.type)
        and not (ctx.dialect is None or ctx.dialect.writable_inputs)
    ):
        return False
    ctx.err(
        Code.WRITE_TO_INPUT,
        e.span,
        f"'{sym.name}' is an input of {pou.name} and cannot be written here",
        "copy it into a local variable first",
    )
    return True
