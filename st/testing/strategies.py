"""Hypothesis strategies for IEC 61131-3 types, to property-test ST code from Python.

    from st.testing import strategies as iec

    @given(iec.ints(min_value=0), iec.times(max_value="10s"))
    def test_something(n, pt): ...

Every strategy generates values in the form `PLC.__getitem__` returns (`values.to_python`), so a
value written to a variable of that type reads back equal:

- BOOL → bool; integers and bit strings → int; REAL/LREAL → float (REAL: float32-representable);
- TIME/LTIME → int ns; DATE → int ns since 1970-01-01 at midnight; TOD → int ns since
  midnight (0 ≤ v < 1 day); DT → int ns since 1970-01-01;
- STRING/CHAR → str of code points 0..255; WSTRING/WCHAR → str of BMP code points
  (no surrogates); never longer than the declared length;
- enums → the member name (as declared); subranges → int within the range;
- arrays → lists (multi-dimensional: nested lists, row-major, as `to_python` returns them);
  structs → dicts keyed by the declared field names; REF_TO → None (NULL, the only reference a
  Python value can express).

Arrays and structs cannot be written whole through `plc[path] = value`: write them element by
element (`plc["main.a[1,2]"] = v`, `plc["main.p.x"] = v`).
"""

from __future__ import annotations

import re
import struct
from typing import Literal, cast

import hypothesis.strategies as st

from ..model import types as T
from ..runtime.values import from_python, parse_duration_arg

__all__ = [
    "for_type",
    "for_variable",
    "bools",
    "sints",
    "ints",
    "dints",
    "lints",
    "usints",
    "uints",
    "udints",
    "ulints",
    "bytes_",
    "words",
    "dwords",
    "lwords",
    "reals",
    "lreals",
    "times",
    "ltimes",
    "dates",
    "tods",
    "dts",
    "strings",
    "wstrings",
    "chars",
    "wchars",
]

_DAY = 86_400 * 10**9
_WIDE_MAX = 0xFFFF
_STRING_NAME = re.compile(r"\s*(W?STRING)\s*[\[(]\s*([0-9]+)\s*[\])]\s*$", re.I)


# --------------------------------------------------------------------------- helpers


def _check_bounds(tname: str, lo, hi, min_value, max_value, fmt=str):
    """The effective (min, max): the type's range narrowed by the options, which must lie inside it."""
    for opt, v in (("min_value", min_value), ("max_value", max_value)):
        if v is not None and not (lo <= v <= hi):
            raise ValueError(f"{opt}={fmt(v)} is outside the range of {tname} ({fmt(lo)}..{fmt(hi)})")
    a = lo if min_value is None else min_value
    b = hi if max_value is None else max_value
    if a > b:
        raise ValueError(f"min_value={fmt(a)} is greater than max_value={fmt(b)} for {tname}")
    return a, b


def _integers(t: T.Type, min_value=None, max_value=None):
    ut = T.unalias(t)
    assert isinstance(ut, (T.ElemType, T.SubrangeType))  # an integer type (its callers')
    for opt, v in (("min_value", min_value), ("max_value", max_value)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, int)):
            raise ValueError(f"{opt} must be an integer for {ut.name}, got {v!r}")
    a, b = _check_bounds(ut.name, ut.lo, ut.hi, min_value, max_value)
    return st.integers(a, b)


def _f32_bits(x: float) -> int:
    return struct.unpack("<I", struct.pack("<f", x))[0]


def _from_f32_bits(b: int) -> float:
    return struct.unpack("<f", struct.pack("<I", b))[0]


def _f32_inward(x: float, up: bool) -> float:
    """The float32 nearest to x on the side `up` (hypothesis wants width-32 bounds exact)."""
    y = struct.unpack("<f", struct.pack("<f", x))[0]
    if y == x or (y > x) == up:
        return y
    if y == 0.0:
        return _from_f32_bits(1 if up else 0x80000001)
    b = _f32_bits(y)
    return _from_f32_bits(b + 1 if (y > 0) == up else b - 1)


