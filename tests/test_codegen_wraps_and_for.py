"""Generated code: wraps of conversion arguments, a FOR's bounds evaluated once, and an interval
analysis that does not trust what a POINTER can break (both tiers run this code)."""

from __future__ import annotations

import pytest

from helpers import fault, program, run

# ------------------------------------------------------------------ conversions


def test_a_conversions_argument_wraps_to_its_source_type_first():
    """The rule: integer arithmetic is exact and only a store wraps (docs/semantics.md); a
    conversion X_TO_Y (and TO_Y) converts a value of type X, so its argument is stored in an X
    first, as a user FUNCTION's input is (and as MatIEC's typed conversion functions take it):
    `USINT_TO_DWORD(u - w)` with u = 2, w = 5 is USINT_TO_DWORD(253) = 253, while `dw := u - w`
    stores the exact -3 into the DWORD: 4294967293 (what MatIEC's C computes). The standard
    functions' other arguments stay exact, as operands (tests/fixtures/run/operators/
    ranges_div_min_max_limit.st: LIMIT(-100, s + s, 100) = 100 for the SINT s = 100)."""
    plc = run(
        program(
            """
dw := USINT_TO_DWORD(u - w);
direct := u - w;
generic := TO_DWORD(u - w);
plus1 := USINT_TO_DINT(u - w) + 1;
i1 := INT_TO_DINT(i + 1);
i2 := INT_TO_DINT(i + 1) - 1;
s1 := SINT_TO_INT(s * 2);
s2 := SINT_TO_LINT(s + s);
ui := UINT_TO_DINT(ui0 - 1);
ud := UINT_TO_UDINT(ui0 - 1) + 1;
b1 := BYTE_TO_WORD(b + 1);
b2 := BYTE_TO_UINT(b + 1) * 10;
w1 := WORD_TO_DWORD(wd + 1);
w2 := WORD_TO_DINT(wd + 1);
d1 := DINT_TO_LINT(d + 1);
r1 := INT_TO_REAL(i + 1);
l1 := INT_TO_LREAL(i + 1);
bo := USINT_TO_BOOL(u + 254);
t1 := INT_TO_TIME(i + 1);
""",
            """u : USINT := 2; w : USINT := 5; dw : DWORD; direct : DWORD; generic : DWORD; plus1 : DINT;
i : INT := 32767; i1 : DINT; i2 : DINT; s : SINT := 100; s1 : INT; s2 : LINT;
ui0 : UINT; ui : DINT; ud : UDINT; b : BYTE := 255; b1 : WORD; b2 : UINT;
wd : WORD := 65535; w1 : DWORD; w2 : DINT; d : DINT := 2147483647; d1 : LINT;
r1 : REAL; l1 : LREAL; bo : BOOL; t1 : TIME;""",
        )
    )
    assert plc["main.dw"] == 253
    assert plc["main.direct"] == 4294967293
    assert plc["main.generic"] == 253
    assert plc["main.plus1"] == 254
    assert plc["main.i1"] == -32768
    assert plc["main.i2"] == -32769
    assert plc["main.s1"] == -56
    assert plc["main.s2"] == -56
    assert plc["main.ui"] == 65535
    assert plc["main.ud"] == 65536
    assert plc["main.b1"] == 0
    assert plc["main.b2"] == 0
    assert plc["main.w1"] == 0
    assert plc["main.w2"] == 0
    assert plc["main.d1"] == -2147483648
    assert plc["main.r1"] == -32768.0
    assert plc["main.l1"] == -32768.0
    assert plc["main.bo"] is False  # 2 + 254 = 256 wraps to the USINT 0
    assert plc["main.t1"] == -32768 * 1_000_000


def test_narrowing_conversions_and_in_range_arguments_stay_as_they_were():
    """A conversion to a type no wider than its source wraps once (to the result), and an
    argument whose interval fits its type is passed as it is: no wrap is added."""
    from st.api import compile_text

    src = program(
        "n := DINT_TO_INT(d + 1); m := INT_TO_WORD(i - 1); k := USINT_TO_DINT(u); j := INT_TO_DINT(u + 1);",
        "d : DINT := 2147483647; n : INT; i : INT := -32768; m : WORD; u : USINT := 7; k : DINT; j : DINT;",
    )
    code = compile_text(src, "t.st", use_cache=False, emit_python=True).python_source["t.st"]
    assert "self.n = (self.d + 1 + 32768 & 65535) - 32768  #" in code
    assert "self.m = self.i - 1 & 65535  #" in code
    assert "self.k = self.u  #" in code
    assert "self.j = self.u + 1  #" in code
    plc = run(src)
    assert (plc["main.n"], plc["main.m"], plc["main.k"], plc["main.j"]) == (0, 32767, 7, 8)


