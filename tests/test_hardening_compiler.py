"""Hardening of the compiler: no input crashes it, resource limits are located errors, `st check`
refuses what `st run` could not start, and generated names never collide."""

import keyword
import subprocess
import sys
import tracemalloc

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st_

from st import PLC
from st.api import compile_text
from st.compiler.names import mangle, qualified


def _errors(src: str, name: str = "t.st") -> list:
    r = compile_text(src, name, raise_on_error=False, use_cache=False)
    return [(d.code, d.span.line, d.span.col, d.message) for d in r.diagnostics if d.is_error and d.span.file == name]


def _program(body: str, decls: str = "y : DINT;") -> str:
    return f"PROGRAM main\nVAR {decls} END_VAR\n{body}\nEND_PROGRAM\n"


# ---------------------------------------------------------------------- inputs that crashed it


@pytest.mark.slow
def test_an_unknown_dialect_pragma_is_a_located_error(tmp_path):
    src = "(* a header *)\n  {dialect 'foo'}\n" + _program("y := 1;")
    f = tmp_path / "p.st"
    f.write_text(src)
    r = subprocess.run([sys.executable, "-m", "st.cli", "check", str(f)], capture_output=True, text=True)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr
    assert r.stderr.splitlines()[0] == f"{f}:2:13: error[E045]: unknown dialect 'foo' in a {{dialect}} pragma"
    assert "= hint: the presets are openplc, iec, codesys, twincat" in r.stderr


def test_an_unknown_dialect_pragma_through_the_api_is_a_diagnostic_like_any_other():
    src = "{dialect 'bogus'}\n" + _program("y := 1;")
    assert _errors(src, "p.st") == [("E045", 1, 11, "unknown dialect 'bogus' in a {dialect} pragma")]
    with pytest.raises(Exception) as info:
        compile_text(src, "p.st", use_cache=False)  # raise_on_error=True: the CompileError
    assert type(info.value).__name__ == "CompileError"


def test_a_5000_deep_member_chain_with_a_syntax_error_is_a_syntax_error():
    src = _program("y := a" + ".a" * 5000 + " 1;")
    assert _errors(src) == [
        ("E001", 3, 10008, "syntax error: unexpected '1'; expected '&', '(', '*', '**', '+', '-', '.', '/', …")
    ]


def test_a_date_beyond_any_calendar_is_a_malformed_literal():
    assert _errors(_program("y := DT#99999999999999999999-01-01-00:00:00;", "y : DT;")) == [
        (
            "E004",
            3,
            6,
            "invalid literal 'DT#99999999999999999999-01-01-00:00:00': year 99999999999999999999 is out of range",
        )
    ]


def test_an_integer_literal_of_5000_digits_is_a_malformed_literal():
    assert _errors(_program("y := 16#" + "F" * 5000 + ";", "y : LWORD;")) == [
        (
            "E004",
            3,
            6,
            "invalid literal '16#FFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFF…': 5000 digits: too long for any "
            "integer type (ULINT holds 20 decimal digits)",
        )
    ]
    # a long literal within the limit still gets the ordinary range check, with a short message
    big = "*".join(["16#" + "F" * 120] * 40)
    assert _errors(_program(f"y := {big};", "y : LWORD;")) == [
        ("E021", 3, 6, "a value of 19200 bits does not fit in LWORD (0..18446744073709551615)")
    ]


def test_negating_a_string_in_a_constant_expression_is_a_type_error():
    assert _errors(_program("y := 7 * -'a';")) == [
        ("E014", 3, 6, "operator * cannot combine integer literal and STRING[1]"),
        ("E014", 3, 10, "operator - cannot be applied to STRING[1]"),
    ]


def test_assigning_to_an_enumeration_value_is_an_error_not_an_internal_one():
    # found by the fuzzer (bench/fuzz_programs.py, seed 1, mutant 14122): `CARS_AMBER := CARS_GREEN;`
    src = "TYPE E : (A, B); END_TYPE\n" + _program("A := B;\ne := A;", "e : E;")
    assert _errors(src) == [("E018", 4, 1, "'A' is a value of the enumeration E, not a variable")]