def _floats(t: T.ElemType, min_value=None, max_value=None, *, allow_nan=False, allow_infinity=False):
    for opt, v in (("min_value", min_value), ("max_value", max_value)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or v != v):
            raise ValueError(f"{opt} must be a number for {t.name}, got {v!r}")
    min_value = None if min_value is None else float(min_value)
    max_value = None if max_value is None else float(max_value)
    a, b = _check_bounds(t.name, t.lo, t.hi, min_value, max_value, repr)
    if t.bits == 32:
        a, b = _f32_inward(a, True), _f32_inward(b, False)
        if a > b:
            raise ValueError(f"no REAL lies between min_value={min_value!r} and max_value={max_value!r}")
    # the type's own limits are only passed when the user gave a bound: infinities need an open side
    core = st.floats(
        a if min_value is not None else None,
        b if max_value is not None else None,
        allow_nan=allow_nan,
        allow_infinity=allow_infinity,
        width=cast(Literal[32, 64], t.bits),  # REAL or LREAL
    )
    # the extremes and zero on purpose: where conversions and overflow checks break, and hypothesis
    # versions differ in how often they reach them
    edges = sorted({v for v in (a, b, 0.0) if a <= v <= b})
    return st.one_of(st.sampled_from(edges), core)


def _fmt_ns(v) -> str:
    return f"{v} ns"


def _durations(t: T.ElemType, min_value=None, max_value=None):
    """TIME/LTIME: bounds as the PLC API takes durations ('10ms', 'T#1s', 2.5 s, timedelta, int ns)."""
    conv = [None if v is None else parse_duration_arg(v) for v in (min_value, max_value)]
    a, b = _check_bounds(t.name, t.lo, t.hi, conv[0], conv[1], fmt=_fmt_ns)
    return st.integers(a, b)


