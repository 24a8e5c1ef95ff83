"""Conformance probes for object-oriented ST, in the style of third-party suites (STruC++, RuSTy,
CODESYS/TwinCAT example projects): methods, interfaces, properties, inheritance and SUPER^ chains,
abstract/final/override, access specifiers, CLASS, references and pointers, VAR_INST/VAR_STAT,
__NEW/__DELETE, FB_init, dialect presets, and the located diagnostics for the usual mistakes.
Every expected value was worked out by hand from the language semantics."""

from functools import partial

import pytest

from st.api import compile_text

import helpers

run = partial(helpers.run, name="conf.st", use_cache=True)
errors = partial(helpers.errors, name="conf.st")
fault = partial(helpers.fault, name="conf.st")


# --------------------------------------------------------------------------- inheritance, SUPER^


def test_super_method_chain_and_super_body_over_three_levels():
    plc = run("""
FUNCTION_BLOCK A
  VAR_OUTPUT n : INT; END_VAR
  METHOD Name : STRING
    Name := 'A';
  END_METHOD
  METHOD Val : INT
    Val := 1;
  END_METHOD
  n := n + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD Name : STRING
    Name := CONCAT(SUPER^.Name(), '/B');
  END_METHOD
  METHOD Val : INT
    Val := SUPER^.Val() + 10;
  END_METHOD
  SUPER^();
  n := n + 10;
END_FUNCTION_BLOCK
FUNCTION_BLOCK C EXTENDS B
  METHOD Name : STRING
    Name := CONCAT(SUPER^.Name(), '/C');
  END_METHOD
  METHOD Val : INT
    Val := SUPER^.Val() + 100;
  END_METHOD
  SUPER^();
  n := n + 100;
END_FUNCTION_BLOCK
PROGRAM main
  VAR c : C; s : STRING; r : INT; END_VAR
  c();
  s := c.Name();
  r := c.Val();
END_PROGRAM
""")
    assert (plc["main.s"], plc["main.r"], plc["main.c.n"]) == ("A/B/C", 111, 111)


def test_virtual_dispatch_from_a_base_method_with_and_without_this():
    plc = run("""
FUNCTION_BLOCK A
  METHOD Who : STRING
    Who := 'A';
  END_METHOD
  METHOD Describe : STRING
    Describe := CONCAT('I am ', THIS^.Who());
  END_METHOD
  METHOD Describe2 : STRING
    Describe2 := CONCAT('I am ', Who());
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD Who : STRING
    Who := 'B';
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK C EXTENDS B
  METHOD OVERRIDE Who : STRING
    Who := 'C';
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR c : C; b : B; s1, s2, s3 : STRING; END_VAR
  s1 := c.Describe();
  s2 := c.Describe2();
  s3 := b.Describe();
END_PROGRAM
""")
    assert (plc["main.s1"], plc["main.s2"], plc["main.s3"]) == ("I am C", "I am C", "I am B")


def test_abstract_template_body_and_super_body_of_a_bodyless_block():
    plc = run(
        """
FUNCTION_BLOCK ABSTRACT Step
  VAR_OUTPUT trace : STRING; END_VAR
  METHOD ABSTRACT Work : STRING
  END_METHOD
  trace := CONCAT(trace, Work());
END_FUNCTION_BLOCK
FUNCTION_BLOCK S1 EXTENDS Step
  METHOD Work : STRING Work := 'x'; END_METHOD
  SUPER^();
END_FUNCTION_BLOCK
FUNCTION_BLOCK S2 EXTENDS S1
  METHOD Work : STRING Work := 'y'; END_METHOD
  SUPER^();
  trace := CONCAT(trace, '.');
END_FUNCTION_BLOCK
PROGRAM main VAR a : S1; b : S2; END_VAR
  a(); b();
END_PROGRAM
""",
        2,
    )
    assert (plc["main.a.trace"], plc["main.b.trace"]) == ("xx", "y.y.")


def test_protected_and_internal_members_are_usable_in_derived_blocks():
    plc = run("""
FUNCTION_BLOCK A
  VAR PROTECTED cnt : INT; END_VAR
  VAR INTERNAL tag : INT := 3; END_VAR
  METHOD PROTECTED Inc
    cnt := cnt + 1;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD PUBLIC Go : INT
    Inc(); Inc(); THIS^.Inc(); SUPER^.Inc();
    Go := cnt + tag;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; r : INT; t : INT; END_VAR
  r := b.Go();
  t := b.tag;
END_PROGRAM
""")
    assert (plc["main.r"], plc["main.t"]) == (7, 3)


def test_super_and_this_reach_inherited_variables():
    plc = run("""
FUNCTION_BLOCK A
  VAR_OUTPUT x : INT := 5; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  VAR_OUTPUT y : INT; END_VAR
  y := SUPER^.x + THIS^.x;
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR
  b();
END_PROGRAM
""")
    assert plc["main.b.y"] == 10


def test_virtual_property_read_from_a_base_method():
    plc = run("""
FUNCTION_BLOCK A
  VAR_INPUT inp : INT; END_VAR
  PROPERTY Kind : STRING
  GET Kind := 'a'; END_GET
  END_PROPERTY
  METHOD Show : STRING
    Show := CONCAT('<', CONCAT(THIS^.Kind, CONCAT(Kind, '>')));
  END_METHOD
  METHOD SetInp
    inp := 42;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  PROPERTY Kind : STRING
  GET Kind := 'b'; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; s : STRING; END_VAR
  s := b.Show();
  b.SetInp();
END_PROGRAM
""")
    assert (plc["main.s"], plc["main.b.inp"]) == ("<bb>", 42)


# --------------------------------------------------------------------------- methods


def test_method_struct_and_array_results_outputs_and_in_outs():
    plc = run("""
TYPE Pt : STRUCT x : INT; y : INT; END_STRUCT END_TYPE
TYPE Arr3 : ARRAY[0..2] OF INT; END_TYPE
FUNCTION_BLOCK G
  METHOD MkPt : Pt
    VAR_INPUT a : INT; b : INT := 7; END_VAR
    MkPt.x := a; MkPt.y := b;
  END_METHOD
  METHOD MkArr : Arr3
    VAR_INPUT base : INT; END_VAR
    VAR i : INT; END_VAR
    FOR i := 0 TO 2 DO MkArr[i] := base + i; END_FOR;
  END_METHOD
  METHOD DivMod : BOOL
    VAR_INPUT a, b : INT; END_VAR
    VAR_OUTPUT q, r : INT; END_VAR
    IF b = 0 THEN DivMod := FALSE; RETURN; END_IF;
    q := a / b; r := a MOD b; DivMod := TRUE;
  END_METHOD
  METHOD Inc
    VAR_IN_OUT v : INT; END_VAR
    VAR_INPUT by : INT := 1; END_VAR
    v := v + by;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR g : G; p, p2 : Pt; a : Arr3; ok, ok2 : BOOL; q, r : INT; q2 : INT := -1; v : INT := 10;
      px : INT; END_VAR
  p := g.MkPt(a := 3);
  p2 := g.MkPt(b := 1, a := 2);
  a := g.MkArr(100);
  ok := g.DivMod(17, 5, q => q, r => r);
  ok2 := g.DivMod(a := 1, b := 0, q => q2);
  g.Inc(v, 1);
  g.Inc(v := v, by := 5);
  px := g.MkPt(9, 0).x;
END_PROGRAM
""")
    assert plc["main.p"] == {"x": 3, "y": 7} and plc["main.p2"] == {"x": 2, "y": 1}
    assert plc["main.a"] == [100, 101, 102]
    assert (plc["main.ok"], plc["main.q"], plc["main.r"]) == (True, 3, 2)
    assert (plc["main.ok2"], plc["main.q2"]) == (False, 0)  # outputs are copied out on RETURN too
    assert (plc["main.v"], plc["main.px"]) == (16, 9)


def test_recursive_methods():
    plc = run("""
FUNCTION_BLOCK M
  METHOD Fact : DINT
    VAR_INPUT n : DINT; END_VAR
    IF n <= 1 THEN Fact := 1; ELSE Fact := n * Fact(n - 1); END_IF;
  END_METHOD
  METHOD Fib : DINT
    VAR_INPUT n : DINT; END_VAR
    IF n < 2 THEN Fib := n; ELSE Fib := THIS^.Fib(n - 1) + THIS^.Fib(n - 2); END_IF;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR m : M; f, g : DINT; END_VAR
  f := m.Fact(10);
  g := m.Fib(15);
END_PROGRAM
""")
    assert (plc["main.f"], plc["main.g"]) == (3628800, 610)


