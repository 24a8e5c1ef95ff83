"""st.testing.strategies: generated values round-trip through a PLC, ranges hold, bad options fail."""

from __future__ import annotations

import itertools
import math
import struct

import hypothesis.strategies as st
import pytest
from hypothesis import HealthCheck, find, given, settings

from st import PLC
from st.model import types as T
from st.testing import strategies as iec

FAST = settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
DAY = 86_400_000_000_000

# every elementary type the strategies know by name, with the variable declared for it
ELEMENTARY = [
    "BOOL",
    "SINT",
    "INT",
    "DINT",
    "LINT",
    "USINT",
    "UINT",
    "UDINT",
    "ULINT",
    "BYTE",
    "WORD",
    "DWORD",
    "LWORD",
    "REAL",
    "LREAL",
    "TIME",
    "LTIME",
    "DATE",
    "LDATE",
    "TOD",
    "TIME_OF_DAY",
    "LTOD",
    "DT",
    "DATE_AND_TIME",
    "LDT",
    "STRING",
    "STRING[5]",
    "WSTRING",
    "WSTRING[3]",
    "CHAR",
    "WCHAR",
]

INT_RANGES = {
    "SINT": (-128, 127),
    "INT": (-32768, 32767),
    "DINT": (-2147483648, 2147483647),
    "LINT": (-9223372036854775808, 9223372036854775807),
    "USINT": (0, 255),
    "UINT": (0, 65535),
    "UDINT": (0, 4294967295),
    "ULINT": (0, 18446744073709551615),
    "BYTE": (0, 255),
    "WORD": (0, 65535),
    "DWORD": (0, 4294967295),
    "LWORD": (0, 18446744073709551615),
}

SHORTCUTS = {
    "BOOL": iec.bools,
    "SINT": iec.sints,
    "INT": iec.ints,
    "DINT": iec.dints,
    "LINT": iec.lints,
    "USINT": iec.usints,
    "UINT": iec.uints,
    "UDINT": iec.udints,
    "ULINT": iec.ulints,
    "BYTE": iec.bytes_,
    "WORD": iec.words,
    "DWORD": iec.dwords,
    "LWORD": iec.lwords,
    "REAL": iec.reals,
    "LREAL": iec.lreals,
    "TIME": iec.times,
    "LTIME": iec.ltimes,
    "DATE": iec.dates,
    "TOD": iec.tods,
    "DT": iec.dts,
    "STRING": iec.strings,
    "WSTRING": iec.wstrings,
    "CHAR": iec.chars,
    "WCHAR": iec.wchars,
}


def var(tname: str) -> str:
    return "x_" + tname.lower().replace("[", "").replace("]", "")


SOURCE = """
TYPE Color : (Red, Green := 5, Blue, Teal := 5); END_TYPE
TYPE Small : INT(-5..5); END_TYPE
TYPE Meters : LREAL; END_TYPE
TYPE Point : STRUCT x : REAL; y : DINT; tag : STRING[4]; c : Color; END_STRUCT; END_TYPE
PROGRAM main
VAR
{decls}
  col : Color; sr : Small; sr2 : USINT(10..20); m : Meters; p : Point; r : REF_TO INT;
  arr : ARRAY[1..4] OF INT; grid : ARRAY[0..1, 1..3] OF Color; pts : ARRAY[1..2] OF Point;
END_VAR
END_PROGRAM
""".format(decls="\n".join(f"  {var(t)} : {t};" for t in ELEMENTARY))


@pytest.fixture(scope="module")
def plc():
    return PLC.from_source(SOURCE, use_cache=False)


def type_of(plc, path):
    return plc.ref(path).type


def assign(plc, path, t, value):
    """Write an aggregate element by element (the PLC API takes only scalars)."""
    ut = T.unalias(t)
    if isinstance(ut, T.ArrayType):
        for idx in itertools.product(*(range(lo, hi + 1) for lo, hi in ut.dims)):
            v = value
            for i, (lo, _) in zip(idx, ut.dims):
                v = v[i - lo]
            assign(plc, f"{path}[{','.join(map(str, idx))}]", ut.element, v)
    elif isinstance(ut, T.StructType):
        for m in ut.members.values():
            assign(plc, f"{path}.{m.name}", m.type, value[m.name])
    else:
        plc[path] = value


