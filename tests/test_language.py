"""Language corners: lexing, comments, case, literals, name safety, the generated code."""

from __future__ import annotations

import pytest

from st import PLC
from st.api import compile_text
from st.grammar.comments import strip_comments


def run(body: str, decls: str = "", scans: int = 1, extra: str = "", **kw) -> PLC:
    plc = PLC.from_source(f"{extra}\nPROGRAM main\nVAR\n{decls}\nEND_VAR\n{body}\nEND_PROGRAM\n", use_cache=False, **kw)
    plc.scan(scans)
    return plc


def test_comments_nest_and_keep_positions():
    text = "a (* x (* y *) z *) b // c\n/* d\n e */ f { prag } g"
    out, pragmas, errors = strip_comments(text)
    assert out.split() == ["a", "b", "f", "g"]
    assert [out.index(w) for w in "bfg"] == [text.index(" b ") + 1, text.index(" f ") + 1, text.rindex("g")]
    assert out.count("\n") == text.count("\n")
    assert [p.text for p in pragmas] == ["{ prag }"]
    assert errors == []
    assert len(out) == len(text)


def test_comments_nest_so_an_inner_opener_needs_its_own_close():
    out, _, errors = strip_comments("x (* see (*note *) y")
    assert [(e.offset, e.message.split(" (")[0]) for e in errors] == [(2, "unterminated comment '(*'")]


def test_strings_protect_comment_markers():
    out, _, _ = strip_comments("s := '(* not a comment *)'; // real")
    assert out == "s := '(* not a comment *)';        "


def test_openplc_debug_comment_megabytes_long_and_eof_inside_comment_line():
    dbg = "(*DBG:" + "x" * 2_000_000 + "*)"
    src = "PROGRAM main\nVAR a : INT; END_VAR\na := a + 1;\nEND_PROGRAM\n" + dbg + "\n// last line, no newline"
    plc = PLC.from_source(src, use_cache=False)
    plc.scan(2)
    assert plc["main.a"] == 2


def test_keywords_and_identifiers_are_case_insensitive():
    src = "program Main\nvar Counter : int; END_var\nif TRUE then counter := COUNTER + 1; end_if;\nEnd_Program\n"
    plc = PLC.from_source(src, use_cache=False)
    plc.scan(3)
    assert plc["MAIN.counter"] == 3
    assert plc.variables() == {"Main.Counter": 3}


def test_soft_keywords_work_as_identifiers():
    plc = run(
        "step := step + 1; on := NOT on; action := step * 2; from := 1;",
        "step : INT; on : BOOL; action : INT; from : INT;",
        scans=3,
    )
    assert (plc["main.step"], plc["main.on"], plc["main.action"], plc["main.from"]) == (3, True, 6, 1)


def test_python_keywords_and_builtins_as_st_names_are_harmless():
    plc = run(
        "def := 1; len := def + 1; self := len * 2; class := CONCAT('a', 'b'); print := LEN(class);u_x_ := 5; _x := 6;",
        "def : INT; len : INT; self : INT; class : STRING; print : INT; _x : INT; u_x_ : INT;",
    )
    assert [plc[f"main.{n}"] for n in ("def", "len", "self", "class", "print", "_x", "u_x_")] == [
        1,
        2,
        4,
        "ab",
        2,
        6,
        5,
    ]


def test_strings_cannot_inject_code():
    plc = run("s := '__import__($'os$').system($'x$')'; n := LEN(s);", "s : STRING; n : INT;")
    assert plc["main.s"] == "__import__('os').system('x')"
    assert plc["main.n"] == 28


