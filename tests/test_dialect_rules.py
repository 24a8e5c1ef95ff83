"""Rules that differ between the dialect presets, each checked in every preset it belongs to
(issue 18: real code accepted as the compiler it was written for accepts it)."""

from __future__ import annotations

import struct

import pytest

from st import PLC
from st.api import compile_text

from helpers import diagnostics, errors, fault, run

WRITES_OWN_INPUT = """
FUNCTION_BLOCK Cnt
VAR_INPUT n : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
n := n + 1;
q := n;
END_FUNCTION_BLOCK
PROGRAM main
VAR c : Cnt; a, b : INT; END_VAR
c(n := 10);
a := c.q;
c();
b := c.q;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "openplc", "codesys", "twincat"])
def test_a_block_may_write_its_own_input_and_keeps_it_until_a_call_sets_it(dialect):
    plc = run(WRITES_OWN_INPUT, 2, dialect)
    # each scan: the call with n := 10 counts to 11; the call without n counts on from there
    assert (plc["main.a"], plc["main.b"], plc["main.c.n"]) == (11, 12, 12)


def test_iec_keeps_inputs_read_only_inside_their_block():
    assert "t.st:5:1: error[E048]: 'n' is an input of Cnt and cannot be written here" in errors(WRITES_OWN_INPUT, "iec")


BITS_AND_NUMBERS = """
PROGRAM main
VAR
  b : BYTE := 200; w : WORD := 16#FFFF; dw : DWORD := 16#FFFFFFFF; n : INT := -2;
  i : INT; u : UINT; d : DINT; l : LINT; r : REAL; lr : LREAL; w2 : WORD; x : BOOL; m : INT;
END_VAR
i := b;                 (* 200: every BYTE fits an INT *)
u := w;                 (* 65535 *)
d := w;
l := dw;                (* 4294967295 *)
r := w;                 (* 65535.0: exact in a REAL *)
lr := dw;
w2 := n;                (* the bit pattern of -2: 16#FFFE *)
d := n + b;             (* INT + BYTE is an INT: 198 *)
l := n * w;             (* INT * WORD: a DINT, -131070 *)
x := b > n;
m := b MOD 7;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_bit_strings_and_numbers_convert_implicitly_where_the_value_is_kept(dialect):
    plc = run(BITS_AND_NUMBERS, 1, dialect)
    got = {k: plc[f"main.{k}"] for k in ("i", "u", "d", "l", "r", "lr", "w2", "x", "m")}
    assert got == {
        "i": 200,
        "u": 65535,
        "d": 198,
        "l": -131070,
        "r": 65535.0,
        "lr": 4294967295.0,
        "w2": 0xFFFE,
        "x": True,
        "m": 4,
    }
    assert isinstance(got["r"], float) and isinstance(got["lr"], float)


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_iec_and_matiec_convert_bit_strings_and_numbers_only_explicitly_and_say_so(dialect):
    text = errors(BITS_AND_NUMBERS, dialect)
    assert (
        "t.st:7:6: error[E027]: BYTE is a bit string and INT a number: IEC 61131-3 converts between them "
        "only explicitly (the codesys and twincat dialects do it implicitly)"
    ) in text
    assert "hint: convert explicitly with BYTE_TO_INT(...)" in text
    assert (
        "t.st:13:7: error[E027]: INT is a number and WORD a bit string: IEC 61131-3 converts between them "
        "only explicitly"
    ) in text
    assert "t.st:14:6: error[E014]: operator + cannot combine INT and BYTE" in text


LOSSY = """
PROGRAM main
VAR
  w : WORD := 65535; d : DINT := 70000; n : INT := -1; lr : LREAL := 1.1; big : LINT := 16#1_0000_0005;
  i : INT; b : BYTE; u : UINT; r : REAL; r2 : REAL; k : DINT;
END_VAR
i := w;
b := d;
u := n;
r := lr;
r2 := d;
k := big;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_conversions_that_may_lose_data_are_warnings_and_wrap_as_codesys_does(dialect):
    result = compile_text(LOSSY, "t.st", dialect=dialect, use_cache=False)
    assert [(d.code, d.span.line, d.message) for d in result.diagnostics if d.span.file == "t.st"] == [
        ("W008", 7, "implicit conversion from WORD to INT may lose data (the value is wrapped to INT)"),
        ("W008", 8, "implicit conversion from DINT to BYTE may lose data (the value is wrapped to BYTE)"),
        ("W008", 9, "implicit conversion from INT to UINT may lose data (the value is wrapped to UINT)"),
        ("W008", 10, "implicit conversion from LREAL to REAL may lose precision"),
        ("W008", 11, "implicit conversion from DINT to REAL may lose precision"),
        ("W008", 12, "implicit conversion from LINT to DINT may lose data (the value is wrapped to DINT)"),
    ]
    plc = PLC(result)
    plc.scan()
    got = {k: plc[f"main.{k}"] for k in ("i", "b", "u", "r", "r2", "k")}
    assert got == {
        "i": -1,
        "b": 70000 % 256,
        "u": 65535,
        "r": struct.unpack("f", struct.pack("f", 1.1))[0],
        "r2": 70000.0,
        "k": 5,
    }


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_iec_and_matiec_refuse_conversions_that_may_lose_data(dialect):
    text = errors(LOSSY, dialect)
    assert "t.st:7:6: error[E027]: implicit conversion from WORD to INT may lose data" in text
    assert "t.st:12:6: error[E027]: implicit conversion from LINT to DINT may lose data" in text


@pytest.mark.parametrize("dialect", [None, "codesys", "iec", "openplc"])
def test_a_real_never_becomes_an_integer_implicitly(dialect):
    src = "PROGRAM main\nVAR r : REAL; k : DINT; END_VAR\nk := r;\nEND_PROGRAM\n"
    assert "t.st:3:6: error[E027]: implicit conversion from REAL to DINT may lose data" in errors(src, dialect)


ZERO_ONE = """
PROGRAM main
VAR RST : BOOL := 0; on : BOOL := 1; a, b, c, d : INT := 7; t : TON; x, y, z : BOOL; END_VAR
b := 9;
c := SEL(0, a, b);
d := SEL(1, a, b);
IF 1 THEN a := 5; END_IF;
WHILE 0 DO a := 1; END_WHILE;
x := 1;
y := RST OR 0;
z := 1 AND on;
t(IN := 1, PT := T#1s);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "iec", "openplc", "codesys", "twincat"])
def test_zero_and_one_are_bool_literals_where_a_bool_is_expected(dialect):
    plc = run(ZERO_ONE, 1, dialect)
    got = {k: plc[f"main.{k}"] for k in ("RST", "on", "a", "c", "d", "x", "y", "z")}
    assert got == {"RST": False, "on": True, "a": 5, "c": 7, "d": 9, "x": True, "y": False, "z": True}
    assert all(type(v) is bool for k, v in got.items() if k in ("RST", "on", "x", "y", "z"))
    assert plc["main.t.IN"] is True


def test_other_integers_are_still_not_bool():
    assert "t.st:1:41: error[E013]: type mismatch: cannot assign integer literal to BOOL" in errors(
        "PROGRAM main VAR x : BOOL; END_VAR x := 2; END_PROGRAM"
    )


@pytest.mark.parametrize("name", ["PID", "RAMP", "TON", "HYSTERESIS"])
def test_a_library_block_nothing_else_in_the_library_uses_may_be_replaced_by_a_function(name):
    src = (
        f"FUNCTION {name} : REAL\nVAR_INPUT x : REAL; END_VAR\n{name} := x * 2.0;\nEND_FUNCTION\n"
        f"PROGRAM main\nVAR y : REAL; END_VAR\ny := {name}(2.5);\nEND_PROGRAM\n"
    )
    result = compile_text(src, "t.st", use_cache=False)
    assert [(d.code, d.span.line) for d in result.diagnostics if d.span.file == "t.st"] == [("W004", 1)]
    plc = PLC(result)
    plc.scan()
    assert plc["main.y"] == 5.0


@pytest.mark.parametrize("name", ["R_TRIG", "INTEGRAL"])
def test_a_library_block_the_library_itself_uses_keeps_its_kind(name):
    src = f"FUNCTION {name} : REAL\nVAR_INPUT x : REAL; END_VAR\n{name} := x;\nEND_FUNCTION\n"
    assert f"t.st:1:10: error[E011]: '{name}' is a function block of the standard library" in errors(src)


OPENPLC_COMMENT = """(* MatIEC: (* is plain text inside a comment *)
PROGRAM main
VAR x : INT; END_VAR
x := x + 1; (* done *)
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "openplc"])
def test_a_comment_ends_at_its_first_close_as_matiec_reads_it(dialect):
    assert run(OPENPLC_COMMENT, 3, dialect)["main.x"] == 3


@pytest.mark.parametrize("dialect", ["iec", "codesys", "twincat"])
def test_comments_nest_in_iec_codesys_and_twincat(dialect):
    assert "t.st:1:1: error[E002]: unterminated comment '(*' (comments nest" in errors(OPENPLC_COMMENT, dialect)


NESTED = """PROGRAM main
VAR x : INT; END_VAR
(* outer (* inner *) still outer *)
x := 2;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "iec", "codesys"])
def test_nested_comments_by_default_and_in_iec_and_codesys(dialect):
    assert run(NESTED, 1, dialect)["main.x"] == 2


