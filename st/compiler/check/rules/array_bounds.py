"""What the declarations bound, a constant stays within: an array index that is a constant lies
within the dimension's bounds, a bit number within the variable's width (x.16 of a WORD), an
array initializer holds no more values than the array has elements. Under every preset (an
index known only at run time faults there instead).

Codes: E022.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_bit_number(ctx: CheckContext, e: A.Bit, t: T.Type, bits: int, width: int) -> None:
    """`e`, the bit (or byte, word, ... of `width` bits) number e.index of a value of type `t`, `bits` wide."""
    if (e.index + 1) * width > bits:
        ctx.err(Code.INDEX_OUT_OF_BOUNDS, e.span, f"{t} has no {'bit' if e.size == 'X' else e.size} {e.index}")


def check_index(ctx: CheckContext, i: A.Expr, value, lo: int, hi: int) -> None:
    """The index `i`, whose constant value is `value` (None: not a constant), of a dimension lo..hi
    (hi < lo: ARRAY[*], bounds known at run time)."""
    if isinstance(value, int) and hi >= lo and not (lo <= value <= hi):
        ctx.err(Code.INDEX_OUT_OF_BOUNDS, i.span, f"index {value} is outside the bounds {lo}..{hi}")


def check_initializer_count(ctx: CheckContext, init: A.ArrayInit, count: int, size: int) -> None:
    """An array initializer of `count` values for an array of `size` elements."""
    if count > size:
        ctx.err(Code.INDEX_OUT_OF_BOUNDS, init.span, f"{count} initial values for an array of {size} elements")