def test_every_literal_form():
    decls = (
        "a : INT; b : DINT; c : BYTE; d : SINT; e : REAL; f : TIME; g : TIME; h : TIME; i : DATE;"
        "j : TOD; k : DT; l : STRING; m : WSTRING; n : BOOL; o : LTIME; p : WORD;"
    )
    body = (
        "a := INT#5; b := 16#FF; c := 2#1010_0101; d := 8#17; e := 1.5E3; f := T#1h2m3s4ms5us6ns;"
        "g := T#1.5s; h := TIME#-5s; i := D#2024-01-31; j := TOD#12:30:15.5; k := DT#2024-01-31-12:30:00;"
        "l := 'text $N $'quote$' $41'; m := \"wide $\"q$\"\"; n := TRUE; o := LTIME#1d; p := WORD#16#ABCD;"
    )
    plc = run(body, decls)
    v = plc.variables()
    assert v == {
        "main.a": 5,
        "main.b": 255,
        "main.c": 165,
        "main.d": 15,
        "main.e": 1500.0,
        "main.f": "T#1h2m3s4ms5us6ns",
        "main.g": "T#1s500ms",
        "main.h": "T#-5s",
        "main.i": "D#2024-01-31",
        "main.j": "TOD#12:30:15.5",
        "main.k": "DT#2024-01-31-12:30:00",
        "main.l": "text \n 'quote' A",
        "main.m": 'wide "q"',
        "main.n": True,
        "main.o": "LTIME#1d",
        "main.p": 43981,
    }


def test_operator_precedence_follows_the_iec_grammar():
    plc = run(
        "a := 2 + 3 * 4; b := 2 ** 3 ** 2; c := -2 ** 2; d := 10 - 4 - 3; x := 1 < 2 = 3 < 4;"
        "y := TRUE OR FALSE AND FALSE; z := TRUE XOR TRUE OR TRUE; e := 7 MOD 4 * 2;",
        "a : INT; b : LREAL; c : LREAL; d : INT; x : BOOL; y : BOOL; z : BOOL; e : INT;",
    )
    assert plc.variables() == {
        "main.a": 14,
        "main.b": 64.0,
        "main.c": 4.0,
        "main.d": 3,
        "main.x": True,
        "main.y": True,
        "main.z": True,
        "main.e": 6,
    }


def test_integer_wraparound_division_and_mod():
    plc = run(
        "i := 32767; i := i + 1; u := 0; u := u - 1; b := 250; b := b + 10; q := -7 / 2; m := -7 MOD 2;"
        "z := 5 MOD 0; d := DINT#2147483647; d := d * 2; l := 16#7FFFFFFFFFFFFFFF; l := l + 1;",
        "i : INT; u : UINT; b : BYTE; q : INT; m : INT; z : INT; d : DINT; l : LINT;",
    )
    assert plc.variables() == {
        "main.i": -32768,
        "main.u": 65535,
        "main.b": 4,
        "main.q": -3,
        "main.m": -1,
        "main.z": 0,
        "main.d": -2,
        "main.l": -9223372036854775808,
    }


def test_real_is_single_precision_and_lreal_double():
    plc = run("r := 0.1; l := 0.1; r2 := r * 3.0; l2 := l * 3.0;", "r : REAL; l : LREAL; r2 : REAL; l2 : LREAL;")
    assert plc["main.r"] == 0.10000000149011612
    assert plc["main.l"] == 0.1
    assert plc["main.r2"] == 0.30000001192092896
    assert plc["main.l2"] == 0.30000000000000004


def test_generated_code_carries_st_lines_and_file():
    r = compile_text(
        "PROGRAM main\nVAR a : INT; END_VAR\na := a + 1;\nEND_PROGRAM\n", "lines.st", use_cache=False, emit_python=True
    )
    ((path, code),) = [(p, c) for p, c in r.modules if p == "lines.st"]
    assert code.co_filename == "lines.st"
    cls = [c for c in code.co_consts if hasattr(c, "co_name") and c.co_name == "_prg_main"][0]
    body = [c for c in cls.co_consts if hasattr(c, "co_name") and c.co_name == "_body"][0]
    lines = {ln for _, _, ln in body.co_lines() if ln}
    assert 3 in lines
    assert "class _prg_main(_FB):" in r.python_source["lines.st"]


