"""Which Modbus table and address serves which PLC data: OpenPLC v3's map plus a map file.

OpenPLC v3's map (kept, so existing HMI projects work unchanged):

| table | addresses | PLC data |
|---|---|---|
| coils | 0–8191 | `%QX` (coil = byte × 8 + bit) |
| discrete inputs | 0–8191 | `%IX` |
| input registers | 0–1023 | `%IW` |
| holding registers | 0–1023 | `%QW` |
| holding registers | 1024–2047 | `%MW` |
| holding registers | 2048–4095 | `%MD`, two registers each, high word first |
| holding registers | 4096–8191 | `%ML`, four registers each, high word first |

A map file (TOML) binds any variable path to a table and address:

    [[register]]
    path = "instance0.speed"     # any variable path the PLC knows
    table = "holding"            # holding | input | coil | discrete
    address = 10000
    type = "REAL"                # optional: checked against the variable's type
    word_order = "big"           # big (high word first, default) | little
    access = "read"              # read | readwrite (default for holding and coils)

REAL takes two registers (IEEE 754), LREAL four, DINT/UDINT/DWORD two, LINT/ULINT/LWORD four,
INT/UINT/WORD/SINT/USINT/BYTE one, BOOL one coil (or one register, 0/1), STRING(n) n/2 registers
rounded up (two characters per register, first character in the high byte, NUL padded).
"""

from __future__ import annotations

import re
import struct
import tomllib
from dataclasses import dataclass
from typing import NoReturn

from .exchange import COILS, DISCRETE, HOLDING, INPUT, TABLE_NAMES, N

TABLES = {
    "coil": COILS,
    "coils": COILS,
    "discrete": DISCRETE,
    "discrete_input": DISCRETE,
    "discrete_inputs": DISCRETE,
    "input": INPUT,
    "input_register": INPUT,
    "input_registers": INPUT,
    "holding": HOLDING,
    "holding_register": HOLDING,
    "holding_registers": HOLDING,
}
OPENPLC_LIMIT = {COILS: 8192, DISCRETE: 8192, INPUT: 1024, HOLDING: 8192}


class MapError(ValueError):
    """A map file problem, located as file:line:column."""


def openplc_cell(table: int, address: int):
    """(area, size, index, word) of the image cell behind a Modbus address, or None. `word` is the
    register's position inside a %MD/%ML cell, 0 = the high word."""
    if table == COILS and address < 8192:
        return "Q", "X", address, 0
    if table == DISCRETE and address < 8192:
        return "I", "X", address, 0
    if table == INPUT and address < 1024:
        return "I", "W", address, 0
    if table == HOLDING:
        if address < 1024:
            return "Q", "W", address, 0
        if address < 2048:
            return "M", "W", address - 1024, 0
        if address < 4096:
            return "M", "D", (address - 2048) // 2, (address - 2048) % 2
        if address < 8192:
            return "M", "L", (address - 4096) // 4, (address - 4096) % 4
    return None


def modbus_address(area: str, size: str, index: int):
    """(table, first address, registers) of an image cell, or None when OpenPLC does not serve it."""
    if size == "X":
        return {"Q": (COILS, index, 1), "I": (DISCRETE, index, 1)}.get(area)
    if area == "I" and size == "W" and index < 1024:
        return INPUT, index, 1
    if area == "Q" and size == "W" and index < 1024:
        return HOLDING, index, 1
    if area == "M":
        if size == "W" and index < 1024:
            return HOLDING, 1024 + index, 1
        if size == "D" and index < 1024:
            return HOLDING, 2048 + 2 * index, 2
        if size == "L" and index < 1024:
            return HOLDING, 4096 + 4 * index, 4
    return None


# ---------------------------------------------------------------------------- encodings

_WIDTH = {
    "BOOL": 1,
    "SINT": 1,
    "USINT": 1,
    "BYTE": 1,
    "INT": 1,
    "UINT": 1,
    "WORD": 1,
    "DINT": 2,
    "UDINT": 2,
    "DWORD": 2,
    "REAL": 2,
    "LINT": 4,
    "ULINT": 4,
    "LWORD": 4,
    "LREAL": 4,
}
_SIGNED = {"SINT": 8, "INT": 16, "DINT": 32, "LINT": 64}


