"""Negating an unsigned value wraps around: a warning, under every preset; a bit string negated
as an unsigned number (where the dialect converts bit strings and numbers: codesys, twincat, the
default) is warned the same way.

Codes: W005.
"""

from __future__ import annotations

from typing import cast

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_negation(ctx: CheckContext, e: A.Unary, t: T.Type) -> None:
    """`e` (a unary + or -) applied to a number of type `t`."""
    b = T.base_of(t)
    if e.op == "-" and b.is_int and not cast(T.ElemType, b).signed:
        ctx.warn(Code.UNSIGNED_NEGATION, e.span, f"negating an unsigned {t} wraps around")


def negates_bits(ctx: CheckContext, e: A.Unary, t: T.Type) -> bool:
    """Is `e` a bit string of type `t` negated as an unsigned number (CODESYS, TwinCAT)? Then warned."""
    b = T.base_of(t)
    if not (e.op == "-" and b.is_bit and not b.is_bool and ctx.bits_as_numbers()):
        return False
    ctx.warn(Code.UNSIGNED_NEGATION, e.span, f"negating an unsigned {t} wraps around")
    return True
