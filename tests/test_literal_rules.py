"""Literals as IEC 61131-3 writes them (issue 32): a '_' only between digits (E004), and a literal
that its type cannot hold (E021): TIME, LTIME, DATE, DT beyond 64-bit ns, a REAL beyond
±3.4028234663852886E38, an LREAL beyond ±1.7976931348623157E308. docs/semantics.md, "Values and
types", states the rules; test_dialect_rules.py checks that every preset applies them."""

from __future__ import annotations

import pytest

from st import PLC
from st.api import compile_text
from st.diagnostics import CompileError
from st.model.literals import underscore_problem

from helpers import program, run

RULE = "IEC 61131-3 allows a single '_' only between two digits"
DECLS = "i : DINT; r : REAL; l : LREAL; t : TIME; lt : LTIME; d : DATE; ld : LDATE; x : DT; tod1 : TOD;"
TIME_MAX = "T#106751d23h47m16s854ms775us807ns"
TIME_MIN = "T#-106751d23h47m16s854ms775us808ns"
TIME_RANGE = f"{TIME_MIN}..{TIME_MAX}"
REAL_RANGE = "-3.4028234663852886E38..3.4028234663852886E38"
LREAL_RANGE = "-1.7976931348623157E308..1.7976931348623157E308"


def found(src: str, dialect: str | None = None) -> list[tuple[str, int, int, str]]:
    """Every diagnostic of t.st as (code, line, column, message)."""
    result = compile_text(src, "t.st", dialect=dialect, use_cache=False, raise_on_error=False)
    return [(d.code, d.span.line, d.span.col, d.message) for d in result.diagnostics if d.span.file == "t.st"]


def one_statement(stmt: str) -> list[tuple[str, int, int, str]]:
    """The diagnostics of `stmt` as the body (line 6) of a program that declares DECLS."""
    return [d for d in found(program(stmt, DECLS)) if d[0] != "W002"]


# ------------------------------------------------------------------------------------ underscores


@pytest.mark.parametrize(
    "stmt, col, shown, problem",
    [
        ("i := 1__0;", 6, "1__0", "two '_' in a row"),
        ("i := 1_;", 6, "1_", "'_' at its end"),
        ("i := 1_000__000;", 6, "1_000__000", "two '_' in a row"),
        ("i := 16#FF__FF;", 6, "16#FF__FF", "two '_' in a row"),
        ("i := 2#1_;", 6, "2#1_", "'_' at its end"),
        ("i := 8#7__7;", 6, "8#7__7", "two '_' in a row"),
        ("i := 16#FF_;", 6, "16#FF_", "'_' at its end"),
        ("i := DINT#1__0;", 6, "DINT#1__0", "two '_' in a row"),
        ("i := -1__0;", 7, "1__0", "two '_' in a row"),
        ("r := 1_.5;", 6, "1_.5", "'_' before '.'"),
        ("r := 1.5_;", 6, "1.5_", "'_' at its end"),
        ("r := 1.5_E3;", 6, "1.5_E3", "'_' before 'E'"),
        ("r := 1__0.5;", 6, "1__0.5", "two '_' in a row"),
        ("r := REAL#1_.5;", 6, "REAL#1_.5", "'_' before '.'"),
        ("t := T#1__0ms;", 6, "T#1__0ms", "two '_' in a row"),
        ("t := T#1_ms;", 6, "T#1_ms", "'_' before 'ms'"),
        ("t := T#1d__2h;", 6, "T#1d__2h", "two '_' in a row"),
        ("t := T#1d_;", 6, "T#1d_", "'_' at its end"),
        ("t := T#1.5_s;", 6, "T#1.5_s", "'_' before 's'"),
        ("t := T#1_.5s;", 6, "T#1_.5s", "'_' before '.'"),
        ("t := T#1._5s;", 6, "T#1._5s", "'_' after '.'"),
        ("lt := LTIME#-1__0ns;", 7, "LTIME#-1__0ns", "two '_' in a row"),
    ],
)
def test_an_underscore_not_alone_between_digits_is_a_located_e004(stmt, col, shown, problem):
    assert one_statement(stmt) == [("E004", 6, col, f"invalid literal '{shown}': {problem}; {RULE}")]


