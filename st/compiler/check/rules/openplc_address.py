"""An address as the preset reads it (st/model/addresses.py says where each form lands).

A bit address with one number (`%IX1`, `%QX1`) is bit 0 of that byte, `%IX1.0`, under every preset
(IEC allows the form, MatIEC passes it on and OpenPLC's glue generator binds it so); it is written
so here, silently, so that `%IX1` and `%IX1.0` are one variable and one binding.

OpenPLC binds a hierarchical address by its leading numbers (its glue generator drops the rest:
%IW0.0 is %IW0, %QX0.4.2 is %QX0.4). Under the presets whose `dotted_word_addresses` is on
(openplc) and the default the address is read so, with a warning; the other presets (iec, codesys,
twincat, whose compilers leave its meaning to the I/O configuration) keep it as written: the
declaration is accepted and `st run` says, at the declaration, that its image has no place for it.

Codes: W011.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model.addresses import AddressError, canonical, openplc_reading, split_address
from ....source import Span
from ..context import CheckContext


def openplc_address(ctx: CheckContext, addr: str, span: Span) -> str:
    """The address `addr` (at `span`) as the dialect reads it."""
    try:
        _area, size, numbers = split_address(addr)
    except AddressError:
        return addr  # '%I*', or malformed: the checker says so
    if size == "X" and len(numbers) == 1:
        return canonical(addr)
    reading = openplc_reading(addr)
    if reading is None or not (ctx.dialect is None or ctx.dialect.dotted_word_addresses):
        return addr
    ignored = "." + ".".join(map(str, numbers[2 if size == "X" else 1 :]))
    hint = (
        f"write {reading}; a bit address is byte.bit"
        if size == "X"
        else f"write {reading}; only bit addresses (X) have a '.'"
    )
    ctx.warn(Code.ADDRESS_PART_IGNORED, span, f"'{addr}': OpenPLC binds it to {reading} and ignores '{ignored}'", hint)
    return reading
