"""Diagnostics: exact codes and locations, hints, all errors together, never a traceback."""

from __future__ import annotations

import pytest

from st.api import compile_text
from st.diagnostics import CompileError

from helpers import compile_error, diagnostics


def diags(text: str, name: str = "t.st"):
    with pytest.raises(CompileError) as info:
        compile_text(text, name, use_cache=False)
    return info.value


def codes(err: CompileError):
    return [(d.code, d.span.line, d.span.col) for d in err.diagnostics if d.is_error]


def test_undeclared_identifier_has_location_and_suggestion():
    e = diags("PROGRAM p\nVAR counter : INT; END_VAR\ncounter := countr + 1;\nEND_PROGRAM\n")
    assert codes(e) == [("E010", 3, 12)]
    d = e.errors[0]
    assert d.hint == "did you mean 'counter'?"
    text = e.render()
    assert text.splitlines()[0] == "t.st:3:12: error[E010]: undeclared identifier 'countr'"
    assert "    3 | counter := countr + 1;" in text
    assert "|            ^^^^^^" in text


def test_all_errors_of_a_run_are_reported_together():
    e = diags("PROGRAM p\nVAR a : INT; b : BOOL; END_VAR\na := TRUE;\nb := 5;\nc := 1;\nEND_PROGRAM\n")
    assert codes(e) == [("E013", 3, 6), ("E013", 4, 6), ("E010", 5, 1)]


def test_missing_semicolon_is_repaired_and_later_errors_reported():
    e = diags("PROGRAM p\nVAR a : INT; END_VAR\na := 1\na := 2\nb := 3;\nEND_PROGRAM\n")
    got = codes(e)
    assert got[0] == ("E001", 3, 7)
    assert got[1] == ("E001", 4, 7)
    assert e.errors[0].hint == "a ';' is missing at the end of line 3"
    assert ("E010", 5, 1) in got


def test_equals_instead_of_assign_hint():
    e = diags("PROGRAM p\nVAR a : INT; END_VAR\na = 1;\nEND_PROGRAM\n")
    assert codes(e) == [("E001", 3, 3)]
    assert e.errors[0].hint == "use ':=' to assign a value; '=' compares"


def test_else_if_hint():
    src = "PROGRAM p\nVAR a : INT; END_VAR\nIF a > 1 THEN a := 1;\nELSE IF a < 0 THEN a := 2;\nEND_IF;\nEND_PROGRAM\n"
    e = diags(src)
    assert e.errors[0].code == "E001"
    assert e.errors[0].span.line == 6
    assert "ELSIF" in e.errors[0].hint


def test_missing_end_at_end_of_file():
    e = diags("PROGRAM p\nVAR a : INT; END_VAR\na := 1;\n")
    assert e.errors[0].code == "E001"
    assert "END_PROGRAM" in e.errors[0].message


NARROWING = (
    "PROGRAM p\nVAR i : INT; d : DINT; r : REAL; l : LREAL; END_VAR\ni := d;\nr := l;\ni := r;\n"
    "d := i; l := r;\nEND_PROGRAM\n"
)


def test_narrowing_needs_explicit_conversion_in_iec():
    e = compile_error(NARROWING, "iec")
    assert codes(e) == [("E027", 3, 6), ("E027", 4, 6), ("E027", 5, 6)]
    assert e.errors[0].hint == "convert explicitly with DINT_TO_INT(...)"


def test_narrowing_between_numbers_is_a_warning_by_default_but_a_real_never_becomes_an_integer():
    assert codes(diags(NARROWING)) == [("E027", 5, 6)]
    assert [(c, line) for c, line, _ in diagnostics(NARROWING)] == [("W008", 3), ("W008", 4), ("E027", 5)]


def test_literal_out_of_range():
    e = diags("PROGRAM p\nVAR s : SINT := 300; b : BYTE; END_VAR\nb := 256;\nb := 255;\nEND_PROGRAM\n")
    assert codes(e) == [("E021", 2, 17), ("E021", 3, 6)]