def test_underscores_in_case_labels_array_bounds_and_repeat_counts_are_checked_too():
    src = program(
        "CASE i OF\n1__0: i := 1;\nEND_CASE;\nb := i.1_;",
        "i : DINT; b : BOOL; a : ARRAY[0..1__0] OF INT; c : ARRAY[0..3] OF INT := [2_(1), 2__(2)];",
    )
    assert [d[:3] for d in found(src) if d[0] != "W002"] == [
        ("E004", 4, 34),  # the array bound
        ("E004", 4, 75),  # the repeat counts 2_(1)
        ("E004", 4, 82),  # and 2__(2)
        ("E004", 7, 1),  # the CASE label
        ("E004", 9, 8),  # the bit number
    ]


def test_underscores_between_digits_are_the_same_number():
    plc = run(
        program(
            "i := 1_000 + 16#FF_FF + 2#1010_1010 + 16#_F + 8#7_7;\n"
            "l := 1_000.000_1;\nt := T#1d_2h + T#1h_30m + T#1_500ms;\nr := REAL#1_0.2_5;",
            DECLS,
        )
    )
    assert plc["main.i"] == 1000 + 0xFFFF + 0b10101010 + 0xF + 0o77
    assert plc["main.l"] == 1000.0001 and plc["main.r"] == 10.25
    assert plc["main.t"] == ((26 * 60 + 90) * 60 + 1.5) * 10**9  # 1d2h + 1h30m + 1.5s in ns


@pytest.mark.parametrize(
    "text, kind, problem",
    [
        ("1_000", {}, None),
        ("16#_FF", {"based": True}, None),  # the 3rd edition: '_' right after '#'
        ("16#__FF", {"based": True}, f"two '_' in a row; {RULE}"),
        ("_1", {}, f"'_' after ''; {RULE}"),
        ("1d_2h", {"duration": True}, None),
        ("1d_2h", {}, f"'_' after 'd'; {RULE}"),
    ],
)
def test_the_underscore_rule_itself(text, kind, problem):
    assert underscore_problem(text, **kind) == problem


# ------------------------------------------------------------------------------------ times and dates