def test_under_openplc_an_inner_close_ends_the_comment_and_the_error_says_so():
    text = errors(NESTED, "openplc")
    assert (
        "t.st:3:34: error[E002]: '*)' without a matching '(*' (comments do not nest here: an inner '*)' "
        "ends the whole comment)"
    ) in text


EMBEDDED_C = """PROGRAM main
VAR x : INT; END_VAR
{{
  if (x > 0) { printf("%d", x); }
}}
x := x + 1;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "openplc", "iec", "codesys"])
def test_embedded_c_blocks_are_skipped_with_a_located_warning(dialect):
    result = compile_text(EMBEDDED_C, "t.st", dialect=dialect, use_cache=False)
    assert [(d.code, d.span.line, d.span.col, d.message) for d in result.diagnostics if d.span.file == "t.st"] == [
        ("W009", 3, 1, "embedded C code {{ ... }} is skipped: st does not run it")
    ]
    plc = PLC(result)
    plc.scan(2)
    assert plc["main.x"] == 2


MUX_OUT_OF_RANGE = """PROGRAM main
VAR
  k : INT := 5; i : INT := 9; r : REAL := 1.5; s : STRING := 'x'; b : BOOL := TRUE; ok : INT;
  eno_out, eno_in : BOOL := TRUE;
END_VAR
i := MUX(k, 1, 2, 3);
r := MUX(k, 2.5, 3.5);
s := MUX(k, 'a', 'b');
b := MUX(k, TRUE, TRUE);
ok := MUX(1, 10, 20, 30);
i := MUX(K := k, IN0 := 1, IN1 := 2, ENO => eno_out);
ok := MUX(K := 1, IN0 := 10, IN1 := 20, ENO => eno_in);
END_PROGRAM
"""


def test_a_mux_selector_out_of_range_gives_the_default_value_and_eno_false_under_openplc_as_matiec():
    plc = run(MUX_OUT_OF_RANGE, 1, "openplc")
    assert {k: plc[f"main.{k}"] for k in ("i", "r", "s", "b", "ok", "eno_out", "eno_in")} == {
        "i": 0,
        "r": 0.0,
        "s": "",
        "b": False,
        "ok": 20,
        "eno_out": False,
        "eno_in": True,
    }


@pytest.mark.parametrize("dialect", [None, "iec", "codesys"])
def test_a_mux_selector_out_of_range_is_an_index_fault_elsewhere(dialect):
    _, f = fault(MUX_OUT_OF_RANGE, dialect)
    assert (f.kind, f.line, f.message) == ("INDEX", 6, "MUX selector 5 is outside 0..2")


EDGE_NAMES = """FUNCTION_BLOCK F
VAR_INPUT clk : BOOL R_EDGE; END_VAR
VAR_OUTPUT q : BOOL; END_VAR
q := clk;
END_FUNCTION_BLOCK
PROGRAM main
VAR r_edge, F_Edge : BOOL; f : F; n : INT; END_VAR
r_edge := NOT r_edge;
F_Edge := r_edge;
f(clk := r_edge);
IF f.q THEN n := n + 1; END_IF;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_r_edge_and_f_edge_are_names_in_codesys_and_twincat_and_still_edge_qualifiers(dialect):
    plc = run(EDGE_NAMES, 4, dialect)
    assert (plc["main.r_edge"], plc["main.F_Edge"], plc["main.n"]) == (False, False, 2)  # rising edges: scans 1, 3


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_r_edge_and_f_edge_are_keywords_in_iec_and_matiec(dialect):
    assert "t.st:7:5: error[E001]: 'r_edge' is a reserved keyword and cannot be a name" in errors(EDGE_NAMES, dialect)


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_time_function_is_the_plc_clock(dialect):
    plc = run(
        "PROGRAM main\nVAR t : TIME; END_VAR\nt := TIME();\nEND_PROGRAM\n", 3, dialect
    )  # a lone PROGRAM: a 10 ms task
    assert plc["main.t"] == 20_000_000  # the third scan is released at 20 ms


THIS_DOT = """FUNCTION_BLOCK F
VAR x : INT; END_VAR
METHOD Bump : INT
THIS.x := THIS.x + 1;
Bump := THIS^.x;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR f : F; n : INT; END_VAR
n := f.Bump();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "iec"])
def test_this_dot_member_as_iec_writes_it(dialect):
    plc = run(THIS_DOT, 3, dialect)
    assert (plc["main.f.x"], plc["main.n"]) == (3, 3)


THIS_SUPER_CALLS = """FUNCTION_BLOCK B
VAR x : INT; END_VAR
METHOD Get : INT
Get := x + 100;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK D EXTENDS B
METHOD Get : INT
Get := x + 200;
END_METHOD
METHOD Both : INT
Both := THIS.Get() * 100 + SUPER.Get();
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR d : D; n : DINT; END_VAR
n := d.Both();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "iec"])
def test_this_dot_and_super_dot_method_calls_as_iec_writes_them(dialect):
    plc = run(THIS_SUPER_CALLS, 1, dialect)
    assert plc["main.n"] == 200 * 100 + 100  # THIS.Get() is D's, SUPER.Get() is B's


def test_codesys_wants_this_dereferenced_and_says_how():
    text = errors(THIS_DOT, "codesys")
    assert (
        "t.st:4:1: error[E023]: 'REF_TO F' is not a structure or function block instance, it has no field 'x'" in text
    )
    assert "hint: dereference it first: THIS^.x" in text


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_a_bit_string_negated_wraps_as_an_unsigned_number(dialect):
    src = "PROGRAM main\nVAR b : BYTE := 3; c : BYTE; END_VAR\nc := -b;\nEND_PROGRAM\n"
    result = compile_text(src, "t.st", dialect=dialect, use_cache=False)
    assert [(d.code, d.message) for d in result.diagnostics if d.span.file == "t.st"] == [
        ("W005", "negating an unsigned BYTE wraps around")
    ]
    plc = PLC(result)
    plc.scan()
    assert plc["main.c"] == 253


def test_iec_does_not_negate_a_bit_string():
    src = "PROGRAM main\nVAR b : BYTE := 3; c : BYTE; END_VAR\nc := -b;\nEND_PROGRAM\n"
    assert "t.st:3:6: error[E014]: operator - cannot be applied to BYTE" in errors(src, "iec")


