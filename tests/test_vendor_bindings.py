"""Bindings TwinCAT and CODESYS accept and IEC does not (issue 34): a literal or an expression for a
VAR_IN_OUT CONSTANT, initial values and FB_init arguments that name variables (in the order their
values need), ADR of a VAR CONSTANT, a literal 0 for a POINTER, __ISVALIDREF of a REFERENCE TO
member and of a VAR_IN_OUT, __NEW with FB_init arguments. Each runs with exact values under the
codesys and twincat presets and the default, and is refused where iec (or openplc) refuses it."""

from __future__ import annotations

import pytest

from helpers import errors, program, run

VENDOR = [None, "codesys", "twincat"]

# ---------------------------------------------------------------- VAR_IN_OUT CONSTANT

IN_OUT_CONSTANT = """
TYPE Pair : STRUCT a : INT; b : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK Otg
  VAR _msg : STRING; _id : INT; calls : INT; END_VAR
  METHOD PROTECTED AbortErrorId
    VAR_INPUT errorId : INT; END_VAR
    VAR_IN_OUT CONSTANT message : STRING; END_VAR
    _msg := message;
    _id := errorId;
    calls := calls + 1;
  END_METHOD
  METHOD Check
    VAR_INPUT x : INT; END_VAR
    IF x < 0 THEN
      AbortErrorId(3, 'maximum jerk limit should be larger than or equal to zero');
    ELSE
      AbortErrorId(errorId := 0, message := CONCAT('ok ', INT_TO_STRING(x)));
    END_IF
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Scaler
  VAR_IN_OUT CONSTANT factor : DINT; END_VAR
  VAR_INPUT x : DINT; END_VAR
  VAR_OUTPUT y : DINT; END_VAR
  y := x * factor;
END_FUNCTION_BLOCK
FUNCTION MkPair : Pair
  VAR_INPUT x : INT; END_VAR
  MkPair.a := x; MkPair.b := x + 1;
END_FUNCTION
FUNCTION SumPair : INT
  VAR_IN_OUT CONSTANT p : Pair; k : INT; END_VAR
  SumPair := p.a + p.b + k;
END_FUNCTION
PROGRAM main
  VAR CONSTANT K : INT := 40; END_VAR
  VAR
    otg : Otg; sc : Scaler; pr : Pair := (a := 1, b := 2);
    m1, m2 : STRING; id1, id2 : INT; r1, r2, r3 : INT; y1 : DINT; n : INT := 2;
  END_VAR
  otg.Check(-1); m1 := otg._msg; id1 := otg._id;
  otg.Check(7); m2 := otg._msg; id2 := otg._id;
  r1 := SumPair(MkPair(5), K);          (* a call's result, a constant *)
  r2 := SumPair(MkPair(n), n * 3);      (* an expression *)
  r3 := SumPair(pr, n);                 (* variables: by reference, as before *)
  sc(factor := n + 1, x := 7); y1 := sc.y;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_a_literal_or_an_expression_goes_to_a_var_in_out_constant_through_a_temporary(dialect):
    plc = run(IN_OUT_CONSTANT, 1, dialect)
    assert (plc["main.m1"], plc["main.id1"]) == ("maximum jerk limit should be larger than or equal to zero", 3)
    assert (plc["main.m2"], plc["main.id2"], plc["main.otg.calls"]) == ("ok 7", 0, 2)
    assert (plc["main.r1"], plc["main.r2"], plc["main.r3"]) == (5 + 6 + 40, 2 + 3 + 6, 1 + 2 + 2)
    assert plc["main.y1"] == 21
    assert (plc["main.n"], plc["main.pr"]) == (2, {"a": 1, "b": 2})  # nothing written back


def test_a_var_in_out_constant_is_not_written_inside_its_pou():
    src = """
FUNCTION F : INT
  VAR_IN_OUT CONSTANT s : STRING; END_VAR
  s := 'x';
  F := LEN(s);
END_FUNCTION
PROGRAM main VAR r : INT; END_VAR r := F('abc'); END_PROGRAM
"""
    for dialect in VENDOR:
        assert "t.st:4:3: error[E018]: 's' is a CONSTANT" in errors(src, dialect)


def test_a_plain_var_in_out_still_needs_a_variable():
    src = """
FUNCTION F : INT
  VAR_IN_OUT s : STRING; END_VAR
  F := LEN(s);
END_FUNCTION
PROGRAM main VAR r : INT; END_VAR r := F('abc'); END_PROGRAM
"""
    for dialect in VENDOR:
        assert "t.st:6:42: error[E031]: VAR_IN_OUT 's' needs a variable, not an expression" in errors(src, dialect)


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_iec_and_openplc_pass_only_variables_to_a_var_in_out_constant(dialect):
    src = """
FUNCTION F : INT
  VAR_IN_OUT CONSTANT s : STRING; END_VAR
  F := LEN(s);
