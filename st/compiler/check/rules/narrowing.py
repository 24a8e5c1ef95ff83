"""Implicit conversions that may lose data. IEC 61131-3 converts implicitly only where nothing can
be lost (INT into DINT, REAL into LREAL): under iec and openplc a narrowing one (DINT into INT,
LREAL into REAL, a long time or date into a short one) and any between bit strings and numbers
is an error. The codesys and twincat presets and the default (`bits_as_numbers`) make the
conversions between numbers and bit strings as CODESYS and TwinCAT do: silently where the value
is kept, with a warning where it may not be.

Codes: E027, W008.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ..context import CheckContext


def lossy_conversion(ctx: CheckContext, s: T.Type, d: T.Type, src: T.Type, dst: T.Type, span: Span) -> bool:
    """Does the dialect convert `src` (base `s`) into `dst` (base `d`) although data may be lost?
    Then it is warned (W008) and made."""
    if not (ctx.bits_as_numbers() and T.lossy_number_conversion(s, d)):
        return False
    ctx.warn(
        Code.LOSSY_CONVERSION,
        span,
        f"implicit conversion from {src} to {dst} may lose data (the value is wrapped to {dst})"
        if not d.is_real
        else f"implicit conversion from {src} to {dst} may lose precision",
        f"convert explicitly with {s.name}_TO_{d.name}(...) to say it is meant",
    )
    return True


def narrowing(ctx: CheckContext, s: T.Type, d: T.Type, src: T.Type, dst: T.Type, span: Span) -> bool:
    """Is `src` into `dst` a conversion IEC makes only explicitly (reported: E027)? False when it
    is no conversion between numbers, bit strings or times at all (another rule's mismatch)."""
    if not (isinstance(s, T.ElemType) and isinstance(d, T.ElemType) and _numeric_or_shorter_time(s, d)):
        return False
    conv = f"{s.name}_TO_{d.name}"
    if s.kind != d.kind and "bit" in (s.kind, d.kind) and T.bits_numbers_convert(s, d):
        # nothing would be lost: the rule is the type family
        why = (
            f"{src} is a bit string and {dst} a number: IEC 61131-3 converts between them only "
            f"explicitly (the codesys and twincat dialects do it implicitly)"
            if s.kind == "bit"
            else f"{src} is a number and {dst} a bit string: IEC 61131-3 converts between them only "
            f"explicitly (the codesys and twincat dialects do it implicitly)"
        )
    else:
        why = f"implicit conversion from {src} to {dst} may lose data"
    ctx.err(Code.NARROWING, span, why, f"convert explicitly with {conv}(...)")
    return True


def _numeric_or_shorter_time(s: T.ElemType, d: T.ElemType) -> bool:
    """Numbers and bit strings between each other, or a long time or date into a short one."""
    return (
        s.kind in ("int", "real", "bit")
        and d.kind in ("int", "real", "bit")
        or s.kind == d.kind
        and s.kind in ("time", "date", "tod", "dt")
        and s.long
        and not d.long
    )