# ------------------------------------------------------------------ FOR: bounds once

_COUNTED = """
FUNCTION f : INT
VAR_INPUT v : INT; END_VAR
VAR_IN_OUT n : INT; END_VAR
n := n + 1; f := v;
END_FUNCTION
"""


@pytest.mark.parametrize(
    "loop, calls, k, i",
    [
        ("FOR i := f(1, ns) TO 3 DO k := k + 1; END_FOR;", (1, 0, 0), 3, 4),
        ("FOR i := 1 TO f(3, ne) DO k := k + 1; END_FOR;", (0, 1, 0), 3, 4),
        ("FOR i := 1 TO 3 BY f(1, nb) DO k := k + 1; END_FOR;", (0, 0, 1), 3, 4),
        ("FOR i := f(1, ns) TO f(3, ne) BY f(2, nb) DO k := k + 1; END_FOR;", (1, 1, 1), 2, 5),
        ("FOR i := f(5, ns) TO f(3, ne) DO k := k + 1; END_FOR;", (1, 1, 0), 0, 5),
        ("FOR i := f(3, ns) TO f(1, ne) BY f(-1, nb) DO k := k + 1; END_FOR;", (1, 1, 1), 3, 0),
        # the body writes the counter: the "while" form
        ("FOR i := f(1, ns) TO f(6, ne) BY f(1, nb) DO i := i + 1; k := k + 1; END_FOR;", (1, 1, 1), 3, 7),
        # a counter that is not a Python local (its address is taken)
        ("p := ADR(i); FOR i := f(1, ns) TO 3 DO k := k + 1; END_FOR;", (1, 0, 0), 3, 4),
    ],
)
def test_a_for_loops_start_end_and_step_are_evaluated_once(loop, calls, k, i):
    plc = run(program(loop, "i : INT; k : INT; ns : INT; ne : INT; nb : INT; p : POINTER TO INT;", _COUNTED), scans=2)
    # two scans: each loop entry evaluates each bound exactly once
    assert (plc["main.ns"], plc["main.ne"], plc["main.nb"]) == tuple(2 * c for c in calls)
    assert (plc["main.k"], plc["main.i"]) == (2 * k, i)


def test_a_for_start_with_a_global_side_effect_runs_once():
    src = """
VAR_GLOBAL calls : DINT; END_VAR
FUNCTION start : INT
VAR_EXTERNAL calls : DINT; END_VAR
calls := calls + 1; start := 0;
END_FUNCTION
PROGRAM main
VAR i : INT; k : INT; END_VAR
FOR i := start() TO 3 DO k := k + 1; END_FOR;
END_PROGRAM
"""
    plc = run(src, scans=3)
    assert (plc["calls"], plc["main.k"], plc["main.i"]) == (3, 12, 4)


# ------------------------------------------------------------------ intervals a POINTER can break


@pytest.mark.parametrize(
    "value, message", [(9, "array index 9 is outside the bounds 1..5"), (0, "array index 0 is outside the bounds 1..5")]
)
def test_a_subrange_written_through_a_pointer_is_still_index_checked(value, message):
    """A POINTER (or REFERENCE, or a byte view) writes a subrange variable without its check, so
    the interval of a subrange variable is its base type's."""
    _, info = fault(
        program(
            f"p := ADR(s); p^ := {value}; x := a[s];",
            "s : INT(1..5) := 1; p : POINTER TO INT; a : ARRAY[1..5] OF INT := [1, 2, 3, 4, 5]; x : INT;",
        )
    )
    assert (info.kind, info.line, info.message) == ("INDEX", 6, message)


