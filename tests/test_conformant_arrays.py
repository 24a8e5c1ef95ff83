"""ARRAY[*] parameters (IEC 61131-3 3rd edition): the bounds come from the caller's array,
indexes are checked against them, LOWER_BOUND / UPPER_BOUND read them."""

import pytest

from st import PLC, PLCFaultError
from st.api import compile_text
from st.diagnostics import CompileError

SRC = """
FUNCTION SumAll : DINT
  VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
  VAR i : DINT; END_VAR
  FOR i := LOWER_BOUND(a, 1) TO UPPER_BOUND(a, 1) DO SumAll := SumAll + a[i]; END_FOR
  a[LOWER_BOUND(a, 1)] := 0;
END_FUNCTION
FUNCTION Diagonal : DINT
  VAR_IN_OUT m : ARRAY[*, *] OF DINT; END_VAR
  VAR i : DINT; END_VAR
  FOR i := LOWER_BOUND(m, 1) TO UPPER_BOUND(m, 1) DO
    Diagonal := Diagonal + m[i, i - LOWER_BOUND(m, 1) + LOWER_BOUND(m, 2)];
  END_FOR
  Diagonal := Diagonal + Columns(m) * 1000;      (* passed on to another ARRAY[*] *)
END_FUNCTION
FUNCTION Columns : DINT
  VAR_IN_OUT m : ARRAY[*, *] OF DINT; END_VAR
  Columns := UPPER_BOUND(m, 2) - LOWER_BOUND(m, 2) + 1;
END_FUNCTION
FUNCTION_BLOCK Count
  VAR_IN_OUT data : ARRAY[*] OF INT; END_VAR
  VAR_OUTPUT n : DINT; END_VAR
  n := UPPER_BOUND(data, 1) - LOWER_BOUND(data, 1) + 1;
END_FUNCTION_BLOCK
PROGRAM main
  VAR
    x : ARRAY[2..4] OF INT := [1, 2, 3];
    y : ARRAY[0..1] OF INT := [10, 20];
    m : ARRAY[1..2, 5..6] OF DINT := [1, 2, 3, 4];
    s1, s2, d, lo, hi, cnt : DINT; c : Count;
  END_VAR
  s1 := SumAll(x); s2 := SumAll(y); d := Diagonal(m);
  lo := LOWER_BOUND(x, 1); hi := UPPER_BOUND(m, 2);
  c(data := y); cnt := c.n;
END_PROGRAM
"""


def test_conformant_arrays_index_by_the_callers_bounds():
    plc = PLC(compile_text(SRC, "conf.st"))
    plc.scan()
    assert (plc["main.s1"], plc["main.s2"], plc["main.d"]) == (6, 30, 1 + 4 + 2000)
    assert plc["main.x"] == [0, 2, 3] and plc["main.y"] == [0, 20]  # written through a[lo]
    assert (plc["main.lo"], plc["main.hi"], plc["main.cnt"]) == (2, 6, 2)


def test_an_index_outside_the_callers_bounds_is_an_index_fault():
    plc = PLC(
        compile_text(
            """
FUNCTION Get : INT
  VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
  VAR_INPUT i : DINT; END_VAR
  Get := a[i];
END_FUNCTION
PROGRAM main VAR x : ARRAY[2..4] OF INT := [1, 2, 3]; v : INT; END_VAR
  v := Get(x, 4);
  v := Get(x, 1);
END_PROGRAM
""",
            "conf.st",
        )
    )
    with pytest.raises(PLCFaultError) as e:
        plc.scan()
    assert (e.value.fault.kind, e.value.fault.line) == ("INDEX", 5)
    assert plc["main.v"] == 3


@pytest.mark.parametrize(
    "src, diagnostic",
    [
        (
            "FUNCTION F : INT VAR_INPUT a : ARRAY[*] OF INT; END_VAR F := 1; END_FUNCTION",
            "conf.st:1:32: error[E012]: ARRAY[*] takes its bounds from an argument: it is only allowed for a VAR_IN_OUT",
        ),
        (
            "FUNCTION F : INT VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR F := 1; END_FUNCTION\n"
            "PROGRAM main VAR m : ARRAY[0..1, 0..1] OF INT; r : INT; END_VAR r := F(m); END_PROGRAM",
            "conf.st:2:72: error[E013]: VAR_IN_OUT 'a' is ARRAY[*] OF INT; ARRAY[0..1, 0..1] OF INT cannot be passed",
        ),
        (
            "PROGRAM main VAR x : ARRAY[0..1] OF INT; r : DINT; END_VAR r := UPPER_BOUND(x, 2); END_PROGRAM",
            "conf.st:1:80: error[E029]: the dimension must be a constant from 1 to 1",
        ),
        (
            "PROGRAM main VAR x : INT; r : DINT; END_VAR r := LOWER_BOUND(x, 1); END_PROGRAM",
            "conf.st:1:62: error[E013]: LOWER_BOUND needs an array, not INT",
        ),
    ],
)
def test_conformant_array_errors_are_located(src, diagnostic):
    with pytest.raises(CompileError) as e:
        compile_text(src, "conf.st")
    assert diagnostic in str(e.value)