STRING_NAMES = """PROGRAM main
VAR s : STRING := 'hello world'; a, b, c, d, e, f, g : STRING; n, k : INT; END_VAR
n := LEN(STR := s);
a := LEFT(STR := s, SIZE := 5);
b := RIGHT(STR := s, SIZE := 5);
c := MID(STR := s, LEN := 3, POS := 2);
d := CONCAT(STR1 := a, STR2 := b);
k := FIND(STR1 := s, STR2 := 'world');
e := DELETE(STR := s, LEN := 6, POS := 1);
f := INSERT(STR1 := a, STR2 := '!', POS := 5);
g := REPLACE(STR1 := s, STR2 := 'W', L := 1, P := 7);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_twincat_names_of_the_string_functions_parameters(dialect):
    plc = run(STRING_NAMES, 1, dialect)
    got = {k: plc[f"main.{k}"] for k in ("n", "a", "b", "c", "d", "k", "e", "f", "g")}
    assert got == {
        "n": 11,
        "a": "hello",
        "b": "world",
        "c": "ell",
        "d": "helloworld",
        "k": 7,
        "e": "world",
        "f": "hello!",
        "g": "hello World",
    }


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_iec_names_only_in_iec_and_matiec(dialect):
    assert "t.st:3:10: error[E016]: LEN has no parameter 'STR' (parameters: IN)" in errors(STRING_NAMES, dialect)


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_a_property_declaration_may_end_in_a_semicolon_as_twincat_writes_it(dialect):
    src = (
        "FUNCTION_BLOCK F\nVAR x : INT := 4; END_VAR\nEND_FUNCTION_BLOCK\nPROPERTY P : INT;\nGET P := x; END_GET\n"
        "END_PROPERTY\nPROGRAM main\nVAR f : F; n : INT; END_VAR\nn := f.P;\nEND_PROGRAM\n"
    )
    assert run(src, 1, dialect)["main.n"] == 4


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_ref_assign_zero_unbinds_a_reference_as_codesys_does(dialect):
    src = (
        "PROGRAM main\nVAR p : REFERENCE TO INT; x : INT := 5; ok1, ok2 : BOOL; END_VAR\n"
        "p REF= x;\nok1 := __ISVALIDREF(p);\np REF= 0;\nok2 := __ISVALIDREF(p);\nEND_PROGRAM\n"
    )
    plc = run(src, 1, dialect)
    assert (plc["main.ok1"], plc["main.ok2"]) == (True, False)


UNNAMED_LOCATED = """PROGRAM main
VAR
  AT %IX0.1 : BOOL;
  AT %QW2 : INT := 7;
  speed AT %MW3 : INT := 40;
  x : BOOL; w, s : INT;
END_VAR
x := NOT %IX0.1;
w := %QW2 + 1;
%QW2 := w;
s := %MW3 + speed;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "iec", "openplc", "codesys"])
def test_a_direct_address_is_the_variable_declared_at_it_named_or_not(dialect):
    plc = run(UNNAMED_LOCATED, 2, dialect)
    # scan 1: w = 7 + 1, %QW2 := 8; scan 2: w = 9, %QW2 := 9
    assert (plc["main.x"], plc["main.w"], plc["%QW2"], plc["main.s"]) == (True, 9, 9, 80)


@pytest.mark.parametrize("dialect", [None, "codesys", "iec"])
def test_a_constant_of_the_pou_may_be_used_in_a_section_above_its_own(dialect):
    src = (
        "PROGRAM main\nVAR a : ARRAY[1..N] OF INT; s : STRING[LEN_S]; END_VAR\n"
        "VAR CONSTANT N : INT := 3; LEN_S : INT := 2 * N; END_VAR\na[N] := 1;\ns := 'abcdef';\nEND_PROGRAM\n"
    )
    plc = run(src, 1, dialect)
    assert (plc["main.a"], plc["main.s"]) == ([0, 0, 1], "abcdef")


CHAINED = """PROGRAM main
VAR a : INT; b : SINT; d : INT := 300; r1, r2 : REAL; arr : ARRAY[0..3] OF INT; END_VAR
a := b := d;
r1 := r2 := d + 9;
IF TRUE THEN arr[1] := arr[2] := 7; END_IF
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_chained_assignment_gives_each_target_the_value_of_the_one_to_its_right(dialect):
    plc = run(CHAINED, 1, dialect)
    # b := 300 wraps to the SINT 44, and a gets b's value (CODESYS: the assignment's value is its target's)
    assert (plc["main.b"], plc["main.a"], plc["main.r1"], plc["main.r2"]) == (44, 44, 309.0, 309.0)
    assert plc["main.arr"] == [0, 7, 7, 0]


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_chained_assignment_is_a_vendor_extension(dialect):
    assert f"t.st:4:1: error[E044]: chained assignment (a := b := c) is not part of the {dialect} dialect" in errors(
        CHAINED.replace("a := b := d;", "a := d;"), dialect
    )


def test_chained_assignment_checks_each_step_with_the_target_to_its_right():
    src = "PROGRAM main\nVAR i : INT; r : REAL; END_VAR\ni := r := i;\nEND_PROGRAM\n"
    assert "t.st:3:6: error[E027]: implicit conversion from REAL to INT" in errors(src, "codesys")


FB_INIT_ARGS = """
INTERFACE I_Get
METHOD Get : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_A IMPLEMENTS I_Get
VAR v, w : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; n : INT; m : INT; END_VAR
v := n; w := m;
END_METHOD
METHOD Get : INT
Get := v;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_S
VAR o : REFERENCE TO FB_A; seen : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; other : REFERENCE TO FB_A; END_VAR
o REF= other;
seen := other.v;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR
  k : INT := 4; arr : ARRAY[0..2] OF INT := [1, 2, 3];
  a : FB_A(5, 6); fs : FB_S(other := a);
  p : POINTER TO INT := ADR(k); q : REF_TO INT := REF(arr[2]); itf : I_Get := a;
  rr : REFERENCE TO INT := k;
  x, y, z, w : INT;
END_VAR
a.v := a.v + 1;
x := fs.o.v;
y := p^ + q^;
z := itf.Get();
k := 40;
w := rr + fs.seen;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_initial_values_that_name_other_variables_of_the_instance(dialect):
    plc = run(FB_INIT_ARGS, 1, dialect)
    # a : FB_A(5, 6) gives FB_init n = 5, m = 6; fs's FB_init saw a.v = 5 and keeps a reference to a
    assert (plc["main.a.v"], plc["main.a.w"], plc["main.fs.seen"]) == (6, 6, 5)
    # x follows a through the reference; p and q point at k and arr[2]; itf is a; rr is k (40 by then)
    assert (plc["main.x"], plc["main.y"], plc["main.z"], plc["main.w"]) == (6, 7, 6, 45)


def test_initial_values_naming_variables_are_checked():
    src = FB_INIT_ARGS.replace(
        "  x, y, z, w : INT;",
        "  x, y, z, w : INT; i2 : I_Get := b; b : FB_A(1, 2); bad : POINTER TO INT := ADR(arr[k]);\n"
        "  r2 : REFERENCE TO INT := a; c : FB_A(1, 2, 3); d : FB_A(n := 1, 2);",
    )
    out = errors(src, "codesys")
    # CODESYS sets initial values in the order they need (an interface may name an instance
    # declared below it) and evaluates an index there; iec keeps declaration order and constants
    assert "declared below" not in out and "an index in an initial value" not in out
    iec = errors(src, "iec")
    assert "t.st:30:35: error[E029]: 'b' is declared below; initial values are set in declaration order" in iec
    assert "t.st:30:86: error[E029]: an index in an initial value must be a constant; 'k' is a variable" in iec
    assert "t.st:31:28: error[E054]: a REFERENCE TO INT needs a INT variable, not FB_A" in out
    assert "t.st:31:46: error[E017]: FB_init of FB_A takes 2 argument(s) here, not 3" in out
    assert "t.st:31:67: error[E017]: a positional argument cannot follow named ones" in out


