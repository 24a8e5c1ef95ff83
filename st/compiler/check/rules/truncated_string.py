"""A string literal longer than the STRING it is assigned or passed to is truncated: a warning,
under every preset (not in library sources).

Codes: W003.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ..context import CheckContext


def check_truncation(ctx: CheckContext, e, dst: T.StringType, span: Span) -> None:
    """The value `e` going into a string of type `dst`."""
    if isinstance(e, A.Literal) and isinstance(e.value, str) and len(e.value) > dst.length:
        ctx.warn(Code.TRUNCATED_STRING, span, f"the string ({len(e.value)} characters) is truncated to {dst.length}")
