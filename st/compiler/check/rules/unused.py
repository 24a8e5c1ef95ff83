"""A variable declared and never used: a warning, under every preset, for the VAR and VAR_TEMP
variables of the program's own POUs (not located ones, which the process image uses, and not in
library sources). The checker's last step, once every body is checked.

Codes: W002.
"""

from __future__ import annotations

from ....diagnostics import Code
from ..context import CheckContext


def warn_unused(ctx: CheckContext) -> None:
    for pou in ctx.project.pous.values():
        if pou.library:
            continue
        for sym in pou.vars.values():
            if sym.section in ("VAR", "VAR_TEMP") and not sym.used and not sym.location:
                ctx.warn(Code.UNUSED_VARIABLE, sym.span, f"variable '{sym.name}' is never used")