def test_a_function_s_initial_value_cannot_name_a_variable():
    """Under iec; CODESYS evaluates a function's locals' initial values at every call
    (test_vendor_bindings.py)."""
    src = "FUNCTION f : INT\nVAR k : INT; p : POINTER TO INT := ADR(k); END_VAR\nf := 1;\nEND_FUNCTION\n"
    assert "t.st:2:40: error[E029]: an initial value must be a constant; 'k' is a variable" in errors(src, "iec")


POINTERS = """PROGRAM main
VAR arr : ARRAY[1..5] OF INT := [1, 2, 3, 4, 5]; p, pEnd : POINTER TO INT; pb : POINTER TO BYTE;
  sum, n : DINT; dw : DWORD; words : ARRAY[0..1] OF WORD := [16#1122, 16#3344]; b0, b3 : BYTE; END_VAR
p := ADR(arr);
pEnd := ADR(arr[5]);
WHILE p <= pEnd DO
  sum := sum + p^;
  p^ := p^ * 10;
  p := p + SIZEOF(p^);
END_WHILE
n := pEnd - ADR(arr);
p := ADR(arr[2]);
p[1] := -7;
pb := ADR(dw);
pb^ := 16#AA; pb[3] := 16#BB;
pb := ADR(words);
b0 := pb^;
pb := pb + 3;
b3 := pb^;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_pointer_arithmetic_and_indexing_within_one_array(dialect):
    plc = run(POINTERS, 1, dialect)
    # the loop walks arr by SIZEOF(INT) bytes up to its last element; pEnd - ADR(arr) is 4 INTs
    assert (plc["main.sum"], plc["main.n"]) == (15, 8)
    # p[1] with p at arr[2] is arr[3]
    assert plc["main.arr"] == [10, 20, -7, 40, 50]
    assert (plc["main.p"], plc["main.pEnd"]) == ("REF(main.arr[2])", "REF(main.arr[5])")


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_a_pointer_to_byte_reads_and_writes_the_bytes_of_another_type(dialect):
    plc = run(POINTERS, 1, dialect)
    # little-endian, as on the PLCs: byte 0 and byte 3 of the DWORD written, of the WORDs read
    assert plc["main.dw"] == 0xBB0000AA
    assert (plc["main.b0"], plc["main.b3"]) == (0x22, 0x33)
    assert plc["main.pb"] == "REF(main.words[0]) + 3 byte(s)"


@pytest.mark.parametrize(
    "body, message",
    [
        ("p := ADR(arr[5]); p := p + 2 * SIZEOF(INT);", "a pointer moved to element 6 of an array of 5"),
        ("p := ADR(arr[1]); p := p - 2;", "a pointer moved to element -1 of an array of 5"),
        ("p := ADR(arr[1]); p := p + 1;", "a pointer to 2-byte elements moved by 1 byte(s), not a whole element"),
        (
            "p := ADR(k); p := p + 2;",
            "a pointer to a single variable moved by 2 byte(s): st moves pointers within one array",
        ),
        ("p := ADR(arr[5]); k := p[1];", "p[1] is past the end of an array of 5"),
        ("pb := ADR(k); pb := pb + 2; b := pb^;", "a pointer read past the 2 byte(s) of the variable it points into"),
        ("k := p[0];", "indexing a NULL pointer"),
    ],
)
def test_a_pointer_leaving_its_array_or_variable_is_a_located_fault(body, message):
    src = (
        "PROGRAM main\nVAR arr : ARRAY[1..5] OF INT; p : POINTER TO INT; pb : POINTER TO BYTE; k : INT; b : BYTE;"
        f" END_VAR\n{body}\nEND_PROGRAM\n"
    )
    _plc, f = fault(src, "codesys")
    assert (f.message, f.line) == (message, 3)


def test_pointer_arithmetic_is_a_vendor_extension():
    src = "PROGRAM main\nVAR p : POINTER TO INT; k : INT; END_VAR\np := ADR(k);\np := p + 2;\nEND_PROGRAM\n"
    out = errors(src, "iec")
    assert "t.st:4:6: error[E044]: pointer arithmetic is not part of the iec dialect" in out


ACCESS = """TYPE INTERNAL E_X : (a, b); END_TYPE
FUNCTION_BLOCK PUBLIC FB_P
VAR _v : INT; END_VAR
PROPERTY PUBLIC P : INT
GET PRIVATE
P := _v;
END_GET
SET
_v := P * 2;
END_SET
END_PROPERTY
METHOD PUBLIC Twice : INT
Twice := THIS^.P;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION INTERNAL F_Y : INT
F_Y := 1;
END_FUNCTION
INTERFACE PUBLIC I_X
END_INTERFACE
PROGRAM PUBLIC main
VAR p : FB_P; n : INT; e : E_X := E_X.b; END_VAR
p.P := 3;
n := p.Twice() + F_Y();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_access_specifiers_on_top_level_pous_types_and_accessors(dialect):
    plc = run(ACCESS, 1, dialect)
    assert (plc["main.n"], plc["main.p._v"]) == (7, 6)


def test_an_accessor_s_own_access_is_checked_for_that_accessor():
    out = errors(ACCESS.replace("n := p.Twice()", "n := p.P"), "codesys")
    # the SET is public (p.P := 3 is fine), the GET private
    assert out.count("error[") == 1
    assert "t.st:24:8: error[E043]: property P of FB_P is PRIVATE: only FB_P itself may use it" in out


def test_a_function_cannot_be_abstract():
    out = errors("FUNCTION ABSTRACT F : INT\nF := 1;\nEND_FUNCTION\n", "codesys")
    assert "t.st:1:19: error[E001]: ABSTRACT is not allowed on a FUNCTION" in out


UNIONS = """TYPE U_Val :
UNION
  dw : DWORD;
  w : ARRAY[0..1] OF WORD;
  b : ARRAY[0..3] OF BYTE;
  r : REAL;
  s : STRING(3);
  x : BOOL;
END_UNION
END_TYPE
TYPE ST_Msg : STRUCT id : INT; v : U_Val; END_STRUCT END_TYPE
PROGRAM main
VAR u, u2 : U_Val; m : ST_Msg; lo, hi : WORD; b0 : BYTE; d, d2, d3 : DWORD; n : DINT; s : STRING; END_VAR
u.dw := 16#12345678;
lo := u.w[0]; hi := u.w[1]; b0 := u.b[0];
u2 := u;
u.r := 1.0;
d := u.dw; d2 := u2.dw;
u.b[3] := 16#41; u.b[2] := 0;
m.v := u;
m.v.w[0] := 16#4443;
d3 := m.v.dw;
s := m.v.s;
n := SIZEOF(U_Val);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_a_union_s_members_share_their_bytes(dialect):
    plc = run(UNIONS, 1, dialect)
    # little-endian, as on the PLCs: the DWORD's low WORD first, its low byte first
    assert (plc["main.lo"], plc["main.hi"], plc["main.b0"]) == (0x5678, 0x1234, 0x78)
    # 1.0 as a REAL is 16#3F800000; u2 is a copy taken before
    assert (plc["main.d"], plc["main.d2"]) == (0x3F800000, 0x12345678)
    # bytes 43 44 00 41: the STRING(3) ends at the NUL
    assert (plc["main.d3"], plc["main.s"], plc["main.n"]) == (0x41004443, "CD", 4)
    assert plc["main.m.v"] == {
        "dw": 0x41004443,
        "w": [0x4443, 0x4100],
        "b": [0x43, 0x44, 0, 0x41],
        "r": 8.0166654586792,  # the REAL whose bits are 16#41004443
        "s": "CD",
        "x": True,
    }


def test_a_union_member_must_have_bytes_and_no_initial_value():
    src = (
        "TYPE ST_A : STRUCT a : INT; END_STRUCT END_TYPE\nTYPE U : UNION\n  s : ST_A;\n  t : TIME;\n  i : INT := 3;\n"
        "END_UNION END_TYPE\nPROGRAM main\nVAR u : U; END_VAR\nu.i := 1;\nEND_PROGRAM\n"
    )
    out = errors(src, "codesys")
    assert (
        "t.st:3:7: error[E012]: a UNION member must be an elementary value or a one-dimensional array of numbers, "
        "not ST_A" in out
    )
    assert "t.st:4:" not in out  # a TIME has bytes (4, in ms)
    assert "t.st:5:14: error[E057]: a UNION member cannot have an initial value (they share their bytes)" in out


TIME_UNION = """TYPE U_Any : UNION
  t : TIME;
  lt : LTIME;
  d : DATE;
  tod : TOD;
  ws : WSTRING(7);
  raw : ARRAY[0..15] OF BYTE;
