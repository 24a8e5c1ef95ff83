"""The names generated code may use: one namespace per PLC is built from these.

Everything here is small and hot. Generated code reaches Python only through
these names (all begin with '_'), never through builtins directly.
"""

from __future__ import annotations

import math
import struct
from array import array
from collections.abc import Callable
from typing import Any, NoReturn

from . import byteimage
from .faults import CATCHABLE, PLCFault, exception_code

_F32 = struct.Struct("<f")
_pack, _unpack = _F32.pack, _F32.unpack


def round_f32(v: float) -> float:
    """Round to IEEE single precision (REAL on store); generated code calls it `_f32`."""
    try:
        r: float = _unpack(_pack(v))[0]
        return r
    except OverflowError:
        if v != v:
            return v
        return math.inf if v > 0 else -math.inf
    except struct.error:
        return math.nan


def make_f32() -> Callable[[float], float]:
    """A faster REAL rounding for one PLC's generated code (its own buffer: no sharing between PLCs)."""
    buf = array("f", [0.0])

    def _f32(v: float) -> float:
        buf[0] = v  # C float conversion: overflow gives ±inf, NaN stays NaN
        return buf[0]

    return _f32


def _idiv(a: int, b: int) -> int:
    """Integer division truncating toward zero (IEC/C)."""
    if b == 0:
        raise PLCFault("division by zero", "DIV0")
    q = a // b
    if q < 0 and q * b != a:
        q += 1
    return q


def _imod(a: int, b: int) -> int:
    """MOD with the sign of the dividend; x MOD 0 = 0 (IEC 61131-3)."""
    if b == 0:
        return 0
    r = abs(a) % abs(b)
    return -r if a < 0 else r


def _umod(a: int, b: int) -> int:
    return a % b if b else 0


def _fdiv(a: float, b: float) -> float:
    """REAL division: IEEE semantics for a zero divisor."""
    try:
        return a / b
    except ZeroDivisionError:
        if a == 0 or a != a:
            return math.nan
        neg = (a < 0) != (math.copysign(1.0, b) < 0)
        return -math.inf if neg else math.inf


def _pow(a: float, b: float) -> float:
    try:
        r = math.pow(a, b)
    except OverflowError:
        odd = float(b).is_integer() and int(b) % 2 == 1
        return -math.inf if a < 0 and odd else math.inf
    except ValueError:
        return math.nan
    return r


def round_half_away(v: float) -> int:
    """Nearest integer, halves away from zero (IEC REAL_TO_INT). From the truncated value and the
    exact fraction `v - q`: floor(v + 0.5) would round the sum, making 0.49999999999999994 a 1."""
    if v != v or v in (math.inf, -math.inf):
        raise PLCFault(f"cannot convert {v} to an integer", "CONVERSION")
    q = int(v)
    d = v - q
    if d >= 0.5:
        return q + 1
    if d <= -0.5:
        return q - 1
    return q


_round = round_half_away  # (the generated code's name)


def _trunc(v: float) -> int:
    if v != v or v in (math.inf, -math.inf):
        raise PLCFault(f"cannot convert {v} to an integer", "CONVERSION")
    return int(v)


def _ix(i: int, lo: int, hi: int) -> int:
    """Array index check → 0-based offset."""
    if lo <= i <= hi:
        return i - lo
    raise PLCFault(f"array index {i} is outside the bounds {lo}..{hi}", "INDEX")


def _subrange(v: int, lo: int, hi: int) -> int:
    if lo <= v <= hi:
        return v
    raise PLCFault(f"value {v} is outside the subrange {lo}..{hi}", "RANGE")


def _clamp_subrange(v: int, lo: int, hi: int) -> int:
    """A value outside a subrange as MatIEC stores it: the nearest limit."""
    return lo if v < lo else hi if v > hi else v


def _setbit(x: int, n: int, v: Any, bits: int, signed: bool) -> int:
    x = (x | (1 << n)) if v else (x & ~(1 << n))
    x &= (1 << bits) - 1
    if signed and x >> (bits - 1):
        x -= 1 << bits
    return x


