"""Every runtime error of the standard functions is a located PLC fault of a named kind, or the
documented IEC/IEEE result (docs/semantics.md, "Errors of the standard functions"): never
Python's own exception text, never a silently wrong value."""

import itertools
import math
import re

import pytest

from st import PLC, PLCFaultError
from st.api import compile_text
from st.model import types as T
from st.stdlib.iec import default_library

NAMED = {"DIV0", "INDEX", "RANGE", "CONVERSION", "OVERFLOW", "NULL"}
PYTHON_TEXT = re.compile(
    r"Error\b|math domain|invalid literal|Exceeds the limit|too large to|unsupported operand|"
    r"NoneType|object|could not convert|int\(\)|float\(\)",
    re.I,
)

INTS = ["SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT"]
BITS = ["BYTE", "WORD", "DWORD", "LWORD"]
REALS = ["REAL", "LREAL"]
GROUPS = {
    "ANY_REAL": REALS,
    "ANY_INT": ["SINT", "DINT", "ULINT"],
    "ANY_BIT": ["BYTE", "LWORD", "BOOL"],
    "ANY_NUM": ["DINT", "LREAL", "UDINT"],
    "ANY_MAGNITUDE": ["DINT", "LREAL", "TIME"],
    "ANY_DATE": ["DATE", "TOD", "DT"],
    "ANY_STRING": ["STRING"],
    "ANY_CHARS": ["STRING"],
    "ANY_ELEMENTARY": ["DINT", "LREAL", "STRING", "TIME"],
    "ANY": ["DINT"],
}
DAY = 86_400 * 10**9


def extremes(t: str) -> list:
    """Values of a type worth trying, as the Python API writes them (times and dates in ns)."""
    if t in INTS or t in BITS:
        b = T.ELEMENTARY[t]
        return sorted({b.lo, b.hi, 0, 1, -1 if b.lo < 0 else 2, 7})
    if t in REALS:
        return [0.0, -1.0, 0.5, 1.0e30, -1.0e30, math.inf, -math.inf, math.nan, 1.0e-40]
    if t == "BOOL":
        return [False, True]
    if t == "STRING":
        return ["", "abc", "-12", "1E400", "9" * 30, "7" * 6000, "  7", "16#FF", "T#5s"]
    if t == "TIME":
        return [0, -(10**9), 2**63 - 1, -(2**63)]
    if t == "DATE":
        return [0, 2932896 * DAY, -DAY]
    if t == "TOD":
        return [0, DAY - 1]
    if t == "DT":
        return [0, 253402300799 * 10**9, -(10**9)]
    return [0]


def _decl(t: str) -> str:
    return "STRING(7000)" if t == "STRING" else t


def _program(cases: list) -> str:
    """One program for many calls: case j is on line 4 + j, over its own variables c<j>_a<i>,
    chosen by `sel` so that each runs alone."""
    decls = " ".join(f"c{j}_a{i} : {_decl(t)};" for j, (_, types) in enumerate(cases) for i, t in enumerate(types))
    branches = "".join(
        f"{j}: {call.format(*[f'c{j}_a{i}' for i in range(len(types))])};\n" for j, (call, types) in enumerate(cases)
    )
    return f"PROGRAM main\nVAR sel : INT; {decls} END_VAR\nCASE sel OF\n{branches}END_CASE;\nEND_PROGRAM\n"


def _sweep(cases: list):
    """Compile the cases together (those a function does not take are dropped: a compile error on
    their line), then run one scan per combination of extreme values (one argument at a time,
    the others at a typical value). Yields (call, types, values, 'ok' or the fault)."""
    compiled = compile_text(_program(cases), "sweep.st", raise_on_error=False, use_cache=False)
    errors = [d for d in compiled.diagnostics if d.is_error]
    assert not [d for d in errors if d.code == "E099"], errors
    if errors:
        refused = {d.span.line - 4 for d in errors}
        cases = [c for j, c in enumerate(cases) if j not in refused]
        compiled = compile_text(_program(cases), "sweep.st", raise_on_error=False, use_cache=False)
        assert not [d for d in compiled.diagnostics if d.is_error], compiled.diagnostics
    plc = PLC(compiled, watchdog="5s")
    for j, (call, types) in enumerate(cases):
        plc["main.sel"] = j
        typical = [extremes(t)[min(3, len(extremes(t)) - 1)] for t in types]
        for i, t in enumerate(types):
            for v in extremes(t):
                vals = list(typical)
                vals[i] = v
                for k, x in enumerate(vals):
                    plc[f"main.c{j}_a{k}"] = x
                try:
                    plc.scan()
                    yield call, types, vals, "ok"
                except PLCFaultError as e:
                    yield call, types, vals, e.fault
                    plc.reset_fault()


