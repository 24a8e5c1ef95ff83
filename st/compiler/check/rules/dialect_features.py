"""A construct outside the chosen preset is refused: object-oriented ST (METHOD, INTERFACE, EXTENDS,
THIS, ?=, ...) where the preset's `oop` is off (openplc), the vendor extensions (POINTER TO,
REFERENCE TO, REF=, ADR, SIZEOF, __NEW, VAR_STAT, ...) where its `vendor_extensions` is off (iec,
openplc). Without a preset every construct is allowed; library sources are written for every
preset.

Codes: E044.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....diagnostics import Code
from ....source import Span
from ...dialect import PRESETS, Dialect

if TYPE_CHECKING:
    from ..context import CheckContext


def allows(dialect: Dialect | None, kind: str) -> bool:
    """Does the dialect allow the constructs of `kind` ("oop" or "vendor")? (No preset: every one.)"""
    return dialect is None or (dialect.oop if kind == "oop" else dialect.vendor_extensions)


def check_feature(ctx: CheckContext, kind: str, span: Span, what: str) -> bool:
    """Is `what`, a construct of `kind` ("oop" or "vendor") at `span`, part of the chosen dialect?
    Reported if not."""
    d = ctx.dialect
    if d is None or (span is not None and span.file in ctx.library_units):
        return True
    if (kind == "oop" and d.oop) or (kind == "vendor" and d.vendor_extensions):
        return True
    others = [n for n, p in PRESETS.items() if (p.oop if kind == "oop" else p.vendor_extensions)]
    ctx.err(
        Code.NOT_IN_DIALECT,
        span,
        f"{what} is not part of the {d.name} dialect",
        f"choose --dialect {' or '.join(others)} (or a {{dialect '…'}} pragma) to use it",
    )
    return False


def presets_with(kind: str) -> str:
    """The presets that allow the constructs of `kind`, for a hint: 'codesys and twincat'."""
    names = [n for n, p in PRESETS.items() if (p.oop if kind == "oop" else p.vendor_extensions)]
    return " and ".join(names)
