"""A call that has no value stands as a statement: a function block call, __DELETE, a unit-test
statement (ASSERT_EQ, ...) is not used inside an expression, under every preset.

Codes: E049.
"""

from __future__ import annotations

from ....diagnostics import Code
from ... import ast as A
from ..context import CheckContext


def check_statement_call(ctx: CheckContext, c: A.Call, statement: bool, message: str, hint: str = "") -> bool:
    """`c` is a call with no value, met as a statement (`statement`) or in an expression: reported
    (True) in an expression."""
    if statement:
        return False
    ctx.err(Code.CALL_WITHOUT_VALUE, c.span, message, hint)
    return True
