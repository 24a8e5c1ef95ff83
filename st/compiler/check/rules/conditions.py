"""A condition is BOOL: IF, ELSIF, WHILE and UNTIL conditions and SFC transition conditions, under
every preset (an integer is not true or false in ST).

Codes: E015.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_condition(ctx: CheckContext, e: A.Expr, t: T.Type | None, what: str) -> None:
    """The condition `e` of an IF, ELSIF, WHILE or UNTIL, of type `t` (None: reported already)."""
    if t is not None and not T.base_of(t).is_bool:
        ctx.err(
            Code.CONDITION_NOT_BOOL,
            e.span,
            f"the {what} condition must be BOOL, not {t}",
            "compare explicitly, e.g. x <> 0" if T.base_of(t).is_num else "",
        )


def check_transition_condition(ctx: CheckContext, cond: A.Expr, t: T.Type | None) -> None:
    """An SFC transition's condition, of type `t` (None: reported already)."""
    if t is not None and not T.base_of(t).is_bool:
        ctx.err(Code.CONDITION_NOT_BOOL, cond.span, f"a transition condition must be BOOL, not {t}")
