"""A set or reset assignment (x S= c, x R= c) works on BOOLs: its variable and its value are
both BOOL, under every preset.

Codes: E056.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_set_reset(ctx: CheckContext, s: A.Assign, target: T.Type | None, value: T.Type | None) -> None:
    """`s` (S= or R=) whose target is of type `target` and value of type `value` (None: reported already)."""
    if (target is not None and not T.base_of(target).is_bool) or (value is not None and not T.base_of(value).is_bool):
        ctx.err(Code.SET_RESET_NOT_BOOL, s.span, f"'{s.kind}' needs BOOL operands")
