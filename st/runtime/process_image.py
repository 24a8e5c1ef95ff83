"""The process image: %I, %Q and %M in OpenPLC v3's layout, latched at scan boundaries.

OpenPLC keeps one table per area and size (`bool_input[1024][8]`, `int_input[1024]`,
`int_memory[1024]`, `dint_memory[1024]`, …) instead of IEC's overlapping byte view, and so
do we: `%IX3.2` is bit 2 of byte 3 of the input bits, `%IW3` is the fourth input word, and the
two do not alias. Each table has 1024 entries (8192 bits for X). Cells hold raw unsigned bits
(a REAL at `%MD0` is its IEEE-754 pattern); variables are converted on latch.

A scan of a task: `latch_in` copies `%I` (and `%M`, which an HMI may have written) into the
located variables of the task's program instances and the located globals; `publish`
copies `%Q` and `%M` variables back into the image at the end.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from ..model import types as T
from ..model.addresses import SIZES, SPECIAL_LEN, TABLE_LEN, AddressError, parse_address  # noqa: F401 (re-exported)

__all__ = ["ProcessImage", "Binding", "to_raw", "from_raw", "AddressError", "parse_address", "SIZES", "TABLE_LEN"]


class ProcessImage:
    def __init__(self) -> None:
        self.tables: dict[tuple[str, str], list[Any]] = {
            (a, s): ([False] if s == "X" else [0]) * (TABLE_LEN * (8 if s == "X" else 1)) for a in "IQM" for s in SIZES
        }
        self.tables[("M", "L")] += [0] * SPECIAL_LEN  # OpenPLC's special function registers

    def get(self, addr: str) -> Any:
        area, size, i = parse_address(addr)
        return self.tables[(area, size)][i]

    def set(self, addr: str, raw: Any) -> None:
        area, size, i = parse_address(addr)
        self.tables[(area, size)][i] = _mask(raw, size)

    def clear(self, area: str) -> None:
        for s in SIZES:
            t = self.tables[(area, s)]
            t[:] = [False if s == "X" else 0] * len(t)


def _mask(raw: Any, size: str) -> Any:
    if size == "X":
        return bool(raw)
    return int(raw) & ((1 << SIZES[size]) - 1)


# ---------------------------------------------------------------------- value ↔ raw bits

_F = struct.Struct("<f")
_D = struct.Struct("<d")


def to_raw(v: Any, t: T.Type, size: str) -> Any:
    """A variable's value as the unsigned bits of its image cell."""
    if size == "X":
        return bool(v)
    bt = T.base_of(t)
    bits = SIZES[size]
    if bt.is_real:
        return int.from_bytes(_F.pack(v) if bits == 32 else _D.pack(v), "little") if bits in (32, 64) else 0
    return int(v) & ((1 << bits) - 1)


def from_raw(raw: Any, t: T.Type, size: str) -> Any:
    """An image cell's bits as a value of the variable's type."""
    if size == "X":
        return bool(raw)
    bt = T.base_of(t)
    bits = SIZES[size]
    if bt.is_real:
        if bits == 32:
            return _F.unpack(raw.to_bytes(4, "little"))[0]
        if bits == 64:
            return _D.unpack(raw.to_bytes(8, "little"))[0]
        return 0.0
    if bt.is_bool:
        return bool(raw)
    if isinstance(bt, T.ElemType) and bt.signed and raw >= 1 << (bits - 1):
        return raw - (1 << bits)
    return raw


def _converters(t: T.Type, size: str) -> tuple[Callable[[Any], Any], Callable[[Any], Any]]:
    """(raw → value, value → raw) for one variable type and cell size, decided once per binding."""
    if size == "X":
        return bool, bool
    bt = T.base_of(t)
    bits = SIZES[size]
    mask = (1 << bits) - 1
    if bt.is_real or bt.is_bool or not (isinstance(bt, T.ElemType) and bt.signed):
        return (lambda raw: from_raw(raw, t, size)), (lambda v: to_raw(v, t, size))
    half = 1 << (bits - 1)
    full = 1 << bits
    return (lambda raw: raw - full if raw >= half else raw), (lambda v: v & mask)


class Binding:
    """One located variable: where it lives (container + attribute/key) and its image cell."""

    __slots__ = ("addr", "area", "size", "index", "container", "key", "type", "table", "conv_in", "conv_out", "is_dict")

    def __init__(self, addr: str, container: Any, key: Any, t: T.Type, image: ProcessImage):
        self.addr = addr
        self.area, self.size, self.index = parse_address(addr)
        self.container, self.key, self.type = container, key, t
        self.table = image.tables[(self.area, self.size)]
        self.conv_in, self.conv_out = _converters(t, self.size)
        self.is_dict = isinstance(container, dict)

    def read_var(self) -> Any:
        c = self.container
        return c[self.key] if self.is_dict else getattr(c, self.key)

    def write_var(self, v: Any) -> None:
        if self.is_dict:
            self.container[self.key] = v
        else:
            setattr(self.container, self.key, v)

    def latch_in(self) -> None:
        v = self.conv_in(self.table[self.index])
        if self.is_dict:
            self.container[self.key] = v
        else:
            setattr(self.container, self.key, v)

    def publish(self) -> None:
        c = self.container
        self.table[self.index] = self.conv_out(c[self.key] if self.is_dict else getattr(c, self.key))