END_UNION END_TYPE
PROGRAM main
VAR u : U_Any; t : TIME; d : DATE; ms, days : UDINT; lt : LTIME; w : WSTRING; b0, b1 : BYTE; n : DINT; END_VAR
u.t := T#1s500ms;
ms := BYTE_TO_UDINT(u.raw[0]) + BYTE_TO_UDINT(u.raw[1]) * 256;
t := u.t;
u.d := D#1970-01-02;
days := (BYTE_TO_UDINT(u.raw[0]) + BYTE_TO_UDINT(u.raw[1]) * 256 + BYTE_TO_UDINT(u.raw[2]) * 65536) / 86400;
d := u.d;
u.tod := TOD#00:00:02;
t := t + UDINT_TO_TIME(BYTE_TO_UDINT(u.raw[0]) + BYTE_TO_UDINT(u.raw[1]) * 256);
u.lt := LTIME#3us;
lt := u.lt;
u.ws := "Hé";
w := u.ws;
b0 := u.raw[0]; b1 := u.raw[2];
n := SIZEOF(U_Any);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "twincat"])
def test_union_members_of_times_dates_and_wstrings_share_bytes_as_twincat_stores_them(dialect):
    plc = run(TIME_UNION, 1, dialect)
    assert (plc["main.ms"], plc["main.days"], plc["main.d"]) == (1500, 1, 86_400_000_000_000)  # TIME in ms, DATE in s
    assert (plc["main.t"], plc["main.lt"]) == (1_500_000_000 + 2_000_000_000, 3000)  # TOD in ms, LTIME in ns
    assert (plc["main.w"], plc["main.b0"], plc["main.b1"], plc["main.n"]) == ("Hé", ord("H"), 0xE9, 16)  # UTF-16


def test_a_union_is_a_vendor_extension():
    src = "TYPE U : UNION a : INT; b : WORD; END_UNION END_TYPE\nPROGRAM main\nVAR u : U; END_VAR\nu.a := 1;\nEND_PROGRAM\n"
    assert "t.st:1:10: error[E044]: UNION is not part of the iec dialect" in errors(src, "iec")


@pytest.mark.parametrize("dialect", [None, "iec", "openplc", "codesys", "twincat"])
def test_an_instance_s_eno_is_readable_after_its_call(dialect):
    src = (
        "FUNCTION_BLOCK FB_A\nVAR_INPUT x : INT; END_VAR\nIF x > 5 THEN ENO := FALSE; END_IF\nEND_FUNCTION_BLOCK\n"
        "PROGRAM main\nVAR a : FB_A; big, small : BOOL; END_VAR\na(x := 7);\nbig := a.ENO;\na(x := 3);\n"
        "small := a.ENO;\nEND_PROGRAM\n"
    )
    plc = run(src, 1, dialect)
    assert (plc["main.big"], plc["main.small"]) == (False, True)


def test_a_call_skipped_by_en_leaves_the_instance_s_eno_false():
    src = (
        "FUNCTION_BLOCK FB_A\nVAR_INPUT x : INT; END_VAR\nIF x > 5 THEN ENO := FALSE; END_IF\nEND_FUNCTION_BLOCK\n"
        "PROGRAM main\nVAR a : ARRAY[0..1] OF FB_A; i : INT := 1; ran, skipped : BOOL; END_VAR\n"
        "a[i](x := 3);\nran := a[i].ENO;\na[i](EN := FALSE, x := 3);\nskipped := a[i].ENO;\nEND_PROGRAM\n"
    )
    plc = run(src, 1)
    assert (plc["main.ran"], plc["main.skipped"]) == (True, False)


OWN_MC_POWER = """FUNCTION_BLOCK MC_Power
VAR_INPUT Enable : BOOL; END_VAR
VAR_OUTPUT Status : BOOL; n : INT; END_VAR
n := n + 1;
Status := Enable;
END_FUNCTION_BLOCK
PROGRAM main
VAR p : MC_Power; END_VAR
p(Enable := TRUE);
END_PROGRAM
"""


def test_a_project_block_named_like_a_plcopen_block_runs_its_own_body():
    assert diagnostics(OWN_MC_POWER) == [("W004", 1, 16)]
    plc = run(OWN_MC_POWER, 2)
    assert (plc["main.p.n"], plc["main.p.Status"]) == (2, True)  # not st's MC_Power (no axis here)


OWN_MOTION_LIBRARY = """TYPE MC_DIRECTION : (mcPositiveDirection := 1, mcNegativeDirection := -1); END_TYPE
TYPE AXIS_REF : STRUCT pos : LREAL; END_STRUCT END_TYPE
FUNCTION_BLOCK MC_MoveVelocity
VAR_IN_OUT Axis : AXIS_REF; END_VAR
VAR_INPUT Velocity : LREAL; Direction : MC_DIRECTION; END_VAR
IF Direction = mcNegativeDirection THEN
Axis.pos := Axis.pos - Velocity;
ELSE
Axis.pos := Axis.pos + Velocity;
END_IF;
END_FUNCTION_BLOCK
PROGRAM main
VAR ax : AXIS_REF; mv : MC_MoveVelocity; END_VAR
mv(Axis := ax, Velocity := 2.5, Direction := mcNegativeDirection);
END_PROGRAM
"""


def test_a_project_with_its_own_motion_types_leaves_st_plcopen_library_out():
    result = compile_text(OWN_MOTION_LIBRARY, "t.st", use_cache=False)
    assert [(d.code, d.span.line, d.span.col, d.message) for d in result.diagnostics] == [
        (
            "W010",
            1,
            6,
            "the project declares its own MC_DIRECTION and 1 more of its types: st's plcopen library is left out",
        )
    ]
    plc = PLC(result)
    plc.scan(3)
    assert plc["main.ax.pos"] == -7.5


SPECIALS = """PROGRAM main
VAR
  local AT %ML1024 : LINT;
  cycles AT %ML1025 : ULINT;
  utc AT %ML1027 : ULINT;
  exec_us AT %ML1028 : ULINT;
  spare AT %ML1030 : ULINT;
  seen : ULINT;
END_VAR
seen := cycles;
cycles := 0;   (* overwritten before the next scan, as OpenPLC does *)
spare := spare + 2;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
TASK t(INTERVAL := T#250ms, PRIORITY := 0);
PROGRAM inst WITH t : main;
END_RESOURCE END_CONFIGURATION
"""


@pytest.mark.parametrize("dialect", [None, "openplc"])
def test_openplc_special_registers_are_filled_before_each_scan(dialect):
    plc = run(SPECIALS, 9, dialect)  # ticks at 0, 250 ms, ..., 2 s
    assert (plc["inst.seen"], plc["inst.local"], plc["inst.utc"]) == (9, 2, 2)  # virtual time: PLC seconds
    assert (plc["inst.exec_us"], plc["inst.spare"]) == (0, 18)  # no cost on virtual time; %ML1030: memory
    assert plc.image.get("%ML1025") == 0  # the program's own write, published; the next scan overwrites it