def test_a_subrange_written_through_a_reference_is_still_index_checked():
    _, info = fault(
        program(
            "r REF= s; r := 0; x := a[s];",
            "s : INT(1..5) := 1; r : REFERENCE TO INT; a : ARRAY[1..5] OF INT := [1, 2, 3, 4, 5]; x : INT;",
        ),
        dialect="codesys",
    )
    assert (info.kind, info.line, info.message) == ("INDEX", 6, "array index 0 is outside the bounds 1..5")


def test_a_subrange_keeps_any_value_under_codesys_so_its_index_is_checked():
    # codesys keeps a value outside the subrange (no CheckRange): nothing may assume the subrange
    _, info = fault(
        program("s := k; x := a[s];", "k : INT := 0; s : INT(1..5) := 1; a : ARRAY[1..5] OF INT; x : INT;"),
        dialect="codesys",
    )
    assert (info.kind, info.line, info.message) == ("INDEX", 6, "array index 0 is outside the bounds 1..5")


def test_a_for_counter_written_behind_the_loops_back_is_still_index_checked():
    """A FOR counter's interval (start..end) holds only for a counter that is a Python local, which
    nothing but the body's own statements can write; a global one can change in a called function,
    an addressed one through its pointer."""
    src = """
VAR_GLOBAL g : INT; END_VAR
FUNCTION bump : INT
VAR_EXTERNAL g : INT; END_VAR
g := 0; bump := 0;
END_FUNCTION
PROGRAM main
VAR a : ARRAY[1..5] OF INT := [1, 2, 3, 4, 5]; x : INT; END_VAR
FOR g := 1 TO 5 DO x := bump(); x := a[g]; END_FOR;
END_PROGRAM
"""
    _, info = fault(src)
    assert (info.kind, info.line, info.message) == ("INDEX", 9, "array index 0 is outside the bounds 1..5")
    _, info = fault(
        program(
            "p := ADR(i); FOR i := 1 TO 5 DO p^ := 0; x := a[i]; END_FOR;",
            "i : INT; p : POINTER TO INT; a : ARRAY[1..5] OF INT; x : INT;",
        )
    )
    assert (info.kind, info.line, info.message) == ("INDEX", 6, "array index 0 is outside the bounds 1..5")


@pytest.mark.parametrize(
    "loop, k, i",
    [
        ("i := 2; FOR i := i TO 5 DO k := k + 1; END_FOR;", 4, 6),
        ("i := 3; FOR i := 1 TO i DO k := k + 1; END_FOR;", 3, 4),
        ("i := 3; FOR i := 1 TO i + 1 DO k := k + 1; END_FOR;", 4, 5),
        ("i := 3; s := 1; FOR i := 1 TO i BY s DO k := k + 1; END_FOR;", 3, 4),
        ("i := 3; FOR i := 1 TO i DO k := k + 1; i := i + 0; END_FOR;", 3, 4),
        ("i := 3; FOR i := f(1, ns) TO i DO k := k + 1; i := i + 0; END_FOR;", 3, 4),
        ("i := 3; FOR i := f(1, ns) TO i DO k := k + 1; END_FOR;", 3, 4),
    ],
)
def test_a_for_bound_that_reads_the_counter_reads_its_value_before_the_loop(loop, k, i):
    # the loop below makes the counters Python locals (the cheap form this checks)
    plc = run(
        program(
            loop + " FOR j := 1 TO 2 DO m := m + 1; END_FOR;",
            "i : INT; k : INT; s : INT; j : INT; m : INT; ns : INT;",
            _COUNTED,
        )
    )
    assert (plc["main.k"], plc["main.i"]) == (k, i)


def test_a_functions_addressed_or_external_for_counter_is_counted_in_its_own_storage():
    """A FUNCTION's counter whose address is taken lives in a box, an external one is the global:
    the loop counts in that storage (it was counted in a Python local of the same name)."""
    src = """
VAR_GLOBAL gi : INT; END_VAR
FUNCTION g : INT
VAR i : INT; p : POINTER TO INT; END_VAR
VAR_EXTERNAL gi : INT; END_VAR
p := ADR(i);
FOR i := 1 TO 3 DO g := g + p^; END_FOR;
FOR gi := 1 TO 2 DO g := g + gi; END_FOR;
g := g * 100 + i * 10 + gi;
END_FUNCTION
PROGRAM main VAR x : INT; END_VAR x := g(); END_PROGRAM
"""
    plc = run(src)
    assert (plc["main.x"], plc["gi"]) == (943, 3)
