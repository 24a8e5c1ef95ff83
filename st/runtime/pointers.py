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

from typing import Any

from . import byteimage
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
    if isinstance(p, ByteView):
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


class ByteView:
    """A pointer of one type over the byte image of a value, or of an array from an element on, of
    another (`ADR(s)` as a POINTER TO BYTE): reads unpack, writes pack back (runtime/byteimage.py).
    `src` is the image spec of the value (or element) pointed into, `dst` the pointer's own."""

    __slots__ = ("ref", "src", "dst", "offset")

    def __init__(self, ref: Any, src: byteimage.Spec, dst: byteimage.Spec, offset: int = 0):
        self.ref, self.src, self.dst, self.offset = ref, src, dst, offset

    def _values(self) -> list[Any]:
        r = self.ref
        if isinstance(r, _ItemRef) and isinstance(r.obj, list):
            return r.obj[r.key :]
        return [r.get()]

    def _size(self) -> int:
        return byteimage.size(self.src) * len(self._values())

    def _byte_list(self) -> list[int] | None:
        """The list of BYTE (or USINT) values pointed into, when it is one (the fast path)."""
        r = self.ref
        if self.src[0] == "i" and self.src[1] == 1 and isinstance(r, _ItemRef) and isinstance(r.obj, list):
            return r.obj
        return None

    def room(self) -> int:
        """How many bytes there are from the pointer's position to the end of what it points into."""
        raw = self._byte_list()
        if raw is not None:
            start: int = self.ref.key + self.offset
            return max(0, len(raw) - start)
        return max(0, self._size() - self.offset)

    def image(self, limit: int | None = None) -> bytes:
        """The bytes of what the pointer points into, from its own position on (the first `limit`
        of them: a MEMCPY of 10 bytes into a 64 KiB buffer packs 10, not 64 Ki)."""
        raw = self._byte_list()
        if raw is not None:
            start = self.ref.key + self.offset
            part = raw[start:] if limit is None else raw[start : start + limit]
            if not self.src[2]:  # unsigned bytes: 0..255 already (bytes() copies them in C)
                try:
                    return bytes(part)
                except ValueError:
                    pass
            return bytes(v & 0xFF for v in part)
        vals = self._values()
        if limit is not None:
            es = byteimage.size(self.src)
            vals = vals[: (self.offset + limit + es - 1) // es if es else len(vals)]
        data = b"".join(byteimage.pack(self.src, v) for v in vals)[self.offset :]
        return data if limit is None else data[:limit]

    def write_image(self, data: bytes) -> None:
        """Replace the bytes from the pointer's position on by `data` (at most as many as there are)."""
        raw = self._byte_list()
        if raw is not None:
            start = self.ref.key + self.offset
            if start + len(data) > len(raw):
                size = len(raw) - self.ref.key
                raise _fault(f"a write of {len(data)} byte(s) past the {size} byte(s) of the variable pointed into")
            signed = self.src[2]
            raw[start : start + len(data)] = [b - 256 if signed and b > 127 else b for b in data]
            return
        vals = self._values()
        whole = bytearray(b"".join(byteimage.pack(self.src, v) for v in vals))
        if self.offset + len(data) > len(whole):
            raise _fault(f"a write of {len(data)} byte(s) past the {len(whole)} byte(s) of the variable pointed into")
        whole[self.offset : self.offset + len(data)] = data
        es = byteimage.size(self.src)
        new = [byteimage.unpack(self.src, whole[i * es : (i + 1) * es], v) for i, v in enumerate(vals)]
        r = self.ref
        if isinstance(r, _ItemRef) and isinstance(r.obj, list):
            r.obj[r.key :] = new
        else:
            r.set(new[0])

    def get(self) -> Any:
        n = byteimage.size(self.dst)
        data = self.image(n)
        if n > len(data):
            raise _fault(f"a pointer read past the {self._size()} byte(s) of the variable it points into")
        return byteimage.unpack(self.dst, data[:n])

    def set(self, v: Any) -> None:
        self.write_image(byteimage.pack(self.dst, v))

    def __getitem__(self, _: Any) -> Any:
        return self.get()

    def __setitem__(self, _: Any, v: Any) -> None:
        self.set(v)

    def _moved(self, nbytes: int, size: int) -> ByteView:
        off = self.offset + nbytes
        if not 0 <= off <= self._size():
            raise _fault(f"a pointer moved to byte {off} of a variable of {self._size()} byte(s)")
        return ByteView(self.ref, self.src, self.dst, off)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ByteView) and other.ref == self.ref and other.offset == self.offset

    __hash__ = None  # type: ignore[assignment]


def _ptr_elems(p: Any) -> Any:
    """A pointer to a whole array as a pointer to its first element (ADR(arr) into POINTER TO INT)."""
    if p is None:
        return None
    return _ItemRef(p.get(), 0, getattr(p, "spec", None))


def _ptr_bytes(p: Any, src: byteimage.Spec, dst: byteimage.Spec) -> Any:
    """A pointer to values of image spec `src` as a pointer to `dst` values (NULL stays NULL)."""
    if p is None:
        return None
    if isinstance(p, ByteView):
        return ByteView(p.ref, p.src, dst, p.offset)
    return ByteView(p, src, dst)


_BYTE = ("i", 1, False, 1)


def byte_view(p: Any, spec: byteimage.Spec | None = _BYTE, what: str = "a memory function") -> ByteView:
    """A pointer as a view of the bytes from where it points on (for library code that reads or
    writes memory: MEMCPY, a file write): a byte view already, or one over what it points to,
    whose image spec is `spec` (BYTE for a POINTER TO BYTE into an array of bytes)."""
    if p is None:
        raise PLCFault(f"{what} was given a NULL pointer", "NULL")
    if isinstance(p, ByteView):
        return p
    if spec is None:
        raise PLCFault(f"{what}: what the pointer points to has no bytes st can copy", "MEMORY")
    return ByteView(p, spec, _BYTE)


def _any_value(cls: Any, ref: Any, spec: byteimage.Spec, type_class: int, names: tuple[str, str, str]) -> Any:
    """The AnyType an ANY input receives: `pValue` a POINTER TO BYTE over the argument's bytes (the
    caller's variable itself, or a temporary for an expression), `diSize` their number, `TypeClass`."""
    value = cls()
    pv, size, tc = names
    setattr(value, pv, ByteView(ref, spec, _BYTE))
    setattr(value, size, byteimage.size(spec))
    setattr(value, tc, type_class)
    return value


def _new_items(make: Any, n: int, wrap: Any) -> Any:
    """`__NEW(T, n)`: a POINTER TO the first of `n` fresh values of T, which it may move over;
    NULL when `n` < 1 (CODESYS's __NEW gives 0 when it cannot allocate)."""
    if n < 1:
        return None
    return _ItemRef([make() for _ in range(n)], 0, wrap)


POINTER_HELPERS = {
    "_any_value": _any_value,
    "_new_items": _new_items,
    "_PtrView": _PtrView,
    "_ptr_add": _ptr_add,
    "_ptr_diff": _ptr_diff,
    "_ptr_bytes": _ptr_bytes,
    "_ptr_elems": _ptr_elems,
}
