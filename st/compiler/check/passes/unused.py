"""The last pass: variables declared and never used (W002)."""

from __future__ import annotations

from ..context import CheckContext


def warn_unused(ctx: CheckContext) -> None:
    for pou in ctx.project.pous.values():
        if pou.library:
            continue
        for sym in pou.vars.values():
            if sym.section in ("VAR", "VAR_TEMP") and not sym.used and not sym.location:
                ctx.warn("W002", sym.span, f"variable '{sym.name}' is never used")