def test_the_largest_and_smallest_time_fit_and_convert_without_wrapping():
    plc = run(
        program(
            f"t := {TIME_MAX}; lt := L{TIME_MAX}; i1 := TIME_TO_LINT(t); i2 := LTIME_TO_LINT(lt);\n"
            f"t2 := {TIME_MIN}; i3 := TIME_TO_LINT(t2); i4 := LTIME_TO_LINT(LTIME#-106751d23h47m16s854ms775us808ns);",
            "t, t2 : TIME; lt : LTIME; i1, i2, i3, i4 : LINT;",
        )
    )
    assert plc["main.t"] == plc["main.lt"] == 2**63 - 1 and plc["main.t2"] == -(2**63)
    assert plc["main.i1"] == (2**63 - 1) // 10**6 and plc["main.i2"] == 2**63 - 1  # ms; ns
    assert plc["main.i3"] == -((2**63) // 10**6) and plc["main.i4"] == -(2**63)  # ms toward 0


@pytest.mark.parametrize(
    "stmt, col, shown, kind",
    [
        ("t := T#9999999999999999999d;", 6, "T#9999999999999999999d", "TIME"),
        ("t := T#106751d23h47m16s854ms775us808ns;", 6, "T#106751d23h47m16s854ms775us808ns", "TIME"),
        ("t := T#-106751d23h47m16s854ms775us809ns;", 6, "T#-106751d23h47m16s854ms775us809ns", "TIME"),
        ("t := TIME#106752d;", 6, "TIME#106752d", "TIME"),
        ("t := T#9223372036.854775808s;", 6, "T#9223372036.854775808s", "TIME"),
        ("lt := LTIME#-106752d;", 7, "LTIME#-106752d", "LTIME"),
    ],
)
def test_a_time_beyond_64_bit_ns_does_not_fit(stmt, col, shown, kind):
    """(A positive LTIME up to 2**64 - 1 ns is one under codesys and twincat: the test below.)"""
    prefix = "LT#" if kind == "LTIME" else "T#"
    rng = TIME_RANGE.replace("T#", prefix)
    assert one_statement(stmt) == [("E021", 6, col, f"{shown} does not fit in {kind} ({rng})")]


def test_the_first_and_last_dates_fit():
    plc = run(
        program(
            "d := D#2262-04-11; d2 := D#1677-09-22; ld := LDATE#2262-04-11;\n"
            "x := DT#2262-04-11-23:47:16.854775807; x2 := DT#1677-09-21-00:12:43.145224192;",
            "d, d2 : DATE; ld : LDATE; x, x2 : DT;",
        )
    )
    day = 86400 * 10**9
    assert (plc["main.d"], plc["main.ld"], plc["main.d2"]) == (106751 * day, 106751 * day, -106751 * day)
    assert (plc["main.x"], plc["main.x2"]) == (2**63 - 1, -(2**63))


DATE_RANGE = "D#1677-09-22..D#2262-04-11"
DT_RANGE = "DT#1677-09-21-00:12:43.145224192..DT#2262-04-11-23:47:16.854775807"


@pytest.mark.parametrize(
    "stmt, col, shown, message",
    [
        ("d := D#2262-04-12;", 6, "D#2262-04-12", f"does not fit in DATE ({DATE_RANGE})"),
        ("d := D#1677-09-21;", 6, "D#1677-09-21", f"does not fit in DATE ({DATE_RANGE})"),
        ("d := DATE#9999-12-31;", 6, "DATE#9999-12-31", f"does not fit in DATE ({DATE_RANGE})"),
        ("ld := LDATE#0001-01-01;", 7, "LDATE#0001-01-01", f"does not fit in LDATE ({DATE_RANGE})"),
        (
            "x := DT#2262-04-11-23:47:16.854775808;",
            6,
            "DT#2262-04-11-23:47:16.854775808",
            f"does not fit in DATE_AND_TIME ({DT_RANGE})",
        ),
        (
            "x := DATE_AND_TIME#1677-09-21-00:12:43.145224191;",
            6,
            "DATE_AND_TIME#1677-09-21-00:12:43.145224191",
            f"does not fit in DATE_AND_TIME ({DT_RANGE})",
        ),
    ],
)
def test_a_date_beyond_64_bit_ns_does_not_fit(stmt, col, shown, message):
    assert one_statement(stmt) == [("E021", 6, col, f"{shown} {message}")]


def test_a_time_of_day_out_of_its_day_stays_a_malformed_literal():
    assert one_statement("tod1 := TOD#24:00:00;") == [
        ("E004", 6, 9, "invalid literal 'TOD#24:00:00': time of day out of range '24:00:00'")
    ]


# ------------------------------------------------------------------------------------ REAL and LREAL


def test_the_largest_reals_fit_and_what_only_rounds_is_fine():
    plc = run(
        program(
            "r := 3.4E38; r2 := 3.4028235E38; r3 := -3.4028235E38; r4 := 1E-50; r5 := REAL#3.4028235E38;\n"
            "l := 1.7976931348623157E308; l2 := 1E39; l3 := 1E-400; l4 := -1.7976931348623157E308;",
            "r, r2, r3, r4, r5 : REAL; l, l2, l3, l4 : LREAL;",
        )
    )
    top = 3.4028234663852886e38  # 3.4028235E38 rounds to the largest single
    assert plc["main.r2"] == plc["main.r5"] == top and plc["main.r3"] == -top and plc["main.r4"] == 0.0
    assert plc["main.r"] > 3.39e38
    assert plc["main.l"] == 1.7976931348623157e308 and plc["main.l4"] == -1.7976931348623157e308
    assert (plc["main.l2"], plc["main.l3"]) == (1e39, 0.0)


@pytest.mark.parametrize(
    "decls, stmt, col, shown, real",
    [
        ("r : REAL := 1E39;", "", 13, "1E39", "REAL"),
        ("r : REAL;", "r := 1E39;", 6, "1E39", "REAL"),
        ("r : REAL;", "r := -1E39;", 6, "-1E39", "REAL"),
        ("r : REAL;", "r := 3.4028236E38;", 6, "3.4028236E38", "REAL"),
        ("r : REAL;", "r := r * 1E39;", 10, "1E39", "REAL"),
        ("r : REAL;", "r := 1E39 + r;", 6, "1E39", "REAL"),
        ("r : REAL; b : BOOL;", "b := r < 1E39;", 10, "1E39", "REAL"),
        ("r : REAL;", "r := REAL#1E39;", 6, "REAL#1E39", "REAL"),
        ("r : REAL;", "r := REAL#-3.5E38;", 6, "REAL#-3.5E38", "REAL"),
        (
            "r : REAL;",
            "r := 1000000000000000000000000000000000000000;",
            6,
            "1000000000000000000000000000000000000000",
            "REAL",
        ),
        ("l : LREAL;", "l := 1E309;", 6, "1E309", "LREAL"),
        ("l : LREAL;", "l := -1E309;", 7, "1E309", "LREAL"),
        ("l : LREAL := 2.0E308;", "", 14, "2.0E308", "LREAL"),
        ("l : LREAL;", "l := LREAL#1E309;", 6, "LREAL#1E309", "LREAL"),
        ("r : REAL;", "r := REAL#1E309;", 6, "REAL#1E309", "REAL"),
    ],
)
def test_a_real_number_beyond_its_type_does_not_fit(decls, stmt, col, shown, real):
    line = 4 if not stmt else 6
    rng = REAL_RANGE if real == "REAL" else LREAL_RANGE
    got = [d for d in found(program(stmt, decls)) if d[0] != "W002"]
    assert got == [("E021", line, col, f"{shown} does not fit in {real} ({rng})")]


def test_a_real_parameter_takes_no_number_beyond_real():
    src = "FUNCTION Half : REAL\nVAR_INPUT a : REAL; END_VAR\nHalf := a / 2.0;\nEND_FUNCTION\n" + program(
        "r := Half(1E39); r := Half(a := 3.4E38);", "r : REAL;"
    )
    assert found(src) == [("E021", 10, 11, f"1E39 does not fit in REAL ({REAL_RANGE})")]


def test_ltime_is_unsigned_in_codesys_and_twincat_and_signed_elsewhere():
    """TcUnit's verifier asserts on LTIME#213503d23h34m33s709ms551us615ns (2**64 - 1 ns): CODESYS and
    TwinCAT hold LTIME unsigned; st keeps those 64 bits in its signed LTIME (issue 34)."""
    src = (
        "PROGRAM main\nVAR\n  a : LTIME := LTIME#213503D23H34M33S709MS551US615NS;\n  b : LTIME;\n"
        "  same : BOOL;\nEND_VAR\nb := LT#213503d23h34m33s709ms551us615ns;\nsame := a = b;\nEND_PROGRAM\n"
    )
    for dialect in ("codesys", "twincat", None):
        plc = PLC(compile_text(src, "lt.st", dialect=dialect, use_cache=False))
        plc.scan(1)
        assert plc["main.a"] == -1 and plc["main.b"] == -1 and plc["main.same"] is True
    for dialect in ("iec", "openplc"):
        with pytest.raises(CompileError) as info:
            compile_text(src, "lt.st", dialect=dialect, use_cache=False)
        assert [(d.code, d.span.line, d.span.col) for d in info.value.diagnostics] == [("E021", 3, 16), ("E021", 7, 6)]
    with pytest.raises(CompileError) as info:  # one ns more is no LTIME anywhere
        compile_text(src.replace("615ns", "616ns"), "lt.st", dialect="twincat", use_cache=False)
    assert [(d.code, d.span.line) for d in info.value.diagnostics] == [("E021", 7)]