@dataclass
class Encoding:
    """How one variable's value becomes registers (or one bit) and back."""

    type_name: str  # BOOL, INT, REAL, STRING, …
    registers: int  # 0 for a coil/discrete bit
    word_order: str = "big"
    strlen: int = 0

    def to_words(self, v) -> list:
        t = self.type_name
        if t == "STRING":
            data = str(v).encode("latin-1", "replace")[: self.strlen].ljust(2 * self.registers, b"\0")
            return [data[i] << 8 | data[i + 1] for i in range(0, len(data), 2)]
        if t == "BOOL":
            return [1 if v else 0]
        if t == "REAL":
            raw = struct.unpack(">I", struct.pack(">f", float(v)))[0]
        elif t == "LREAL":
            raw = struct.unpack(">Q", struct.pack(">d", float(v)))[0]
        else:
            raw = int(v) & ((1 << (16 * self.registers)) - 1)
        words = [(raw >> (16 * (self.registers - 1 - i))) & 0xFFFF for i in range(self.registers)]
        return words if self.word_order == "big" else words[::-1]

    def from_words(self, words: list):
        t = self.type_name
        if t == "STRING":
            data = b"".join(bytes((w >> 8, w & 0xFF)) for w in words)
            return data.split(b"\0", 1)[0].decode("latin-1")[: self.strlen]
        if t == "BOOL":
            return bool(words[0])
        if self.word_order != "big":
            words = words[::-1]
        raw = 0
        for w in words:
            raw = raw << 16 | (w & 0xFFFF)
        if t == "REAL":
            return struct.unpack(">f", struct.pack(">I", raw))[0]
        if t == "LREAL":
            return struct.unpack(">d", struct.pack(">Q", raw))[0]
        bits = _SIGNED.get(t)
        if bits is not None:
            raw &= (1 << bits) - 1
            return raw - (1 << bits) if raw >= 1 << (bits - 1) else raw
        if t in ("USINT", "BYTE"):
            return raw & 0xFF
        return raw


@dataclass
class MapEntry:
    path: str
    table: int
    address: int
    encoding: Encoding
    writable: bool
    line: int = 0

    @property
    def count(self) -> int:
        return self.encoding.registers or 1

    @property
    def end(self) -> int:
        return self.address + self.count


def _type_info(t):
    """(type name, string length) of a compiled type, for the encodings above."""
    from ...model import types as T

    bt = T.base_of(t)
    name = getattr(bt, "name", str(bt)).upper()
    if name.startswith("STRING") or name.startswith("WSTRING"):
        m = re.search(r"\[(\d+)\]|\((\d+)\)", str(t))
        n = int(next(g for g in m.groups() if g)) if m else getattr(bt, "length", 80) or 80
        return "STRING", n
    if name in ("TIME", "LTIME"):
        return "LINT", 0
    return name, 0


def load_map(path: str, plc) -> list:
    """Parse a map file against a PLC's variables. Raises MapError naming file, line and column."""
    try:
        text = open(path, encoding="utf-8").read()
    except OSError as e:
        raise MapError(f"{path}: cannot read the map file: {e.strerror}") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"line (\d+), column (\d+)", str(e))
        where = f"{m.group(1)}:{m.group(2)}" if m else "1:1"
        raise MapError(f"{path}:{where}: error: {str(e).split(' (at')[0]}") from None
    lines = text.splitlines()
    unknown = set(doc) - {"register", "coil", "bit"}
    if unknown:
        key = sorted(unknown)[0]
        ln, col = _locate(lines, key)
        raise MapError(f"{path}:{ln}:{col}: error: unknown section '{key}' (use [[register]] entries)")
    entries = []
    for item in doc.get("register", []) + doc.get("coil", []) + doc.get("bit", []):
        entries.append(_entry(path, lines, item, plc))
    _check_overlaps(path, entries)
    return entries


def _locate(lines: list, needle: str, after: int = 0):
    for i, line in enumerate(lines[after:], after + 1):
        col = line.find(needle)
        if col >= 0:
            return i, col + 1
    return 1, 1


def _entry(path, lines, item: dict, plc) -> MapEntry:
    var = item.get("path")
    ln, col = _locate(lines, f'"{var}"') if isinstance(var, str) else _locate(lines, "[[")

    def fail(msg: str, hint: str = "") -> NoReturn:
        raise MapError(f"{path}:{ln}:{col}: error: {msg}" + (f"\n  = hint: {hint}" if hint else ""))

    if not isinstance(var, str):
        fail('an entry needs path = "program.variable"')
    extra = set(item) - {"path", "table", "address", "type", "word_order", "access"}
    if extra:
        fail(f"unknown key '{sorted(extra)[0]}'", "keys: path, table, address, type, word_order, access")
    table = TABLES.get(str(item.get("table", "holding")).lower())
    if table is None:
        fail(f"unknown table {item.get('table')!r}", "one of holding, input, coil, discrete")
    address = item.get("address")
    if not isinstance(address, int) or not 0 <= address < N:
        fail("address must be an integer 0..65535")
    try:
        t = plc.ref(var).type
    except (KeyError, ValueError, TypeError, IndexError) as e:
        fail(f"no variable '{var}' in the program: {e.args[0] if e.args else e}")
    tname, strlen = _type_info(t)
    if tname not in _WIDTH and tname != "STRING":
        fail(
            f"'{var}' is a {tname}: only elementary types and strings can be mapped",
            "map the fields of a structure or the elements of an array one by one",
        )
    want = item.get("type")
    if want is not None and str(want).upper() != tname:
        fail(f"'{var}' is {tname}, the map says {want}")
    order = str(item.get("word_order", "big")).lower()
    if order not in ("big", "little"):
        fail(f"word_order must be big or little, not {order!r}")
    if table in (COILS, DISCRETE):
        if tname != "BOOL":
            fail(f"'{var}' is {tname}: only BOOL variables go into the {TABLE_NAMES[table]}")
        enc = Encoding("BOOL", 0)
    else:
        regs = (strlen + 1) // 2 if tname == "STRING" else _WIDTH[tname]
        enc = Encoding(tname, regs, order, strlen)
    access = str(item.get("access", "readwrite")).lower()
    if access not in ("read", "readwrite"):
        fail(f"access must be read or readwrite, not {access!r}")
    entry = MapEntry(var, table, address, enc, access == "readwrite" and table in (COILS, HOLDING), ln)
    if entry.end > N:
        fail(f"'{var}' needs {entry.count} registers from {address}: past 65535")
    return entry


