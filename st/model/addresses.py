"""Direct addresses (%IX0.0, %QW3, %MD10) and the process image they must fit: OpenPLC v3's
layout, one table per area (I, Q, M) and size with TABLE_LEN entries (8 × TABLE_LEN bits for X);
%ML has OpenPLC's special function registers after them.

The checker and the runtime both ask `parse_address`, so `st check` refuses exactly the
addresses `st run` could not bind.
"""

from __future__ import annotations

import re

SIZES = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}
TABLE_LEN = 1024
# OpenPLC v3's special function registers follow %ML's table: %ML1024 local time, %ML1025 the cycle
# count, ... (runtime/special_registers.py); the glue generator accepts %ML1024-%ML2047
SPECIAL_BASE = TABLE_LEN
SPECIAL_LEN = 1024
_ADDR = re.compile(r"%([IQM])([XBWDL]?)([0-9]+)(?:\.([0-9]+))?$", re.I)


class AddressError(KeyError):
    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


def canonical(addr: str) -> str:
    """One spelling per cell: upper case, the size written out ('%q0.1' → '%QX0.1')."""
    a = addr.strip().upper()
    if len(a) > 2 and a[2].isdigit():
        a = a[:2] + "X" + a[2:]
    return a


def parse_address(addr: str) -> tuple[str, str, int]:
    """'%QX1.2' → ('Q', 'X', 10); '%IW3' → ('I', 'W', 3). Bits count byte × 8 + bit."""
    m = _ADDR.match(addr.strip().upper())
    if not m:
        raise AddressError(f"malformed address {addr!r}")
    area, size, a, b = m.group(1), m.group(2) or "X", int(m.group(3)), m.group(4)
    if size == "X":
        if b is None:
            raise AddressError(f"{addr}: a bit address needs byte.bit, e.g. %{area}X0.0")
        bit = int(b)
        if bit > 7:
            raise AddressError(f"{addr}: bit {bit} is not 0..7")
        index = a * 8 + bit
        limit = TABLE_LEN * 8
    else:
        if b is not None:
            raise AddressError(f"{addr}: only bit addresses (X) have a '.'")
        index, limit = a, TABLE_LEN + (SPECIAL_LEN if (area, size) == ("M", "L") else 0)
    if index >= limit:
        raise AddressError(f"{addr} is outside the process image ({TABLE_LEN} entries per table)")
    return area, size, index


def is_special(area: str, size: str, index: int) -> bool:
    """Is this cell one of OpenPLC's special function registers (%ML1024 and up)?"""
    return area == "M" and size == "L" and index >= SPECIAL_BASE
