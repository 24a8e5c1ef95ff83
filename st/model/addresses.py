"""Direct addresses (%IX0.0, %QW3, %MD10) and the process image they must fit: OpenPLC v3's
layout, one table per area (I, Q, M) and size with TABLE_LEN entries (8 × TABLE_LEN bits for X);
%ML has OpenPLC's special function registers after them.

The checker and the runtime both ask `parse_address`, so `st check` refuses exactly the
addresses `st run` could not bind.

The forms IEC 61131-3 allows and where they land (docs/runtime.md, "The process image"):

- `%IX3.2`: bit 2 of input byte 3; `%IW3`, `%QB7`, `%MD48`, `%ML1`: the cell of that size.
- `%IX1`, `%QX1`, `%I1` (a bit address with one number; IEC allows it, MatIEC passes it on and
  OpenPLC's glue generator binds `%IX1` as `bool_input[1][0]`): bit 0 of byte 1, `%IX1.0`.
- `%QX0.4.2`, `%IW2.5.7.1` (IEC's hierarchical addresses, more numbers than the cell needs):
  their meaning is the controller's I/O configuration. OpenPLC's glue generator binds them by
  their leading numbers (`%QX0.4`, `%IW2`: `openplc_reading`), which the openplc preset and the
  default do with a warning; CODESYS, TwinCAT and IEC accept the declaration, and st accepts it
  too, but its image has no place for it: `parse_address` raises `UnplacedAddress`, which the
  checker lets through under those presets and the runtime reports, located, when it binds.
"""

from __future__ import annotations

import re

SIZES = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}
TABLE_LEN = 1024
# OpenPLC v3's special function registers follow %ML's table: %ML1024 local time, %ML1025 the cycle
# count, ... (runtime/special_registers.py); the glue generator accepts %ML1024-%ML2047
SPECIAL_BASE = TABLE_LEN
SPECIAL_LEN = 1024
_ADDR = re.compile(r"%([IQM])([XBWDL]?)([0-9]+(?:\.[0-9]+)*)$", re.I)


class AddressError(KeyError):
    """An address the process image cannot hold: malformed, out of range, or (UnplacedAddress) one
    whose place only a controller's I/O configuration knows."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class UnplacedAddress(AddressError):
    """A well-formed hierarchical address (`%QX0.4.2`, `%IW2.5`): valid IEC, no cell of st's image."""


def split_address(addr: str) -> tuple[str, str, tuple[int, ...]]:
    """'%qx0.4.2' → ('Q', 'X', (0, 4, 2)); the size defaults to X. AddressError if malformed."""
    m = _ADDR.match(addr.strip().upper())
    if not m:
        raise AddressError(f"malformed address {addr!r}")
    return m.group(1), m.group(2) or "X", tuple(int(n) for n in m.group(3).split("."))


def _places(size: str) -> int:
    """How many numbers address one cell of this size: byte.bit for X, one number otherwise."""
    return 2 if size == "X" else 1


def canonical(addr: str) -> str:
    """One spelling per cell: upper case, the size written out, a bit address's bit too
    ('%q0.1' → '%QX0.1', '%IX1' → '%IX1.0'). A malformed address is only upper-cased."""
    try:
        area, size, numbers = split_address(addr)
    except AddressError:
        return addr.strip().upper()
    if size == "X" and len(numbers) == 1:
        numbers += (0,)
    return f"%{area}{size}" + ".".join(map(str, numbers))


def openplc_reading(addr: str) -> str | None:
    """The address OpenPLC's glue generator binds a hierarchical one to: its leading numbers, the
    rest dropped ('%IW0.0' → '%IW0', '%QX0.4.2' → '%QX0.4'); None if `addr` has no surplus part."""
    try:
        area, size, numbers = split_address(addr)
    except AddressError:
        return None
    keep = _places(size)
    if len(numbers) <= keep:
        return None
    return f"%{area}{size}" + ".".join(map(str, numbers[:keep]))


def parse_address(addr: str) -> tuple[str, str, int]:
    """'%QX1.2' → ('Q', 'X', 10); '%IX1' → ('I', 'X', 8); '%IW3' → ('I', 'W', 3). Bits count
    byte × 8 + bit. A hierarchical address raises UnplacedAddress, any other misfit AddressError."""
    area, size, numbers = split_address(addr)
    if len(numbers) > _places(size):
        raise UnplacedAddress(
            f"{addr}: a hierarchical address (its place is the controller's I/O configuration); st's "
            f"process image is OpenPLC's (%{area}X<byte>.<bit>, %{area}B/W/D/L<n>) and has no place for it"
        )
    if size == "X":
        byte, bit = numbers if len(numbers) == 2 else (numbers[0], 0)
        if bit > 7:
            raise AddressError(f"{addr}: bit {bit} is not 0..7")
        index = byte * 8 + bit
        limit = TABLE_LEN * 8
    else:
        index, limit = numbers[0], TABLE_LEN + (SPECIAL_LEN if (area, size) == ("M", "L") else 0)
    if index >= limit:
        raise AddressError(f"{addr} is outside the process image ({TABLE_LEN} entries per table)")
    return area, size, index


def is_special(area: str, size: str, index: int) -> bool:
    """Is this cell one of OpenPLC's special function registers (%ML1024 and up)?"""
    return area == "M" and size == "L" and index >= SPECIAL_BASE