def test_a_statement_before_the_first_case_label_is_a_syntax_error_not_an_internal_one():
    # found by the fuzzer (bench/fuzz_programs.py, seed 1, mutant 1242): a line moved above the labels
    src = _program("CASE y OF\n  y := 2;\n  1: y := 3;\nEND_CASE;")
    assert _errors(src) == [("E001", 4, 3, "a statement in a CASE needs a label before it")]


def test_a_library_block_cannot_be_replaced_by_a_function():
    # found by the fuzzer (bench/fuzz_programs.py, seed 2, mutant 19991): FUNCTION R_TRIG made the
    # standard library's own code (F_TRIG's R_TRIG instance) fail inside the library file
    src = "FUNCTION R_TRIG : REAL\nVAR_INPUT x : REAL; END_VAR\nR_TRIG := x;\nEND_FUNCTION\n" + _program("y := 1;")
    assert _errors(src) == [
        ("E011", 1, 10, "'R_TRIG' is a function block of the standard library; a FUNCTION cannot replace it")
    ]


def test_a_library_block_replaced_by_a_block_is_a_warning_and_the_replacement_runs():
    src = (
        "FUNCTION_BLOCK R_TRIG\nVAR_INPUT CLK : BOOL; END_VAR\nVAR_OUTPUT Q : BOOL; END_VAR\nQ := NOT CLK;\n"
        "END_FUNCTION_BLOCK\n" + _program("t(CLK := FALSE); y := BOOL_TO_DINT(t.Q);", "y : DINT; t : R_TRIG;")
    )
    r = compile_text(src, "t.st", raise_on_error=False, use_cache=False)
    assert [(d.code, d.span.line) for d in r.diagnostics if d.span.file == "t.st"] == [("W004", 1)]
    plc = PLC(r)
    plc.scan()
    assert plc["main.y"] == 1


def test_a_parser_failure_is_an_internal_error_diagnostic_not_an_exception(monkeypatch):
    from st.compiler import driver

    parser, _ = driver._get_parser()

    def broken(src, *options):
        raise KeyError("boom")

    monkeypatch.setattr(parser, "parse", broken)
    assert _errors(_program("y := 1;"), "broken.st") == [
        ("E099", 1, 1, "internal compiler error while parsing: KeyError: 'boom'")
    ]


def test_a_one_megabyte_string_literal_is_lexed_in_linear_memory():
    src = _program("s := '" + "a" * 1_000_000 + "';", "s : STRING;")
    tracemalloc.start()
    try:
        r = compile_text(src, "big.st", raise_on_error=False, use_cache=False)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert [d.code for d in r.diagnostics] == ["W003"]  # truncated to STRING[80]: a warning only
    assert peak < 64 * 2**20, f"{peak / 2**20:.0f} MiB"  # it took 876 MB with a backtracking lexer rule


# ---------------------------------------------------------------------- resource limits


def _struct_chain(n: int) -> str:
    return (
        "TYPE\n"
        + "".join(f"S{i} : STRUCT a : S{i + 1}; END_STRUCT;\n" for i in range(n))
        + f"S{n} : STRUCT a : INT; END_STRUCT;\nEND_TYPE\n"
        + _program(f"v{'.a' * (n + 1)} := v{'.a' * (n + 1)} + 1;", "v : S0;")
    )


def _block_chain(n: int) -> str:
    return (
        "".join(f"FUNCTION_BLOCK F{i}\nVAR f : F{i + 1}; END_VAR\nf();\nEND_FUNCTION_BLOCK\n" for i in range(n))
        + f"FUNCTION_BLOCK F{n}\nVAR x : INT; END_VAR\nx := x + 1;\nEND_FUNCTION_BLOCK\n"
        + _program("f();", "f : F0;")
    )


NESTED = (
    "this declaration's type nests 101 levels deep (structures, arrays and function blocks inside each "
    "other; at most 100)"
)


def test_600_nested_structures_are_refused_where_the_nesting_crosses_the_limit():
    # S500's depth is 101 (S600 is 1): the member of S499 that holds it is where the limit is crossed
    assert _errors(_struct_chain(600)) == [("E041", 501, 15, NESTED)]


def test_a_1000_deep_chain_of_blocks_is_refused_where_the_nesting_crosses_the_limit():
    assert _errors(_block_chain(1000)) == [("E041", 3598, 5, NESTED)]