def _types_of(constraint: str) -> list[str]:
    """The types a parameter's constraint allows ("ANY_MAGNITUDE or ANY_DATE": either family)."""
    return [t for part in constraint.split(" or ") for t in GROUPS.get(part, [part])]


def _functions():
    """Per standard function, its calls over the type combinations its parameters allow."""
    lib = default_library()
    for name, sig in sorted(lib.functions.items()):
        if name.startswith("__"):
            continue
        calls = []
        for types in itertools.product(*[_types_of(p.constraint) for p in sig.params]):
            if len({t for t, p in zip(types, sig.params) if p.group}) <= 1:
                calls.append((f"{name}({', '.join('{' + str(i) + '}' for i in range(len(types)))})", types))
        yield calls


def _conversions():
    """Per source type, every X_TO_Y conversion from it; then TRUNC, BCD and TO_* forms."""
    for s in INTS + BITS + REALS + ["BOOL", "STRING", "TIME", "DATE", "TOD", "DT"]:
        yield [
            (f"{s}_TO_{d}({{0}})", (s,))
            for d in INTS + BITS + REALS + ["BOOL", "STRING", "TIME", "LTIME", "DATE", "TOD", "DT", "WSTRING", "CHAR"]
            if d != s
        ]
    yield [
        (call + "({0})", (t,))
        for call, t in (
            ("TRUNC", "LREAL"),
            ("LREAL_TRUNC_INT", "LREAL"),
            ("TRUNC_DINT", "REAL"),
            ("BCD_TO_INT", "WORD"),
            ("INT_TO_BCD", "INT"),
            ("WORD_BCD_TO_INT", "WORD"),
            ("INT_TO_BCD_WORD", "INT"),
            ("TO_DINT", "LREAL"),
            ("TO_STRING", "LREAL"),
        )
    ]


GROUPS_OF_CASES = list(_functions()) + list(_conversions())


def _batches(groups: list, size: int = 120):
    """The groups' cases, whole groups together in programs of at most `size` cases (a larger
    group alone): a handful of compiles instead of one per function."""
    batch: list = []
    for cases in groups:
        if batch and len(batch) + len(cases) > size:
            yield batch
            batch = []
        batch = batch + cases
    if batch:
        yield batch


@pytest.mark.slow
@pytest.mark.parametrize("chunk", range(2))
def test_every_standard_function_and_conversion_faults_cleanly_on_extreme_arguments(chunk):
    bad, ran = [], 0
    for cases in _batches(GROUPS_OF_CASES[chunk::2]):
        for call, types, vals, outcome in _sweep(cases):
            ran += 1
            if outcome != "ok" and (
                outcome.kind not in NAMED or PYTHON_TEXT.search(outcome.message) or outcome.file != "sweep.st"
            ):
                bad.append(f"{call} {types} {vals!r:.80}: {outcome}")
    assert not bad, "\n".join(bad[:40])
    assert ran > 2000  # the sweep really ran (each half: thousands of calls)


# ---------------------------------------------------------------------- the cases, exactly


def _run(body: str, decls: str):
    plc = PLC.from_source(f"PROGRAM main\nVAR {decls} END_VAR\n{body}\nEND_PROGRAM\n", name="f.st", use_cache=False)
    plc.scan()
    return plc


def _fault(body: str, decls: str):
    plc = PLC.from_source(f"PROGRAM main\nVAR {decls} END_VAR\n{body}\nEND_PROGRAM\n", name="f.st", use_cache=False)
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    f = info.value.fault
    return f.kind, f.line, f.message


def test_mod_and_division_by_a_literal_on_unsigned_and_bit_string_types():
    plc = _run(
        "r1 := x MOD 7; r2 := y MOD 3; r3 := b / 7; r4 := x MOD 0; r5 := d MOD 16#10;",
        "x : UDINT := 20; y : WORD := 20; b : BYTE := 250; d : DWORD := 16#FF; "
        "r1 : UDINT; r2 : WORD; r3 : BYTE; r4 : UDINT; r5 : DWORD;",
    )
    assert [plc[f"main.r{i}"] for i in range(1, 6)] == [6, 2, 35, 0, 15]


def test_a_negative_shift_count_is_a_range_fault():
    assert _fault("x := SHL(x, n);", "x : DWORD := 5; n : INT := -1;") == (
        "RANGE",
        3,
        "SHL: the shift count -1 is negative",
    )
    assert _fault("x := SHR(x, n);", "x : BYTE := 5; n : DINT := -3;") == (
        "RANGE",
        3,
        "SHR: the shift count -3 is negative",
    )