def test_special_registers_end_at_ml2047():
    src = "PROGRAM main\nVAR a AT %ML2047 : ULINT; b AT %ML2048 : ULINT; END_VAR\nEND_PROGRAM\n"
    assert diagnostics(src) == [("E004", 2, 27)]  # b


WORD_DOT = """PROGRAM main
VAR
  t1 AT %IW3.0 : UINT;
  copy : UINT;
END_VAR
copy := t1 + %IW3.7;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "openplc"])
def test_openplc_reads_a_word_address_with_a_dot_by_its_first_number(dialect):
    assert diagnostics(WORD_DOT, dialect=dialect) == [("W011", 3, 3), ("W011", 6, 14)]
    plc = PLC(compile_text(WORD_DOT, "t.st", dialect=dialect, use_cache=False))
    plc.image.set("%IW3", 1200)
    plc.scan()
    assert plc["main.copy"] == 2400


@pytest.mark.parametrize("dialect, more", [("iec", [("E014", 6, 9)]), ("codesys", [])])
def test_other_presets_accept_a_word_address_with_a_dot_that_a_run_cannot_place(dialect, more):
    # IEC's hierarchical address, whose place is the I/O configuration's, declared; used directly in
    # code, st's image has no cell for it (tests/test_address_forms.py); iec: UINT + WORD
    assert diagnostics(WORD_DOT, dialect=dialect) == more + [("E004", 6, 14)]


NEW_ARRAY = """PROGRAM main
VAR p, q, z : POINTER TO DINT; n : INT := 4; i : INT; s : DINT; END_VAR
IF p = 0 THEN
  p := __NEW(DINT, n);
  FOR i := 0 TO n - 1 DO p[i] := (i + 1) * 10; END_FOR;
  q := p + 2 * SIZEOF(s);
  z := __NEW(DINT, 0);
END_IF;
s := q^ + p[3];
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_new_with_a_count_makes_that_many_values_behind_one_pointer(dialect):
    plc = run(NEW_ARRAY, 2, dialect)
    assert (plc["main.s"], plc["main.z"]) == (30 + 40, None)  # a count below 1: NULL


def test_new_with_a_count_cannot_move_past_its_values():
    _plc, info = fault(NEW_ARRAY.replace("p[3]", "p[4]"))
    assert (info.kind, info.line) == ("INDEX", 9)


def test_new_of_a_function_block_takes_no_count():
    src = "FUNCTION_BLOCK F\nEND_FUNCTION_BLOCK\nPROGRAM main\nVAR p : POINTER TO F; END_VAR\np := __NEW(F, 2);\nEND_PROGRAM\n"
    assert "t.st:5:15: error[E017]: __NEW of a FUNCTION_BLOCK makes one instance; 'F' takes no count" in errors(src)


SHADOWED_ENUM = """TYPE State : (IDLE, RUNNING, DONE); END_TYPE
FUNCTION_BLOCK Machine
VAR_OUTPUT state : State := State.RUNNING; END_VAR
IF state = State.RUNNING THEN
  state := State.DONE;
END_IF;
END_FUNCTION_BLOCK
PROGRAM main
VAR m : Machine; before : State; END_VAR
before := m.state;
m();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_a_variable_named_like_its_enumeration_type_still_reaches_the_type_values(dialect):
    plc = run(SHADOWED_ENUM, 1, dialect)
    assert (plc["main.before"], plc["main.m.state"]) == ("RUNNING", "DONE")


def test_time_converts_to_and_from_dates_counted_from_1970():
    src = (
        "PROGRAM main\nVAR t : TIME := T#1d2h; dt1 : DT; d : DATE; back : TIME; END_VAR\n"
        "dt1 := TO_DT(t); d := TIME_TO_DATE(t); back := DT_TO_TIME(DT#1970-01-01-00:01:00);\nEND_PROGRAM\n"
    )
    plc = run(src, 1)
    day, hour = 86_400_000_000_000, 3_600_000_000_000
    assert (plc["main.dt1"], plc["main.d"], plc["main.back"]) == (day + 2 * hour, day, 60_000_000_000)


ANY_INPUTS = """FUNCTION_BLOCK FB_Assert
METHOD Same : BOOL
VAR_INPUT Expected : ANY; Actual : ANY; END_VAR
VAR i : DINT; END_VAR
IF Expected.TypeClass <> Actual.TypeClass OR Expected.diSize <> Actual.diSize THEN
  RETURN;
END_IF
FOR i := 0 TO Expected.diSize - 1 DO
  IF Expected.pValue[i] <> Actual.pValue[i] THEN
    RETURN;
  END_IF
END_FOR
Same := TRUE;
END_METHOD
METHOD AsDint : DINT
VAR_INPUT v : ANY_INT; END_VAR
VAR d : DINT; END_VAR
IF v.TypeClass = __SYSTEM.TYPE_CLASS.TYPE_DINT THEN
  MEMCPY(destAddr := ADR(d), srcAddr := v.pValue, n := SIZEOF(DINT));
END_IF
AsDint := d;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION Size : DINT
VAR_INPUT x : ANY; END_VAR
Size := x.diSize;
END_FUNCTION
PROGRAM main
VAR
  a : FB_Assert; same, mixed, text, times : BOOL; n, m : DINT := 42; k : INT := 42;
  s : STRING := 'abc'; t : TIME := T#5s; got, sz_s, sz_k, sz_t, cls : DINT;
