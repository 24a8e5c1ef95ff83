"""The variable of a __CATCH(exc) (CODESYS, TwinCAT exception handling) is of the type
__SYSTEM.ExceptionCode, the enumeration of the runtime's exception codes it receives, under every
preset that has __TRY (the construct itself is a vendor extension: E044 elsewhere).

Codes: E013.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_exception_variable(ctx: CheckContext, var: A.Expr, t: T.Type | None) -> None:
    """The __CATCH variable `var`, of type `t` (None: reported already)."""
    if t is None:
        return
    u = T.unalias(t)
    if not (isinstance(u, T.EnumType) and u.name.lower() == "exceptioncode"):
        ctx.err(
            Code.TYPE_MISMATCH,
            var.span,
            f"the variable of __CATCH must be of type __SYSTEM.ExceptionCode, not {t}",
            "declare it as exc : __SYSTEM.ExceptionCode;",
        )
