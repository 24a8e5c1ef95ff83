"""Only a variable is written: the target of an assignment (or of an output argument, a VAR_IN_OUT
argument, REF=, ...) is not a literal, a call, an operator's result, a typed enumeration value or
an SFC step, under every preset.

Codes: E053.
"""

from __future__ import annotations

from ....diagnostics import Code
from ... import ast as A
from ..common import STEP
from ..context import CheckContext


def check_not_assignable(ctx: CheckContext, e: A.Expr) -> bool:
    """`e`, which is not a variable, is written: reported (True) if it is a value or a step."""
    if isinstance(e, (A.Literal, A.Call, A.Binary, A.Unary, A.EnumLit)):
        ctx.err(Code.NOT_ASSIGNABLE, e.span, "this expression cannot be assigned to")
        return True
    if isinstance(e, A.Name) and e.sym is STEP:
        ctx.err(Code.NOT_ASSIGNABLE, e.span, "a step cannot be assigned to")
        return True
    return False