def _setbits(x: int, shift: int, width: int, v: int, bits: int, signed: bool) -> int:
    """Write a partial access (x.%B1 := v): `width` bits at `shift`."""
    m = ((1 << width) - 1) << shift
    x = (x & ~m) | ((v << shift) & m)
    x &= (1 << bits) - 1
    if signed and x >> (bits - 1):
        x -= 1 << bits
    return x


def _for_dir(step: Any) -> int:
    if step > 0:
        return 1
    if step < 0:
        return -1
    raise PLCFault("FOR loop with a step of 0 never ends", "LOOP")


class _Struct:
    """Base of generated STRUCT classes: value semantics on assignment."""

    __slots__: tuple[str, ...] = ()

    def _copy(self) -> Any:
        new = object.__new__(type(self))
        for s in self.__slots__:
            setattr(new, s, _copy(getattr(self, s)))
        return new


class _Union(_Struct):
    """Base of generated UNION classes: the members are views of one bytearray (little-endian)."""

    __slots__ = ("_b",)
    _size = 0

    def __init__(self) -> None:
        self._b = bytearray(self._size)

    def _copy(self) -> Any:
        new = object.__new__(type(self))
        new._b = bytearray(self._b)
        return new


class _UnionArray:
    """An array member of a UNION: its elements read and written in the union's bytes."""

    __slots__ = ("b", "spec", "n", "es")

    def __init__(self, b: bytearray, spec: byteimage.Spec, n: int):
        self.b, self.spec, self.n, self.es = b, spec, n, byteimage.size(spec)

    def __len__(self) -> int:
        return self.n

    def _all(self) -> list[Any]:
        return [self[i] for i in range(self.n)]

    def __iter__(self) -> Any:
        return iter(self._all())

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return self._all()[i]
        if not 0 <= i < self.n:
            raise IndexError(i)
        return byteimage.unpack(self.spec, self.b[i * self.es : (i + 1) * self.es])

    def __setitem__(self, i: Any, v: Any) -> None:
        if isinstance(i, slice):
            vals = self._all()
            vals[i] = v
            if len(vals) != self.n:
                raise IndexError("an array member of a UNION keeps its length")
            self.b[: self.n * self.es] = b"".join(byteimage.pack(self.spec, x) for x in vals)
            return
        if not 0 <= i < self.n:
            raise IndexError(i)
        self.b[i * self.es : (i + 1) * self.es] = byteimage.pack(self.spec, v)


def _union_member(spec: byteimage.Spec) -> property:
    """A member of a UNION: a value of its byte image, or an array over it (byteimage specs)."""
    if spec[0] == "a":
        elem, n = spec[2], spec[1]

        def get_a(self: _Union) -> _UnionArray:
            return _UnionArray(self._b, elem, n)

        def set_a(self: _Union, v: Any) -> None:
            data = byteimage.pack(spec, v)
            self._b[: len(data)] = data

        return property(get_a, set_a)
    width = byteimage.size(spec)

    def get(self: _Union) -> Any:
        return byteimage.unpack(spec, self._b[:width])

    def set_(self: _Union, v: Any) -> None:
        self._b[:width] = byteimage.pack(spec, v)

    return property(get, set_)


def _union_class(name: str, size: int, members: tuple[tuple[str, byteimage.Spec], ...]) -> type:
    ns: dict[str, Any] = {"__slots__": (), "_size": size, "_members": tuple(m[0] for m in members)}
    for pyname, spec in members:
        ns[pyname] = _union_member(spec)
    return type("_st_" + name, (_Union,), ns)


class _FB:
    """Base of generated FUNCTION_BLOCK and PROGRAM classes."""

    __slots__: tuple[str, ...] = ()
    _from_library = False  # set by the generated class: a library's block, not the project's

    def _body(self) -> None:  # pragma: no cover - always overridden
        pass

    def _copy(self) -> Any:
        new = object.__new__(type(self))
        for s in self.__slots__:
            setattr(new, s, _copy(getattr(self, s)))
        return new


