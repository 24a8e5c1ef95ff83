"""Calls: functions (outputs, in-outs, EN/ENO, positional), FB instances, arrays of FBs, actions."""

from __future__ import annotations

from st import PLC

import helpers

run = helpers.run


def test_function_outputs_in_outs_and_positional_arguments():
    plc = run("""
FUNCTION DivMod : BOOL
  VAR_INPUT a : DINT; b : DINT := 7; END_VAR
  VAR_OUTPUT q : DINT; r : DINT; END_VAR
  VAR_IN_OUT calls : INT; END_VAR
  calls := calls + 1;
  IF b = 0 THEN DivMod := FALSE; RETURN; END_IF;
  q := a / b; r := a MOD b; DivMod := TRUE;
END_FUNCTION
PROGRAM main
VAR ok1, ok2, ok3 : BOOL; q1, r1, q2, r2, q3 : DINT; n : INT; arr : ARRAY[1..2] OF DINT; END_VAR
ok1 := DivMod(a := 45, b := 6, q => q1, r => r1, calls := n);
ok2 := DivMod(23, 5, q2, r2, n);
ok3 := DivMod(a := 1, b := 0, q => q3, calls := n);
ok1 := ok1 AND DivMod(a := 50, q => arr[2], calls := n);
END_PROGRAM
""")
    v = plc.variables()
    assert (v["main.q1"], v["main.r1"], v["main.q2"], v["main.r2"], v["main.q3"]) == (7, 3, 4, 3, 0)
    assert (v["main.ok1"], v["main.ok2"], v["main.ok3"], v["main.n"], v["main.arr"]) == (True, True, False, 4, [0, 7])


def test_en_eno():
    plc = run("""
FUNCTION Add1 : INT
  VAR_INPUT x : INT; END_VAR
  Add1 := x + 1;
END_FUNCTION
PROGRAM main
VAR y : INT := 5; z : INT := 5; e1, e2 : BOOL; t : TON; e3 : BOOL := TRUE; m : INT; END_VAR
y := Add1(EN := TRUE, x := 10, ENO => e1);
z := Add1(EN := FALSE, x := 10, ENO => e2);
t(EN := FALSE, IN := TRUE, PT := T#1s, ENO => e3);
m := MAX(EN := TRUE, IN1 := 3, IN2 := 9);
END_PROGRAM
""")
    v = plc.variables()
    assert (v["main.y"], v["main.e1"], v["main.z"], v["main.e2"], v["main.e3"], v["main.m"]) == (
        11,
        True,
        5,
        False,
        False,
        9,
    )
    assert v["main.t"]["IN"] is False


def test_arrays_of_fb_instances_nested_instances_and_struct_results():
    plc = run(
        """
TYPE Pair : STRUCT lo : INT; hi : INT; END_STRUCT; END_TYPE
FUNCTION Order : Pair
  VAR_INPUT a, b : INT; END_VAR
  IF a < b THEN Order.lo := a; Order.hi := b; ELSE Order.lo := b; Order.hi := a; END_IF;
END_FUNCTION
FUNCTION_BLOCK Pulse
  VAR_INPUT trig : BOOL; END_VAR
  VAR_OUTPUT n : INT; END_VAR
  VAR edge : R_TRIG; END_VAR
  edge(CLK := trig);
  IF edge.Q THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
PROGRAM main
VAR p : ARRAY[1..3] OF Pulse; i : INT; k : INT; pr : Pair; total : INT; END_VAR
k := k + 1;
FOR i := 1 TO 3 DO
  p[i](trig := (k MOD i) = 0);
END_FOR;
total := p[1].n + p[2].n * 10 + p[3].n * 100;
pr := Order(9, 4);
END_PROGRAM
""",
        scans=6,
    )
    v = plc.variables()
    # p[1] sees TRUE every scan: one rising edge; p[2] edges at k=2,4,6; p[3] at k=3,6
    assert v["main.total"] == 1 + 3 * 10 + 2 * 100
    assert v["main.pr"] == {"lo": 4, "hi": 9}


def test_actions_and_bit_and_partial_access():
    plc = run("""
PROGRAM main
VAR w : WORD; d : DWORD; i : INT := -1; n : INT; b : BOOL; hb : BYTE; END_VAR
w.15 := TRUE; w.0 := TRUE;
d.%B2 := 16#AB;
i.15 := FALSE;
b := d.%X17;
hb := w.%B1;
bump();
bump();
ACTION bump: n := n + 1; END_ACTION
END_PROGRAM
""")
    v = plc.variables()
    assert (v["main.w"], v["main.d"], v["main.i"], v["main.b"], v["main.hb"], v["main.n"]) == (
        0x8001,
        0xAB0000,
        32767,
        True,
        0x80,
        2,
    )


def test_string_functions_and_truncation():
    plc = run("""
PROGRAM main
VAR s : STRING[10]; t : STRING; n : INT; p : INT; w : WSTRING; END_VAR
s := CONCAT('Hello', ', ', 'world!');
t := INSERT('abcdef', 'XY', 2);
t := CONCAT(t, '|', DELETE('abcdef', 2, 3), '|', LEFT('abcdef', 2), RIGHT('abcdef', 2), MID('abcdef', 3, 2));
n := LEN(s);
p := FIND('abcabc', 'ca');
w := "größe";
END_PROGRAM
""")
    v = plc.variables()
    assert (v["main.s"], v["main.t"], v["main.n"], v["main.p"], v["main.w"]) == (
        "Hello, wor",
        "abXYcdef|abef|abefbcd",
        10,
        3,
        "größe",
    )


def test_split_and_concat_date_time_functions():
    plc = run("""
PROGRAM main
VAR y, mo, d, h, mi, s, ms : INT; y2, mo2, d2 : INT; dt1 : DT; dow : INT; END_VAR
SPLIT_DT(DT#2024-02-29-23:59:58.250, y, mo, d, h, mi, s, ms);
SPLIT_DATE(IN := D#1969-12-31, YEAR => y2, MONTH => mo2, DAY => d2);
dt1 := CONCAT_DT(2000, 1, 2, 3, 4, 5, 6);
dow := DAY_OF_WEEK(D#2026-11-22);
END_PROGRAM
""")
    assert plc.variables() == {
        "main.y": 2024,
        "main.mo": 2,
        "main.d": 29,
        "main.h": 23,
        "main.mi": 59,
        "main.s": 58,
        "main.ms": 250,
        "main.y2": 1969,
        "main.mo2": 12,
        "main.d2": 31,
        "main.dt1": "DT#2000-01-02-03:04:05.006",
        "main.dow": 0,
    }


def test_openplc_editor_ld_export_with_function_form_operators():
    """What the OpenPLC Editor emits for LD/FBD: AND(...), ADD(EN := ..., ENO => ...), GT(...)."""
    from pathlib import Path

    plc = PLC.from_files(str(Path(__file__).parent / "fixtures" / "openplc_ld_export.st"), use_cache=False)
    plc["%IX0.0"] = True
    plc.advance("3s")
    # the motor latches at once; 2 s later the timer enables the counter, which then counts every 20 ms scan
    assert (plc["%QX0.0"], plc["%MW0"], plc["instance0._TMP_GT7_OUT"], plc["instance0._TMP_OR2_OUT"]) == (
        True,
        50,
        True,
        255,
    )
    assert plc["instance0.CTU0.CV"] == 1
