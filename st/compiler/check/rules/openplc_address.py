"""OpenPLC binds a byte, word, double or long address by its first number only (its glue
generator drops the rest: %IW0.0 is %IW0). Under the presets whose `dotted_word_addresses` is on
(openplc) and the default the address is read so, with a warning; the other presets keep it as
written, and the process image refuses it (E004).

Codes: W011.
"""

from __future__ import annotations

import re

from ....diagnostics import Code
from ....source import Span
from ..context import CheckContext

_WORD_WITH_BIT = re.compile(r"(%[IQM][BWDL][0-9]+)((?:\.[0-9]+)+)", re.I)


def openplc_address(ctx: CheckContext, addr: str, span: Span) -> str:
    """The address `addr` (at `span`) as the dialect reads it."""
    m = _WORD_WITH_BIT.fullmatch(addr.strip())
    if m is None or not (ctx.dialect is None or ctx.dialect.dotted_word_addresses):
        return addr
    ctx.warn(
        Code.ADDRESS_PART_IGNORED,
        span,
        f"'{addr}': OpenPLC binds it to {m.group(1).upper()} and ignores '{m.group(2)}'",
        f"write {m.group(1).upper()}; only bit addresses (X) have a '.'",
    )
    return m.group(1)