class _LateDefault:
    """Passed for an omitted input whose default names the callee's own variables (a METHOD's
    `inB : Builder(specs := tmp)` with `tmp` a local): the callee computes it where those have values."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "_LATE"


_LATE = _LateDefault()


def _copy(v: Any) -> Any:
    if isinstance(v, list):
        if v and isinstance(v[0], (list, _Struct, _FB)):
            return [_copy(x) for x in v]
        return v[:]
    if isinstance(v, (_Struct, _FB)):
        return v._copy()
    return v


def _assign(dst: Any, src: Any) -> None:
    """Aggregate assignment in place (so references into dst stay valid)."""
    if isinstance(dst, list):
        if len(dst) != len(src):
            raise PLCFault(f"cannot assign an array of {len(src)} elements to one of {len(dst)}", "INDEX")
        if dst and isinstance(dst[0], (list, _Struct, _FB)):
            for d, s in zip(dst, src):
                _assign(d, s)
        else:
            dst[:] = src
        return
    if isinstance(dst, _Union):
        dst._b[:] = src._b
        return
    for s in dst.__slots__:
        sv = getattr(src, s)
        if isinstance(sv, (list, _Struct, _FB)):
            _assign(getattr(dst, s), sv)
        else:
            setattr(dst, s, sv)


def _init_fields(obj: Any, pairs: Any) -> Any:
    for name, value in pairs:
        setattr(obj, name, value)
    return obj


def _init_props(obj: Any, pairs: Any) -> Any:
    """A block instance's declared values for its properties: each SET called, in order."""
    for setter, value in pairs:
        getattr(obj, setter)(value)
    return obj


# ------------------------------------------------------------------ references


def _wrap_to(v: Any, spec: Any) -> Any:
    if spec is None:
        return v
    if spec == "f32":
        return round_f32(v)
    if spec[0] == "str":
        return v[: spec[1]]
    bits, signed = spec
    if isinstance(v, bool):
        return v
    m = (1 << bits) - 1
    if signed:
        h = 1 << (bits - 1)
        return ((v + h) & m) - h
    return v & m


class _Conf:
    """An ARRAY[*] argument: the caller's (flat, row-major) list and its actual bounds."""

    __slots__ = ("data", "dims")

    def __init__(self, data: list[Any], dims: list[tuple[int, int]]):
        self.data, self.dims = data, dims


def _conf(arr: Any, dims: list[tuple[int, int]]) -> _Conf:
    """Bind an array to an ARRAY[*] parameter (one already bound is passed on as it is)."""
    return arr if isinstance(arr, _Conf) else _Conf(arr, dims)


def _cix(a: _Conf, *idx: int) -> int:
    """Flat index into a conformant array, checked against the bounds the caller's array has."""
    flat = 0
    for i, (lo, hi) in zip(idx, a.dims):
        if not lo <= i <= hi:
            raise IndexError(f"index {i} outside {lo}..{hi}")
        flat = flat * (hi - lo + 1) + (i - lo)
    return flat


class _AttrRef:
    """A reference to an attribute (a variable of an instance or a struct field)."""

    __slots__ = ("obj", "name", "spec")

    def __init__(self, obj: Any, name: str, spec: Any = None):
        self.obj, self.name, self.spec = obj, name, spec

    def get(self) -> Any:
        return getattr(self.obj, self.name)

    def set(self, v: Any) -> None:
        setattr(self.obj, self.name, _wrap_to(v, self.spec))

    # a reference can stand for a one-element box: `x[0]` (an in-out whose address is taken)
    def __getitem__(self, _: Any) -> Any:
        return getattr(self.obj, self.name)

    def __setitem__(self, _: Any, v: Any) -> None:
        setattr(self.obj, self.name, _wrap_to(v, self.spec))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _AttrRef) and other.obj is self.obj and other.name == self.name

    __hash__ = None  # type: ignore[assignment]      # equal by identity of the target, not hashable


class _ObjRef:
    """A reference to an instance itself (THIS): dereferencing gives the object."""

    __slots__ = ("obj",)

    def __init__(self, obj: Any):
        self.obj = obj

    def get(self) -> Any:
        return self.obj

    def set(self, v: Any) -> None:
        raise TypeError("THIS cannot be assigned")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _ObjRef) and other.obj is self.obj

    __hash__ = None  # type: ignore[assignment]      # equal by identity of the target, not hashable