def test_writes_to_inputs_and_constants():
    src = (
        "FUNCTION_BLOCK F\nVAR_INPUT i : INT; END_VAR\nVAR CONSTANT k : INT := 3; END_VAR\n"
        "i := 1;\nk := 2;\nEND_FUNCTION_BLOCK\n"
    )
    assert codes(compile_error(src, "iec")) == [("E048", 4, 1), ("E018", 5, 1)]  # inputs are read-only in IEC
    assert codes(diags(src)) == [("E018", 5, 1)]  # MatIEC, CODESYS, TwinCAT: writable


def test_non_bool_conditions():
    src = (
        "PROGRAM p\nVAR i : INT; END_VAR\nIF i THEN i := 1; END_IF;\nWHILE i + 1 DO i := 0; END_WHILE;\n"
        "REPEAT i := 1; UNTIL 5 END_REPEAT;\nEND_PROGRAM\n"
    )
    e = diags(src)
    assert codes(e) == [("E015", 3, 4), ("E015", 4, 7), ("E015", 5, 22)]


def test_wrong_argument_names_and_counts():
    src = (
        "FUNCTION F : INT\nVAR_INPUT a : INT; END_VAR\nF := a;\nEND_FUNCTION\n"
        "PROGRAM p\nVAR x : INT; t : TON; END_VAR\nx := F(b := 1);\nx := F(1, 2);\nt(IN := TRUE, PX := T#1s);\n"
        "x := LIMIT(1, 2);\nEND_PROGRAM\n"
    )
    e = diags(src)
    assert codes(e) == [("E016", 7, 8), ("E017", 8, 11), ("E016", 9, 15), ("E017", 10, 6)]
    assert "parameters: a" in e.errors[0].message


def test_case_label_checks():
    src = (
        "TYPE C : (Red, Green); END_TYPE\nPROGRAM p\nVAR i : INT; c : C; END_VAR\n"
        "CASE i OF 1: i := 0; 1: i := 2; 3..5: i := 1; 4: i := 3; END_CASE;\n"
        "CASE c OF Red: i := 0; 2: i := 1; END_CASE;\nEND_PROGRAM\n"
    )
    e = diags(src)
    assert [c for c, _, _ in codes(e)] == ["E019", "E019", "E019"]
    assert [l for _, l, _ in codes(e)] == [4, 4, 5]


def test_duplicates_and_unknown_types():
    src = "PROGRAM p\nVAR a : INT; a : BOOL; b : Nope; END_VAR\na := 1;\nEND_PROGRAM\n"
    e = diags(src)
    assert codes(e) == [("E011", 2, 14), ("E012", 2, 28)]


def test_exit_outside_loop():
    e = diags("PROGRAM p\nVAR i : INT; END_VAR\nEXIT;\nEND_PROGRAM\n")
    assert codes(e) == [("E024", 3, 1)]


def test_unused_variable_and_truncation_warnings():
    r = compile_text(
        "PROGRAM p\nVAR s : STRING[3]; u : INT; END_VAR\ns := 'abcdef';\nEND_PROGRAM\n", "w.st", use_cache=False
    )
    got = [(d.code, d.span.line, d.span.col) for d in r.diagnostics]
    assert got == [("W002", 2, 20), ("W003", 3, 6)]


def test_pragma_is_accepted_with_a_warning():
    r = compile_text(
        "PROGRAM p\n{attribute 'hide'}\nVAR a : INT; END_VAR\na := 1;\nEND_PROGRAM\n", "w.st", use_cache=False
    )
    assert [(d.code, d.span.line) for d in r.diagnostics] == [("W001", 2)]


def test_unterminated_comment():
    e = diags("PROGRAM p\nVAR a : INT; END_VAR\n(* open\na := 1;\nEND_PROGRAM\n")
    assert codes(e)[0] == ("E002", 3, 1)


def test_bad_literals():
    e = diags("PROGRAM p\nVAR t : TIME; d : DATE; END_VAR\nt := T#5x;\nd := D#2024-13-01;\nEND_PROGRAM\n")
    assert [(c, l) for c, l, _ in codes(e)] == [("E004", 3), ("E004", 4)]


def test_fb_type_called_instead_of_instance():
    e = diags("PROGRAM p\nVAR q : BOOL; END_VAR\nTON(IN := q);\nEND_PROGRAM\n")
    assert codes(e) == [("E020", 3, 1)]
    assert "instance" in e.errors[0].message