END_FUNCTION
PROGRAM main VAR r : INT; END_VAR r := F('abc'); END_PROGRAM
"""
    out = errors(src, dialect)
    assert "t.st:6:42: error[E031]: VAR_IN_OUT 's' needs a variable, not an expression" in out
    assert "hint: codesys and twincat pass an expression to a VAR_IN_OUT CONSTANT" in out


# ---------------------------------------------------------------- initial values that name variables

BUILDER = """
INTERFACE I_State
  METHOD Name : STRING END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Off IMPLEMENTS I_State
  VAR_INPUT pMachine : POINTER TO Machine; END_VAR
  METHOD Name : STRING Name := 'off'; END_METHOD
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; pMachine : POINTER TO Machine; END_VAR
    THIS^.pMachine := pMachine;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Machine
  VAR_OUTPUT ipState : I_State := fbOff; END_VAR    (* an instance declared below *)
  VAR fbOff : FB_Off(THIS); serial : INT := 17; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK Builder
  VAR specs : ARRAY[1..2] OF STRING; n : INT := 7; seen : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; s : ARRAY[1..2] OF STRING; k : INT; END_VAR
    VAR blockSize : UDINT := SIZEOF(INT) * INT_TO_UDINT(k); END_VAR   (* a method's local from its input *)
    specs := s;
    seen := n;          (* the declared value, set before FB_init runs *)
    n := k + UDINT_TO_INT(blockSize);
    s[1] := 'changed';  (* a copy: the caller's array keeps its value *)
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION Scaled : DINT
  VAR_INPUT x : INT; END_VAR
  VAR b : DINT := a + 1; a : DINT := x * 10; END_VAR   (* at every call, b after a *)
  Scaled := b;
END_FUNCTION
PROGRAM main
  VAR
    specs1 : ARRAY[1..2] OF STRING := ['Red', 'Sedan'];
    b1 : Builder(s := specs1, k := base + 1);
    self : Builder(s := specs1, k := self.n);   (* its own declared value *)
    a : INT := b + 1; b : INT := c * 2; c : INT := base - 36;
    base : INT := 41;
    m : Machine;
    name : STRING; back : INT; r1, r2 : DINT;
  END_VAR
  name := m.ipState.Name();
  back := m.fbOff.pMachine^.serial;
  r1 := Scaled(4); r2 := Scaled(-2);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_fb_init_arguments_and_initial_values_name_variables_in_the_order_their_values_need(dialect):
    plc = run(BUILDER, 2, dialect)
    # b1's FB_init got a copy of specs1 and base + 1 = 42 (base is declared below it); its local
    # blockSize = SIZEOF(INT) * 42 = 84; it saw n's declared value 7
    assert (plc["main.b1.specs"], plc["main.b1.n"], plc["main.b1.seen"]) == (["Red", "Sedan"], 42 + 84, 7)
    assert plc["main.specs1"] == ["Red", "Sedan"]
    assert (plc["main.self.n"], plc["main.self.seen"]) == (7 + 14, 7)  # k := self.n read its declared 7
    assert (plc["main.a"], plc["main.b"], plc["main.c"]) == (11, 10, 5)
    # an interface initialised with an instance declared below it; THIS as an FB_init argument
    assert (plc["main.name"], plc["main.back"], plc["main.m.ipState"]) == ("off", 17, "FB_Off")
    assert (plc["main.r1"], plc["main.r2"]) == (41, -19)


def test_initial_values_that_need_each_other_are_an_error():
    src = "PROGRAM main\nVAR\n  p : INT := q + 1;\n  q : INT := p;\nEND_VAR\np := q;\nEND_PROGRAM\n"
    for dialect in VENDOR:
        assert "t.st:3:3: error[E029]: the initial values of p → q → p need each other's values" in errors(src, dialect)
    # an instance's FB_init arguments that need the instance's own constructed value
    src = """
FUNCTION_BLOCK FB
  VAR_OUTPUT n : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; k : INT; END_VAR
    n := k;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR x : FB(k := y); y : INT := x.n; END_VAR
y := x.n;
END_PROGRAM
"""
    assert "t.st:10:5: error[E029]: the initial values of x → y → x need each other's values" in errors(src)


LATE_DEFAULTS = """
FUNCTION_BLOCK Builder
  VAR_OUTPUT n : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; n0 : INT; END_VAR
    n := n0;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION Twice : INT
  VAR_INPUT a : INT := k * 2; END_VAR
  VAR k : INT := 4; END_VAR
  Twice := a + k;
END_FUNCTION
FUNCTION_BLOCK Director
  VAR_OUTPUT made : INT; viaMethod : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; inB : Builder(n0 := dflt); END_VAR
    VAR dflt : INT := 9; END_VAR
    made := inB.n;
  END_METHOD
  METHOD Build : INT
    VAR_INPUT b : Builder(n0 := base + 1); END_VAR
    VAR base : INT := 20; END_VAR
    Build := b.n;
  END_METHOD
  viaMethod := Build();
END_FUNCTION_BLOCK
PROGRAM main
VAR
  d : Director;
  mine : Builder(n0 := 3);
  d2 : Director(inB := mine);
  x : INT; y : INT; z : INT; w : INT;
END_VAR
d();
x := Twice();
y := Twice(a := 1);
z := d.Build(b := mine);
w := d2.made;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_an_omitted_input_whose_default_names_the_callees_variables_is_computed_by_the_callee(dialect):
    """The design-pattern course's Director: FB_init's `inB : Builder(specs := defaultArray)` with
    defaultArray a local of FB_init declared below it."""
    plc = run(LATE_DEFAULTS, 1, dialect)
    got = [plc[f"main.{n}"] for n in ("d.made", "d.viamethod", "x", "y", "z", "w")]
    assert got == [9, 21, 12, 5, 3, 3]


def test_iec_refuses_an_input_default_naming_a_variable():
    src = LATE_DEFAULTS[LATE_DEFAULTS.index("FUNCTION Twice") : LATE_DEFAULTS.index("FUNCTION_BLOCK Director")]
    out = errors(src + "PROGRAM main VAR x : INT; END_VAR x := Twice(); END_PROGRAM\n", "iec")
    assert "t.st:2:24: error[E029]: an initial value must be a constant; 'k' is a variable" in out


def test_iec_keeps_initial_values_constant():
    out = errors(BUILDER.replace("ARRAY[1..2] OF STRING := ['Red', 'Sedan'];", "ARRAY[1..2] OF STRING;"), "iec")
    assert "error[E029]: an initial value must be a constant; 'a' is a variable" in out  # Scaled's b
    assert "error[E029]: an initial value must be a constant; 'x' is a variable" in out  # Scaled's a
    assert "error[E029]: an initial value must be a constant; 'b' is a variable" in out  # main's a
    assert "error[E029]: an initial value must be a constant; THIS is the instance" in out
    assert "error[E029]: 'fbOff' is declared below; initial values are set in declaration order" in out


# ---------------------------------------------------------------- ADR of a VAR CONSTANT

ADR_OF_CONSTANT = """
FUNCTION IsInf : BOOL
  VAR_INPUT val : LREAL; END_VAR
  VAR CONSTANT InfinityBits : ULINT := ULINT#16#7FF0000000000000; END_VAR
  VAR InfinityPtr : POINTER TO LREAL := ADR(InfinityBits); END_VAR
  IsInf := val = InfinityPtr^ OR val = -InfinityPtr^;
END_FUNCTION
FUNCTION LrealBits : ULINT
  VAR_INPUT x : LREAL; END_VAR
  VAR b : POINTER TO ULINT := ADR(x); END_VAR
  LrealBits := b^;
END_FUNCTION
FUNCTION LrealFromBits : LREAL
  VAR_INPUT b : ULINT; END_VAR
  VAR x : POINTER TO LREAL := ADR(b); END_VAR
  LrealFromBits := x^;
END_FUNCTION
PROGRAM main
  VAR CONSTANT K : INT := 7; END_VAR
  VAR p : POINTER TO INT; v, w, z : INT; i1, i2 : BOOL; bits : ULINT; big : LREAL; END_VAR
  p := ADR(K);
  v := p^;
  p^ := 99;        (* that memory changes; K's uses are its value *)
  w := K + p^;
  z := K;
  bits := LrealBits(1.0);
  big := LrealFromBits(ULINT#16#4059000000000000);
  i1 := IsInf(LrealFromBits(ULINT#16#FFF0000000000000));
  i2 := IsInf(big);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_adr_of_a_constant_reads_its_value_and_a_write_through_it_leaves_the_constant(dialect):
    plc = run(ADR_OF_CONSTANT, 1, dialect)
    assert (plc["main.v"], plc["main.w"], plc["main.z"]) == (7, 7 + 99, 7)
    assert (plc["main.bits"], plc["main.big"]) == (0x3FF0000000000000, 100.0)
    assert (plc["main.i1"], plc["main.i2"]) == (True, False)


def test_ref_of_a_constant_stays_refused():
    src = "PROGRAM main\nVAR CONSTANT K : INT := 7; END_VAR\nVAR r : REF_TO INT; END_VAR\nr := REF(K);\nEND_PROGRAM\n"
    for dialect in [*VENDOR, "iec"]:
        assert "t.st:4:10: error[E018]: 'K' is a CONSTANT" in errors(src, dialect)


# ---------------------------------------------------------------- a literal 0 for a POINTER

ZERO_POINTER = """
TYPE Node : STRUCT v : INT; next : POINTER TO Node := 0; END_STRUCT END_TYPE
FUNCTION Get : INT
  VAR_INPUT p : POINTER TO INT; dflt : INT; END_VAR
  IF p = 0 THEN Get := dflt; ELSE Get := p^; END_IF
END_FUNCTION
FUNCTION_BLOCK Holder
  VAR_INPUT p : POINTER TO INT; END_VAR
  VAR_OUTPUT isNull : BOOL; END_VAR
  isNull := p = 0;
END_FUNCTION_BLOCK
PROGRAM main
  VAR x : INT := 5; q : POINTER TO INT := 0; h : Holder; n : Node; a, b : INT; c, d, e : BOOL; END_VAR
  a := Get(0, -1);
  b := Get(ADR(x), -1);
  h(p := ADR(x)); c := h.isNull;
  h(p := 0); d := h.isNull;
  e := q = 0 AND n.next = 0;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_a_literal_0_passed_or_given_as_a_pointer_is_null(dialect):
    plc = run(ZERO_POINTER, 1, dialect)
    assert (plc["main.a"], plc["main.b"], plc["main.c"], plc["main.d"], plc["main.e"]) == (-1, 5, False, True, True)
    assert (plc["main.q"], plc["main.h.p"]) == (None, None)


def test_only_the_literal_0_is_a_null_pointer():
    src = ZERO_POINTER.replace("a := Get(0, -1);", "a := Get(5, -1);")
    for dialect in VENDOR:
        assert "t.st:14:12: error[E013]: type mismatch: cannot pass integer literal to POINTER TO INT" in errors(
            src, dialect
        )


def test_iec_passes_no_literal_0_for_a_reference():
    src = """
FUNCTION Get : INT
  VAR_INPUT r : REF_TO INT; END_VAR
  IF r <> NULL THEN Get := r^; END_IF
END_FUNCTION
PROGRAM main VAR a : INT; END_VAR a := Get(0); END_PROGRAM
"""
    assert run(src, 1, "codesys")["main.a"] == 0
    assert "t.st:6:44: error[E013]: type mismatch: cannot pass integer literal to REF_TO INT" in errors(src, "iec")


# ---------------------------------------------------------------- __ISVALIDREF

IS_VALID_REF = """
FUNCTION_BLOCK Hoist
  VAR_OUTPUT moves : INT; END_VAR
  METHOD Down moves := moves + 1; END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Command
  VAR refHoist : REFERENCE TO Hoist; END_VAR
  VAR_OUTPUT valid : BOOL; END_VAR
  METHOD Bind VAR_INPUT h : REFERENCE TO Hoist; END_VAR refHoist REF= h; END_METHOD
  METHOD Execute
    valid := __ISVALIDREF(THIS^.refHoist);    (* the reference, not the block it refers to *)
    IF __ISVALIDREF(THIS^.refHoist) THEN THIS^.refHoist.Down(); END_IF
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Acc
  VAR_IN_OUT io : INT; END_VAR
  VAR_OUTPUT bound : BOOL; END_VAR
  METHOD Check : BOOL Check := __ISVALIDREF(io); END_METHOD
  bound := __ISVALIDREF(io);
  IF bound THEN io := io + 1; END_IF
END_FUNCTION_BLOCK
FUNCTION Inc : BOOL
  VAR_IN_OUT x : INT; END_VAR
  Inc := __ISVALIDREF(x);
  x := x + 1;
END_FUNCTION
PROGRAM main
  VAR
    h : Hoist; c1, c2 : Command; acc : Acc; n : INT := 10;
    cv1, cv2, outside1, outside2, v1, v2, v3, v4, f : BOOL;
  END_VAR
  c1.Execute(); cv1 := c1.valid; outside1 := __ISVALIDREF(c1.refHoist);
  c2.Bind(h); c2.Execute(); cv2 := c2.valid; outside2 := __ISVALIDREF(c2.refHoist);
  v1 := acc.Check();            (* never given: FALSE, no fault *)
  acc(); v2 := acc.bound;
  acc(io := n); v3 := acc.bound; v4 := acc.Check();
  f := Inc(n);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_isvalidref_checks_a_reference_member_and_a_var_in_out_themselves(dialect):
    plc = run(IS_VALID_REF, 1, dialect)
    assert (plc["main.cv1"], plc["main.outside1"], plc["main.cv2"], plc["main.outside2"]) == (False, False, True, True)
    assert plc["main.h.moves"] == 1
    assert (plc["main.v1"], plc["main.v2"], plc["main.v3"], plc["main.v4"], plc["main.f"]) == (
        False,
        False,
        True,
        True,
        True,
    )
    assert plc["main.n"] == 12  # the block's call and the function's both added 1


def test_isvalidref_needs_a_reference():
    src = "PROGRAM main\nVAR x : INT; b : BOOL; END_VAR\nb := __ISVALIDREF(x);\nEND_PROGRAM\n"
    assert "t.st:3:19: error[E013]: __ISVALIDREF needs a reference, not INT" in errors(src, "codesys")
    assert "t.st:3:6: error[E044]: __ISVALIDREF is not part of the iec dialect" in errors(src, "iec")


# ---------------------------------------------------------------- __NEW with FB_init arguments

NEW_WITH_ARGS = """
FUNCTION_BLOCK FB_Runner
  VAR_OUTPUT n : INT; label : STRING; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; a : INT; name : STRING; END_VAR
    n := a; label := name;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR p, q : POINTER TO FB_Runner; k : INT := 5; m1, m2 : INT; l1, l2 : STRING; END_VAR
  p := __NEW(FB_Runner(a := k + 1, name := 'first'));
  q := __NEW(FB_Runner(k * 3, 'second'));
  m1 := p^.n; l1 := p^.label;
  m2 := q^.n; l2 := q^.label;
  __DELETE(p);
  k := k + 1;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_new_passes_fb_init_arguments_evaluated_where_it_runs(dialect):
    plc = run(NEW_WITH_ARGS, 2, dialect)  # the second scan: k = 6
    assert (plc["main.m1"], plc["main.l1"], plc["main.m2"], plc["main.l2"]) == (7, "first", 18, "second")
    assert plc["main.p"] is None


def test_new_with_arguments_names_fb_init_inputs():
    src = NEW_WITH_ARGS.replace("a := k + 1", "b := k + 1")
    assert "FB_init of FB_Runner has no input 'b' to set here" in errors(src, "codesys")


def test_new_in_a_method_passes_the_instance_s_own_address():
    src = """
FUNCTION_BLOCK Snapshot
  VAR_OUTPUT title : STRING; owner : POINTER TO Editor; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; pEditor : POINTER TO Editor; sTitle : STRING; END_VAR
    owner := pEditor; title := sTitle;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Editor
  VAR sTitle : STRING := 'recipe 1'; pSnapshot : POINTER TO Snapshot; n : INT := 3; END_VAR
  METHOD Save
    THIS^.pSnapshot := __NEW(Snapshot(pEditor := ADR(THIS^), sTitle := THIS^.sTitle));
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR e : Editor; t : STRING; back : INT; x : INT := 4; px, py : POINTER TO INT; END_VAR
  e.Save();
  t := e.pSnapshot^.title;
  back := e.pSnapshot^.owner^.n;
  px := ADR(x); py := ADR(px^);   (* what px points at: x *)
  py^ := 9;
END_PROGRAM
"""
    for dialect in VENDOR:
        plc = run(src, 1, dialect)
        assert (plc["main.t"], plc["main.back"], plc["main.x"]) == ("recipe 1", 3, 9)


def test_initial_values_and_new_arguments_read_properties_and_qualified_globals():
    src = """{gvl 'GVL'}
{attribute 'qualified_only'}
VAR_GLOBAL
  gX : INT := 5;
END_VAR
FUNCTION_BLOCK FB_P
  VAR _v : INT := 3; END_VAR
  PROPERTY P : INT
    GET P := _v * 2; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_R
  VAR_OUTPUT n : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; a : INT; END_VAR
    n := a;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR
    fp : FB_P; a : INT := GVL.gX + 1; b : INT := fp.P; r : FB_R(a := fp.P + GVL.gX);
    pr : POINTER TO FB_R; m : INT;
  END_VAR
  pr := __NEW(FB_R(a := fp.P * GVL.gX));
  m := pr^.n;
END_PROGRAM
"""
    for dialect in VENDOR:
        plc = run(src, 1, dialect)
        assert (plc["main.a"], plc["main.b"], plc["main.r.n"], plc["main.m"]) == (6, 6, 11, 30)


ANY_HANDED_ON = """
FUNCTION Inner : UDINT
VAR_INPUT v : ANY; END_VAR
Inner := TO_UDINT(v.diSize) * 100 + TO_UDINT(v.TypeClass);
END_FUNCTION
FUNCTION Outer : UDINT
VAR_INPUT data : ANY; END_VAR
Outer := Inner(data);
END_FUNCTION
FUNCTION OnlyNum : UDINT
VAR_INPUT n : ANY_NUM; END_VAR
OnlyNum := Inner(n);
END_FUNCTION
PROGRAM main
VAR d : DINT := 7; s : STRING := 'ab'; a, b, c : UDINT; END_VAR
a := Outer(d);
b := Outer(s);
c := OnlyNum(d);
END_PROGRAM
"""


def test_an_any_input_handed_on_to_another_keeps_the_first_callers_descriptor():
    """TcLog's AnyToString(data) inside a method whose `data` is ANY: the callee sees the first
    caller's value (DINT: 4 bytes, class 8; STRING: 81 bytes, class 16)."""
    for dialect in ("twincat", "codesys", None):
        plc = run(ANY_HANDED_ON, 1, dialect)
        assert (plc["main.a"], plc["main.b"], plc["main.c"]) == (408, 8116, 408)
    bad = ANY_HANDED_ON.replace("VAR_INPUT v : ANY; END_VAR", "VAR_INPUT v : ANY_NUM; END_VAR")
    text = errors(bad, "twincat")
    assert "t.st:8:16: error[E013]: 'v' is ANY_NUM; an ANY input cannot be handed on to it" in text


ZERO_CONSTANT = """
INTERFACE ILog
METHOD Log : BOOL
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Logger IMPLEMENTS ILog
METHOD Log : BOOL
Log := TRUE;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR CONSTANT Invalid : UDINT := 0; One : UDINT := 1; END_VAR
VAR l : Logger; used : ILog; before, after : BOOL; END_VAR
before := used <> Invalid;
used := l;
after := used <> Invalid AND used <> 0;
END_PROGRAM
"""


def test_an_interface_compared_with_an_integer_constant_that_is_zero():
    """TcLog: `IF _usedLogger <> InvalidLoggerReference` (a VAR CONSTANT UDINT := 0) tests for NULL."""
    for dialect in ("twincat", "codesys", None):
        plc = run(ZERO_CONSTANT, 1, dialect)
        assert (plc["main.before"], plc["main.after"]) == (False, True)
    text = errors(ZERO_CONSTANT.replace("used <> Invalid AND", "used <> One AND"), "twincat")
    assert "t.st:16:10: error[E014]: operator <> cannot combine ILog and UDINT" in text


QUALIFIED_LIST = """{attribute 'qualified_only'}
{gvl 'Constants'}
VAR_GLOBAL CONSTANT
  Overhead : UDINT := 10;
  BufferSize : UDINT := 100 * (80 + Overhead);
END_VAR
PROGRAM main
VAR n : UDINT; END_VAR
n := Constants.BufferSize;
END_PROGRAM
"""


def test_a_qualified_only_list_names_its_own_constants_plainly_in_its_initial_values():
    """TcLog's CONSTANTS.TcGVL: `BufferSize : UDINT := 100 * (MAX_STRING_LENGTH + FifoOverhead)`."""
    for dialect in ("twincat", "codesys", None):
        assert run(QUALIFIED_LIST, 1, dialect)["main.n"] == 9000
    text = errors(QUALIFIED_LIST.replace("n := Constants.BufferSize;", "n := BufferSize;"), "twincat")
    assert "t.st:9:6: error[E010]: 'BufferSize' belongs to Constants, a {attribute 'qualified_only'} list" in text


def test_a_block_called_and_its_method_called_through_a_reference_to_it():
    """struckig's benchmark: `otg : REFERENCE TO Struckig.Otg; otg();` (the variable is named like
    its type), and a REFERENCE TO input of a block called with arguments."""
    src = """
FUNCTION_BLOCK Otg
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT n : INT; END_VAR
n := n + step;
METHOD Twice : INT
Twice := 2 * n;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Holder
VAR_INPUT r : REFERENCE TO Otg; END_VAR
VAR_OUTPUT t : INT; END_VAR
r(step := 5);
t := r.Twice();
END_FUNCTION_BLOCK
FUNCTION Run : INT
VAR_INPUT otg : REFERENCE TO Otg; END_VAR
otg();
otg(step := 10);
Run := otg.Twice();
END_FUNCTION
PROGRAM main
VAR o : Otg; h : Holder; r, t : INT; END_VAR
r := Run(o);
h(r := o);
t := h.t;
END_PROGRAM
"""
    for dialect in ("twincat", "codesys", None):
        plc = run(src, 1, dialect)
        # Run: n = 1 (step 1), then 11 (step 10), Twice 22; Holder: n = 16 (step 5), Twice 32
        assert (plc["main.r"], plc["main.o.n"], plc["main.t"]) == (22, 16, 32)


VAR_INST_FROM_BLOCK = """
INTERFACE IGen
METHOD Next : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Gen IMPLEMENTS IGen
VAR seed, v : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; s : INT; END_VAR
seed := s;
END_METHOD
METHOD Next : INT
v := v + seed;
Next := v;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Wrap
VAR g : IGen; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; gen : IGen; END_VAR
g := gen;
END_METHOD
METHOD Draw : INT
Draw := g.Next();
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Suite
VAR
  dist : Gen(s := 3);
  base : INT := 10;
END_VAR
METHOD Test : INT
VAR_INST
  w : Wrap(dist);
  k : INT := base + 1;
END_VAR
VAR
  local : INT := base * 2;
END_VAR
Test := w.Draw() + k + local;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR s : Suite; r, r2 : INT; END_VAR
r := s.Test();
r2 := s.Test();
END_PROGRAM
"""


def test_a_method_s_var_inst_is_initialised_from_the_block_s_variables():
    """struckig's RandomTest: `p : Randomizer(_positionDist);` in a METHOD's VAR_INST names an
    instance variable of the block (given to FB_init as an interface: the same instance)."""
    src = VAR_INST_FROM_BLOCK
    for dialect in ("twincat", "codesys", None):
        plc = run(src, 1, dialect)
        # Draw: dist.Next() = 3, then 6; k = base + 1 = 11; local = base * 2 = 20
        assert (plc["main.r"], plc["main.r2"], plc["main.s.dist.v"]) == (34, 37, 6)
    assert "error[E010]: undeclared identifier 'base'" in errors(src.replace("  base : INT := 10;\n", ""), "twincat")


def test_adr_of_an_array_of_structures_into_a_pointer_to_its_element():
    """struckig's SecondaryFeaturesTest: `profiles : POINTER TO ProfileDesc := ADR(otg._profiles);`."""
    src = """TYPE P : STRUCT x : INT := 4; END_STRUCT END_TYPE
FUNCTION_BLOCK Otg
VAR _profiles : ARRAY[0..3] OF P := [(x := 1), (x := 20)]; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK T
METHOD M : INT
VAR_INST otg : Otg; END_VAR
VAR profiles : POINTER TO P := ADR(otg._profiles); END_VAR
M := profiles^.x + (profiles + SIZEOF(otg._profiles[0]))^.x;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR t : T; r : INT; END_VAR
r := t.M();
END_PROGRAM
"""
    for dialect in ("twincat", "codesys", None):
        assert run(src, 1, dialect)["main.r"] == 21


ASSIGNING_CONDITIONS = """
FUNCTION Next : BOOL
VAR_IN_OUT n : INT; END_VAR
n := n + 1;
Next := n < 4;
END_FUNCTION
PROGRAM main
VAR n, m, k, rounds, r2 : INT; b, c, d : BOOL; which : INT; END_VAR
IF b := Next(n) THEN which := 1; END_IF
IF FALSE THEN which := 9; ELSIF c := (n = 1) THEN which := which + 10; ELSE which := which + 100; END_IF
IF TRUE THEN which := which + 1000; ELSIF d := TRUE THEN which := 0; END_IF
WHILE b := Next(m) DO rounds := rounds + 1; END_WHILE
REPEAT r2 := r2 + 1; UNTIL c := NOT Next(k) END_REPEAT
END_PROGRAM
"""


def test_a_condition_that_assigns_assigns_where_it_is_evaluated():
    """CODESYS/TwinCAT (ExST): `IF b := f() THEN`, in ELSIF (only when reached), WHILE (before each
    round) and UNTIL (after each round)."""
    for dialect in ("twincat", "codesys", None):
        plc = run(ASSIGNING_CONDITIONS, 1, dialect)
        got = [plc[f"main.{x}"] for x in ("n", "which", "m", "rounds", "k", "r2", "b", "c", "d")]
        # d: its ELSIF is never reached, so it is never assigned
        assert got == [1, 1011, 4, 3, 4, 4, False, True, False]
    text = errors(ASSIGNING_CONDITIONS, "iec")
    assert "t.st:9:4: error[E044]: an assignment as a condition (IF b := f() THEN) is not part of the iec" in text
    assert text.count("error[E044]") == 5


def test_delete_this_releases_an_instance_made_by_new():
    """The design-pattern course's Disposable: `METHOD Dispose ... __DELETE(THIS);`."""
    src = """
FUNCTION_BLOCK Disposable
VAR_OUTPUT disposed : INT; END_VAR
METHOD Dispose
disposed := disposed + 1;
__DELETE(THIS);
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR p : POINTER TO Disposable; n, made : INT; END_VAR
IF p = 0 THEN p := __NEW(Disposable); made := made + 1; END_IF
p^.Dispose();
n := p^.disposed;
__DELETE(p);
END_PROGRAM
"""
    for dialect in ("twincat", "codesys", None):
        plc = run(src, 2, dialect)
        assert (plc["main.n"], plc["main.made"], plc["main.p"]) == (1, 2, None)  # a fresh instance each scan
    assert "error[E044]: __DELETE is not part of the iec dialect" in errors(src, "iec")


# ---------------------------------------------------------------- arrays of blocks with FB_init arguments

ARRAY_CTORS = """
TYPE E_Runner : (RUNNER_START, R1, R2, R3, RUNNER_END); END_TYPE
FUNCTION_BLOCK FB_Runner
  VAR_OUTPUT name : STRING; n : INT; k : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; instanceName : STRING; num : INT; END_VAR
    name := instanceName;
    n := num;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR
  runners : ARRAY[E_Runner.RUNNER_START + 1 .. E_Runner.RUNNER_END - 1] OF FB_Runner[
    (instanceName := 'one', num := 1), (instanceName := 'two'), ('three', 3)];
  same : ARRAY[0..1] OF FB_Runner('s', 7) := [(k := 5), (k := 6)];
  part : ARRAY[1..3] OF FB_Runner[(num := 4)] := [2((k := 8))];
END_VAR
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_an_array_of_blocks_gets_fb_init_arguments_for_every_element_or_element_by_element(dialect):
    plc = run(ARRAY_CTORS, 1, dialect)
    runners = [(plc[f"main.runners[{i}].name"], plc[f"main.runners[{i}].n"]) for i in (1, 2, 3)]
    assert runners == [("one", 1), ("two", 0), ("three", 3)]
    same = [(plc[f"main.same[{i}].name"], plc[f"main.same[{i}].n"], plc[f"main.same[{i}].k"]) for i in (0, 1)]
    assert same == [("s", 7, 5), ("s", 7, 6)]
    part = [(plc[f"main.part[{i}].n"], plc[f"main.part[{i}].k"]) for i in (1, 2, 3)]
    assert part == [(4, 8), (0, 8), (0, 0)]


def test_an_array_of_blocks_fb_init_arguments_have_their_form():
    src = ARRAY_CTORS.replace("[(num := 4)] := [2((k := 8))]", "[(num := 4), (num := 5), (num := 6), (num := 7)]")
    src = src.replace("('s', 7) := [(k := 5), (k := 6)]", "('s', 7) := 3")
    out = errors(src, "twincat")
    assert "t.st:15:46: error[E057]: an array of function blocks takes an array initializer ([...])" in out
    assert "t.st:16:10: error[E057]: 4 FB_init argument lists for an array of 3 elements" in out
    out = errors(ARRAY_CTORS, "iec")
    assert "t.st:13:13: error[E044]: FB_init arguments in a declaration is not part of the iec dialect" in out


# ---------------------------------------------------------------- blark's samples, completed

BLARK_FORMS = """
TYPE someColor : (off := 0, red := 5, green := 9) DINT; END_TYPE
{attribute 'qualified_only'}
TYPE color : (
  off := ANY_TO_DINT(someColor.off),
  red := ANY_TO_DINT(someColor.red),
  green := TO_DINT(someColor.green) + 1
) DINT;
END_TYPE
TYPE grp : STRUCT someValue : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK FB_Sample
  VAR_INPUT nInput : INT; END_VAR
  VAR_OUTPUT init : INT; prop : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; nInitParam : INT; END_VAR
    init := nInitParam;
  END_METHOD
  PROPERTY nMyProperty : INT
    GET nMyProperty := prop; END_GET
    SET prop := nMyProperty * 10; END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK class_SomethingCool
  VAR
    _object : ARRAY[1..3] OF grp := [(someValue := 1), (someValue := 2), (someValue := 3)];
    currentChannel : ARRAY[1..3] OF POINTER TO grp := [ADR(_object[1]), ADR(_object[2]), ADR(_object[3])];
  END_VAR
  VAR_OUTPUT s : INT; END_VAR
  s := currentChannel[2]^.someValue + currentChannel[3]^.someValue;
END_FUNCTION_BLOCK
PROGRAM main
VAR
  fbSample : FB_Sample(nInitParam := 1) := (nInput := 2, nMyProperty := 3);
  c : color := color.red;
  cool : class_SomethingCool;
  k : DINT; s : INT;
END_VAR
k := color.green;
cool();
s := cool.s;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", ["codesys", "twincat"])  # (the default: an enumeration is no DINT)
def test_blark_sample_forms_with_their_declarations(dialect):
    """Forms from blark's parser samples, with the declarations the samples leave out: enumeration
    values converted from another enumeration's, a property given its value in a declaration
    (through SET, after FB_init), an array of pointers initialised with ADR of elements."""
    plc = run(BLARK_FORMS, 1, dialect)
    got = [plc[f"main.{n}"] for n in ("k", "c", "fbsample.init", "fbsample.ninput", "fbsample.prop", "s")]
    assert got == [10, "red", 1, 2, 30, 5]


def test_a_property_without_set_gets_no_initial_value():
    src = BLARK_FORMS.replace("    SET prop := nMyProperty * 10; END_SET\n", "")
    assert "error[E023]: property nMyProperty of FB_Sample has no SET to give it a value" in errors(src, "twincat")


@pytest.mark.parametrize("dialect", [None, "iec", "twincat"])
def test_a_stray_semicolon_between_declarations_is_nothing(dialect):
    src = "(* a comment *);\nFUNCTION_BLOCK F\nVAR_OUTPUT x : INT; END_VAR\nx := 7;\nEND_FUNCTION_BLOCK;\n"
    plc = run(src + program("f(); k := f.x;", "f : F; k : INT;"), 1, dialect)
    assert plc["main.k"] == 7