def assert_valid(tname: str, v) -> None:
    """What a value of the type must look like, from the IEC ranges (not from the strategies' code)."""
    base = tname.split("[")[0]
    if base == "BOOL":
        assert type(v) is bool
    elif base in INT_RANGES:
        lo, hi = INT_RANGES[base]
        assert type(v) is int and lo <= v <= hi
    elif base == "REAL":
        assert type(v) is float and math.isfinite(v)
        assert struct.unpack("<f", struct.pack("<f", v))[0] == v
    elif base == "LREAL":
        assert type(v) is float and math.isfinite(v)
    elif base in ("TIME", "LTIME", "DT", "DATE_AND_TIME", "LDT"):
        assert type(v) is int and -9223372036854775808 <= v <= 9223372036854775807
    elif base in ("DATE", "LDATE"):
        assert type(v) is int and v % DAY == 0 and -9223372036854775808 <= v <= 9223372036854775807
    elif base in ("TOD", "TIME_OF_DAY", "LTOD"):
        assert type(v) is int and 0 <= v < DAY
    elif base in ("STRING", "WSTRING"):
        n = int(tname[len(base) + 1 : -1]) if "[" in tname else 80
        assert type(v) is str and len(v) <= n
        if base == "STRING":
            assert all(ord(c) <= 255 for c in v)
        else:
            assert all(ord(c) <= 0xFFFF and not 0xD800 <= ord(c) <= 0xDFFF for c in v)
    elif base in ("CHAR", "WCHAR"):
        assert type(v) is str and len(v) == 1 and ord(v) <= (255 if base == "CHAR" else 0xFFFF)
    else:
        raise AssertionError(f"no check for {tname}")


@pytest.mark.parametrize("tname", ELEMENTARY)
def test_elementary_values_round_trip_through_the_plc(plc, tname):
    path = "main." + var(tname)
    shortcut = SHORTCUTS.get(tname)

    @FAST
    @given(a=iec.for_type(tname.lower()), b=iec.for_variable(plc, path), c=shortcut() if shortcut else st.none())
    def check(a, b, c):
        for v in (a, b) if c is None else (a, b, c):
            assert_valid(tname, v)
            plc[path] = v
            back = plc[path]
            assert back == v and type(back) is type(v)

    check()


@pytest.mark.parametrize(
    "strategy, value",
    [
        (iec.ints(), 32767),
        (iec.ints(), -32768),
        (iec.usints(), 255),
        (iec.ulints(), 18446744073709551615),
        (iec.reals(), 3.4028234663852886e38),
        (iec.reals(), -3.4028234663852886e38),
        (iec.times(), 9223372036854775807),
        (iec.tods(), DAY - 1),
        (iec.strings(5), "\xff"),
    ],
)
def test_the_whole_range_is_explored(strategy, value):
    found = find(
        strategy,
        lambda v: v == value if not isinstance(value, str) else value in v,
        settings=settings(max_examples=500, database=None, deadline=None, derandomize=True),
    )
    assert found == value


@pytest.mark.parametrize(
    "make, lo, hi",
    [
        (lambda: iec.ints(-3, 7), -3, 7),
        (lambda: iec.usints(min_value=250), 250, 255),
        (lambda: iec.for_type("DINT", max_value=-2147483600), -2147483648, -2147483600),
        (lambda: iec.times("10ms", "T#20ms"), 10_000_000, 20_000_000),
        (lambda: iec.times(max_value=0.5), -9223372036854775808, 500_000_000),
        (lambda: iec.tods("TOD#12:00", None), 12 * 3_600_000_000_000, DAY - 1),
        (lambda: iec.dates("D#2024-01-01", "D#2024-12-31"), 19723 * DAY, 20088 * DAY),
        (lambda: iec.reals(0.1, 0.2), 0.10000000149011612, 0.20000000298023224),  # rounded inwards to float32
        (lambda: iec.lreals(-1.5, 2), -1.5, 2.0),
    ],
)
def test_bounds_are_honoured(make, lo, hi):
    @FAST
    @given(make())
    def check(v):
        assert lo <= v <= hi

    check()


