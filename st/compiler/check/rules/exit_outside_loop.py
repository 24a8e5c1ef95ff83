"""EXIT and CONTINUE stand inside a loop (FOR, WHILE, REPEAT), under every preset.

Codes: E024.
"""

from __future__ import annotations

from ....diagnostics import Code
from ... import ast as A
from ..context import CheckContext


def check_exit(ctx: CheckContext, s: A.Exit | A.Continue, loop_depth: int) -> None:
    """`s` at `loop_depth` loops deep (0: in none)."""
    if loop_depth == 0:
        ctx.err(Code.EXIT_OUTSIDE_LOOP, s.span, f"{'EXIT' if isinstance(s, A.Exit) else 'CONTINUE'} outside a loop")