END_VAR
same := a.Same(n, m);
mixed := a.Same(n, k);             (* DINT against INT: other class and size *)
text := a.Same(s, s);
times := a.Same(T#5s, t);
got := a.AsDint(n + 1);
sz_s := Size(s); sz_k := Size(k); sz_t := Size(t);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_any_inputs_receive_type_class_size_and_a_byte_pointer_to_the_argument(dialect):
    plc = run(ANY_INPUTS, 1, dialect)
    assert [plc["main." + k] for k in ("same", "mixed", "text", "times", "got")] == [True, False, True, True, 43]
    assert (plc["main.sz_s"], plc["main.sz_k"], plc["main.sz_t"]) == (81, 2, 4)  # STRING(80), INT, TIME


def test_an_any_input_checks_its_family_and_is_a_vendor_extension():
    src = ANY_INPUTS.replace("got := a.AsDint(n + 1);", "got := a.AsDint(1.5);")
    assert "error[E013]: 'v' is ANY_INT; LREAL cannot be passed to it" in errors(src, "codesys")
    assert "error[E044]: an ANY input is not part of the iec dialect" in errors(ANY_INPUTS, "iec")


REF_RESULTS = """FUNCTION_BLOCK F
VAR x : INT := 5; END_VAR
METHOD GetX : REFERENCE TO INT
GetX REF= x;
END_METHOD
METHOD Again : REFERENCE TO INT
Again REF= GetX();
Again := Again + 100;              (* through the result: x itself *)
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR f : F; r : REFERENCE TO INT; v, w, z : INT; END_VAR
r REF= f.GetX();
v := f.GetX();
r := 7;
w := f.GetX() + 1;
z := f.Again();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_a_reference_to_result_is_bound_with_ref_and_read_through(dialect):
    plc = run(REF_RESULTS, 1, dialect)
    assert (plc["main.v"], plc["main.w"], plc["main.z"], plc["main.f.x"]) == (5, 8, 107, 107)


TWINCAT_BITS = """{gvl 'GVL_App'}
{attribute 'qualified_only'}
VAR_GLOBAL
  queue : FB_Queue;
END_VAR
VAR_GLOBAL CONSTANT
  N : UINT := 3;
END_VAR
TYPE ST_M : STRUCT a : DINT; b : INT; flag : BIT; END_STRUCT END_TYPE
TYPE E_Kind : (KIND_A := 1, KIND_B := 2) UDINT; END_TYPE
FUNCTION_BLOCK FB_Queue
VAR_OUTPUT calls : INT; END_VAR
VAR
  buf : ARRAY[0..((GVL_App.N * (SIZEOF(ST_M) + EXTRA)) - 1)] OF BYTE;
  t : TON := (IN := TRUE, PT := GAP);  (* constants declared below *)
END_VAR
VAR CONSTANT
  EXTRA : USINT := 4;
  GAP : TIME := T#10MS;
END_VAR
calls := calls + 1;
END_FUNCTION_BLOCK
FUNCTION Pair : DINT
VAR_INPUT a, b : DINT; END_VAR
Pair := a * 10 + b;
END_FUNCTION
FUNCTION Note
VAR_INPUT x : INT; END_VAR
VAR note : INT; END_VAR     (* no result type: no result variable of the function's name *)
note := x;
END_FUNCTION
PROGRAM main
VAR
  n, p : DINT; k : E_Kind; code : INT; lw : LWORD; u : UDINT := 16#FFFFFFFF; name : STRING;
  s : STRING := 'hello'; c : STRING := 'xyz'; pb, pc : POINTER TO BYTE; i : UDINT; calls : INT;
END_VAR
GVL_App.queue();
n := UPPER_BOUND(GVL_App.queue.buf, 1);
p := Pair(a := 3, 2);                    (* a positional argument after a named one takes its place's parameter *)
calls := GVL_App.queue.calls;
k := 2;                                   (* an integer into a non-strict enumeration *)
code := UDINT_TO_INT(k);
CASE code OF KIND_A: name := 'A'; KIND_B: name := 'B'; END_CASE
lw := DWORD_TO_LWORD(u);
Note(1);
FOR i := 0 TO 2 DO
  pc := ADR(c) + i;
  pb := ADR(s) + i + 1;
  pb^ := pc^;
END_FOR
END_PROGRAM
"""


def test_twincat_library_code_constructs():
    plc = run(TWINCAT_BITS, 1, "twincat")
    # GVL_App.queue() calls the instance; SIZEOF(ST_M) = 8 (DINT, INT, BIT as a BOOL byte, aligned to 4)
    assert (plc["main.calls"], plc["main.n"], plc["main.p"]) == (1, 3 * (8 + 4) - 1, 32)
    assert (plc["main.code"], plc["main.name"], plc["main.lw"]) == (2, "B", 0xFFFFFFFF)
    assert plc["main.s"] == "hxyzo"  # ADR(x) + n: the byte n bytes into x


ACTION_ARGS = """FUNCTION_BLOCK FB_Acc
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT total : INT; calls : INT; END_VAR
ACTION A_Add:
  total := total + step;
  calls := calls + 1;
END_ACTION
END_FUNCTION_BLOCK
PROGRAM main
VAR acc : FB_Acc; seen : INT; END_VAR
acc.A_Add(step := 5);
acc.A_Add(step := 2, total => seen);
acc.A_Add();                 (* the input keeps its last value *)
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "twincat"])
def test_an_action_call_passes_the_blocks_inputs_and_reads_its_outputs(dialect):
    plc = run(ACTION_ARGS, 1, dialect)
    assert (plc["main.seen"], plc["main.acc.total"], plc["main.acc.calls"]) == (7, 9, 3)


def test_action_arguments_are_a_vendor_extension():
    assert "t.st:11:1: error[E044]: an action call with arguments is not part of the iec dialect" in errors(
        ACTION_ARGS, "iec"
    )


ADR_OF_RESULT = """FUNCTION SetVia : DINT
VAR_INPUT p : POINTER TO DINT; END_VAR
p^ := 17;
SetVia := 1;
END_FUNCTION
FUNCTION_BLOCK F
METHOD Open : DINT
SetVia(ADR(Open));           (* the callee writes the method's result *)
END_METHOD
END_FUNCTION_BLOCK
FUNCTION G : DINT
SetVia(p := ADR(G));
G := G + 1;
END_FUNCTION
PROGRAM main
VAR f : F; a, b : DINT; END_VAR
a := f.Open();
b := G();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_adr_of_a_functions_own_result(dialect):
    plc = run(ADR_OF_RESULT, 1, dialect)
    assert (plc["main.a"], plc["main.b"]) == (17, 18)


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_a_parenthesised_pointer_expression_is_dereferenced(dialect):
    src = (
        "PROGRAM main\nVAR a : ARRAY[0..3] OF INT := [1, 2, 3, 4]; p : POINTER TO INT; v : INT; END_VAR\n"
        "p := ADR(a[0]);\nv := (p + 4)^;\n(p + SIZEOF(v) * 2)^ := 9;\nEND_PROGRAM\n"
    )
    plc = run(src, 1, dialect)
    assert (plc["main.v"], plc["main.a"]) == (3, [1, 2, 9, 4])


SUBRANGE_OUTSIDE = """PROGRAM main
VAR n : UINT(1..10); m : INT(-5..5); before : UINT; zero : UINT := 0; seven : INT := 7; END_VAR
before := n;
n := zero;
m := seven;
END_PROGRAM
"""


@pytest.mark.parametrize(
    ("dialect", "n", "m"),
    [("openplc", 1, 5), ("codesys", 0, 7), ("twincat", 0, 7)],  # MatIEC clamps; CODESYS/TwinCAT keep the value
)
def test_a_value_outside_a_subrange_is_what_the_dialects_compiler_makes_of_it(dialect, n, m):
    plc = run(SUBRANGE_OUTSIDE, 1, dialect)
    assert (plc["main.before"], plc["main.n"], plc["main.m"]) == (1, n, m)  # the default is the lower limit


@pytest.mark.parametrize("dialect", [None, "iec"])
def test_a_value_outside_a_subrange_is_a_range_fault_in_iec_and_the_default(dialect):
    _, f = fault(SUBRANGE_OUTSIDE, dialect)
    assert (f.kind, f.line, f.message) == ("RANGE", 4, "value 0 is outside the subrange 1..10")


@pytest.mark.parametrize("dialect", [None, "openplc", "twincat"])
def test_a_literal_outside_a_subrange_is_refused(dialect):
    src = "PROGRAM main\nVAR n : UINT(1..10); END_VAR\nn := 0;\nEND_PROGRAM\n"
    assert "t.st:3:6: error[E021]: 0 does not fit in UINT(1..10) (1..10)" in errors(src, dialect)


GLOBAL_CONSTANT_INITS = """{gvl 'GVL_P'}
VAR_GLOBAL CONSTANT
  N : UINT := 3;
END_VAR
VAR_GLOBAL CONSTANT
  TOP : DINT := 40;
END_VAR
TYPE ST_Rec : STRUCT a : DINT; b : DINT; END_STRUCT END_TYPE
FUNCTION_BLOCK F
VAR CONSTANT
  M : UINT := GVL_P.N + 100;
END_VAR
VAR x : UINT := GVL_P.N; y : DINT := TOP + 2; END_VAR
METHOD Fill : DINT
VAR r : ST_Rec; END_VAR
MEMSET(ADR(r), 1, SIZEOF(r));       (* ADR of a structure held in the method's local *)
Fill := r.b;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR f : F; m : UINT; x : UINT; y : DINT; filled : DINT; END_VAR
m := f.M; x := f.x; y := f.y;
filled := f.Fill();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "twincat"])
def test_global_constants_in_the_initial_values_of_a_pous_variables(dialect):
    plc = run(GLOBAL_CONSTANT_INITS, 1, dialect)
    assert (plc["main.m"], plc["main.x"], plc["main.y"], plc["main.filled"]) == (103, 3, 42, 0x01010101)