def test_methods_of_nested_instances_in_an_array():
    plc = run("""
FUNCTION_BLOCK Motor
  VAR_OUTPUT speed : INT; END_VAR
  METHOD SetSpeed : BOOL
    VAR_INPUT s : INT; END_VAR
    speed := LIMIT(0, s, 100); SetSpeed := speed = s;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Axis
  VAR m : Motor; END_VAR
  VAR_OUTPUT lastOk : BOOL; END_VAR
  METHOD Move : INT
    VAR_INPUT s : INT; END_VAR
    lastOk := m.SetSpeed(s);
    Move := m.speed;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR axes : ARRAY[0..2] OF Axis; i : INT; sum : INT; oks : INT; END_VAR
  FOR i := 0 TO 2 DO
    sum := sum + axes[i].Move(i * 60);
    IF axes[i].lastOk THEN oks := oks + 1; END_IF;
  END_FOR;
END_PROGRAM
""")
    assert (plc["main.sum"], plc["main.oks"], plc["main.axes[2].m.speed"]) == (160, 2, 100)


def test_method_returning_a_reference_is_written_through():
    plc = run("""
FUNCTION_BLOCK Cells
  VAR cells : ARRAY[0..3] OF INT; END_VAR
  METHOD Cell : REF_TO INT
    VAR_INPUT i : INT; END_VAR
    Cell := REF(cells[i]);
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR c : Cells; x : INT; END_VAR
  c.Cell(2)^ := 42;
  c.Cell(1)^ := c.Cell(2)^ + 1;
  x := c.Cell(1)^;
END_PROGRAM
""")
    assert (plc["main.c.cells"], plc["main.x"]) == ([0, 43, 42, 0], 43)


def test_methods_of_a_global_instance_from_two_programs():
    plc = run(
        """
VAR_GLOBAL g : Acc; END_VAR
FUNCTION_BLOCK Acc
  VAR_OUTPUT total : INT; END_VAR
  METHOD Add VAR_INPUT v : INT; END_VAR total := total + v; END_METHOD
END_FUNCTION_BLOCK
PROGRAM p1 g.Add(1); END_PROGRAM
PROGRAM p2 VAR t : INT; END_VAR g.Add(10); t := g.total; END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t1(INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM i1 WITH t1 : p1;
  PROGRAM i2 WITH t1 : p2;
END_RESOURCE END_CONFIGURATION
""",
        3,
    )
    assert plc["i2.t"] == 33


def test_methods_and_properties_after_end_function_block_twincat_layout():
    plc = run(
        """
FUNCTION_BLOCK FB_Valve
VAR_INPUT
  bOpen : BOOL;
END_VAR
VAR_OUTPUT
  nState : INT;
END_VAR
VAR
  _nCycles : UDINT;
END_VAR
IF bOpen THEN nState := 1; ELSE nState := 0; END_IF
END_FUNCTION_BLOCK

METHOD PUBLIC M_Open : BOOL
VAR_INPUT
  bForce : BOOL;
END_VAR
bOpen := TRUE;
_nCycles := _nCycles + 1;
M_Open := bForce OR TRUE;
END_METHOD

PROPERTY PUBLIC Cycles : UDINT
GET
Cycles := _nCycles;
END_GET
END_PROPERTY

PROGRAM MAIN
VAR
  fbValve : FB_Valve;
  bRes : BOOL;
  nCyc : UDINT;
END_VAR
bRes := fbValve.M_Open(bForce := FALSE);
fbValve();
nCyc := fbValve.Cycles;
END_PROGRAM
""",
        2,
        dialect="twincat",
    )
    assert (plc["MAIN.bRes"], plc["MAIN.fbValve.nState"], plc["MAIN.nCyc"]) == (True, 1, 2)


def test_a_method_of_a_program():
    plc = run(
        """
PROGRAM main
  VAR x : INT; y : INT; END_VAR
  METHOD Twice : INT
    VAR_INPUT v : INT; END_VAR
    Twice := v * 2;
  END_METHOD
  x := x + 1;
  y := Twice(x);
END_PROGRAM
""",
        3,
        dialect="codesys",
    )
    assert (plc["main.x"], plc["main.y"]) == (3, 6)


# --------------------------------------------------------------------------- properties


def test_property_setter_clamps_and_methods_use_this_property():
    plc = run("""
FUNCTION_BLOCK Tank
  VAR _level : REAL; writes : INT; END_VAR
  PROPERTY Level : REAL
  GET
    Level := _level;
  END_GET
  SET
    IF Level < 0.0 THEN _level := 0.0;
    ELSIF Level > 100.0 THEN _level := 100.0;
    ELSE _level := Level; END_IF;
    writes := writes + 1;
  END_SET
  END_PROPERTY
  METHOD Fill
    VAR_INPUT amount : REAL; END_VAR
    THIS^.Level := THIS^.Level + amount;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR t : Tank; a, c, d : REAL; END_VAR
  t.Level := 150.0;
  a := t.Level;
  t.Level := -5.0;
  c := t.Level;
  t.Fill(30.0);
  t.Fill(amount := 20.0);
  d := t.Level;
END_PROGRAM
""")
    assert (plc["main.a"], plc["main.c"], plc["main.d"], plc["main.t.writes"]) == (100.0, 0.0, 50.0, 4)


def test_struct_and_array_properties_and_string_methods_in_conditions():
    plc = run("""
TYPE Pt : STRUCT x : INT; y : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK F
  VAR p : Pt := (x := 3, y := 4); arr : ARRAY[1..3] OF INT := [1,2,3]; END_VAR
  PROPERTY Pos : Pt
  GET Pos := p; END_GET
  SET p := Pos; END_SET
  END_PROPERTY
  PROPERTY Items : ARRAY[1..3] OF INT
  GET Items := arr; END_GET
  END_PROPERTY
  METHOD Label : STRING(40)
    VAR_INPUT pre : STRING; END_VAR
    Label := CONCAT(pre, INT_TO_STRING(p.x));
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; a, b : INT; q : Pt; s : STRING; ok : BOOL; END_VAR
  a := f.Pos.x + f.Pos.y;
  b := f.Items[2];
  q.x := 10; q.y := 20;
  f.Pos := q;
  s := f.Label(f.Label('n='));
  IF f.Pos.y = 20 AND f.Label('') = '10' THEN ok := TRUE; END_IF;
END_PROGRAM
""")
    assert (plc["main.a"], plc["main.b"], plc["main.s"], plc["main.ok"]) == (7, 2, "n=1010", True)
    assert plc["main.f.p"] == {"x": 10, "y": 20}


def test_class_extends_and_implements_with_an_interface_property():
    plc = run("""
INTERFACE ICount
  METHOD Inc : DINT
  END_METHOD
  PROPERTY Value : DINT
  GET END_GET
  SET END_SET
  END_PROPERTY
END_INTERFACE
CLASS Counter IMPLEMENTS ICount
  VAR PROTECTED v : DINT; END_VAR
  METHOD PUBLIC Inc : DINT
    v := v + 1; Inc := v;
  END_METHOD
  PROPERTY PUBLIC Value : DINT
  GET Value := v; END_GET
  SET v := Value; END_SET
  END_PROPERTY
END_CLASS
CLASS StepCounter EXTENDS Counter
  VAR PUBLIC stepSize : DINT := 5; END_VAR
  METHOD PUBLIC OVERRIDE Inc : DINT
    v := v + stepSize; Inc := v;
  END_METHOD
END_CLASS
PROGRAM main VAR c : Counter; s : StepCounter; i : ICount; a, b, d : DINT; END_VAR
  i := s;
  i.Value := 100;
  a := i.Inc();
  i := c;
  b := i.Inc();
  i.Value := i.Value + 40;
  d := c.Value;
END_PROGRAM
""")
    assert (plc["main.a"], plc["main.b"], plc["main.d"]) == (105, 1, 41)


# --------------------------------------------------------------------------- interfaces


