"""A CANopen-over-EtherCAT object dictionary: typed entries addressed by (index, subindex).

Devices build one (`ObjectDictionary.add`), the CoE mailbox serves SDO upload/download from it,
and PDO mapping objects (0x1600…, 0x1A00…) plus the SyncManager assignment (0x1C12/0x1C13) say
which entries travel in process data. Values are Python ints/floats/bytes; the byte form is
little endian as on the wire.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import cast

# CoE data types: name → (struct format or None, bit length, CoE data type index)
DTYPES = {
    "BOOL": ("<B", 1, 0x0001),
    "SINT": ("<b", 8, 0x0002),
    "INT": ("<h", 16, 0x0003),
    "DINT": ("<i", 32, 0x0004),
    "USINT": ("<B", 8, 0x0005),
    "UINT": ("<H", 16, 0x0006),
    "UDINT": ("<I", 32, 0x0007),
    "REAL": ("<f", 32, 0x0008),
    "STRING": (None, 0, 0x0009),
    "OCTETS": (None, 0, 0x000A),
    "LREAL": ("<d", 64, 0x0011),
    "LINT": ("<q", 64, 0x0015),
    "ULINT": ("<Q", 64, 0x001B),
}

# SDO abort codes (CiA 301)
ABORT_TOGGLE = 0x05030000
ABORT_TIMEOUT = 0x05040000
ABORT_COMMAND = 0x05040001
ABORT_UNSUPPORTED = 0x06010000
ABORT_WRITE_ONLY = 0x06010001
ABORT_READ_ONLY = 0x06010002
ABORT_SUBINDEX_CA = 0x06010004  # complete access not supported
ABORT_NO_OBJECT = 0x06020000
ABORT_NOT_MAPPABLE = 0x06040041
ABORT_PDO_TOO_LONG = 0x06040042
ABORT_LENGTH = 0x06070010
ABORT_TOO_LONG = 0x06070012
ABORT_TOO_SHORT = 0x06070013
ABORT_NO_SUBINDEX = 0x06090011
ABORT_VALUE_RANGE = 0x06090030
ABORT_GENERAL = 0x08000000
ABORT_STATE = 0x08000022  # not in this device state


class SdoAbort(Exception):
    def __init__(self, code: int, what: str = ""):
        super().__init__(f"SDO abort {code:#010x}{': ' + what if what else ''}")
        self.code = code


@dataclass(slots=True)
class Entry:
    index: int
    sub: int
    name: str
    dtype: str
    value: object = 0
    access: str = "rw"  # ro, rw, wo
    pdo: bool = False  # may be mapped into process data
    size: int = 0  # bytes, for STRING/OCTETS
    on_write: Callable | None = None  # f(entry, new_value) → abort code or 0 (before the store)
    writable_in: tuple = ("PREOP", "SAFEOP", "OP")

    @property
    def bits(self) -> int:
        fmt, bits, _ = DTYPES[self.dtype]
        return bits if fmt else self.size * 8

    def encode(self, value=None) -> bytes:
        v = self.value if value is None else value
        fmt = DTYPES[self.dtype][0]
        if fmt is None:
            # a string or octets (bytes, or a list of byte values)
            b = v.encode("latin-1") if isinstance(v, str) else bytes(cast(Iterable[int], v))
            return b[: self.size].ljust(self.size, b"\0") if self.size else b
        if self.dtype == "BOOL":
            return struct.pack(fmt, 1 if v else 0)
        return struct.pack(fmt, v)

    def decode(self, data: bytes):
        fmt = DTYPES[self.dtype][0]
        if fmt is None:
            return data.rstrip(b"\0").decode("latin-1") if self.dtype == "STRING" else bytes(data)
        n = struct.calcsize(fmt)
        if len(data) != n:
            raise SdoAbort(ABORT_TOO_LONG if len(data) > n else ABORT_TOO_SHORT, f"{self.index:#06x}:{self.sub}")
        v = struct.unpack(fmt, data)[0]
        return bool(v) if self.dtype == "BOOL" else v


class ObjectDictionary:
    def __init__(self):
        self.entries: dict = {}  # (index, sub) → Entry
        self._by_key: dict = {}  # the same entries by (index, sub) and, for subindex 0, by index
        self.state = "INIT"  # the device's AL state, for writable_in checks
        self.writes = 0  # writes from outside the device: od[k] = v, an SDO download, the PDO outputs

    # ------------------------------------------------------------------ building
    def add(
        self,
        index: int,
        sub: int,
        name: str,
        dtype: str,
        value=0,
        access: str = "rw",
        pdo: bool = False,
        size: int = 0,
        on_write=None,
        writable_in=("PREOP", "SAFEOP", "OP"),
    ) -> Entry:
        if dtype not in DTYPES:
            raise ValueError(f"unknown CoE data type {dtype}")
        e = Entry(index, sub, name, dtype, value, access, pdo, size, on_write, writable_in)
        self.entries[(index, sub)] = e
        self._by_key[(index, sub)] = e
        if sub == 0:
            self._by_key[index] = e
        return e

    def add_record(self, index: int, name: str, subs: list, access: str = "rw", writable_in=("PREOP",)) -> None:
        """A record/array with subindex 0 = number of entries (UDINT subs unless given (name, dtype, value))."""
        self.add(index, 0, name, "USINT", len(subs), access, writable_in=writable_in)
        for i, s in enumerate(subs, 1):
            sname, dtype, value = s
            self.add(index, i, sname, dtype, value, access, writable_in=writable_in)

    def add_pdo_mapping(self, index: int, name: str, mapped: list, access: str = "rw") -> None:
        """A PDO mapping object: mapped = [(index, sub, bits)] → UDINT entries 0xIIIISSBB."""
        self.add_record(
            index,
            name,
            [(f"entry {i}", "UDINT", (ix << 16) | (sx << 8) | bits) for i, (ix, sx, bits) in enumerate(mapped, 1)],
            access,
        )
        subs = self.entries[(index, 0)]
        subs.on_write = self._check_count(index)

    def add_assignment(self, index: int, name: str, pdos: list, access: str = "rw") -> None:
        """0x1C12/0x1C13: the PDO mapping objects assigned to a SyncManager."""
        self.add_record(index, name, [(f"PDO {i}", "UINT", p) for i, p in enumerate(pdos, 1)], access)
        self.entries[(index, 0)].on_write = self._check_count(index)

    def _check_count(self, index: int):
        def check(entry, value):
            n = max(s for (i, s) in self.entries if i == index)
            return 0 if 0 <= value <= n else ABORT_VALUE_RANGE

        return check

    # ------------------------------------------------------------------ access
    def entry(self, index: int, sub: int = 0) -> Entry:
        e = self.entries.get((index, sub))
        if e is None:
            if any(i == index for (i, _) in self.entries):
                raise SdoAbort(ABORT_NO_SUBINDEX, f"{index:#06x}:{sub}")
            raise SdoAbort(ABORT_NO_OBJECT, f"{index:#06x}")
        return e

    def has(self, index: int, sub: int = 0) -> bool:
        return (index, sub) in self.entries

    def __getitem__(self, key):
        """od[index] (subindex 0) or od[index, sub]: the value."""
        return self._by_key[key].value

    def __setitem__(self, key, value):
        self._by_key[key].value = value
        self.writes += 1

    def subindices(self, index: int) -> list:
        return sorted(s for (i, s) in self.entries if i == index)

    # ------------------------------------------------------------------ SDO
    def upload(self, index: int, sub: int, complete: bool = False) -> bytes:
        if complete:
            subs = self.subindices(index)
            if not subs:
                raise SdoAbort(ABORT_NO_OBJECT, f"{index:#06x}")
            out = bytearray()
            n = self.entries[(index, 0)].value if (index, 0) in self.entries else len(subs)
            for s in subs:
                if s > 0 and s > n:
                    break
                e = self.entries[(index, s)]
                b = e.encode()
                out += b if s != 0 else b[:1] + b"\0"  # CiA 301 CA: subindex 0 padded to 16 bits
            return bytes(out)
        e = self.entry(index, sub)
        if e.access == "wo":
            raise SdoAbort(ABORT_WRITE_ONLY)
        return e.encode()

    def download(self, index: int, sub: int, data: bytes, complete: bool = False) -> None:
        if complete:
            subs = self.subindices(index)
            if not subs:
                raise SdoAbort(ABORT_NO_OBJECT, f"{index:#06x}")
            pos = 0
            values = []
            for s in subs:
                if pos >= len(data):
                    break
                e = self.entries[(index, s)]
                n = 2 if s == 0 else e.bits // 8 or len(data) - pos
                chunk = data[pos : pos + n]
                values.append((e, e.decode(chunk[:1] if s == 0 else chunk)))
                pos += n
            if pos < len(data):
                raise SdoAbort(ABORT_TOO_LONG, f"{index:#06x}")
            # subindex 0 last would leave a half-written record visible; CiA 301 writes it first as 0
            for e, v in values:
                self._store(e, v)
            return
        e = self.entry(index, sub)
        self._store(e, e.decode(bytes(data)) if DTYPES[e.dtype][0] else e.decode(bytes(data)))

    def _store(self, e: Entry, v) -> None:
        if e.access == "ro":
            raise SdoAbort(ABORT_READ_ONLY, f"{e.index:#06x}:{e.sub}")
        if self.state not in e.writable_in:
            raise SdoAbort(ABORT_STATE, f"{e.index:#06x}:{e.sub} in {self.state}")
        if e.on_write is not None:
            code = e.on_write(e, v)
            if code:
                raise SdoAbort(code, f"{e.index:#06x}:{e.sub}")
        e.value = v
        self.writes += 1

    # ------------------------------------------------------------------ PDO layouts
    def pdo_entries(self, assign_index: int) -> list:
        """The entries a SyncManager carries: [(Entry or None for padding, bits)] in order."""
        out = []
        for s in range(1, int(self[(assign_index, 0)]) + 1):
            pdo = int(self[(assign_index, s)])
            for k in range(1, int(self[(pdo, 0)]) + 1):
                word = int(self[(pdo, k)])
                ix, sx, bits = word >> 16, (word >> 8) & 0xFF, word & 0xFF
                out.append((None if ix == 0 else self.entries.get((ix, sx)), bits))
        return out
