"""Process-data layouts: which object sits at which bit of a SyncManager's image, and packing.

A layout is built once (from a device's object dictionary, an ESI file, or the CiA 402
default) and packs/unpacks a whole image in one `struct` call when every entry is byte
aligned, which is the case for the drive profiles; bit-sized entries (digital terminals) fall
back to integer arithmetic.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass

from .od import DTYPES


@dataclass(frozen=True)
class PdoEntry:
    index: int
    sub: int
    bits: int
    dtype: str  # a CoE type name; "PAD" for a gap
    name: str = ""
    offset: int = 0  # bit offset within the image

    @property
    def key(self):
        return (self.index, self.sub)


class PdoLayout:
    def __init__(self, entries):
        """entries: [(index, sub, bits, dtype, name)] in image order (index 0 = padding)."""
        out = []
        off = 0
        for ix, sx, bits, dtype, name in entries:
            out.append(PdoEntry(ix, sx, bits, "PAD" if ix == 0 else dtype, name, off))
            off += bits
        self.entries = out
        self.bits = off
        self.size = (off + 7) // 8
        self.data_entries = [e for e in out if e.dtype != "PAD"]
        self.by_key = {e.key: e for e in self.data_entries}
        self.by_name = {e.name.lower(): e for e in self.data_entries if e.name}
        aligned = all(
            e.offset % 8 == 0 and e.bits % 8 == 0 and (e.dtype == "PAD" or DTYPES.get(e.dtype, (None,))[0]) for e in out
        )
        self._struct = None
        if aligned:
            fmt = "<"
            for e in out:
                if e.dtype == "PAD":
                    fmt += f"{e.bits // 8}x"
                else:
                    f = DTYPES[e.dtype][0][1]
                    if struct.calcsize("<" + f) * 8 != e.bits:
                        break
                    fmt += f
            else:
                self._struct = struct.Struct(fmt)

    @classmethod
    def from_od(cls, od, assign_index: int) -> PdoLayout:
        items = []
        for entry, bits in od.pdo_entries(assign_index):
            if entry is None:
                items.append((0, 0, bits, "PAD", ""))
            else:
                items.append(
                    (
                        entry.index,
                        entry.sub,
                        bits,
                        entry.dtype if entry.bits == bits else _dtype_for_bits(bits),
                        entry.name,
                    )
                )
        return cls(items)

    def pack(self, values) -> bytes:
        """values: a sequence in data_entries order."""
        if self._struct is not None:
            try:  # ints for the integer entries (the usual case): no conversion needed
                return self._struct.pack(*values)
            except struct.error:
                pass
            return self._struct.pack(
                *[
                    int(v) if e.dtype != "REAL" and e.dtype != "LREAL" else float(v)
                    for v, e in zip(values, self.data_entries)
                ]
            )
        acc = 0
        for v, e in zip(values, self.data_entries):
            fmt = DTYPES[e.dtype][0]
            if e.dtype in ("REAL", "LREAL"):
                assert fmt is not None  # a REAL's struct format
                raw = int.from_bytes(struct.pack(fmt, float(v)), "little")
            else:
                raw = int(v) & ((1 << e.bits) - 1)
            acc |= raw << e.offset
        return acc.to_bytes(self.size, "little")

    def unpacker(self) -> Callable:
        """A function of an image giving its values in data_entries order, for a cycle's hot path:
        the precompiled struct's unpack_from (a tuple) when there is one, else `unpack`."""
        return self._struct.unpack_from if self._struct is not None else self.unpack

    def unpack(self, data) -> list:
        if self._struct is not None:
            return list(self._struct.unpack_from(data, 0))
        acc = int.from_bytes(bytes(data[: self.size]), "little")
        out = []
        for e in self.data_entries:
            raw = (acc >> e.offset) & ((1 << e.bits) - 1)
            if e.dtype in ("REAL", "LREAL"):
                fmt = DTYPES[e.dtype][0]
                assert fmt is not None  # a REAL's struct format
                out.append(struct.unpack(fmt, raw.to_bytes(e.bits // 8, "little"))[0])
            elif e.dtype in ("SINT", "INT", "DINT", "LINT") and raw >> (e.bits - 1):
                out.append(raw - (1 << e.bits))
            elif e.dtype == "BOOL":
                out.append(bool(raw))
            else:
                out.append(raw)
        return out

    def describe(self) -> list:
        return [
            (e.offset // 8, e.offset % 8, e.bits, f"{e.index:#06x}:{e.sub:02x}", e.dtype, e.name) for e in self.entries
        ]


def _dtype_for_bits(bits: int) -> str:
    return {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT", 64: "ULINT"}.get(bits, "OCTETS")


# The CiA 402 default mapping (the profile's fixed first PDOs as used by most drives)
CIA402_RX = [
    (0x6040, 0, 16, "UINT", "controlword"),
    (0x607A, 0, 32, "DINT", "target_position"),
    (0x60FF, 0, 32, "DINT", "target_velocity"),
    (0x6060, 0, 8, "SINT", "modes_of_operation"),
]
CIA402_TX = [
    (0x6041, 0, 16, "UINT", "statusword"),
    (0x6064, 0, 32, "DINT", "position_actual"),
    (0x606C, 0, 32, "DINT", "velocity_actual"),
    (0x603F, 0, 16, "UINT", "error_code"),
]

# Types and names of the CiA 402 objects (a mapping read over CoE gives only bit lengths)
KNOWN_TYPES = {
    0x603F: "UINT",
    0x6040: "UINT",
    0x6041: "UINT",
    0x6060: "SINT",
    0x6061: "SINT",
    0x6064: "DINT",
    0x606C: "DINT",
    0x6071: "INT",
    0x6077: "INT",
    0x607A: "DINT",
    0x60F4: "DINT",
    0x60FF: "DINT",
    0x6062: "DINT",
    0x60FC: "DINT",
    0x6072: "UINT",
    0x60B1: "DINT",
    0x60B2: "INT",
    0x60B8: "UINT",
    0x60B9: "UINT",
    0x60BA: "DINT",
    0x60FD: "UDINT",
}
KNOWN_NAMES = {
    0x603F: "error_code",
    0x6040: "controlword",
    0x6041: "statusword",
    0x6060: "modes_of_operation",
    0x6061: "modes_of_operation_display",
    0x6064: "position_actual",
    0x606C: "velocity_actual",
    0x6071: "target_torque",
    0x6077: "torque_actual",
    0x607A: "target_position",
    0x60F4: "following_error_actual",
    0x60FF: "target_velocity",
    0x60FD: "digital_inputs",
}