def test_interface_array_dispatch_with_extended_interface_and_property():
    plc = run("""
INTERFACE IShape
  METHOD Area : REAL
  END_METHOD
  PROPERTY Name : STRING
  GET
  END_GET
  END_PROPERTY
END_INTERFACE
INTERFACE IScalable EXTENDS IShape
  METHOD Scale
    VAR_INPUT f : REAL; END_VAR
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK Sq IMPLEMENTS IScalable
  VAR side : REAL := 2.0; END_VAR
  METHOD Area : REAL
    Area := side * side;
  END_METHOD
  METHOD Scale
    VAR_INPUT f : REAL; END_VAR
    side := side * f;
  END_METHOD
  PROPERTY Name : STRING
  GET
    Name := 'sq';
  END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK Rect IMPLEMENTS IShape
  VAR w : REAL := 2.0; h : REAL := 3.0; END_VAR
  METHOD Area : REAL
    Area := w * h;
  END_METHOD
  PROPERTY Name : STRING
  GET
    Name := 'rect';
  END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main
  VAR s : Sq; r : Rect; arr : ARRAY[1..2] OF IShape; i : INT; total : REAL; names : STRING;
      sc : IScalable; END_VAR
  sc := s;
  sc.Scale(f := 3.0);
  arr[1] := sc;
  arr[2] := r;
  total := 0.0; names := '';
  FOR i := 1 TO 2 DO
    total := total + arr[i].Area();
    names := CONCAT(names, arr[i].Name);
  END_FOR;
END_PROGRAM
""")
    assert (plc["main.total"], plc["main.names"], plc["main.s.side"]) == (42.0, "sqrect", 6.0)


ABSTRACT_SENSORS = """
INTERFACE ISensor
  METHOD Read : INT
  END_METHOD
END_INTERFACE
INTERFACE INamed
  METHOD GetName : STRING
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK ABSTRACT Base IMPLEMENTS ISensor
  VAR_INPUT offset : INT; END_VAR
  METHOD ABSTRACT Raw : INT
  END_METHOD
  METHOD Read : INT
    Read := Raw() + offset;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Temp EXTENDS Base IMPLEMENTS INamed
  METHOD Raw : INT
    Raw := 20;
  END_METHOD
  METHOD GetName : STRING
    GetName := 'temp';
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Press EXTENDS Base
  METHOD Raw : INT
    Raw := 3;
  END_METHOD
END_FUNCTION_BLOCK
"""


def test_interfaces_as_inputs_outputs_and_assignment_attempts():
    plc = run(
        ABSTRACT_SENSORS
        + """
FUNCTION ReadTwice : INT
  VAR_INPUT s : ISensor; END_VAR
  ReadTwice := s.Read() * 2;
END_FUNCTION
FUNCTION_BLOCK Picker
  VAR_INPUT a, b : ISensor; useB : BOOL; END_VAR
  VAR_OUTPUT chosen : ISensor; END_VAR
  IF useB THEN chosen := b; ELSE chosen := a; END_IF;
END_FUNCTION_BLOCK
PROGRAM main
  VAR t : Temp; p : Press; pk : Picker; r1, r2, r3 : INT; n : INamed; n2 : INamed; s : ISensor;
      ok1, ok2 : BOOL; nm : STRING; q : ISensor; rb : REF_TO Base; rt : REF_TO Temp;
      rp : REF_TO Press; END_VAR
  t.offset := 1;
  r1 := ReadTwice(t);
  pk(a := t, b := p, useB := TRUE);
  r2 := pk.chosen.Read();
  s := t;
  n ?= s;
  s := p;
  n2 ?= s;
  ok1 := __QUERYINTERFACE(t, q);
  IF n <> NULL THEN nm := n.GetName(); END_IF;
  rb := REF(t);
  rt ?= rb;
  rp ?= rb;
  r3 := rt^.Read();
  ok2 := rp = NULL;
END_PROGRAM
"""
    )
    assert (plc["main.r1"], plc["main.r2"], plc["main.r3"]) == (42, 3, 21)
    assert (plc["main.n"], plc["main.n2"], plc["main.q"]) == ("Temp", None, "Temp")
    assert (plc["main.ok1"], plc["main.ok2"], plc["main.nm"]) == (True, True, "temp")


def test_observer_pattern_with_this_registered_through_a_reference():
    plc = run("""
INTERFACE IObserver
  METHOD Notify
    VAR_INPUT v : INT; END_VAR
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK Subject
  VAR obs : ARRAY[0..3] OF IObserver; n : INT; END_VAR
  METHOD Attach : BOOL
    VAR_INPUT o : IObserver; END_VAR
    IF n > 3 THEN Attach := FALSE; RETURN; END_IF;
    obs[n] := o; n := n + 1; Attach := TRUE;
  END_METHOD
  METHOD Publish
    VAR_INPUT v : INT; END_VAR
    VAR i : INT; END_VAR
    FOR i := 0 TO n - 1 DO obs[i].Notify(v); END_FOR;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Summer IMPLEMENTS IObserver
  VAR_OUTPUT sum : INT; END_VAR
  METHOD Notify
    VAR_INPUT v : INT; END_VAR
    sum := sum + v;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Maxer IMPLEMENTS IObserver
  VAR_OUTPUT mx : INT; END_VAR
  VAR_INPUT subj : REF_TO Subject; END_VAR
  METHOD Notify
    VAR_INPUT v : INT; END_VAR
    mx := MAX(mx, v);
  END_METHOD
  METHOD Register
    subj^.Attach(THIS^);
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR s : Subject; a, b : Summer; m : Maxer; ok : BOOL; END_VAR
  ok := s.Attach(a);
  s.Attach(b);
  m.subj := REF(s);
  m.Register();
  s.Publish(5); s.Publish(-2); s.Publish(3);
END_PROGRAM
""")
    assert (plc["main.a.sum"], plc["main.b.sum"], plc["main.m.mx"]) == (6, 6, 5)
    assert (plc["main.ok"], plc["main.s.n"]) == (True, 3)


def test_method_returning_an_interface_chained_and_compared():
    plc = run("""
INTERFACE IVal
  METHOD Get : INT
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK V IMPLEMENTS IVal
  VAR_INPUT k : INT; END_VAR
  METHOD Get : INT
    Get := k;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Factory
  VAR a : V := (k := 1); b : V := (k := 2); END_VAR
  METHOD Pick : IVal
    VAR_INPUT second : BOOL; END_VAR
    IF second THEN Pick := b; ELSE Pick := a; END_IF;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : Factory; x, y : INT; i : IVal; same : BOOL; END_VAR
  x := f.Pick(FALSE).Get();
  i := f.Pick(TRUE);
  y := i.Get();
  same := i = f.Pick(TRUE);
END_PROGRAM
""")
    assert (plc["main.x"], plc["main.y"], plc["main.same"]) == (1, 2, True)


def test_interface_extending_two_interfaces_upcasts_and_assignment_attempt_back():
    plc = run("""
INTERFACE IA
  METHOD A : INT
  END_METHOD
END_INTERFACE
INTERFACE IB
  METHOD B : INT
  END_METHOD
END_INTERFACE
INTERFACE IC EXTENDS IA, IB
  METHOD C : INT
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK X IMPLEMENTS IC
  METHOD A : INT  A := 1; END_METHOD
  METHOD B : INT  B := 2; END_METHOD
  METHOD C : INT  C := 4; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR x : X; ic : IC; ia : IA; ib : IB; ic2 : IC; r : INT; ok : BOOL; END_VAR
  ic := x;
  ia := ic;
  ib := ic;
  r := ic.A() + ic.B() + ic.C() + ia.A() * 10 + ib.B() * 100;
  ic2 ?= ia;
  ok := ic2 = ic;
END_PROGRAM
""")
    assert (plc["main.r"], plc["main.ok"]) == (217, True)


def test_one_method_serves_two_interfaces_and_interfaces_in_struct_fields():
    plc = run("""
INTERFACE IA METHOD Go : INT END_METHOD END_INTERFACE
INTERFACE IB METHOD Go : INT END_METHOD END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS IA, IB
  VAR_INPUT k : INT := 7; END_VAR
  METHOD Go : INT Go := k; END_METHOD
END_FUNCTION_BLOCK
TYPE Slot : STRUCT name : STRING; h : IA; END_STRUCT END_TYPE
PROGRAM main VAR f : F; g : F := (k := 9); a : IA; b : IB; x, y : INT; s : ARRAY[1..2] OF Slot; END_VAR
  a := f; b := f;
  x := a.Go() + b.Go();
  s[2].h := g;
  y := s[2].h.Go();
END_PROGRAM
""")
    assert (plc["main.x"], plc["main.y"]) == (14, 9)