@pytest.mark.parametrize(
    "make, path", [(_struct_chain, "main.v" + ".a" * 100), (_block_chain, "main.f" + ".f" * 99 + ".x")]
)
def test_the_deepest_nesting_allowed_checks_starts_and_runs(make, path):
    plc = PLC.from_source(make(99), name="deep.st", use_cache=False)
    plc.scan(3)
    assert plc[path] == 3


def test_declarations_holding_too_many_values_are_refused_once_where_they_are_declared():
    src = """TYPE S : STRUCT a : ARRAY[1..10000] OF ARRAY[1..10000] OF BYTE; END_STRUCT; END_TYPE
PROGRAM main
VAR v : ARRAY[1..3] OF S; w : ARRAY[1..20000] OF ARRAY[1..20000] OF INT; ok : ARRAY[1..1000] OF INT; END_VAR
ok[1] := 1;
END_PROGRAM
"""
    assert _errors(src) == [
        ("E042", 1, 17, "this declaration holds 100,000,000 values (at most 50,000,000)"),
        ("E042", 3, 27, "this declaration holds 400,000,000 values (at most 50,000,000)"),
    ]


# ---------------------------------------------------------------------- st check finds what st run refuses


def test_addresses_the_process_image_cannot_hold_are_refused_by_the_checker():
    src = _program(
        "y := TRUE; %QW1024 := 5; %MX0.0 := TRUE;",
        "y AT %QX9000.0 : BOOL; z AT %IW5000 : INT; b AT %QX1.9 : BOOL; w AT %QX1024 : BOOL;",
    )
    assert _errors(src) == [
        ("E004", 2, 5, "%QX9000.0 is outside the process image (1024 entries per table)"),
        ("E004", 2, 28, "%IW5000 is outside the process image (1024 entries per table)"),
        ("E004", 2, 48, "%QX1.9: bit 9 is not 0..7"),
        ("E004", 2, 68, "%QX1024.0 is outside the process image (1024 entries per table)"),
        ("E004", 3, 12, "%QW1024 is outside the process image (1024 entries per table)"),
    ]
    # the last cell of each table is fine
    assert _errors(_program("%QW1023 := 1; %IX1023.7 := TRUE;", "m AT %MD1023 : DINT; q AT %QX1023.7 : BOOL;")) == []


@pytest.mark.parametrize(
    "t",
    ["STRING", "WSTRING[4]", "CHAR", "REFERENCE TO INT", "REF_TO INT", "POINTER TO INT", "ARRAY[0..1] OF INT", "TON"],
)
def test_a_located_variable_must_be_a_value_one_image_cell_holds(t):
    # found by the fuzzer (bench/fuzz_programs.py, seed 1, mutant 15407): `x AT %MW2 : REFERENCE TO INT`
    # checked clean, then crashed the start-up with a TypeError
    src = _program("", f"y : DINT;\n  x AT %MW2 : {t};")
    assert _errors(src) == [
        ("E058", 3, 3, f"'%MW2' is one cell of the process image; it cannot hold a value of type {t}")
    ]


@pytest.mark.parametrize("t, value", [("INT", 0), ("WORD", 0), ("UINT(1..5)", 1), ("E", "A")])
def test_numbers_bit_strings_subranges_and_enumerations_are_located(t, value):
    plc = PLC.from_source(
        "TYPE E : (A, B); END_TYPE\n" + _program("x := x;", f"y : DINT;\n  x AT %MW2 : {t};"), use_cache=False
    )
    plc.scan()
    assert plc["%MW2"] == value  # the initial value (a subrange's starts at its low bound)


def test_a_var_config_address_outside_the_image_is_refused_by_the_checker():
    src = """PROGRAM main
VAR x AT %Q* : INT; END_VAR
x := 1;
END_PROGRAM
CONFIGURATION C
RESOURCE R ON PLC
TASK t(INTERVAL := T#10ms);
PROGRAM p WITH t : main;
END_RESOURCE
VAR_CONFIG p.x AT %QW4096 : INT; END_VAR
END_CONFIGURATION
"""
    errs = _errors(src)
    assert [(c, line, m) for c, line, _, m in errs] == [
        ("E004", 10, "%QW4096 is outside the process image (1024 entries per table)")
    ]


