"""The integer interval arithmetic the code generator and the native tier share
(st/compiler/intervals.py): every result of an operation on values of two intervals lies in the
interval it gives, checked exhaustively on small intervals; the exact figures of a few."""

from __future__ import annotations

import itertools
import random

import pytest

from st.compiler import intervals as I
from st.compiler.codegen import expressions
from st.compiler.native import kinds
from st.model import types as T
from st.runtime.helpers import BASE_NAMESPACE

# IEC DIV and MOD as the generated code computes them (st/runtime/helpers.py)
IEC_DIV, IEC_MOD = BASE_NAMESPACE["_idiv"], BASE_NAMESPACE["_imod"]

# intervals around zero, one-sided, single values: every value of each is tried against every other
SMALL = [I.Interval(lo, hi) for lo, hi in [(-7, 7), (-5, -1), (1, 6), (0, 0), (-1, 0), (3, 3), (-8, 5), (0, 9)]]


def _values(a: I.Interval) -> range:
    return range(a.lo, a.hi + 1)


def _bit(op):
    return lambda x, y: {"and": x & y, "or": x | y, "xor": x ^ y}[op]


TOTAL = {
    "add": (I.add, lambda x, y: x + y),
    "sub": (I.sub, lambda x, y: x - y),
    "mul": (I.mul, lambda x, y: x * y),
    "and": (lambda a, b: I.bitwise("and", a, b), _bit("and")),
    "or": (lambda a, b: I.bitwise("or", a, b), _bit("or")),
    "xor": (lambda a, b: I.bitwise("xor", a, b), _bit("xor")),
    "mod_trunc": (I.mod_trunc, IEC_MOD),  # x MOD 0 = 0
}
# a zero divisor gives no value (a fault, an exception)
DIVISIONS = {
    "div_trunc": (I.div_trunc, IEC_DIV),
    "div_floor": (I.div_floor, lambda x, y: x // y),
    "mod_floor": (I.mod_floor, lambda x, y: x % y),
}


@pytest.mark.parametrize("name", [*TOTAL, *DIVISIONS])
def test_every_result_lies_in_the_interval(name):
    interval, op = {**TOTAL, **DIVISIONS}[name]
    for a, b in itertools.product(SMALL, repeat=2):
        r = interval(a, b)
        for x, y in itertools.product(_values(a), _values(b)):
            if y == 0 and name in DIVISIONS:
                continue
            assert r.lo <= op(x, y) <= r.hi, (name, a, b, x, y, r)


def test_shifts_unary_operators_and_min_max():
    for a, b in itertools.product(SMALL, repeat=2):
        for x, y in itertools.product(_values(a), _values(b)):
            if b.lo >= 0:
                sr = I.shr(a, b)
                assert sr is not None and sr.lo <= x >> y <= sr.hi
                if a.lo >= 0:
                    sl = I.shl(a, b)
                    assert sl is not None and sl.lo <= x << y <= sl.hi
            assert I.minimum([a, b]).lo <= min(x, y) <= I.minimum([a, b]).hi
            assert I.maximum([a, b]).lo <= max(x, y) <= I.maximum([a, b]).hi
        for x in _values(a):
            assert I.neg(a).lo <= -x <= I.neg(a).hi
            assert I.invert(a).lo <= ~x <= I.invert(a).hi
            assert I.absolute(a).lo <= abs(x) <= I.absolute(a).hi
    assert I.shl(I.Interval(-1, 1), I.Interval(1, 1)) is None  # a negative value: Python's meaning
    assert I.shr(I.Interval(0, 8), I.Interval(-1, 1)) is None


def test_exact_figures():
    assert I.div_trunc(I.Interval(-100, 50), I.Interval(3, 10)) == I.Interval(-33, 16)
    assert I.div_trunc(I.Interval(7, 9), I.Interval(-2, 2)) == I.Interval(-9, 9)  # either sign, or 0: a fault
    assert I.div_floor(I.Interval(-100, 50), I.Interval(3, 10)) == I.Interval(-34, 16)
    assert I.mod_trunc(I.Interval(-50, 0), I.Interval(7, 7)) == I.Interval(-6, 0)  # the dividend's sign
    assert I.mod_trunc(I.Interval(5, 9), I.Interval(0, 0)) == I.Interval(0, 0)  # x MOD 0 = 0
    assert I.mod_floor(I.Interval(-50, 50), I.Interval(-5, 7)) == I.Interval(-6, 6)
    assert I.of_type(T.SubrangeType("S", T.INT, 0, 10)) == I.Interval(-32768, 32767)  # the base type's
    assert I.of_type(T.BOOL) == I.Interval(0, 1) and I.of_type(T.REAL) is None
    assert I.meet(I.Interval(0, 10), I.Interval(5, 20)) == I.Interval(5, 10)
    assert I.hull(I.Interval(0, 1), I.Interval(5, 6)) == I.Interval(0, 6)


def test_random_wide_intervals_stay_sound():
    rng = random.Random(33)
    for _ in range(2000):
        a = sorted(rng.randint(-(1 << 40), 1 << 40) for _ in range(2))
        b = sorted(rng.randint(-(1 << 20), 1 << 20) for _ in range(2))
        ia, ib = I.Interval(*a), I.Interval(*b)
        x, y = rng.randint(*a), rng.randint(*b)
        for name, (interval, op) in {**TOTAL, **DIVISIONS}.items():
            if y == 0 and name in DIVISIONS:
                continue
            r = interval(ia, ib)
            assert r.lo <= op(x, y) <= r.hi, (name, ia, ib, x, y)


def test_one_module_for_both_analyses():
    # the native tier's integer kind is the interval, and both sides compute with this module
    assert kinds.Int is I.Interval
    assert expressions.I is I and kinds.I is I
