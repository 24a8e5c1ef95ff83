"""A FOR loop counts with an integer control variable, by a step that is not the constant 0,
under every preset (what its body may do to the counter is for_counter.py's rule).

Codes: E025, E029.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_counter_type(ctx: CheckContext, var: A.Expr, t: T.Type | None) -> None:
    """The control variable `var`, of type `t` (None: reported already)."""
    if t is not None and not T.base_of(t).is_intlike:
        ctx.err(Code.FOR_NOT_INTEGER, var.span, f"a FOR variable must be an integer, not {t}")


def check_step(ctx: CheckContext, step: A.Expr, value) -> None:
    """The BY expression `step`, whose constant value is `value` (None: not a constant)."""
    if value == 0:
        ctx.err(Code.NOT_CONSTANT, step.span, "a FOR step of 0 never ends")