# ---------------------------------------------------------------------- generated names

NAMES = """
FUNCTION_BLOCK A_B
VAR_STAT c : INT; END_VAR
VAR_OUTPUT out : INT; END_VAR
c := c + 1; out := c;
END_FUNCTION_BLOCK
FUNCTION_BLOCK A
VAR_STAT B_c : INT; END_VAR
VAR_OUTPUT out : INT; END_VAR
B_c := B_c + 10; out := B_c;
METHOD a_b : INT
VAR_INST k : INT; END_VAR
k := k + 1; a_b := k;
END_METHOD
METHOD a : INT
VAR_INST b_k : INT; END_VAR
b_k := b_k + 100; a := b_k;
END_METHOD
END_FUNCTION_BLOCK
CONFIGURATION C
VAR_GLOBAL R_y : INT := 7; END_VAR
RESOURCE R ON PLC
VAR_GLOBAL y : INT := 5; END_VAR
TASK t(INTERVAL := T#10ms);
PROGRAM p WITH t : main;
END_RESOURCE
END_CONFIGURATION
PROGRAM main
VAR_EXTERNAL y : INT; R_y : INT; END_VAR
VAR x : A_B; z : A; r1, r2 : INT; d1, d2 : BOOL; END_VAR
x(); z(); r1 := z.a_b(); r2 := z.a();
y := y + 1; R_y := R_y + 2;
%q0.1 := TRUE; d1 := %QX0.1; d2 := %Q0.1;
END_PROGRAM
"""


def test_names_that_used_to_collide_are_separate_variables():
    # FB A_B's static c and FB A's static B_c, the instance variables of methods a_b and a, the
    # configuration's R_y and resource R's y: each its own variable (and no false "declared twice")
    plc = PLC.from_source(NAMES, name="names.st", use_cache=False)
    plc.scan(3)
    assert [plc["p.x.out"], plc["p.z.out"], plc["p.r1"], plc["p.r2"], plc["p.y"], plc["p.R_y"]] == [
        3,
        30,
        3,
        300,
        8,
        13,
    ]
    assert [plc["p.d1"], plc["p.d2"], plc["%QX0.1"]] == [True, True, True]  # one cell, however it is spelled


def test_a_global_declared_twice_in_the_same_scope_is_reported_whatever_its_case():
    src = "VAR_GLOBAL speed : INT; END_VAR\nVAR_GLOBAL SPEED : INT; END_VAR\n" + _program("y := 1;")
    assert _errors(src) == [("E011", 2, 12, "global 'SPEED' is declared twice (first at t.st:1)")]


_ident = st_.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,7}", fullmatch=True)  # ST identifiers


def _unqualify(name: str) -> list:
    """The inverse of `qualified`, read left to right: it exists, so `qualified` is injective."""
    parts, cur, i = [], [], 0
    while i < len(name):
        if name[i] == "_":
            assert name[i + 1] in "01", name
            if name[i + 1] == "0":
                parts.append("".join(cur))
                cur = []
            else:
                cur.append("_")
            i += 2
        else:
            cur.append(name[i])
            i += 1
    return parts + ["".join(cur)]


def _unmangle(name: str) -> str:
    if name.startswith("u_") and name.endswith("0_"):
        return name[1:-2]
    return name[:-1] if name.endswith("_") else name


@pytest.mark.slow
@settings(max_examples=500, deadline=None)
@given(st_.lists(_ident, min_size=1, max_size=4))
def test_qualified_names_are_injective(parts):
    q = qualified(*parts)
    assert _unqualify(q) == parts
    assert ("_g_" + q).isidentifier()


@settings(max_examples=500, deadline=None)
@given(_ident)
def test_mangled_names_are_injective_and_never_reach_python_names(name):
    m = mangle(name)
    assert _unmangle(m) == name
    assert m.isidentifier() and not m.startswith("_") and not keyword.iskeyword(m)


@pytest.mark.parametrize("a, b", [("_x_", "u_x_"), ("_x", "u_x"), ("def", "def_"), ("x_", "x__")])
def test_names_that_look_alike_mangle_apart(a, b):
    assert mangle(a) != mangle(b)