def test_compile_cache_round_trip(tmp_path, monkeypatch):
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path))
    src = "PROGRAM main\nVAR a : INT; END_VAR\na := a + 2;\nEND_PROGRAM\n"
    first = compile_text(src, "c.st")
    second = compile_text(src, "c.st")
    assert not first.from_cache and second.from_cache
    plc = PLC(second)
    plc.scan(3)
    assert plc["main.a"] == 6


@pytest.mark.parametrize(
    "stmt,expected",
    [
        ("FOR i := 1 TO 10 DO n := n + 1; END_FOR;", (11, 10)),
        ("FOR i := 10 TO 1 BY -1 DO n := n + 1; END_FOR;", (0, 10)),
        ("FOR i := 5 TO 1 DO n := n + 1; END_FOR;", (5, 0)),
        ("FOR i := 1 TO 10 DO n := n + 1; IF i = 4 THEN EXIT; END_IF; END_FOR;", (4, 4)),
        ("FOR i := 1 TO 10 BY 3 DO n := n + 1; END_FOR;", (13, 4)),
        ("FOR i := 1 TO 6 DO IF i MOD 2 = 0 THEN CONTINUE; END_IF; n := n + 1; END_FOR;", (7, 3)),
        ("FOR i := 1 TO 10 DO i := i + 1; n := n + 1; END_FOR;", (11, 5)),
        ("s := 2; FOR i := 0 TO 6 BY s DO n := n + 1; END_FOR;", (8, 4)),
        ("s := -2; FOR i := 6 TO 0 BY s DO n := n + 1; END_FOR;", (-2, 4)),
    ],
)
def test_for_loop_final_values(stmt, expected):
    plc = run(stmt, "i : INT; n : INT; s : INT;")
    assert (plc["main.i"], plc["main.n"]) == expected


def test_repeat_with_continue_still_tests_the_condition():
    plc = run(
        "REPEAT i := i + 1; IF i < 3 THEN CONTINUE; END_IF; n := n + 1; UNTIL i >= 5 END_REPEAT;", "i : INT; n : INT;"
    )
    assert (plc["main.i"], plc["main.n"]) == (5, 3)


def test_and_or_in_conditions_short_circuit_only_what_cannot_fault_or_act():
    from helpers import fault, run

    src = """PROGRAM main
VAR a : BOOL; b : BOOL := TRUE; i : INT := 7; n : INT; x : ARRAY[0..3] OF INT; END_VAR
IF a AND b OR i > 3 AND NOT a THEN n := n + 1; END_IF;
WHILE i < 10 AND b DO i := i + 1; END_WHILE;
REPEAT i := i - 1; UNTIL i < 5 OR a END_REPEAT;
IF a AND x[i + 6] > 0 THEN n := 100; END_IF;
END_PROGRAM"""
    plc = run(src.replace("x[i + 6]", "x[i - 1]"), scans=2)
    assert (plc["main.n"], plc["main.i"]) == (2, 4)
    # the index is evaluated although a is FALSE: ST's AND evaluates both operands
    _, info = fault(src)
    assert (info.kind, info.line) == ("INDEX", 6)


def test_element_updated_from_itself_is_located_once_and_still_checked():
    from helpers import fault, run

    src = """PROGRAM main
VAR i : INT := 2; j : INT := 1; x : ARRAY[0..3] OF INT := [1, 2, 3, 32767];
  m : ARRAY[1..2, 1..3] OF DINT := [1, 2, 3, 4, 5, 6]; END_VAR
x[i] := x[i] * 10 + x[i - 1];
m[j + 1, i] := m[j + 1, i] * 2 - m[j, i];
x[i + 1] := x[i + 1] + 1;
END_PROGRAM"""
    plc = run(src)
    assert plc["main.x"] == [1, 2, 32, -32768]  # the INT store still wraps
    assert plc["main.m"] == [[1, 2, 3], [4, 8, 6]]
    _, info = fault(src.replace("i : INT := 2", "i : INT := 3"))
    assert (info.kind, info.line) == ("INDEX", 6)