def test_shifts_past_the_width_give_zero_and_rotations_wrap():
    plc = _run(
        "a := SHL(x, 8); b := SHR(x, 200); c := ROL(x, -1); d := ROR(x, 9);", "x : BYTE := 16#81; a, b, c, d : BYTE;"
    )
    assert [plc["main.a"], plc["main.b"], plc["main.c"], plc["main.d"]] == [0, 0, 0xC0, 0xC0]


def test_trigonometry_of_infinity_is_nan():
    plc = _run(
        "inf := big * 10.0; s := SIN(inf); c := COS(-inf); t := TAN(inf); a := ASIN(2.0); q := SQRT(-1.0);",
        "big : LREAL := 1.0E308; inf, s, c, t, a, q : LREAL;",
    )
    assert plc["main.inf"] == math.inf
    assert all(math.isnan(plc[f"main.{v}"]) for v in "sctaq")


@pytest.mark.parametrize(
    "body, message",
    [
        ("y := LREAL_TO_DINT(r);", "1e+30 is outside the range of DINT (-2147483648..2147483647)"),
        ("y := LREAL_TO_DINT(1.0E30);", "1e+30 is outside the range of DINT (-2147483648..2147483647)"),
        ("w := LREAL_TO_WORD(-r);", "-1e+30 is outside the range of WORD (0..65535)"),
        ("y := TRUNC(r);", "1e+30 is outside the range of DINT (-2147483648..2147483647)"),
        ("y := LREAL_TO_DINT(r - r * 2.0 + r);", "0.0"),  # fine: 0
        (
            "y := LREAL_TO_DINT(r * 1.0E300 - r * 1.0E300);",
            "NaN is outside the range of DINT (-2147483648..2147483647)",
        ),
        ("u := LREAL_TO_USINT(255.6);", "255.6 is outside the range of USINT (0..255)"),
    ],
)
def test_a_real_outside_the_integer_range_is_a_conversion_fault(body, message):
    decls = "y : DINT; w : WORD; u : USINT; r : LREAL := 1.0E30;"
    if message == "0.0":
        assert _run(body, decls)["main.y"] == 0
    else:
        assert _fault(body, decls) == ("CONVERSION", 3, message)


def test_conversions_at_the_edge_of_the_range_round_as_iec_says():
    plc = _run(
        "a := LREAL_TO_DINT(2147483647.4); b := LREAL_TO_DINT(-2147483648.4); c := REAL_TO_INT(2.5); "
        "d := REAL_TO_INT(-2.5); e := LREAL_TO_USINT(255.4); f := TRUNC(-2.9);",
        "a, b : DINT; c, d : INT; e : USINT; f : DINT;",
    )
    assert [plc[f"main.{v}"] for v in "abcdef"] == [2147483647, -2147483648, 3, -3, 255, -2]


def test_expt_overflow_keeps_the_sign_ieee_gives():
    plc = _run("a := EXPT(x, 3); b := EXPT(x, 2); c := EXPT(-8.0, 0.5);", "x : LREAL := -1.0E300; a, b, c : LREAL;")
    assert (plc["main.a"], plc["main.b"]) == (-math.inf, math.inf) and math.isnan(plc["main.c"])


def test_real_to_char_converts_the_code_and_faults_outside_it():
    plc = _run("c := LREAL_TO_CHAR(65.0);", "c : CHAR;")
    assert plc["main.c"] == "A"
    assert _fault("c := LREAL_TO_CHAR(300.0);", "c : CHAR;") == (
        "CONVERSION",
        3,
        "300.0 is outside the range of CHAR (0..255)",
    )


def test_a_function_called_as_a_statement_compiles():
    # its result is dropped; its faults still happen
    plc = _run("ADD(a, b); SHL(w, 1); MUL(a, 2); TRUNC(1.5); NOT(w);", "a, b : DINT := 3; w : BYTE := 1;")
    assert plc.state == "RUN"
    assert _fault("SHL(w, n);", "w : BYTE; n : INT := -2;")[0] == "RANGE"


def test_text_to_number_of_thousands_of_digits_does_not_reach_python_limits():
    plc = _run(
        "s := '1'; FOR k := 1 TO 13 DO s := CONCAT(s, s); END_FOR; r := STRING_TO_LREAL(s); ok := LEN(s) = 8192;",
        "s : STRING(9000); k : INT; r : LREAL; ok : BOOL;",
    )
    assert plc["main.ok"] is True and plc["main.r"] == math.inf
    assert (
        _fault(
            "s := '1'; FOR k := 1 TO 13 DO s := CONCAT(s, s); END_FOR; y := STRING_TO_DINT(s);",
            "s : STRING(9000); k : INT; y : DINT;",
        )[0]
        == "CONVERSION"
    )