def test_query_interface_and_assignment_attempt_from_null():
    plc = run(
        """
INTERFACE I
  METHOD M : INT
  END_METHOD
END_INTERFACE
INTERFACE J
  METHOD N : INT
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
  METHOD M : INT M := 1; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR i : I; j : J; f : F; ok1, ok2 : BOOL := TRUE; END_VAR
  j ?= i;
  ok1 := j = NULL;
  i := f;
  ok2 := __QUERYINTERFACE(i, j);
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.ok1"], plc["main.ok2"], plc["main.j"]) == (True, False, None)


# --------------------------------------------------------------------------- references, vendor extensions


def test_reference_to_pointer_and_sizeof():
    plc = run(
        """
TYPE S : STRUCT a : INT; b : ARRAY[1..3] OF INT; END_STRUCT END_TYPE
TYPE STRUCT_T : STRUCT a : BYTE; b : LREAL; c : INT; d : STRING(10); END_STRUCT END_TYPE
PROGRAM main VAR s : S; rr : REFERENCE TO INT; p : POINTER TO S; ok : BOOL; sz1, sz2, sz3 : DINT;
  t : STRUCT_T; END_VAR
  rr REF= s.b[2];
  rr := 7;
  p := ADR(s);
  p^.a := 42;
  ok := __ISVALIDREF(rr);
  sz1 := SIZEOF(s);
  sz2 := SIZEOF(LREAL);
  sz3 := SIZEOF(t);
END_PROGRAM
""",
        dialect="codesys",
    )
    assert plc["main.s"] == {"a": 42, "b": [0, 7, 0]}
    assert (plc["main.ok"], plc["main.sz1"], plc["main.sz2"], plc["main.sz3"]) == (True, 8, 8, 32)


def test_linked_list_of_classes_built_with_new_and_a_recursive_method():
    plc = run(
        """
CLASS Node
  VAR val : INT; next : POINTER TO Node; END_VAR
  METHOD Init
    VAR_INPUT v : INT; END_VAR
    val := v; next := NULL;
  END_METHOD
  METHOD SumAll : INT
    IF next = NULL THEN SumAll := val;
    ELSE SumAll := val + next^.SumAll(); END_IF;
  END_METHOD
END_CLASS
PROGRAM main
  VAR head, n2, n3 : POINTER TO Node; total : INT; gone : BOOL; END_VAR
  head := __NEW(Node); n2 := __NEW(Node); n3 := __NEW(Node);
  head^.Init(1); n2^.Init(20); n3^.Init(300);
  head^.next := n2; n2^.next := n3;
  total := head^.SumAll();
  __DELETE(n3);
  gone := n3 = NULL;
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.total"], plc["main.gone"]) == (321, True)


def test_base_reference_and_pointer_to_a_derived_instance_dispatch_virtually():
    plc = run(
        """
FUNCTION_BLOCK Shape
  METHOD Area : REAL
    Area := 0.0;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Circle EXTENDS Shape
  VAR_INPUT r : REAL; END_VAR
  METHOD Area : REAL
    Area := 3.0 * r * r;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR c : Circle; rs : REF_TO Shape; p : POINTER TO Shape; a1, a2 : REAL; END_VAR
  c.r := 2.0;
  rs := REF(c);
  a1 := rs^.Area();
  p := ADR(c);
  a2 := p^.Area();
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.a1"], plc["main.a2"]) == (12.0, 12.0)


def test_var_inst_and_var_stat_in_methods():
    plc = run(
        """
FUNCTION_BLOCK C
  METHOD Tick : INT
    VAR_INST n : INT; END_VAR
    VAR_STAT shared : INT; END_VAR
    VAR tmp : INT; END_VAR
    n := n + 1; shared := shared + 1; tmp := tmp + 1;
    Tick := n * 100 + shared * 10 + tmp;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR a, b : C; r1, r2, r3 : INT; END_VAR
  r1 := a.Tick();
  r2 := a.Tick();
  r3 := b.Tick();
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.r1"], plc["main.r2"], plc["main.r3"]) == (111, 221, 131)


def test_var_stat_in_a_function_block_and_a_function():
    plc = run(
        """
FUNCTION_BLOCK Id
  VAR_STAT next : INT := 100; END_VAR
  VAR_OUTPUT id : INT; END_VAR
  IF id = 0 THEN next := next + 1; id := next; END_IF;
END_FUNCTION_BLOCK
FUNCTION Seq : INT
  VAR_STAT c : INT; END_VAR
  c := c + 1; Seq := c;
END_FUNCTION
PROGRAM main VAR a, b, c : Id; s : INT; END_VAR
  a(); b(); c(); a();
  s := Seq() + Seq();
END_PROGRAM
""",
        2,
        dialect="codesys",
    )
    assert (plc["main.a.id"], plc["main.b.id"], plc["main.c.id"], plc["main.s"]) == (101, 102, 103, 7)


def test_fb_init_chain_with_declaration_arguments():
    plc = run(
        """
FUNCTION_BLOCK Base
  VAR_OUTPUT log : STRING; id : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; nId : INT; END_VAR
    id := nId; log := CONCAT(log, 'B');
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
  VAR_OUTPUT scale : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; nId : INT; nScale : INT; END_VAR
    scale := nScale; log := CONCAT(log, 'D');
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR d : Derived(nId := 5, nScale := 3); b : Base(nId := 9); END_VAR
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.d.log"], plc["main.d.id"], plc["main.d.scale"], plc["main.b.id"]) == ("BD", 5, 3, 9)


def test_attribute_pragmas_are_accepted_in_codesys():
    plc = run(
        """
{attribute 'qualified_only'}
VAR_GLOBAL
  g : INT := 4;
END_VAR
{attribute 'hide'}
FUNCTION_BLOCK {attribute 'no_explicit_call' := 'do not call'} F
  VAR_OUTPUT o : INT; END_VAR
  {attribute 'monitoring' := 'call'}
  PROPERTY P : INT
  GET P := o + 1; END_GET
  END_PROPERTY
  {attribute 'call_after_init'}
  METHOD M : INT
    M := 10;
  END_METHOD
  o := 1;
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; {attribute 'hide'} x : INT; y : INT; END_VAR
  f();
  x := f.M() + f.P;
  y := g;
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.x"], plc["main.y"]) == (12, 4)


# --------------------------------------------------------------------------- runtime faults


def test_null_faults_carry_the_st_line():
    _, f = fault("""
INTERFACE I
  METHOD M : INT
  END_METHOD
END_INTERFACE
PROGRAM main VAR i : I; x : INT; ok : BOOL; END_VAR
  ok := i = NULL;
  x := 1;
  x := i.M();
END_PROGRAM
""")
    assert (f.kind, f.line) == ("NULL", 9)
    _, f = fault("""
FUNCTION_BLOCK A
  VAR_OUTPUT v : INT; END_VAR
END_FUNCTION_BLOCK
PROGRAM main VAR r : REF_TO A; x : INT; END_VAR
  x := 1;
  x := r^.v;
END_PROGRAM
""")
    assert (f.kind, f.line) == ("NULL", 7)
    plc, f = fault(
        """
PROGRAM main VAR p : POINTER TO INT; x : INT; END_VAR
  p := __NEW(INT);
  p^ := 5;
  x := p^;
  __DELETE(p);
  x := p^;
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (f.kind, f.line, plc["main.x"]) == ("NULL", 7, 5)


# --------------------------------------------------------------------------- diagnostics

DIAGNOSTICS = [
    (
        """
INTERFACE I
  METHOD M : INT
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; END_VAR END_PROGRAM
""",
        "conf.st:6:16: error[E047]: F does not implement method M of interface I",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD M : INT
    VAR_INPUT x : INT; END_VAR
    M := x;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD M : REAL
    VAR_INPUT x : INT; END_VAR
    M := 1.0;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR END_PROGRAM
""",
        "conf.st:9:10: error[E047]: method M overrides A.M with a different signature",
    ),
    (
        """
INTERFACE I
  METHOD M : INT
    VAR_INPUT x : INT; END_VAR
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
  METHOD M : INT
    VAR_INPUT x : DINT; END_VAR
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; END_VAR END_PROGRAM
""",
        "conf.st:8:10: error[E047]: method M of F does not match I.M",
    ),
    (
        """
FUNCTION_BLOCK ABSTRACT A
  METHOD ABSTRACT M : INT
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD M : INT
    M := SUPER^.M() + 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR END_PROGRAM
""",
        "conf.st:8:10: error[E061]: method M of A is ABSTRACT: it has no implementation to call",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD PRIVATE M : INT
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD N : INT
    N := M() + 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; x : INT; END_VAR
  x := b.N();
END_PROGRAM
""",
        "conf.st:9:10: error[E043]: method M of A is PRIVATE: only A itself may use it",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD PROTECTED M : INT
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD N : INT
    N := M() + 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; x : INT; END_VAR
  x := b.N();
  x := b.M();
END_PROGRAM
""",
        "conf.st:14:8: error[E043]: method M of A is PROTECTED: only A and the blocks that extend it may use it",
    ),
    (
        """
FUNCTION_BLOCK F
  PROPERTY PROTECTED P : INT
  GET P := 1; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; x : INT; END_VAR
  x := f.P;
END_PROGRAM
""",
        "conf.st:8:10: error[E043]: property P of F is PROTECTED",
    ),
    (
        """
FUNCTION_BLOCK A
  VAR PRIVATE secret : INT; END_VAR
END_FUNCTION_BLOCK
PROGRAM main VAR a : A; x : INT; END_VAR
  x := a.secret;
END_PROGRAM
""",
        "conf.st:6:10: error[E043]: variable secret of A is PRIVATE: only A itself may use it",
    ),
    (
        """
FUNCTION_BLOCK ABSTRACT A
  VAR x : INT; END_VAR
END_FUNCTION_BLOCK
PROGRAM main VAR a : A; END_VAR END_PROGRAM
""",
        "conf.st:5:22: error[E061]: 'A' is ABSTRACT and cannot be instantiated",
    ),
    (
        """
FUNCTION_BLOCK ABSTRACT A
END_FUNCTION_BLOCK
PROGRAM main VAR p : POINTER TO A; END_VAR
  p := __NEW(A);
END_PROGRAM
""",
        "conf.st:5:14: error[E061]: 'A' is ABSTRACT and cannot be instantiated",
    ),
    (
        """
FUNCTION_BLOCK FINAL A
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR END_PROGRAM
""",
        "conf.st:4:16: error[E047]: 'A' is FINAL and cannot be extended",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD FINAL M : INT
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD M : INT
    M := 2;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR END_PROGRAM
""",
        "conf.st:8:10: error[E047]: method M of A is FINAL and cannot be overridden",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD OVERRIDE M : INT
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR a : A; END_VAR END_PROGRAM
""",
        "conf.st:3:19: error[E047]: method M is marked OVERRIDE but A inherits no method of that name",
    ),
    (
        """
FUNCTION_BLOCK ABSTRACT A
  METHOD ABSTRACT M : INT
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR END_PROGRAM
""",
        "conf.st:6:16: error[E061]: B does not implement the ABSTRACT method M of A",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD ABSTRACT M : INT
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR a : A; END_VAR END_PROGRAM
""",
        "conf.st:3:19: error[E061]: ABSTRACT method M in A, which is not ABSTRACT",
    ),
    (
        """
FUNCTION_BLOCK ABSTRACT A
  METHOD ABSTRACT M : INT
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main END_PROGRAM
""",
        "conf.st:3:19: error[E061]: ABSTRACT method M has a body",
    ),
    (
        """
INTERFACE I
  METHOD M : INT
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK F
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; i : I; END_VAR
  i := f;
END_PROGRAM
""",
        "conf.st:9:8: error[E013]: cannot assign F to I: F does not implement I",
    ),
    (
        """
INTERFACE IA
  METHOD A : INT
  END_METHOD
END_INTERFACE
INTERFACE IB EXTENDS IA
  METHOD B : INT
  END_METHOD
END_INTERFACE
PROGRAM main VAR a : IA; b : IB; END_VAR
  a := b;
  b := a;
END_PROGRAM
""",
        "conf.st:12:8: error[E013]: cannot assign IA to IB: IA does not implement IB",
    ),
    (
        """
FUNCTION_BLOCK A
  PROPERTY P : INT
  GET P := 1; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR a : A; END_VAR
  a.P := 3;
END_PROGRAM
""",
        "conf.st:8:3: error[E018]: property P has no SET: it cannot be written",
    ),
    (
        """
FUNCTION_BLOCK F
  VAR v : INT; END_VAR
  PROPERTY P : INT
  SET v := P; END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; x : INT; END_VAR
  x := f.P;
END_PROGRAM
""",
        "conf.st:9:8: error[E023]: property P has no GET: it cannot be read",
    ),
    (
        """
INTERFACE I
  PROPERTY P : INT
  GET END_GET
  END_PROPERTY
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
  PROPERTY P : DINT
  GET P := 1; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main END_PROGRAM
""",
        "conf.st:7:16: error[E047]: F does not implement property P of interface I",
    ),
    (
        """
FUNCTION_BLOCK F
  METHOD M : INT
    VAR_INPUT a : INT; END_VAR
    M := a;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; x : INT; END_VAR
  x := f.M(b := 1);
END_PROGRAM
""",
        "conf.st:9:12: error[E016]: M has no parameter 'b' (parameters: a)",
    ),
    (
        """
FUNCTION_BLOCK F
  METHOD M
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main END_PROGRAM
""",
        "conf.st:3:10: error[E059]: METHOD M has no return type but assigns a result",
    ),
    (
        """
FUNCTION_BLOCK A
  METHOD M : INT
    M := 1;
  END_METHOD
  METHOD M : INT
    M := 2;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main END_PROGRAM
""",
        "conf.st:6:10: error[E011]: 'M' is declared twice in A",
    ),
    (
        """
FUNCTION_BLOCK F IMPLEMENTS INope
END_FUNCTION_BLOCK
PROGRAM main END_PROGRAM
""",
        "conf.st:2:16: error[E010]: F IMPLEMENTS: 'INope' is not declared",
    ),
]


@pytest.mark.parametrize("src,diagnostic", DIAGNOSTICS)
def test_oop_mistakes_give_located_diagnostics(src, diagnostic):
    text = errors(src)
    assert diagnostic in text and "Traceback" not in text


def test_dialect_presets_gate_oop_and_vendor_extensions():
    oop = """
INTERFACE I
  METHOD M : INT
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
  METHOD M : INT
    M := 1;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; x : INT; END_VAR
  x := f.M();
END_PROGRAM
"""
    text = errors(oop, dialect="openplc")
    assert "conf.st:2:11: error[E044]: INTERFACE is not part of the openplc dialect" in text
    assert "conf.st:7:10: error[E044]: METHOD is not part of the openplc dialect" in text
    assert "conf.st:3:11: error[E044]: INTERFACE is not part of the openplc dialect" in errors(
        "{dialect 'openplc'}\n" + oop
    )
    assert run(oop, dialect="iec")["main.x"] == 1
    ptr = """
PROGRAM main VAR x : INT; p : POINTER TO INT; END_VAR
  p := ADR(x);
END_PROGRAM
"""
    text = errors(ptr, dialect="iec")
    assert "conf.st:2:31: error[E044]: POINTER TO is not part of the iec dialect" in text
    assert "conf.st:3:8: error[E044]: ADR is not part of the iec dialect" in text
    plc = run(
        """
PROGRAM main VAR x : INT; p : REF_TO INT; END_VAR
  p := REF(x);
  p^ := 3;
END_PROGRAM
""",
        dialect="iec",
    )
    assert plc["main.x"] == 3


# --------------------------------------------------------------------------- more runtime probes


def test_methods_named_like_common_words():
    plc = run("""
FUNCTION_BLOCK F
  VAR_OUTPUT log : INT; END_VAR
  METHOD Set : BOOL VAR_INPUT v : INT; END_VAR log := log + v; Set := TRUE; END_METHOD
  METHOD Reset log := 0; END_METHOD
  METHOD Step log := log + 1; END_METHOD
  METHOD Execute : BOOL Execute := TRUE; END_METHOD
  METHOD Init log := 100; END_METHOD
  METHOD Start log := log + 2; END_METHOD
  METHOD Value : INT Value := log; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; v : INT; b : BOOL; END_VAR
  f.Init(); f.Set(5); f.Step(); f.Start(); b := f.Execute();
  v := f.Value();
END_PROGRAM
""")
    assert (plc["main.v"], plc["main.b"]) == (108, True)


def test_interface_provided_by_inherited_members_and_outputs_through_an_interface():
    plc = run("""
INTERFACE I
  METHOD M : INT END_METHOD
  PROPERTY P : INT GET END_GET END_PROPERTY
END_INTERFACE
INTERFACE IS
  METHOD Split : BOOL
    VAR_INPUT v : INT; END_VAR
    VAR_OUTPUT hi, lo : INT; END_VAR
    VAR_IN_OUT cnt : INT; END_VAR
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK A
  METHOD M : INT M := 3; END_METHOD
  PROPERTY P : INT GET P := 4; END_GET END_PROPERTY
  METHOD Split : BOOL
    VAR_INPUT v : INT; END_VAR
    VAR_OUTPUT hi, lo : INT; END_VAR
    VAR_IN_OUT cnt : INT; END_VAR
    hi := v / 100; lo := v MOD 100; cnt := cnt + 1; Split := TRUE;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A IMPLEMENTS I, IS
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; i : I; s : IS; x, h, l, c : INT; ok : BOOL; END_VAR
  i := b;
  x := i.M() + i.P;
  s := b;
  ok := s.Split(v := 1234, hi => h, lo => l, cnt := c);
  s.Split(567, h, l, c);
END_PROGRAM
""")
    assert (plc["main.x"], plc["main.h"], plc["main.l"], plc["main.c"], plc["main.ok"]) == (7, 5, 67, 2, True)


def test_this_as_a_reference_and_abstract_property_and_property_locals():
    plc = run("""
FUNCTION_BLOCK ABSTRACT A
  VAR arr : ARRAY[1..4] OF INT := [1,2,3,4]; END_VAR
  VAR_OUTPUT x : INT; END_VAR
  PROPERTY ABSTRACT P : INT
  GET END_GET
  END_PROPERTY
  PROPERTY Sum : INT
  GET
    VAR i : INT; s : INT; END_VAR
    FOR i := 1 TO 4 DO s := s + arr[i]; END_FOR;
    Sum := s;
  END_GET
  END_PROPERTY
  METHOD Twice : INT Twice := P * 2; END_METHOD
  METHOD Me : REF_TO A
    Me := THIS;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  PROPERTY P : INT
  GET P := 21; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; t, s1, s2 : INT; r : REF_TO A; END_VAR
  t := b.Twice();
  s1 := b.Sum; s2 := b.Sum;
  r := b.Me();
  r^.x := 9;
END_PROGRAM
""")
    assert (plc["main.t"], plc["main.s1"], plc["main.s2"], plc["main.b.x"]) == (42, 10, 10, 9)


def test_super_skips_a_level_that_does_not_override_and_this_stays_virtual():
    plc = run("""
FUNCTION_BLOCK A
  METHOD M : INT M := 1; END_METHOD
  METHOD Who : STRING Who := 'A'; END_METHOD
  METHOD Desc : STRING Desc := THIS^.Who(); END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  METHOD Who : STRING Who := 'B'; END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK C EXTENDS B
  METHOD M : INT M := SUPER^.M() + 10; END_METHOD
  METHOD Who : STRING Who := 'C'; END_METHOD
  METHOD Desc : STRING Desc := CONCAT('c:', SUPER^.Desc()); END_METHOD
  METHOD W2 : STRING W2 := SUPER^.Who(); END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR c : C; x : INT; s, w : STRING; END_VAR
  x := c.M(); s := c.Desc(); w := c.W2();
END_PROGRAM
""")
    assert (plc["main.x"], plc["main.s"], plc["main.w"]) == (11, "c:C", "B")


def test_array_of_base_references_calls_methods_and_bodies_of_derived_instances():
    plc = run(
        """
FUNCTION_BLOCK Base
  VAR_OUTPUT calls : INT; END_VAR
  METHOD Id : INT Id := 1; END_METHOD
  calls := calls + Id();
END_FUNCTION_BLOCK
FUNCTION_BLOCK D1 EXTENDS Base
  METHOD Id : INT Id := 10; END_METHOD
  SUPER^();
END_FUNCTION_BLOCK
PROGRAM main VAR b : Base; d : D1; refs : ARRAY[0..1] OF REF_TO Base; i : INT; s : INT;
  p : POINTER TO Base; END_VAR
  refs[0] := REF(b); refs[1] := REF(d);
  FOR i := 0 TO 1 DO s := s + refs[i]^.Id(); refs[i]^(); END_FOR;
  p := ADR(d);
  p^();
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.s"], plc["main.b.calls"], plc["main.d.calls"]) == (11, 1, 20)


def test_assignment_attempt_from_an_instance_and_interfaces_swapped_in_out():
    plc = run("""
INTERFACE I METHOD M : INT END_METHOD END_INTERFACE
FUNCTION_BLOCK Base END_FUNCTION_BLOCK
FUNCTION_BLOCK D EXTENDS Base VAR_OUTPUT k : INT := 4; END_VAR END_FUNCTION_BLOCK
FUNCTION_BLOCK F IMPLEMENTS I VAR_INPUT k : INT; END_VAR METHOD M : INT M := k; END_METHOD END_FUNCTION_BLOCK
FUNCTION Swap
  VAR_IN_OUT a, b : I; END_VAR
  VAR t : I; END_VAR
  t := a; a := b; b := t;
END_FUNCTION
PROGRAM main VAR d : D; b : Base; rd : REF_TO D; rd2 : REF_TO D; k : INT; n : BOOL;
  f1 : F := (k := 1); f2 : F := (k := 2); i1, i2 : I; x : INT; eq : BOOL; END_VAR
  rd ?= d;
  k := rd^.k;
  rd2 ?= b;
  n := rd2 = NULL;
  i1 := f1; i2 := f2;
  Swap(i1, i2);
  x := i1.M() * 10 + i2.M();
  eq := i1 = f2;
END_PROGRAM
""")
    assert (plc["main.k"], plc["main.n"], plc["main.x"], plc["main.eq"]) == (4, True, 21, True)


def test_properties_through_array_elements_interfaces_pointers_and_references():
    plc = run(
        """
INTERFACE IP PROPERTY P : INT GET END_GET SET END_SET END_PROPERTY END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS IP
  VAR v : INT; END_VAR
  PROPERTY P : INT
  GET P := v; END_GET
  SET v := P * 2; END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR fs : ARRAY[1..3] OF F; is : ARRAY[1..3] OF IP; i : INT; p : POINTER TO F;
  r : REFERENCE TO F; rr : REF_TO F; s : DINT; END_VAR
  fs[1].P := 1;
  is[2] := fs[2];
  is[2].P := 2;
  p := ADR(fs[3]);
  p^.P := 3;
  r REF= fs[3];
  r.P := r.P + 1;
  rr := REF(fs[1]);
  rr^.P := rr^.P + 10;
  FOR i := 1 TO 3 DO s := s * 100 + fs[i].P; END_FOR;
END_PROGRAM
""",
        dialect="codesys",
    )
    assert plc["main.s"] == 240414


def test_method_results_of_many_types_truncation_and_early_return():
    plc = run("""
TYPE Color : (Red, Green := 5, Blue); END_TYPE
FUNCTION_BLOCK F
  METHOD Short : STRING(5)
    Short := 'abcdefgh';
  END_METHOD
  METHOD TakeShort : INT
    VAR_INPUT s : STRING(3); END_VAR
    TakeShort := LEN(s);
  END_METHOD
  METHOD Dur : TIME Dur := T#1s500ms; END_METHOD
  METHOD Pi : LREAL Pi := 3.25; END_METHOD
  METHOD Col : Color Col := Blue; END_METHOD
  METHOD Never : INT END_METHOD
  METHOD Early : INT
    Early := 1;
    IF TRUE THEN RETURN; END_IF;
    Early := 2;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; s : STRING; n : INT; t : TIME; l : LREAL; c : Color; nv : INT := 5;
  e : INT; ci : INT; ok : BOOL; END_VAR
  s := f.Short();
  n := f.TakeShort('abcdef');
  t := f.Dur();
  ok := t = T#1500ms;
  l := f.Pi();
  c := f.Col();
  ci := TO_INT(c);
  nv := f.Never();
  e := f.Early();
END_PROGRAM
""")
    assert (plc["main.s"], plc["main.n"], plc["main.ok"], plc["main.l"]) == ("abcde", 3, True, 3.25)
    assert (plc["main.c"], plc["main.ci"], plc["main.nv"], plc["main.e"]) == ("Blue", 6, 0, 1)


def test_derived_body_uses_inherited_property_action_and_super_method_bare():
    plc = run("""
FUNCTION_BLOCK A
  VAR v : INT := 2; END_VAR
  PROPERTY P : INT GET P := v; END_GET SET v := P; END_SET END_PROPERTY
  METHOD M : INT M := 100; END_METHOD
  ACTION Dbl v := v * 2; END_ACTION
  METHOD CallDbl THIS^.Dbl(); END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B EXTENDS A
  VAR_OUTPUT o : INT; END_VAR
  METHOD M : INT M := 1; END_METHOD
  P := P + 1;
  Dbl();
  o := P + SUPER^.M() + M();
END_FUNCTION_BLOCK
PROGRAM main VAR b : B; END_VAR
  b();
  b.CallDbl();
END_PROGRAM
""")
    assert (plc["main.b.o"], plc["main.b.v"]) == (107, 12)


def test_fb_init_runs_inner_instances_first_in_arrays():
    plc = run(
        """
FUNCTION_BLOCK Cell
  VAR_OUTPUT id : INT; END_VAR
  VAR_STAT n : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
    n := n + 1; id := n;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Holder
  VAR cells : ARRAY[1..3] OF Cell; END_VAR
  VAR_OUTPUT first : INT; END_VAR
  METHOD FB_init : BOOL
    VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
    first := cells[3].id;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR h : Holder; END_VAR
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.h.cells[1].id"], plc["main.h.cells[3].id"], plc["main.h.first"]) == (1, 3, 3)


def test_globals_in_methods_directly_and_through_the_blocks_var_external():
    plc = run("""
VAR_GLOBAL gCount : INT; END_VAR
FUNCTION_BLOCK F
  VAR_EXTERNAL gCount : INT; END_VAR
  METHOD Bump : INT
    gCount := gCount + 1;
    Bump := gCount;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK G
  METHOD Bump : INT
    gCount := gCount + 10;
    Bump := gCount;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; g : G; x, y : INT; END_VAR
  x := f.Bump();
  y := g.Bump();
END_PROGRAM
""")
    assert (plc["main.x"], plc["main.y"], plc["gCount"]) == (1, 11, 11)


# --------------------------------------------------------------------------- found by these probes, fixed


def test_super_property_in_an_overriding_property_reaches_the_base_accessors():
    plc = run("""
FUNCTION_BLOCK Tank
  VAR _level : REAL := 5.0; END_VAR
  PROPERTY Level : REAL
  GET Level := _level; END_GET
  SET _level := Level; END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK BigTank EXTENDS Tank
  PROPERTY Level : REAL
  GET Level := SUPER^.Level * 2.0; END_GET
  SET SUPER^.Level := Level * 3.0; END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR bt : BigTank; e, f : REAL; END_VAR
  e := bt.Level; bt.Level := 10.0; f := bt.Level;
END_PROGRAM
""")
    assert (plc["main.e"], plc["main.f"], plc["main.bt._level"]) == (10.0, 60.0, 30.0)


def test_a_derived_instance_binds_to_a_base_in_out_and_reference():
    plc = run("""
FUNCTION_BLOCK ABSTRACT Shape  METHOD ABSTRACT Area : REAL END_METHOD  END_FUNCTION_BLOCK
FUNCTION_BLOCK Circle EXTENDS Shape
  METHOD Area : REAL Area := 12.0; END_METHOD
END_FUNCTION_BLOCK
FUNCTION AreaOf : REAL  VAR_IN_OUT s : Shape; END_VAR  AreaOf := s.Area();  END_FUNCTION
FUNCTION_BLOCK User VAR_IN_OUT s : Shape; END_VAR VAR_OUTPUT a : REAL; END_VAR a := s.Area(); END_FUNCTION_BLOCK
PROGRAM main VAR c : Circle; u : User; a, b, d : REAL; r : REFERENCE TO Shape; END_VAR
  a := AreaOf(c);
  r REF= c;  b := r.Area();
  u(s := c); d := u.a;
END_PROGRAM
""")
    assert (plc["main.a"], plc["main.b"], plc["main.d"], plc["main.r"]) == (12.0, 12.0, 12.0, "REF(main.c)")


def test_var_external_in_a_method_and_a_property_accessor():
    plc = run(
        """
VAR_GLOBAL gCount : INT; END_VAR
FUNCTION_BLOCK F
  METHOD Bump : INT
    VAR_EXTERNAL gCount : INT; END_VAR
    gCount := gCount + 1; Bump := gCount;
  END_METHOD
  PROPERTY P : INT
    GET
      VAR_EXTERNAL gCount : INT; END_VAR
      P := gCount * 10;
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; x, y : INT; END_VAR  x := f.Bump(); y := f.P; END_PROGRAM
""",
        2,
    )
    assert (plc["main.x"], plc["main.y"], plc.globals()["gCount"]) == (2, 20, 2)


def test_an_instance_passed_to_a_function_input_is_a_copy():
    plc = run("""
FUNCTION_BLOCK Cnt  VAR_OUTPUT n : INT; END_VAR  METHOD Inc n := n + 1; END_METHOD  END_FUNCTION_BLOCK
FUNCTION UseCopy : INT  VAR_INPUT c : Cnt; END_VAR  c.Inc(); UseCopy := c.n;  END_FUNCTION
FUNCTION_BLOCK Holder METHOD Use : INT VAR_INPUT c : Cnt; END_VAR c(); c.Inc(); Use := c.n; END_METHOD END_FUNCTION_BLOCK
PROGRAM main VAR a : Cnt; h : Holder; r, s : INT; END_VAR
  a.Inc(); a.Inc();  r := UseCopy(a); s := h.Use(a);
END_PROGRAM
""")
    assert (plc["main.a.n"], plc["main.r"], plc["main.s"]) == (2, 3, 3)


def test_en_eno_on_method_calls():
    plc = run("""
FUNCTION_BLOCK F  VAR_OUTPUT k : INT; END_VAR
  METHOD M : INT VAR_INPUT x : INT; END_VAR M := x * 2; END_METHOD
  METHOD N VAR_INPUT x : INT; END_VAR k := x; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; r1 : INT; r2 : INT := -1; e1, e2, e3, e4 : BOOL; END_VAR
  r1 := f.M(EN := TRUE, x := 4, ENO => e1);
  r2 := f.M(EN := FALSE, x := 5, ENO => e2);
  f.N(EN := TRUE, x := 3, ENO => e3);
  f.N(EN := FALSE, x := 9, ENO => e4);
END_PROGRAM
""")
    assert [plc[f"main.{n}"] for n in ("r1", "r2", "e1", "e2", "e3", "e4", "f.k")] == [
        8,
        -1,
        True,
        False,
        True,
        False,
        3,
    ]


def test_reference_to_inputs_are_bound_to_the_argument():
    plc = run("""
FUNCTION AddTo : INT
  VAR_INPUT r : REFERENCE TO INT; n : INT; END_VAR
  r := r + n; AddTo := r;
END_FUNCTION
FUNCTION_BLOCK Inc VAR_INPUT r : REFERENCE TO INT; END_VAR r := r + 1; END_FUNCTION_BLOCK
PROGRAM main VAR x : INT := 1; y, v : INT; f, g : Inc; arr : ARRAY[0..1] OF INT; END_VAR
  y := AddTo(x, 5);
  f(r := x); f(r := arr[1]);
  g.r REF= v; g(); g();
END_PROGRAM
""")
    assert [plc[f"main.{n}"] for n in ("x", "y", "arr", "v", "f.r")] == [7, 6, [0, 1], 2, "REF(main.arr[1])"]
    msg = errors("""
FUNCTION AddTo : INT VAR_INPUT r : REFERENCE TO INT; END_VAR AddTo := r; END_FUNCTION
PROGRAM main VAR y : INT; z : REAL; END_VAR y := AddTo(y + 1); y := AddTo(z); END_PROGRAM
""")
    assert "conf.st:3:56: error[E031]: 'r' is a REFERENCE TO INT: pass a variable" in msg
    assert "conf.st:3:75: error[E054]: 'r' is a REFERENCE TO INT; REAL cannot be bound to it" in msg


def test_an_action_called_from_a_method():
    plc = run("""
FUNCTION_BLOCK F
  VAR_OUTPUT acted : INT; END_VAR
  ACTION Act: acted := acted + 1; END_ACTION
  METHOD CallAct Act(); Act(); END_METHOD
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; END_VAR  f.CallAct();  END_PROGRAM
""")
    assert plc["main.f.acted"] == 2


def test_interfaces_extending_system_iqueryinterface():
    src = """
INTERFACE I EXTENDS __SYSTEM.IQueryInterface METHOD M : INT END_METHOD END_INTERFACE
INTERFACE J EXTENDS __SYSTEM.IQueryInterface, I METHOD K : INT END_METHOD END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS J METHOD M : INT M := 1; END_METHOD METHOD K : INT K := 2; END_METHOD END_FUNCTION_BLOCK
PROGRAM main VAR f : F; i : I; j : J; ok : BOOL; x : INT; END_VAR
  i := f; ok := __QUERYINTERFACE(i, j); x := j.K() + j.M();
END_PROGRAM
"""
    plc = run(src, dialect="codesys")
    assert (plc["main.ok"], plc["main.x"]) == (True, 3)
    assert "conf.st:2:11: error[E044]: __SYSTEM.IQueryInterface is not part of the iec dialect" in errors(src, "iec")


@pytest.mark.parametrize(
    "dialect, ok", [("codesys", True), ("twincat", True), ("openplc", True), (None, True), ("iec", False)]
)
def test_writing_an_own_input_is_a_dialect_switch(dialect, ok):
    src = """
FUNCTION Clamp : INT VAR_INPUT v : INT; END_VAR
  IF v > 10 THEN v := 10; END_IF;  Clamp := v;
END_FUNCTION
PROGRAM main VAR a, b : INT; END_VAR a := Clamp(42); b := Clamp(3); END_PROGRAM
"""
    if ok:
        plc = run(src, dialect=dialect)
        assert (plc["main.a"], plc["main.b"]) == (10, 3)
    else:
        assert "conf.st:3:18: error[E048]: 'v' is an input of Clamp and cannot be written here" in errors(src, dialect)


def test_a_pointer_compared_with_and_assigned_zero_is_null():
    plc = run("""
PROGRAM main VAR p : POINTER TO INT; x : INT; b1, b2, b3 : BOOL; END_VAR
  p := 0;  b1 := p = 0;
  p := ADR(x); b2 := p <> 0; b3 := 0 = p;
END_PROGRAM
""")
    assert [plc[f"main.{n}"] for n in ("b1", "b2", "b3")] == [True, True, False]


@pytest.mark.parametrize(
    "src, diagnostic",
    [
        (
            "FUNCTION Fn : INT Fn := THIS^.y; END_FUNCTION",
            "conf.st:1:25: error[E010]: THIS exists only inside a function block or one of its methods",
        ),
        (
            "INTERFACE I METHOD M : INT END_METHOD END_INTERFACE\nFUNCTION_BLOCK F EXTENDS I END_FUNCTION_BLOCK",
            "conf.st:2:16: error[E012]: F can only extend a FUNCTION_BLOCK; 'I' is an INTERFACE",
        ),
        (
            "FUNCTION_BLOCK F VAR_INST n : INT; END_VAR END_FUNCTION_BLOCK",
            "conf.st:1:18: error[E003]: VAR_INST is not allowed in a FUNCTION_BLOCK",
        ),
        (
            "INTERFACE I METHOD M : INT END_METHOD END_INTERFACE\n"
            "FUNCTION_BLOCK F IMPLEMENTS I METHOD PRIVATE M : INT M := 1; END_METHOD END_FUNCTION_BLOCK",
            "conf.st:2:46: error[E043]: method M of F implements I.M: it must be PUBLIC",
        ),
        (
            "FUNCTION_BLOCK B METHOD PUBLIC M : INT M := 1; END_METHOD END_FUNCTION_BLOCK\n"
            "FUNCTION_BLOCK D EXTENDS B METHOD PROTECTED M : INT M := 2; END_METHOD END_FUNCTION_BLOCK",
            "conf.st:2:45: error[E043]: method M overrides B.M with a narrower access",
        ),
    ],
)
def test_object_oriented_diagnostics_after_qa(src, diagnostic):
    msg = errors(src)
    assert diagnostic in msg and "None" not in msg


def test_a_bare_interface_property_accepts_a_read_only_implementation():
    plc = run("""
INTERFACE I PROPERTY Name : STRING END_PROPERTY END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
  PROPERTY Name : STRING GET Name := 'f'; END_GET END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main VAR f : F; i : I; s : STRING; END_VAR i := f; s := i.Name; END_PROGRAM
""")
    assert plc["main.s"] == "f"


def test_return_in_a_method_without_result_and_in_a_property_set():
    plc = run(
        """
FUNCTION_BLOCK FB
  VAR_OUTPUT n : INT; END_VAR
  METHOD Bump
    IF n >= 2 THEN RETURN; END_IF
    n := n + 1;
  END_METHOD
  PROPERTY P : INT
    GET P := n; END_GET
    SET IF P < 0 THEN RETURN; END_IF n := P; END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION NoResult VAR_IN_OUT x : INT; END_VAR IF x > 5 THEN RETURN; END_IF x := x + 10; END_FUNCTION
PROGRAM main VAR f, g : FB; a : INT := 3; END_VAR f.Bump(); g.P := -1; g.P := 4; NoResult(a); END_PROGRAM
""",
        4,
    )
    assert (plc["main.f.n"], plc["main.g.n"], plc["main.a"], plc.state) == (2, 4, 13, "RUN")


def test_a_reference_to_an_in_out_outlives_the_call():
    plc = run(
        """
FUNCTION_BLOCK FB
  VAR r : REFERENCE TO DINT; p : POINTER TO DINT; END_VAR
  VAR_OUTPUT seen : DINT; END_VAR
  METHOD Bind
    VAR_IN_OUT target : DINT; END_VAR
    r REF= target; p := ADR(target);
    target := target + 1;
  END_METHOD
  METHOD Local : DINT
    VAR tmp : DINT := 5; q : REF_TO DINT; END_VAR
    q := REF(tmp); q^ := q^ * 3; Local := tmp;
  END_METHOD
  METHOD Touch r := r + 100; p^ := p^ + 1000; seen := r; END_METHOD
END_FUNCTION_BLOCK
FUNCTION Inc2 VAR_IN_OUT v : DINT; END_VAR VAR q : REF_TO DINT; END_VAR q := REF(v); q^ := q^ + 2; v := v + 1; END_FUNCTION
PROGRAM main VAR f : FB; x, y, z : DINT; END_VAR f.Bind(x); f.Touch(); y := f.Local(); Inc2(z); END_PROGRAM
""",
        dialect="codesys",
    )
    assert [plc[f"main.{n}"] for n in ("x", "f.seen", "y", "z", "f.r", "f.p")] == [
        1101,
        1101,
        15,
        3,
        "REF(main.x)",
        "REF(main.x)",
    ]


def test_interfaces_and_references_compared_with_and_assigned_zero():
    plc = run(
        """
INTERFACE I METHOD M END_METHOD END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I METHOD M END_METHOD END_FUNCTION_BLOCK
PROGRAM main VAR i : I; f : F; r : REF_TO INT; b1, b2, b3, b4 : BOOL; END_VAR
  b1 := i = 0;
  i := f; b2 := i <> 0;
  i := 0; b3 := i = 0;
  r := 0; b4 := r = 0;
END_PROGRAM
""",
        dialect="codesys",
    )
    assert [plc[f"main.b{k}"] for k in range(1, 5)] == [True, True, True, True]


def test_an_instances_reference_member_is_used_as_its_target():
    plc = run(
        """
FUNCTION_BLOCK FB VAR_OUTPUT r : REFERENCE TO DINT; END_VAR END_FUNCTION_BLOCK
FUNCTION Twice VAR_IN_OUT v : DINT; END_VAR v := v * 2; END_FUNCTION
PROGRAM main VAR f : FB; x, y : DINT; END_VAR
  f.r REF= x; f.r := 5; y := f.r + 1; Twice(f.r);
END_PROGRAM
""",
        dialect="codesys",
    )
    assert (plc["main.x"], plc["main.y"], plc["main.f.r"]) == (10, 6, "REF(main.x)")


def test_enumerations_as_integers_in_codesys_only():
    src = """
TYPE E : (A := 0, B := 1, C := 5); END_TYPE
PROGRAM main VAR e : E := B; n : INT; d : DINT; ok : BOOL; END_VAR
  n := e; n := n * 10 + e; d := C; ok := e > 0 AND e = B;
END_PROGRAM
"""
    plc = run(src, dialect="twincat")
    assert (plc["main.n"], plc["main.d"], plc["main.ok"]) == (11, 5, True)
    assert "conf.st:4:8: error[E013]: type mismatch: cannot assign E to INT" in errors(src, "iec")


def test_w007_only_when_the_function_would_take_the_same_arguments():
    d = compile_text(
        """
FUNCTION_BLOCK Store
  VAR_INPUT s : STRING; END_VAR
  METHOD Find : INT VAR_INPUT what : STRING; END_VAR Find := 7; END_METHOD
  METHOD Use : INT Use := Find('x') + FIND(s, 'x'); END_METHOD
END_FUNCTION_BLOCK
""",
        "conf.st",
    ).diagnostics
    assert [x.code for x in d if x.code == "W007"] == []


def test_a_strict_enumeration_is_not_an_integer_even_in_codesys():
    src = """
{attribute 'qualified_only'}
{attribute 'strict'}
TYPE S : (X := 0, Y := 1); END_TYPE
TYPE E : (A := 0, B := 1); END_TYPE
PROGRAM main VAR ve : E := E.B; vs : S := S.Y; n : INT; END_VAR
  n := ve;
  n := n + vs;
END_PROGRAM
"""
    msg = errors(src, "codesys")
    assert "conf.st:8:8: error[E014]: operator + cannot combine INT and S" in msg and msg.count("error[") == 1
    plc = run(src.replace("n := n + vs;", "n := n + 1;"), dialect="codesys")
    assert plc["main.n"] == 2