def _check_overlaps(path: str, entries: list) -> None:
    spans = sorted(entries, key=lambda e: (e.table, e.address))
    for a, b in zip(spans, spans[1:]):
        if a.table == b.table and b.address < a.end:
            raise MapError(
                f"{path}:{b.line}:1: error: '{b.path}' at {TABLE_NAMES[b.table]} {b.address} overlaps "
                f"'{a.path}' ({a.address}..{a.end - 1})"
            )


# ---------------------------------------------------------------------------- the effective map


@dataclass
class Row:
    table: int
    first: int
    last: int
    source: str  # the variable's path ("main.lamp", a global's name; several joined by ", ")
    type_name: str  # its IEC type
    encoding: str
    writable: bool
    location: str = ""  # a located variable's address ("%QX1.0"); "" for a map file's entry


def variable_paths(plc) -> dict[tuple[int, object], str]:
    """(id(container), key) → the path of the variable stored there, for every variable of the
    program instances (and the block instances, arrays and structures inside them) and the globals:
    how a located variable's binding is named."""
    from ...model import types as T

    out: dict[tuple[int, object], str] = {}
    seen: set[int] = set()

    def walk(v, t, path: str) -> None:
        u = T.unalias(t)
        if v is None or id(v) in seen:
            return
        if isinstance(u, T.ArrayType):
            seen.add(id(v))
            for i, x in enumerate(v):
                sub = _subscript(u.dims, i)
                out[(id(v), i)] = path + sub
                walk(x, u.element, path + sub)
        elif isinstance(u, (T.StructType, T.POUType)) and getattr(u, "pou_kind", "") != "INTERFACE":
            seen.add(id(v))
            members = u.members.values() if isinstance(u, T.StructType) else u.vars.values()
            for m in members:
                if getattr(m, "section", "") in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP", "VAR_STAT"):
                    continue
                out[(id(v), m.pyname)] = f"{path}.{m.name}"
                walk(getattr(v, m.pyname, None), m.type, f"{path}.{m.name}")

    for name, obj, pou in plc.instances.values():
        walk(obj, pou, name)
    for g in plc.project.globals.values():
        if g.pyname in plc.ns:
            out[(id(plc.ns), g.pyname)] = g.name
            walk(plc.ns[g.pyname], g.type, g.name)
    return out


def _subscript(dims, flat: int) -> str:
    """The ST index of a flat array position: '[3]', '[1, 2]'."""
    idx = []
    for lo, hi in reversed(dims):
        n = hi - lo + 1
        idx.append(lo + flat % n)
        flat //= n
    return "[" + ", ".join(str(i) for i in reversed(idx)) + "]"


def located_cells(plc, entries: list | None = None):
    """(bindings, table, first address, registers) of every located variable OpenPLC's map serves,
    except where a map-file entry claims the address."""
    claimed = {(e.table, a) for e in entries or [] for a in range(e.address, e.end)}
    for binds in plc.bindings.values():
        b = binds[0]
        where = modbus_address(b.area, b.size, b.index)
        if where is None:
            continue
        table, first, n = where
        if not any((table, a) in claimed for a in range(first, first + n)):
            yield binds, table, first, n


def effective_map(plc, entries: list | None = None) -> list:
    """Every served range: OpenPLC's located variables (named by their paths), then the map file's
    entries."""
    from ...model.addresses import canonical

    rows = []
    paths = variable_paths(plc)
    for binds, table, first, n in located_cells(plc, entries):
        b = binds[0]
        enc = "bit" if n == 1 and b.size == "X" else ("16-bit" if n == 1 else f"{16 * n}-bit, high word first")
        names = [paths.get((id(x.container), x.key)) for x in binds]
        source = ", ".join(dict.fromkeys(p for p in names if p)) or "-"  # "-": a directly used %address
        rows.append(
            Row(table, first, first + n - 1, source, str(b.type), enc, table in (COILS, HOLDING), canonical(b.addr))
        )
    for e in entries or []:
        enc = e.encoding
        desc = (
            "bit"
            if enc.registers == 0
            else (f"{enc.registers} registers, {enc.word_order} word order" if enc.registers > 1 else "16-bit")
        )
        if enc.type_name == "STRING":
            desc = f"{enc.registers} registers, 2 characters each"
        rows.append(Row(e.table, e.address, e.end - 1, e.path, enc.type_name, desc, e.writable))
    rows.sort(key=lambda r: (r.table, r.first))
    return rows
