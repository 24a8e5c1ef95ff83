"""The generated code's fast paths (issue 20) keep every semantic: an index check is left out only
where the FOR counter's range proves it in bounds, and DIV/MOD by a constant inline keep IEC's
truncation toward zero and the dividend's sign."""

from __future__ import annotations

import pytest

from st import PLC
from st.api import compile_text

from helpers import fault, run

DIV_MOD = """PROGRAM main
VAR
  x : DINT := -7; y : DINT := 7; q1, q2, m1, m2, m3 : DINT; i : INT; neg, pos : DINT;
END_VAR
q1 := x / 2; q2 := y / 2;
m1 := x MOD 3; m2 := y MOD 3; m3 := x MOD 7;
FOR i := -3 TO 3 DO
  neg := neg * 10 + (i MOD 2) + 5;   (* i negative: the inline form's other branch *)
  pos := pos + i / 2;
END_FOR;
END_PROGRAM
"""


def test_div_and_mod_by_a_constant_truncate_toward_zero_with_the_dividends_sign():
    plc = run(DIV_MOD)
    assert [plc[f"main.{k}"] for k in ("q1", "q2", "m1", "m2", "m3")] == [-3, 3, -1, 1, 0]
    # i = -3..3: i MOD 2 = -1, 0, -1, 0, 1, 0, 1; i / 2 = -1, -1, 0, 0, 0, 1, 1
    assert (plc["main.neg"], plc["main.pos"]) == (4545656, 0)


LOOP_PAST_THE_ARRAY = """PROGRAM main
VAR a : ARRAY[0..9] OF INT; i : INT; END_VAR
FOR i := 0 TO 9 DO
  a[i] := i;            (* in range: no check *)
  a[9 - i] := a[9 - i] + 1;
END_FOR;
FOR i := 0 TO 10 DO
  a[i] := 0;            (* one past the end at i = 10 *)
END_FOR;
END_PROGRAM
"""


def test_an_index_the_counter_range_does_not_prove_is_still_checked():
    src = compile_text(LOOP_PAST_THE_ARRAY, "t.st", use_cache=False, emit_python=True).python_source["t.st"]
    assert "a[i] = i" in src and "a[_ix(i, 0, 9)] = 0" in src
    _plc, info = fault(LOOP_PAST_THE_ARRAY)
    assert (info.kind, info.line) == ("INDEX", 8)


@pytest.mark.parametrize("step", ["1", "2", "-1"])
def test_a_counter_range_follows_the_step(step):
    start, end = ("9", "0") if step == "-1" else ("0", "9")
    src = (
        f"PROGRAM main\nVAR a : ARRAY[0..9] OF INT; i : INT; s : INT; END_VAR\n"
        f"FOR i := {start} TO {end} BY {step} DO a[i] := i; s := s + a[i]; END_FOR;\nEND_PROGRAM\n"
    )
    plc = run(src)
    assert plc["main.s"] == (20 if step == "2" else 45)


def test_real_rounding_is_not_repeated_and_gives_the_same_values():
    src = """PROGRAM main
VAR t : REAL := 0.3; a, b, c : REAL; END_VAR
a := SIN(t) * 2.5 + SQRT(ABS(COS(t)) + 1.0);
b := a + t;
c := ABS(b * t);
END_PROGRAM"""
    code = compile_text(src, "r.st", dialect="openplc", use_cache=False, emit_python=True).python_source["r.st"]
    assert not _rounds_twice(code)
    plc = run(src, dialect="openplc")
    # the single-precision values MatIEC's C computes (each operation rounded to float)
    assert [plc[f"main.{k}"] for k in "abc"] == [2.137134075164795, 2.437134027481079, 0.7311402559280396]


def _rounds_twice(code: str) -> bool:
    """Is there a `_f32(_f32(…))` or `_f32(_abs(_f32(…)))` call in the code?"""
    import ast

    def rounded(n):
        return (
            isinstance(n, ast.Call)
            and isinstance(n.func, ast.Name)
            and (n.func.id == "_f32" or (n.func.id == "_abs" and rounded(n.args[0])))
        )

    return any(
        isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "_f32" and rounded(n.args[0])
        for n in ast.walk(ast.parse(code))
    )


def test_an_integer_operand_of_real_arithmetic_converts_as_before():
    src = """PROGRAM main
VAR t : REAL := 0.5; l : LREAL; i : INT := 3; d : DINT := 16777217; r, q : REAL; k : LREAL; END_VAR
l := 2.0 * i;
k := l - i;
r := t * d;       (* DINT -> REAL rounds to single precision first: 16777216 *)
q := t + i;
END_PROGRAM"""
    code = compile_text(src, "f.st", use_cache=False, emit_python=True).python_source["f.st"]
    assert "_float(self.i)" not in code and "_float(i)" not in code
    plc = run(src)
    assert [plc[f"main.{k}"] for k in ("l", "k", "r", "q")] == [6.0, 3.0, 8388608.0, 3.5]
    assert all(type(plc[f"main.{k}"]) is float for k in ("l", "k", "r", "q"))