def test_output_argument_must_be_a_variable():
    e = diags("PROGRAM p\nVAR t : TON; END_VAR\nt(IN := TRUE, Q => 5);\nEND_PROGRAM\n")
    assert codes(e) == [("E031", 3, 20)]


def test_no_traceback_for_garbage():
    for text in [
        "\x00\x01 PROGRAM",
        "PROGRAM",
        "END_PROGRAM",
        "PROGRAM p VAR x : ARRAY[1..] OF INT; END_VAR END_PROGRAM",
        "FUNCTION_BLOCK",
        "TYPE X : STRUCT END_TYPE",
        "PROGRAM p x := ; END_PROGRAM",
        "'unterminated",
    ]:
        e = diags(text)
        assert e.errors, text
        assert "Traceback" not in e.render()


def test_recursion_and_self_containing_types_are_errors():
    src = (
        "{dialect 'iec'}\n"  # CODESYS, TwinCAT and the default warn of recursion (W013) and run it
        "TYPE S : STRUCT a : INT; s : ARRAY[1..2] OF S; END_STRUCT; END_TYPE\n"
        "FUNCTION_BLOCK FB\nVAR inner : FB; END_VAR\nEND_FUNCTION_BLOCK\n"
        "FUNCTION F : INT\nVAR_INPUT n : INT; END_VAR\nF := G(n);\nEND_FUNCTION\n"
        "FUNCTION G : INT\nVAR_INPUT n : INT; END_VAR\nG := F(n - 1);\nEND_FUNCTION\n"
    )
    e = diags(src)
    assert sorted(codes(e)) == [("E032", 8, 6), ("E032", 12, 6), ("E046", 2, 6), ("E046", 3, 16)]


def test_initial_values_must_be_constants():
    """Under iec (CODESYS, TwinCAT and the default let an initial value name a variable)."""
    e = compile_error("PROGRAM p\nVAR a : INT := 1; b : INT := a; END_VAR\nb := a;\nEND_PROGRAM\n", "iec")
    assert codes(e) == [("E029", 2, 30)]


def test_configuration_errors():
    src = (
        "PROGRAM P\nVAR x : INT; END_VAR\nx := 1;\nEND_PROGRAM\n"
        "CONFIGURATION C\n RESOURCE R ON PLC\n  TASK t(INTERVAL := 10, PRIORITY := 0);\n"
        "  PROGRAM a WITH nope : P;\n  PROGRAM b WITH t : Q;\n END_RESOURCE\n"
        " VAR_CONFIG\n  a.x : INT := 1;\n  c.x : INT := 2;\n END_VAR\nEND_CONFIGURATION\n"
    )
    e = diags(src)
    assert [(c, l) for c, l, _ in codes(e)] == [("E013", 7), ("E028", 8), ("E028", 9), ("E010", 12), ("E010", 13)]


def test_limits_give_diagnostics_not_crashes():
    big = diags("PROGRAM p\nVAR s : ARRAY[1..99999999999] OF BOOL; END_VAR\ns[1] := TRUE;\nEND_PROGRAM\n")
    assert codes(big) == [("E042", 2, 9)]
    loops = "".join("FOR i := 1 TO 1 DO\n" for _ in range(25)) + "x := x + 1;\n" + "END_FOR;\n" * 25
    deep = diags("PROGRAM p\nVAR x : INT; i : INT; END_VAR\n" + loops + "END_PROGRAM\n")
    assert [d.code for d in deep.errors] == ["E041"]


def test_set_reset_with_an_undeclared_operand_is_one_error_not_a_crash():
    e = diags("PROGRAM p\nVAR x : BOOL; END_VAR\nnope S= TRUE;\nx R= gone;\nEND_PROGRAM\n")
    assert codes(e) == [("E010", 3, 1), ("E010", 4, 6)]


def test_transition_condition_with_an_undeclared_name_is_one_error_not_a_crash():
    src = (
        "PROGRAM p\nVAR x : BOOL; END_VAR\nINITIAL_STEP s0: END_STEP\n"
        "TRANSITION FROM s0 TO s1 := nope; END_TRANSITION\nSTEP s1: END_STEP\nEND_PROGRAM\n"
    )
    assert codes(diags(src)) == [("E010", 4, 29)]
