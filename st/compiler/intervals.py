"""Integer intervals: the arithmetic both interval analyses of the compiler share.

The code generator proves that a store needs no wrap or an index no check from the interval of
an ST expression (`codegen/expressions.py`, `ExprGen.value_range`); the native tier proves that
C's int64 computes a Python expression exactly from the intervals of its operands
(`native/kinds.py`). Each adapts its own nodes (ST operators there, Python operators here) to
these functions, which know nothing of either: an `Interval` holds every value an integer
expression can take, and each function gives the interval of an operation's result, or None
where it gives none. None of them knows a machine's limits (int64) or a type's: the callers
check those.

Two divisions and two remainders: IEC's DIV and MOD truncate toward zero (the remainder has the
dividend's sign), Python's `//` and `%` round toward minus infinity (the remainder has the
divisor's sign). A zero divisor gives no value (a DIV0 fault, an exception) except for MOD,
whose result is then 0.
"""

from __future__ import annotations

from typing import NamedTuple

from ..model import types as T


class Interval(NamedTuple):
    """lo ≤ every value ≤ hi."""

    lo: int
    hi: int


def of_type(t: T.Type | None) -> Interval | None:
    """The values of an integer type (a subrange: its base type's, which a POINTER or a byte view
    may write without the subrange's check); BOOL is 0..1; None for any other type."""
    if t is None:
        return None
    b = T.base_of(t)
    if isinstance(b, T.ElemType) and b.is_intlike:
        return Interval(b.lo, b.hi)
    if isinstance(b, T.ElemType) and b.is_bool:
        return Interval(0, 1)
    return None


def point(v: int) -> Interval:
    return Interval(v, v)


def within(a: Interval, outer: Interval) -> bool:
    return outer.lo <= a.lo and a.hi <= outer.hi


def hull(*xs: Interval) -> Interval:
    """The smallest interval holding all of `xs` (at least one)."""
    return Interval(min(x.lo for x in xs), max(x.hi for x in xs))


def meet(a: Interval, b: Interval) -> Interval:
    """The values in both (both hold the value, so this is not empty where the value exists)."""
    return Interval(max(a.lo, b.lo), min(a.hi, b.hi))


def add(a: Interval, b: Interval) -> Interval:
    return Interval(a.lo + b.lo, a.hi + b.hi)


def sub(a: Interval, b: Interval) -> Interval:
    return Interval(a.lo - b.hi, a.hi - b.lo)


def mul(a: Interval, b: Interval) -> Interval:
    ps = (a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi)
    return Interval(min(ps), max(ps))


def neg(a: Interval) -> Interval:
    return Interval(-a.hi, -a.lo)


def magnitude(a: Interval) -> int:
    return max(abs(a.lo), abs(a.hi))


def absolute(a: Interval) -> Interval:
    lo = 0 if a.lo <= 0 <= a.hi else min(abs(a.lo), abs(a.hi))
    return Interval(lo, magnitude(a))


def div_trunc(a: Interval, b: Interval) -> Interval:
    """IEC DIV (toward zero). By a positive divisor the quotient is monotone in both operands;
    otherwise its magnitude is at most the dividend's."""
    if b.lo >= 1:
        lo = a.lo // b.hi if a.lo >= 0 else -(-a.lo // b.lo)
        hi = a.hi // b.lo if a.hi >= 0 else -(-a.hi // b.hi)
        return Interval(lo, hi)
    m = magnitude(a)
    return Interval(-m, m) if a.lo < 0 or b.lo < 0 else Interval(0, m)


def div_floor(a: Interval, b: Interval) -> Interval:
    """Python's `//`. By a divisor of one sign the quotient is monotone in each operand (its
    extremes are at the corners); otherwise its magnitude is at most the dividend's."""
    if b.lo >= 1 or b.hi <= -1:
        qs = (a.lo // b.lo, a.lo // b.hi, a.hi // b.lo, a.hi // b.hi)
        return Interval(min(qs), max(qs))
    m = magnitude(a)
    return Interval(-m, m)


def mod_trunc(a: Interval, b: Interval) -> Interval:
    """IEC MOD: below the divisor's magnitude, with the dividend's sign (0 for a zero divisor)."""
    m = max(magnitude(b), 1) - 1
    return Interval(-m if a.lo < 0 else 0, m if a.hi > 0 else 0)


def mod_floor(a: Interval, b: Interval) -> Interval:
    """Python's `%`: below the divisor's magnitude, with the divisor's sign."""
    m = max(magnitude(b), 1) - 1
    return Interval(0 if b.lo > 0 else -m, 0 if b.hi < 0 else m)


def shl(a: Interval, b: Interval) -> Interval | None:
    """`a << b` of a non-negative `a` by a non-negative count (the caller bounds the count)."""
    if a.lo < 0 or b.lo < 0:
        return None
    return Interval(a.lo << b.lo, a.hi << b.hi)


def shr(a: Interval, b: Interval) -> Interval | None:
    """`a >> b` (arithmetic) by a non-negative count."""
    if b.lo < 0:
        return None
    cs = (a.lo >> b.lo, a.lo >> b.hi, a.hi >> b.lo, a.hi >> b.hi)
    return Interval(min(cs), max(cs))


def bitwise(op: str, a: Interval, b: Interval) -> Interval:
    """`a & b`, `a | b` or `a ^ b` (op "and", "or", "xor") of two's-complement integers: of
    non-negative operands, within their bits (AND: at most the smaller); else within the bits of
    the widest operand, either sign."""
    if a.lo >= 0 and b.lo >= 0:
        n = max(a.hi.bit_length(), b.hi.bit_length())
        return Interval(0, min(a.hi, b.hi)) if op == "and" else Interval(0, (1 << n) - 1)
    n = max(abs(v).bit_length() for v in (a.lo, a.hi, b.lo, b.hi))
    return Interval(-(1 << n), (1 << n) - 1)


def invert(a: Interval) -> Interval:
    """`~a` (two's complement: -a - 1)."""
    return Interval(~a.hi, ~a.lo)


def minimum(xs: list[Interval]) -> Interval:
    """MIN of values in each of `xs` (at least one)."""
    return Interval(min(x.lo for x in xs), min(x.hi for x in xs))


def maximum(xs: list[Interval]) -> Interval:
    """MAX of values in each of `xs` (at least one)."""
    return Interval(max(x.lo for x in xs), max(x.hi for x in xs))