ROUNDING = """PROGRAM main
VAR a, b, c, d, e, f : DINT; x : REAL := 2.5; END_VAR
a := REAL_TO_DINT(x);
b := REAL_TO_DINT(3.5);
c := REAL_TO_DINT(-2.5);
d := REAL_TO_DINT(2.4999);
e := LREAL_TO_DINT(-3.5);
f := REAL_TO_DINT(0.49999997);
END_PROGRAM
"""


def test_openplc_rounds_halfway_to_even_as_matiec_does():
    plc = run(ROUNDING, 1, "openplc")
    assert [plc[f"main.{k}"] for k in "abcdef"] == [2, 4, -2, 2, -4, 0]


@pytest.mark.parametrize("dialect", [None, "iec", "codesys"])
def test_other_presets_round_halfway_away_from_zero(dialect):
    plc = run(ROUNDING, 1, dialect)
    assert [plc[f"main.{k}"] for k in "abcdef"] == [3, 4, -3, 2, -4, 0]


NEAR_HALF = """PROGRAM main
VAR a, b, c, d : DINT; x : LREAL := 0.49999999999999994; END_VAR
a := LREAL_TO_DINT(x);
b := LREAL_TO_DINT(-x);
c := TRUNC(x + 1.0);
d := LREAL_TO_DINT(LREAL_TO_REAL(x));
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys"])
def test_the_largest_double_below_a_half_rounds_to_zero(dialect):
    # floor(x + 0.5) would give 1: x + 0.5 rounds up to 1.0 in double precision
    plc = run(NEAR_HALF, 1, dialect)
    assert [plc[f"main.{k}"] for k in "abcd"] == [0, 0, 1, 1]  # (as REAL, x is 0.5: away from zero)


def _f32(v: float) -> float:
    return struct.unpack("<f", struct.pack("<f", v))[0]


SINGLE = """PROGRAM main
VAR a : REAL := 31.343643188476562; b : REAL := 38.47433853149414; r : REAL; w : LREAL; END_VAR
r := a * b - 1000.0;
w := REAL_TO_LREAL(a * 3.1);
END_PROGRAM
"""


def test_openplc_computes_real_with_real_in_single_precision_and_literals_in_double_as_matiec_s_c():
    a, b = 31.343643188476562, 38.47433853149414  # REAL values
    plc = run(SINGLE, 1, "openplc")
    assert plc["main.r"] == _f32(_f32(a * b) - 1000.0) == 205.9259033203125  # C: (float)(a * b), then - 1000.0
    assert _f32(a * b - 1000.0) == 205.92593383789062  # what double precision would give


@pytest.mark.parametrize("dialect", [None, "iec", "codesys"])
def test_real_arithmetic_elsewhere_is_double_rounded_on_store_and_a_real_argument_is_single(dialect):
    a, b = 31.343643188476562, 38.47433853149414
    plc = run(SINGLE, 1, dialect)
    assert plc["main.r"] == _f32(a * b - 1000.0) == 205.92593383789062
    assert plc["main.w"] == _f32(a * 3.1) != a * 3.1  # the REAL parameter holds a single value


WRITES_FOR_COUNTER = """
FUNCTION_BLOCK AddTen
VAR_IN_OUT v : INT; END_VAR
v := v + 10;
END_FUNCTION_BLOCK
PROGRAM main
VAR i, n : INT; b : AddTen; END_VAR
n := 0;
FOR i := 1 TO 30 DO n := n + 1; b(v := i); END_FOR;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_a_for_counter_written_by_its_body_is_tested_again_as_codesys_does(dialect):
    plc = run(WRITES_FOR_COUNTER, 1, dialect)
    assert (plc["main.n"], plc["main.i"]) == (3, 34)


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_iec_and_matiec_refuse_a_for_counter_written_by_its_body(dialect):
    assert (
        "t.st:9:40: error[E052]: 'i' is the control variable of the FOR on line 9: passed to VAR_IN_OUT 'v' in its body"
        in errors(WRITES_FOR_COUNTER, dialect)
    )


LITERALS_NO_TYPE_HOLDS = """
PROGRAM main
VAR i : DINT; r : REAL; l : LREAL; t : TIME; d : DATE; END_VAR
i := 1__0;
r := 1E39;
l := 1E309;
t := T#106752d;
d := D#2262-04-12;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "iec", "openplc", "codesys", "twincat"])
def test_every_preset_refuses_a_doubled_underscore_and_a_literal_its_type_cannot_hold(dialect):
    # issue 32: IEC's '_' rule is E004 everywhere; a REAL beyond REAL (MatIEC: no REAL candidate;
    # CODESYS/TwinCAT: C0001), an LREAL beyond LREAL, a TIME or DATE beyond st's 64-bit ns: E021
    assert diagnostics(LITERALS_NO_TYPE_HOLDS, dialect=dialect) == [
        ("E004", 4, 6),
        ("E021", 5, 6),
        ("E021", 6, 6),
        ("E021", 7, 6),
        ("E021", 8, 6),
    ]


@pytest.mark.parametrize("dialect", [None, "iec", "openplc", "codesys", "twincat"])
def test_a_time_beyond_codesys_32_bit_ms_is_kept_exactly_in_every_preset(dialect):
    # CODESYS and TwinCAT hold TIME as 32-bit ms (T#49d17h2m47s295ms at most); st's TIME is 64-bit
    # ns in every preset, literals and arithmetic alike (docs/semantics.md, "Values and types")
    plc = run("PROGRAM main\nVAR t : TIME := T#50d; u : TIME; END_VAR\nu := t + T#50d;\nEND_PROGRAM\n", 1, dialect)
    assert (plc["main.t"], plc["main.u"]) == (50 * 86400 * 10**9, 100 * 86400 * 10**9)


CONFIGURATION_NAMES = """FUNCTION_BLOCK Logger
VAR _config : INT := 3; END_VAR
PROPERTY Configuration : INT
GET
Configuration := _config;
END_GET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main
VAR l : Logger; c : INT; resource : INT := 2; END_VAR
c := l.Configuration + resource;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_configuration_and_resource_are_names_where_the_vendors_have_no_such_keyword(dialect):
    assert run(CONFIGURATION_NAMES, 1, dialect)["main.c"] == 5  # TcLog's property Configuration


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_configuration_and_resource_stay_keywords_in_iec_and_matiec(dialect):
    text = errors(CONFIGURATION_NAMES, dialect)
    assert "t.st:3:10: error[E001]: 'Configuration' is a reserved keyword and cannot be a name" in text
    assert "t.st:10:26: error[E001]: 'resource' is a reserved keyword and cannot be a name" in text


STRICT_READ = """{attribute 'strict'}
TYPE State : (Idle, Busy := 5, Error) INT; END_TYPE
FUNCTION_BLOCK Check
VAR_INPUT want : INT; END_VAR
VAR_OUTPUT ok : INT; END_VAR
ok := want;
END_FUNCTION_BLOCK
PROGRAM main
VAR s : State := State.Error; c : Check; n : INT; END_VAR
c(want := State.Busy);
n := s;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", ["codesys", "twincat"])
def test_a_strict_enumeration_is_read_as_its_integer_but_nothing_goes_into_it(dialect):
    """Beckhoff's attribute 'strict' forbids arithmetic and integers into the enumeration, not an
    enumeration value passed to an INT input (struckig's AssertEquals_INT(TrajectoryState.Error, ...))."""
    plc = run(STRICT_READ, 1, dialect)
    assert (plc["main.c.ok"], plc["main.n"]) == (5, 6)
    text = errors(STRICT_READ.replace("n := s;", "s := n;\nn := s + 1;"), dialect)
    assert "t.st:11:6: error[E013]: type mismatch: cannot assign INT to State" in text
    assert "t.st:12:6: error[E014]: operator + cannot combine State and integer literal" in text
