"""POINTER arithmetic, indexing and byte views for generated code (CODESYS/TwinCAT semantics on
st's value model).

st has no flat memory: a pointer is a reference object (`_ItemRef` into a list, `_AttrRef` to an
attribute). Arithmetic is therefore defined where CODESYS code uses it: within one array, where
`p + n` moves by n bytes (a whole number of elements), `p - q` is the distance in bytes and
`p[i]` is the element i places on; and over the bytes of a number or an array of numbers seen
through a pointer of another type (`pb : POINTER TO BYTE := ADR(dw)`). Anything else (moving a
pointer off its array or its variable, mixing pointers into different variables) is a PLC fault
that says so, never a read of some other variable.
"""

from __future__ import annotations

import struct
from typing import Any

from .faults import PLCFault
from .helpers import _ItemRef


def _fault(message: str) -> PLCFault:
    return PLCFault(message, "INDEX")


def _ptr_add(p: Any, nbytes: int, size: int) -> Any:
    """`p + nbytes` for a POINTER TO a value of `size` bytes."""
    if p is None:
        raise PLCFault("pointer arithmetic on a NULL pointer", "NULL")
    if nbytes == 0:
        return p
    if isinstance(p, _ItemRef):
        return _item_moved(p, nbytes, size)
    moved = getattr(p, "_moved", None)
    if moved is None:
        raise _fault(f"a pointer to a single variable moved by {nbytes} byte(s): st moves pointers within one array")
    return moved(nbytes, size)


def _ptr_diff(p: Any, q: Any, size: int) -> int:
    """`p - q` in bytes (also what `p < q` compares): both into the same array or variable."""
    if p is None or q is None:
        raise PLCFault("pointer arithmetic on a NULL pointer", "NULL")
    a, b = _position(p, size), _position(q, size)
    if a[0] is not b[0]:
        raise _fault("the difference of pointers into two different variables")
    return a[1] - b[1]


def _position(p: Any, size: int) -> tuple[Any, int]:
    """(what p points into, byte offset in it)."""
    if isinstance(p, _Bytes):
        return _position(p.ref, size)[0], p.offset
    if isinstance(p, _ItemRef) and isinstance(p.obj, list):
        return p.obj, p.key * size
    if isinstance(p, _ItemRef) and isinstance(p.obj, _PtrView):
        inner = _ptr_add(p.obj.p, p.key * p.obj.size, p.obj.size)
        return _position(inner, size)
    return (getattr(p, "obj", p), getattr(p, "key", getattr(p, "name", None))), 0


def _item_moved(self: _ItemRef, nbytes: int, size: int) -> Any:
    """An element of a list, moved within the list."""
    if isinstance(self.obj, _PtrView):  # ADR(p[i]): p moved by i elements first
        return _ptr_add(self.obj.p, self.key * self.obj.size + nbytes, size)
    if not isinstance(self.obj, list):
        raise _fault(f"a pointer to a single variable moved by {nbytes} byte(s): st moves pointers within one array")
    if nbytes % size:
        raise _fault(f"a pointer to {size}-byte elements moved by {nbytes} byte(s), not a whole element")
    k = self.key + nbytes // size
    if not 0 <= k <= len(self.obj):  # one past the end may be formed, not read
        raise _fault(f"a pointer moved to element {k} of an array of {len(self.obj)}")
    return _ItemRef(self.obj, k, self.spec)


class _PtrView:
    """`p[i]`: the elements from where p points on, indexed from 0 (generated code subscripts it)."""

    __slots__ = ("p", "size")

    def __init__(self, p: Any, size: int):
        if p is None:
            raise PLCFault("indexing a NULL pointer", "NULL")
        self.p, self.size = p, size

    def _at(self, i: int) -> Any:
        q = _ptr_add(self.p, i * self.size, self.size)
        obj = getattr(q, "obj", None)
        if isinstance(obj, list) and q.key >= len(obj):
            raise _fault(f"p[{i}] is past the end of an array of {len(obj)}")
        return q

    def __getitem__(self, i: int) -> Any:
        return self._at(i).get()

    def __setitem__(self, i: int, v: Any) -> None:
        self._at(i).set(v)


class _Bytes:
    """A pointer of one type over the bytes of a number, or of an array of numbers from an element
    on, of another (`ADR(dw)` as a POINTER TO BYTE): reads unpack, writes pack back."""

    __slots__ = ("ref", "src", "dst", "offset")

    def __init__(self, ref: Any, src: str, dst: str, offset: int = 0):
        self.ref, self.src, self.dst, self.offset = ref, src, dst, offset

    def _values(self) -> list[Any]:
        r = self.ref
        if isinstance(r, _ItemRef) and isinstance(r.obj, list):
            return r.obj[r.key :]
        return [r.get()]

    def _size(self) -> int:
        return struct.calcsize("<" + self.src) * len(self._values())

    def get(self) -> Any:
        vals = self._values()
        data = struct.pack(f"<{len(vals)}{self.src}", *vals)
        if self.offset + struct.calcsize("<" + self.dst) > len(data):
            raise _fault(f"a pointer read past the {len(data)} byte(s) of the variable it points into")
        return struct.unpack_from("<" + self.dst, data, self.offset)[0]

    def set(self, v: Any) -> None:
        vals = self._values()
        data = bytearray(struct.pack(f"<{len(vals)}{self.src}", *vals))
        if self.offset + struct.calcsize("<" + self.dst) > len(data):
            raise _fault(f"a pointer write past the {len(data)} byte(s) of the variable it points into")
        struct.pack_into("<" + self.dst, data, self.offset, v)
        new = list(struct.unpack(f"<{len(vals)}{self.src}", data))
        r = self.ref
        if isinstance(r, _ItemRef) and isinstance(r.obj, list):
            r.obj[r.key :] = new
        else:
            r.set(new[0])

    def __getitem__(self, _: Any) -> Any:
        return self.get()

    def __setitem__(self, _: Any, v: Any) -> None:
        self.set(v)

    def _moved(self, nbytes: int, size: int) -> _Bytes:
        off = self.offset + nbytes
        if not 0 <= off <= self._size():
            raise _fault(f"a pointer moved to byte {off} of a variable of {self._size()} byte(s)")
        return _Bytes(self.ref, self.src, self.dst, off)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Bytes) and other.ref == self.ref and other.offset == self.offset

    __hash__ = None  # type: ignore[assignment]


def _ptr_elems(p: Any) -> Any:
    """A pointer to a whole array as a pointer to its first element (ADR(arr) into POINTER TO INT)."""
    if p is None:
        return None
    return _ItemRef(p.get(), 0, getattr(p, "spec", None))


def _ptr_bytes(p: Any, src: str, dst: str) -> Any:
    """A pointer to values of format `src` as a pointer to `dst` values (NULL stays NULL)."""
    if p is None:
        return None
    if isinstance(p, _Bytes):
        return _Bytes(p.ref, p.src, dst, p.offset)
    return _Bytes(p, src, dst)


POINTER_HELPERS = {
    "_PtrView": _PtrView,
    "_ptr_add": _ptr_add,
    "_ptr_diff": _ptr_diff,
    "_ptr_bytes": _ptr_bytes,
    "_ptr_elems": _ptr_elems,
}