def test_strings_respect_length_and_alphabet():
    @FAST
    @given(iec.strings(3), iec.wstrings(2, min_size=1), iec.strings(alphabet="ab$"), iec.for_type("string(4)"))
    def check(s, w, a, f):
        assert len(s) <= 3 and all(ord(c) < 256 for c in s)
        assert 1 <= len(w) <= 2
        assert set(a) <= {"a", "b", "$"}
        assert len(f) <= 4

    check()


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: iec.ints(min_value=-32769), "min_value=-32769 is outside the range of INT"),
        (lambda: iec.ints(max_value=32768), "max_value=32768 is outside the range of INT"),
        (lambda: iec.sints(5, 4), "greater than"),
        (lambda: iec.usints(min_value=-1), "USINT"),
        (lambda: iec.ulints(max_value=18446744073709551616), "ULINT"),
        (lambda: iec.words(max_value=65536), "WORD"),
        (lambda: iec.ints(min_value=1.5), "must be an integer"),
        (lambda: iec.reals(max_value=3.5e38), "REAL"),
        (lambda: iec.lreals(min_value=-math.inf), "LREAL"),
        (lambda: iec.times(max_value=9223372036854775808), "TIME"),
        (lambda: iec.tods(min_value=-1), "TIME_OF_DAY"),
        (lambda: iec.dates("D#2024-01-02", "D#2024-01-01"), "greater than"),
        (lambda: iec.for_type("STRING[5]", max_size=6), r"max_size=6 exceeds the length of STRING\[5\]"),
        (lambda: iec.strings(alphabet="a\u20ac"), "cannot be stored in a STRING"),
        (lambda: iec.for_type("NOPE"), "unknown elementary type"),
    ],
)
def test_out_of_range_options_raise_value_error(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_subrange_options_must_lie_in_the_subrange(plc):
    small = type_of(plc, "main.sr")
    with pytest.raises(ValueError, match=r"min_value=-6 is outside the range of Small \(-5..5\)"):
        iec.for_type(small, min_value=-6)

    @FAST
    @given(iec.for_type(small), iec.for_type(small, min_value=0), iec.for_variable(plc, "main.sr2"))
    def check(a, b, c):
        assert -5 <= a <= 5 and 0 <= b <= 5 and 10 <= c <= 20
        for path, v in (("main.sr", a), ("main.sr", b), ("main.sr2", c)):
            plc[path] = v
            assert plc[path] == v

    check()


def test_enum_alias_and_ref_round_trip(plc):
    @FAST
    @given(iec.for_variable(plc, "main.col"), iec.for_variable(plc, "main.m"), iec.for_variable(plc, "main.r"))
    def check(col, m, r):
        assert col in ("Red", "Green", "Blue")  # Teal has Green's value: it reads back as Green
        assert type(m) is float and math.isfinite(m)
        assert r is None
        for path, v in (("main.col", col), ("main.m", m), ("main.r", r)):
            plc[path] = v
            assert plc[path] == v

    check()


@pytest.mark.parametrize("path", ["main.arr", "main.grid", "main.p", "main.pts"])
def test_aggregates_round_trip(plc, path):
    t = type_of(plc, path)

    @FAST
    @given(iec.for_variable(plc, path))
    def check(v):
        if path == "main.arr":
            assert len(v) == 4 and all(-32768 <= x <= 32767 for x in v)
        elif path == "main.grid":
            assert len(v) == 2 and all(len(row) == 3 and set(row) <= {"Red", "Green", "Blue"} for row in v)
        elif path == "main.p":
            assert list(v) == ["x", "y", "tag", "c"] and len(v["tag"]) <= 4
        else:
            assert len(v) == 2 and all(list(p) == ["x", "y", "tag", "c"] for p in v)
        assign(plc, path, t, v)
        assert plc[path] == v

    check()


def test_aggregate_options_reach_elements_and_fields(plc):
    @FAST
    @given(
        iec.for_variable(plc, "main.arr", min_value=0, max_value=9),
        iec.for_variable(plc, "main.p", x=st.just(1.5), TAG=st.just("ok")),
    )
    def check(arr, p):
        assert all(0 <= x <= 9 for x in arr)
        assert p["x"] == 1.5 and p["tag"] == "ok" and -2147483648 <= p["y"] <= 2147483647

    check()
    with pytest.raises(ValueError, match="Point has no field 'z'"):
        iec.for_variable(plc, "main.p", z=st.just(1))


def test_non_value_types_are_rejected(plc):
    with pytest.raises(TypeError, match="not a value type"):
        iec.for_variable(plc, "main")
    with pytest.raises(KeyError):
        iec.for_variable(plc, "main.nope")


COUNTER = """
PROGRAM main
VAR_INPUT cu : BOOL; r : BOOL; pv : INT; END_VAR
VAR_OUTPUT cv : INT; q : BOOL; END_VAR
VAR c : CTU; END_VAR
c(CU := cu, R := r, PV := pv);
cv := c.CV;
q := c.Q;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def counter():
    return PLC.from_source(COUNTER, use_cache=False).compiled


def test_ctu_never_counts_past_pv(counter):
    pulses = st.lists(st.tuples(iec.bools(), st.integers(0, 9).map(lambda n: n == 0)), max_size=80)

    @FAST
    @given(pv=iec.ints(min_value=0, max_value=30), steps=pulses)
    def check(pv, steps):
        plc = PLC(counter)
        plc["main.pv"] = pv
        cv, prev = 0, False  # a model of CTU: count rising edges of CU up to PV, R resets
        for cu, reset in steps:
            plc["main.cu"], plc["main.r"] = cu, reset
            plc.scan()
            if reset:
                cv = 0
            elif cu and not prev and cv < pv:
                cv += 1
            prev = cu
            assert plc["main.cv"] <= pv
            assert (plc["main.cv"], plc["main.q"]) == (cv, cv >= pv)

    check()