def _datetimes(t: T.ElemType, min_value=None, max_value=None):
    """DATE/TOD/DT: bounds as int ns or IEC literals ('D#2024-01-31', 'TOD#12:00', 'DT#...')."""
    conv = [
        None if v is None else from_python(v, t, opt) for opt, v in (("min_value", min_value), ("max_value", max_value))
    ]
    if t.kind == "tod":
        lo, hi = 0, _DAY - 1
    elif t.kind == "date":
        lo, hi = -(-t.lo // _DAY) * _DAY, t.hi // _DAY * _DAY
    else:
        lo, hi = t.lo, t.hi
    a, b = _check_bounds(t.name, lo, hi, conv[0], conv[1], fmt=_fmt_ns)
    if t.kind != "date":
        return st.integers(a, b)
    first, last = -(-a // _DAY), b // _DAY  # whole days only: a DATE is a midnight
    if first > last:
        raise ValueError(f"no {t.name} (a midnight) lies between min_value and max_value")
    return st.integers(first, last).map(lambda d: d * _DAY)


_SURROGATES: tuple[Literal["Cs"]] = ("Cs",)  # the surrogate category: lone surrogates are no text


def _alphabet(wide: bool):
    if wide:
        return st.characters(min_codepoint=0, max_codepoint=_WIDE_MAX, exclude_categories=_SURROGATES)
    return st.characters(min_codepoint=0, max_codepoint=0xFF)


def _check_alphabet(alphabet, wide: bool, tname: str):
    if alphabet is None:
        return _alphabet(wide)
    if isinstance(alphabet, str):
        limit = _WIDE_MAX if wide else 0xFF
        bad = [c for c in alphabet if ord(c) > limit or (wide and 0xD800 <= ord(c) <= 0xDFFF)]
        if bad:
            raise ValueError(f"alphabet: {bad[0]!r} cannot be stored in a {tname}")
        if not alphabet:
            raise ValueError("alphabet is empty")
        return st.sampled_from(sorted(set(alphabet)))
    return alphabet  # a strategy for single characters: the caller's responsibility


def _strings(t: T.StringType, max_size=None, *, min_size=0, alphabet=None):
    n = t.length
    if max_size is None:
        max_size = n
    if max_size > n:
        raise ValueError(f"max_size={max_size} exceeds the length of {t.name} ({n})")
    if min_size < 0 or min_size > max_size:
        raise ValueError(f"min_size={min_size} must lie in 0..max_size ({max_size})")
    return st.text(_check_alphabet(alphabet, t.wide, t.name), min_size=min_size, max_size=max_size)


def _chars(t: T.ElemType, *, alphabet=None):
    return _check_alphabet(alphabet, t.name == "WCHAR", t.name)


def _nest(flat: list, dims: list) -> list:
    if len(dims) <= 1:
        return flat
    inner = 1
    for lo, hi in dims[1:]:
        inner *= hi - lo + 1
    return [_nest(flat[i : i + inner], dims[1:]) for i in range(0, len(flat), inner)]


def _named_type(name: str) -> T.Type:
    m = _STRING_NAME.match(name)
    if m:
        return T.StringType(int(m.group(2)), m.group(1).upper() == "WSTRING")
    t = T.ELEMENTARY.get(name.strip().upper())
    if t is None:
        raise ValueError(f"unknown elementary type {name!r} (user types: pass the Type, or use for_variable)")
    return t


# --------------------------------------------------------------------------- the entry points


def for_type(t, **opts):
    """A strategy for values of IEC type `t` (a type name such as "INT" or "STRING[10]", or a Type).

    Options go to the matching shortcut (min_value/max_value, max_size, allow_nan, ...). For an
    array they apply to its elements; for a struct they are per-field strategies by field name.
    """
    if isinstance(t, str):
        t = _named_type(t)
    ut = T.unalias(t)
    if isinstance(ut, T.SubrangeType):
        return _integers(ut, **opts)
    if isinstance(ut, T.EnumType):
        if opts:
            raise TypeError(f"for_type({ut.name}) takes no options, got {sorted(opts)}")
        # one name per value: to_python reads a value back as the first name declared for it
        return st.sampled_from([name for _, name in sorted(ut.names_by_value.items())])
    if isinstance(ut, T.ArrayType):
        if any(hi < lo for lo, hi in ut.dims):
            raise ValueError(f"{ut.name}: an ARRAY[*] has no fixed size")
        n = ut.size
        return st.lists(for_type(ut.element, **opts), min_size=n, max_size=n).map(
            lambda flat, dims=ut.dims: _nest(flat, dims)
        )
    if isinstance(ut, T.StructType):
        fields = {m.name.lower(): m for m in ut.members.values()}
        unknown = [k for k in opts if k.lower() not in fields]
        if unknown:
            raise ValueError(f"{ut.name} has no field {unknown[0]!r}")
        given = {k.lower(): v for k, v in opts.items()}
        names = [m.name for m in fields.values()]
        # tuples, not fixed_dictionaries: keep the declared field order, as to_python does
        return st.tuples(*(given[k] if k in given else for_type(m.type) for k, m in fields.items())).map(
            lambda vals, names=names: dict(zip(names, vals))
        )
    if isinstance(ut, T.RefType):
        if opts:
            raise TypeError(f"for_type({ut.name}) takes no options")
        return st.none()
    if isinstance(ut, T.StringType):
        return _strings(ut, **opts)
    if isinstance(ut, T.ElemType):
        k = ut.kind
        if k == "bool":
            if opts:
                raise TypeError(f"for_type(BOOL) takes no options, got {sorted(opts)}")
            return st.booleans()
        if k in ("int", "bit"):
            return _integers(ut, **opts)
        if k == "real":
            return _floats(ut, **opts)
        if k == "time":
            return _durations(ut, **opts)
        if k in ("date", "tod", "dt"):
            return _datetimes(ut, **opts)
        if k == "char":
            return _chars(ut, **opts)
    raise TypeError(
        f"no strategy for {getattr(ut, 'name', ut)!r}: not a value type (for a function block, generate its inputs)"
    )


def for_variable(plc, path: str, **opts):
    """The strategy for the declared type of the variable at `path` of a PLC (e.g. "main.speed")."""
    return for_type(plc.ref(path).type, **opts)


# --------------------------------------------------------------------------- named shortcuts


def bools():
    return st.booleans()


def sints(min_value=None, max_value=None):
    return _integers(T.SINT, min_value, max_value)


def ints(min_value=None, max_value=None):
    return _integers(T.INT, min_value, max_value)


def dints(min_value=None, max_value=None):
    return _integers(T.DINT, min_value, max_value)


def lints(min_value=None, max_value=None):
    return _integers(T.LINT, min_value, max_value)


def usints(min_value=None, max_value=None):
    return _integers(T.USINT, min_value, max_value)


def uints(min_value=None, max_value=None):
    return _integers(T.UINT, min_value, max_value)


def udints(min_value=None, max_value=None):
    return _integers(T.UDINT, min_value, max_value)


def ulints(min_value=None, max_value=None):
    return _integers(T.ULINT, min_value, max_value)


def bytes_(min_value=None, max_value=None):
    return _integers(T.BYTE, min_value, max_value)


def words(min_value=None, max_value=None):
    return _integers(T.WORD, min_value, max_value)


def dwords(min_value=None, max_value=None):
    return _integers(T.DWORD, min_value, max_value)


def lwords(min_value=None, max_value=None):
    return _integers(T.LWORD, min_value, max_value)


def reals(min_value=None, max_value=None, *, allow_nan=False, allow_infinity=False):
    """Single-precision floats (exactly what a REAL stores); bounds are rounded inwards to float32."""
    return _floats(T.REAL, min_value, max_value, allow_nan=allow_nan, allow_infinity=allow_infinity)


def lreals(min_value=None, max_value=None, *, allow_nan=False, allow_infinity=False):
    return _floats(T.LREAL, min_value, max_value, allow_nan=allow_nan, allow_infinity=allow_infinity)


def times(min_value=None, max_value=None):
    """TIME values (int ns). Without bounds: the whole 64-bit range, negative durations included."""
    return _durations(T.TIME, min_value, max_value)


def ltimes(min_value=None, max_value=None):
    return _durations(T.LTIME, min_value, max_value)


def dates(min_value=None, max_value=None):
    """DATE values: int ns at midnight, 1677-09-22..2262-04-11 (what 64-bit ns can hold)."""
    return _datetimes(T.DATE, min_value, max_value)


def tods(min_value=None, max_value=None):
    return _datetimes(T.TOD, min_value, max_value)


def dts(min_value=None, max_value=None):
    return _datetimes(T.DT, min_value, max_value)


def strings(max_size=80, *, min_size=0, alphabet=None):
    """STRING[max_size] values: code points 0..255 (one byte each), at most max_size of them."""
    if max_size < 0:
        raise ValueError(f"max_size={max_size} must not be negative")
    return _strings(T.StringType(max_size, False), max_size, min_size=min_size, alphabet=alphabet)


def wstrings(max_size=80, *, min_size=0, alphabet=None):
    """WSTRING[max_size] values: BMP code points (UCS-2, so no surrogates)."""
    if max_size < 0:
        raise ValueError(f"max_size={max_size} must not be negative")
    return _strings(T.StringType(max_size, True), max_size, min_size=min_size, alphabet=alphabet)


def chars(*, alphabet=None):
    return _chars(T.CHAR, alphabet=alphabet)


def wchars(*, alphabet=None):
    return _chars(T.WCHAR, alphabet=alphabet)
