"""A variable located AT an address of the process image has a type one cell holds: a number, a
bit string, BOOL, a time or a date (not a string, a structure, an array or a block), as wide as the
address's size (%IW: 16 bits; %IX, %QX: one bit, a BOOL). Under every preset.

Codes: E058.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ..context import CheckContext


def check_located_type(ctx: CheckContext, loc: str, t: T.Type, size: str, want: T.ElemType, span: Span) -> None:
    """The variable AT `loc` (of the size letter `size`, whose cells are of type `want`) of type `t`."""
    bt = T.base_of(t)
    if not (isinstance(bt, T.EnumType) or isinstance(bt, T.ElemType) and bt.kind not in ("string", "char")):
        ctx.err(
            Code.LOCATED_TYPE,
            span,
            f"'{loc}' is one cell of the process image; it cannot hold a value of type {t}",
            "locate a number, a bit string, BOOL, a time or a date, or use an unlocated variable",
        )
        return
    if isinstance(bt, T.ElemType) and bt.bits != want.bits and not (size in ("", "X") and bt.is_bool):
        ctx.err(Code.LOCATED_TYPE, span, f"'{loc}' is {want.bits} bit(s) wide; it cannot hold a {t}")
