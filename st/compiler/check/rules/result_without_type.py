"""A FUNCTION or METHOD declared without a return type has no result: its body does not assign
its name (unless a variable has that name, as TwinCAT allows), and MOCK_FUNCTION gives it no
RETURNS value. Under every preset.

Codes: E059.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ..context import CheckContext


def check_assigned_result(ctx: CheckContext, pou: T.POUType, what: str, body: list, names, span: Span) -> None:
    """The body of the FUNCTION or METHOD (`what`) `pou`, whose variables are `names`."""
    if pou.return_type is None and pou.name.lower() not in names and _assigns_name(body, pou.name):
        ctx.err(Code.RESULT_WITHOUT_TYPE, span, f"{what} {pou.name} has no return type but assigns a result")


def check_mocked_result(ctx: CheckContext, pou: T.POUType, value: A.Expr) -> bool:
    """MOCK_FUNCTION pou RETURNS value: reported (False) when `pou` returns nothing."""
    if pou.return_type is None:
        ctx.err(Code.RESULT_WITHOUT_TYPE, value.span, f"FUNCTION {pou.name} returns nothing")
        return False
    return True


def _assigns_name(body: list, name: str) -> bool:
    key = name.lower()
    for s in body:
        if isinstance(s, A.Assign) and isinstance(s.target, A.Name) and s.target.name.lower() == key:
            return True
    return False
