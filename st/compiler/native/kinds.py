"""What C type each value of a generated body can have without changing what it computes.

The native tier compiles the Python the code generator printed, so every semantic decision
(where a store wraps, where REAL rounds, where an index is checked) is already made. What it
adds is representation: a local that holds a BOOL, an integer of at most 32 bits, a REAL or an
LREAL becomes a C `bint`, `int64_t` or `double`. That is exact only while no C operation can
leave the values Python would compute, so every integer expression carries the interval of its
values: an operation whose result may not fit in int64 (a product of three DINTs, a shift by a
variable count) is done on Python integers instead, as are operations whose C and Python
meanings differ at the edges (`**`, a float `//` or `%`). An int converted to double must lie
within ±2^53, where the conversion is exact in both. The interval arithmetic is the compiler's
own (compiler/intervals.py, shared with the code generator); what is C's here is the int64 bound
and which operations C computes as Python does.
"""

from __future__ import annotations

import ast as py
from dataclasses import dataclass

from ...model import types as T
from .. import intervals as I
from ..intervals import Interval as Int  # an integer (a C int64_t) whose values lie in lo..hi

INT64_MIN, INT64_MAX = -(1 << 63), (1 << 63) - 1
EXACT = 1 << 53  # integers a double holds exactly


@dataclass(frozen=True)
class Float:
    pass


@dataclass(frozen=True)
class Bool:
    pass


@dataclass(frozen=True)
class Inst:
    """An instance of the generated class `cls` (a FUNCTION_BLOCK or PROGRAM): a Python object
    whose slots the tier reads and writes at their offsets once its exact type is checked."""

    cls: str


@dataclass(frozen=True)
class Arr:
    """An ARRAY (a Python list, flat for any number of dimensions) whose elements are of kind `elem`."""

    elem: Int | Float | Bool


Kind = Int | Float | Bool | Inst | Arr | None  # None: a Python object
FLOAT, BOOL = Float(), Bool()


def ctype(kind: Kind) -> str | None:
    if isinstance(kind, Int):
        return "int64_t"
    if isinstance(kind, Float):
        return "double"
    if isinstance(kind, Bool):
        return "bint"
    return None


def of_type(t: T.Type | None) -> Kind:
    """The kind of a variable of IEC type `t` (None: it stays a Python object)."""
    if t is None:
        return None
    t = T.unalias(t)
    if isinstance(t, T.POUType) and t.pou_kind in ("FUNCTION_BLOCK", "PROGRAM") and t.pyname:
        return Inst(t.pyname)
    if isinstance(t, T.StructType) and t.kind == "struct" and t.pyname:
        return Inst(t.pyname)  # a STRUCT's value: an instance of its slotted class
    if isinstance(t, T.ArrayType):
        elem = element_kind(t)
        return Arr(elem) if isinstance(elem, (Int, Float, Bool)) else None
    if isinstance(t, T.SubrangeType):
        # the base type's range, not the subrange's: a POINTER (or ANY) writes without the check
        base = t.base
        return Int(base.lo, base.hi) if base.bits <= 32 else None
    if not isinstance(t, T.ElemType):
        return None
    if t.kind == "bool":
        return BOOL
    if t.kind in ("int", "bit") and t.bits <= 32:
        return Int(t.lo, t.hi)
    if t.kind == "real":
        return FLOAT
    return None


def element_kind(t: T.Type | None) -> Kind:
    """The kind of an element of an ARRAY (one Python list, a multi-dimensional one flattened in
    row-major order), else None."""
    if t is None:
        return None
    t = T.unalias(t)
    if isinstance(t, T.ArrayType) and all(hi >= lo for lo, hi in t.dims):
        return of_type(t.element)
    return None


def join(a: Kind, b: Kind) -> Kind:
    if isinstance(a, Int) and isinstance(b, Int):
        return I.hull(a, b)
    if a == b:
        return a
    return None


def fits(lo: int, hi: int, bound_lo: int = INT64_MIN, bound_hi: int = INT64_MAX) -> bool:
    return bound_lo <= lo and hi <= bound_hi


def as_int(k: Kind) -> Int | None:
    """An integer view of a kind: BOOL takes part in arithmetic as 0 or 1."""
    if isinstance(k, Int):
        return k
    if isinstance(k, Bool):
        return Int(0, 1)
    return None


def exact_float(k: Kind) -> bool:
    """Whether a value of kind `k` converts to double exactly (C and Python agree)."""
    if isinstance(k, Float):
        return True
    i = as_int(k)
    return i is not None and fits(i.lo, i.hi, -EXACT, EXACT)


def divides(a: Int, b: Int) -> bool:
    """Whether C divides `a` by `b` without overflow: everything but INT64_MIN / -1."""
    return fits(a.lo, a.hi) and fits(b.lo, b.hi) and not (a.lo == INT64_MIN and b.lo <= -1 <= b.hi)


def int_binop(op: py.operator, a: Int, b: Int) -> Int | None:
    """The interval of `a op b` on integers when C's int64 computes it as Python does, else None."""
    r: Int | None
    if isinstance(op, py.Add):
        r = I.add(a, b)
    elif isinstance(op, py.Sub):
        r = I.sub(a, b)
    elif isinstance(op, py.Mult):
        r = I.mul(a, b)
    elif isinstance(op, (py.FloorDiv, py.Mod)):
        if not divides(a, b):
            return None
        r = I.div_floor(a, b) if isinstance(op, py.FloorDiv) else I.mod_floor(a, b)
    elif isinstance(op, py.LShift):
        r = I.shl(a, b) if b.hi <= 62 else None  # C: a count below the width, a result in int64
    elif isinstance(op, py.RShift):
        r = I.shr(a, b) if b.hi <= 63 else None
    elif isinstance(op, (py.BitAnd, py.BitOr, py.BitXor)):
        r = I.bitwise(_BITWISE[type(op)], a, b)
    else:
        return None
    return r if r is not None and fits(r.lo, r.hi) else None


_BITWISE = {py.BitAnd: "and", py.BitOr: "or", py.BitXor: "xor"}