def _query_itf(obj: Any, itf: str, dest: Any) -> bool:
    """__QUERYINTERFACE: store obj in dest when its block provides interface `itf`."""
    if obj is not None and itf in getattr(type(obj), "_kinds", ()):
        dest.set(obj)
        return True
    return False


def _attempt(src: Any, kind: str, src_is_ref: bool, dest_is_ref: bool) -> Any:
    """`dest ?= src`: what dest receives, the instance (or a reference to it) when it is a `kind`
    (that block, a block extending it, or a provider of that interface), else NULL (None)."""
    if src is None:
        return None
    obj = src.get() if src_is_ref else src
    if kind not in getattr(type(obj), "_kinds", ()):
        return None
    if dest_is_ref:
        return src if src_is_ref else _ObjRef(obj)
    return obj


class _ItemRef:
    """A reference to a list element or a namespace (global) entry."""

    __slots__ = ("obj", "key", "spec")

    def __init__(self, obj: Any, key: Any, spec: Any = None):
        self.obj, self.key, self.spec = obj, key, spec

    def get(self) -> Any:
        return self.obj[self.key]

    def set(self, v: Any) -> None:
        self.obj[self.key] = _wrap_to(v, self.spec)

    def __getitem__(self, _: Any) -> Any:
        return self.obj[self.key]

    def __setitem__(self, _: Any, v: Any) -> None:
        self.obj[self.key] = _wrap_to(v, self.spec)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _ItemRef) and other.obj is self.obj and other.key == self.key

    __hash__ = None  # type: ignore[assignment]      # equal by identity of the target, not hashable


class _NegRef:
    __slots__ = ("ref",)

    def __init__(self, ref: Any):
        self.ref = ref

    def get(self) -> Any:
        return not self.ref.get()

    def set(self, v: Any) -> None:
        self.ref.set(not v)


def _deref_null() -> NoReturn:
    raise PLCFault("dereference of a NULL reference", "NULL")


FILL_CHUNK = 1 << 16  # elements: a large array is built this many at a time


def _fill(value: Any, n: int, head: list[Any] | None = None) -> list[Any]:
    """`head + [value] * (n - len(head))` for a large array, built a chunk at a time: between two
    chunks the interpreter may hand over to the scan, so a program built beside the running one (an
    online change) does not hold it for the whole array (a 10-million-element list in one piece
    takes about 60 ms)."""
    out = list(head) if head else []
    while len(out) < n:
        out += [value] * min(FILL_CHUNK, n - len(out))
    return out


BASE_NAMESPACE: dict[str, Any] = {
    "_f32": round_f32,
    "_idiv": _idiv,
    "_imod": _imod,
    "_umod": _umod,
    "_fdiv": _fdiv,
    "_pow": _pow,
    "_round": _round,
    "_trunc": _trunc,
    "_ix": _ix,
    "_subrange": _subrange,
    "_clamp_subrange": _clamp_subrange,
    "_setbit": _setbit,
    "_setbits": _setbits,
    "_for_dir": _for_dir,
    "_Struct": _Struct,
    "_FB": _FB,
    "_copy": _copy,
    "_LATE": _LATE,
    "_assign": _assign,
    "_init_fields": _init_fields,
    "_init_props": _init_props,
    "_fill": _fill,
    "_AttrRef": _AttrRef,
    "_ObjRef": _ObjRef,
    "_query_itf": _query_itf,
    "_conf": _conf,
    "_cix": _cix,
    "_attempt": _attempt,
    "_ItemRef": _ItemRef,
    "_union_class": _union_class,
    "_NegRef": _NegRef,
    "_float": float,
    "_int": int,
    "_range": range,
    "_abs": abs,
    "_min": min,
    "_max": max,
    "_len": len,
    "_str": str,
    "_bool": bool,
    "_PLCFault": PLCFault,
    "_catchable": CATCHABLE,
    "_exc_code": exception_code,
}
