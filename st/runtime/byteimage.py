"""The byte image of an st value: the bytes a CODESYS/TwinCAT PLC keeps it in, for the code that
looks at values as bytes (a POINTER TO BYTE over a variable, MEMCPY between types, ANY inputs).

st keeps values as Python objects; where a program reads or writes them as bytes, the value is
packed into its image and unpacked back. The compiler describes a type's image once (a `spec`,
`model.types.byte_layout`), a hashable tuple:

    ("b",)                          BOOL, one byte
    ("i", n, signed, scale)         an integer of n bytes; times and dates are stored / scale
                                    (TIME and TOD in ms, DATE and DT in s, the L-types in ns)
    ("f", n)                        REAL (4) or LREAL (8), IEEE 754
    ("s", n, wide)                  STRING(n): n + 1 bytes; WSTRING(n): 2 (n + 1), UTF-16
    ("a", count, elem)              an array, its elements one after the other
    ("r", size, ((name, offset, spec), ...))   a structure, members at natural alignment
    ("u", size)                     a UNION: its own bytes

Little-endian throughout, as the x86 and ARM targets of those PLCs.
"""

from __future__ import annotations

import struct
from typing import Any

Spec = tuple[Any, ...]  # see the module doc

_REAL = {4: struct.Struct("<f"), 8: struct.Struct("<d")}


def size(spec: Spec) -> int:
    kind = spec[0]
    if kind == "b":
        return 1
    if kind in ("i", "f"):
        return int(spec[1])
    if kind == "s":
        return (int(spec[1]) + 1) * (2 if spec[2] else 1)
    if kind == "a":
        return int(spec[1]) * size(spec[2])
    return int(spec[1])  # "r", "u"


def pack(spec: Spec, v: Any) -> bytes:
    """The image of value `v` of the type `spec` describes."""
    kind = spec[0]
    if kind == "b":
        return b"\x01" if v else b"\x00"
    if kind == "i":
        n, _signed, scale = spec[1], spec[2], spec[3]
        iv = int(v) // scale if scale != 1 else int(v)
        return bytes((iv & ((1 << (8 * n)) - 1)).to_bytes(n, "little"))
    if kind == "f":
        return bytes(_REAL[spec[1]].pack(v))
    if kind == "s":
        n, wide = spec[1], spec[2]
        if wide:
            data = str(v).encode("utf-16-le", "replace")[: 2 * n]
            return data + bytes(2 * (n + 1) - len(data))
        data = str(v).encode("latin-1", "replace")[:n]
        return data + bytes(n + 1 - len(data))
    if kind == "a":
        return b"".join(pack(spec[2], x) for x in v)
    if kind == "r":
        out = bytearray(spec[1])
        for name, off, ms in spec[2]:
            part = pack(ms, getattr(v, name))
            out[off : off + len(part)] = part
        return bytes(out)
    return bytes(v._b)  # "u"


def unpack(spec: Spec, data: bytes | bytearray, old: Any = None) -> Any:
    """The value whose image is `data`; an array or structure `old` is filled in place (so that
    references into it stay valid) and returned."""
    kind = spec[0]
    if kind == "b":
        return data[0] != 0
    if kind == "i":
        n, signed, scale = spec[1], spec[2], spec[3]
        iv = int.from_bytes(bytes(data[:n]), "little", signed=signed)
        return iv * scale
    if kind == "f":
        return _REAL[spec[1]].unpack_from(bytes(data[: spec[1]]))[0]
    if kind == "s":
        n, wide = spec[1], spec[2]
        if wide:
            raw = bytes(data[: 2 * n])
            end = next((i for i in range(0, len(raw) - 1, 2) if raw[i : i + 2] == b"\0\0"), len(raw))
            return raw[:end].decode("utf-16-le", "replace")
        return bytes(data[:n]).split(b"\0", 1)[0].decode("latin-1")
    if kind == "a":
        es = size(spec[2])
        if old is None:
            return [unpack(spec[2], data[i * es : (i + 1) * es]) for i in range(spec[1])]
        for i in range(spec[1]):
            old[i] = unpack(spec[2], data[i * es : (i + 1) * es], old[i])
        return old
    if kind == "r":
        for name, off, ms in spec[2]:
            setattr(old, name, unpack(ms, data[off : off + size(ms)], getattr(old, name)))
        return old
    old._b[:] = bytes(data[: spec[1]])  # "u"
    return old