def test_two_converted_integers_multiply_as_lreals_not_exactly():
    # (2^32-1)^2 is 18446744065119617025 exactly; LREAL arithmetic rounds it to the nearest double
    src = """PROGRAM main
VAR u : UDINT := 4294967295; p, s : LREAL; r : REAL; i : INT := 3; END_VAR
p := UDINT_TO_LREAL(u) * UDINT_TO_LREAL(u);
s := UDINT_TO_LREAL(u) + UDINT_TO_LREAL(u);
r := INT_TO_REAL(i) * INT_TO_REAL(i);
END_PROGRAM"""
    plc = run(src)
    assert plc["main.p"] == 1.8446744065119617e19 and plc["main.p"] != 18446744065119617025
    assert [plc["main.s"], plc["main.r"]] == [8589934590.0, 9.0]
    assert all(type(plc[f"main.{k}"]) is float for k in ("p", "s", "r"))


STANDARD_BLOCKS = """PROGRAM main
VAR
  n : INT; x, y : BOOL;
  ton1 : TON; tof1 : TOF; tp1 : TP; r1 : R_TRIG; f1 : F_TRIG;
  cu : CTU; cd : CTD; cud : CTUD; sr1 : SR; rs1 : RS;
END_VAR
n := n + 1;
x := (n MOD 7) < 3;
y := (n MOD 5) = 0;
ton1(IN := x, PT := T#20ms);
tof1(IN := x, PT := T#20ms);
tp1(IN := y, PT := T#40ms);
r1(CLK := x);
f1(CLK := x);
cu(CU := r1.Q, R := y AND (n MOD 3 = 0), PV := 4);
cd(CD := f1.Q, LD := n = 1, PV := 5);
cud(CU := r1.Q, CD := y, R := FALSE, LD := n = 1, PV := 3);
sr1(S1 := y, R := x);
rs1(S := y, R1 := x);
END_PROGRAM
"""


def test_standard_blocks_copied_into_their_callers_compute_what_their_calls_compute():
    inlined = compile_text(STANDARD_BLOCKS, "b.st", use_cache=False, emit_python=True)
    called = compile_text(STANDARD_BLOCKS, "b.st", use_cache=False, emit_python=True, coverage=True)
    assert "._body()" not in inlined.python_source["b.st"]  # every call inlined …
    assert called.python_source["b.st"].count("._body()") == 10  # … where coverage keeps the calls
    a, b = PLC(inlined), PLC(called)
    trues = dict.fromkeys(("ton1.Q", "tof1.Q", "tp1.Q", "r1.Q", "f1.Q", "sr1.Q1", "rs1.Q1"), 0)
    peak = dict.fromkeys(("cu.CV", "cd.CV", "cud.CV"), 0)
    for _ in range(60):  # 10 ms scans
        a.scan()
        b.scan()
        assert a.variables(all=True) == b.variables(all=True)  # every variable, the blocks' internals included
        for k in trues:
            trues[k] += bool(a[f"main.{k}"])
        for k in peak:
            peak[k] = max(peak[k], a[f"main.{k}"])
    assert trues == {"ton1.Q": 8, "tof1.Q": 44, "tp1.Q": 45, "r1.Q": 9, "f1.Q": 9, "sr1.Q1": 26, "rs1.Q1": 18}
    assert peak == {"cu.CV": 3, "cd.CV": 5, "cud.CV": 3}


def test_a_block_reached_through_an_in_out_runs_its_own_body():
    src = """FUNCTION_BLOCK Counted EXTENDS R_TRIG
VAR_OUTPUT n : INT; END_VAR
SUPER^();
IF Q THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Driver
VAR_IN_OUT trig : R_TRIG; END_VAR
VAR_INPUT x : BOOL; END_VAR
trig(CLK := x);
END_FUNCTION_BLOCK
PROGRAM main
VAR c : Counted; d : Driver; x : BOOL; plain : R_TRIG; k : INT; END_VAR
x := NOT x;
d(trig := c, x := x);
plain(CLK := x);
IF plain.Q THEN k := k + 1; END_IF;
END_PROGRAM"""
    plc = run(src, scans=4)
    assert (plc["main.c.n"], plc["main.k"]) == (2, 2)  # the derived block's body ran through the in-out
