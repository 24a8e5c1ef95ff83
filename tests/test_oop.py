"""Object-oriented ST (IEC 61131-3 3rd edition) and its CODESYS/TwinCAT extensions: METHODs, THIS^,
EXTENDS with virtual dispatch, SUPER^, interfaces, properties, access, ABSTRACT/FINAL/OVERRIDE,
CLASS, references and pointers, VAR_INST, VAR_STAT, __NEW/__DELETE, dialect presets."""

from functools import partial

import pytest

from st import PLC
from st.api import compile_text
from st.diagnostics import CompileError

import helpers

run = partial(helpers.run, name="oop.st", use_cache=True)
errors = partial(helpers.errors, name="oop.st")


COUNTER = """
FUNCTION_BLOCK Counter
  VAR_INPUT step : INT := 1; END_VAR
  VAR_OUTPUT count : INT; END_VAR
  METHOD Add : INT
    VAR_INPUT n : INT; END_VAR
    VAR_OUTPUT was : INT; END_VAR
    VAR tmp : INT; calls : INT; END_VAR
    calls := calls + 1;           (* a method's VAR starts afresh in every call *)
    was := count;
    tmp := n * step * calls;
    count := count + tmp;
    Add := count;
  END_METHOD
  METHOD Swap
    VAR_IN_OUT a, b : INT; END_VAR
    VAR t : INT; END_VAR
    t := a; a := b; b := t;
  END_METHOD
  METHOD Reset
    count := 0;
  END_METHOD
  count := count + step;
  IF count > 100 THEN Reset(); END_IF;         (* this instance's method, without THIS^ *)
END_FUNCTION_BLOCK
"""


def test_methods_with_inputs_outputs_in_outs_and_a_result():
    plc = run(
        COUNTER
        + """
PROGRAM main
  VAR c : Counter; r1, r2, before : INT; x : INT := 1; y : INT := 2; END_VAR
  c(step := 2);                          (* count 2 *)
  r1 := c.Add(n := 5, was => before);    (* 2 + 10 *)
  r2 := r1 + c.Add(1);                   (* 12 + (12 + 2) *)
  c.Swap(x, y);
END_PROGRAM
"""
    )
    assert (plc["main.r1"], plc["main.before"], plc["main.r2"], plc["main.c.count"]) == (12, 2, 26, 14)
    assert (plc["main.x"], plc["main.y"]) == (2, 1)


def test_a_method_called_from_the_body_sees_the_values_the_body_just_wrote():
    plc = run(
        COUNTER
        + """
PROGRAM main
  VAR c : Counter; END_VAR
  c(step := 60);
END_PROGRAM
""",
        2,
    )
    assert plc["main.c.count"] == 0  # 60, then 120 > 100: Reset() in the same call


def test_this_reaches_the_instance_and_its_methods():
    plc = run(
        """
FUNCTION_BLOCK Acc
  VAR_OUTPUT total : DINT; END_VAR
  VAR_INPUT x : DINT; END_VAR
  METHOD Double : DINT
    Double := THIS^.total * 2;
  END_METHOD
  THIS^.total := THIS^.total + x;
  total := THIS^.Double();
END_FUNCTION_BLOCK
PROGRAM main
  VAR a : Acc; END_VAR
  a(x := 3);
END_PROGRAM
""",
        2,
    )
    assert plc["main.a.total"] == 18  # (0 + 3) * 2 = 6, then (6 + 3) * 2


ANIMALS = """
FUNCTION_BLOCK Animal
  VAR_OUTPUT legs : INT := 4; calls : INT; END_VAR
  METHOD Speak : STRING
    Speak := 'generic';
  END_METHOD
  METHOD Describe : STRING
    Describe := CONCAT(THIS^.Speak(), '!');   (* virtual: a derived block's Speak *)
  END_METHOD
  calls := calls + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Dog EXTENDS Animal
  VAR barks : INT; END_VAR
  METHOD Speak : STRING
    barks := barks + 1;
    Speak := CONCAT('woof/', SUPER^.Speak());
  END_METHOD
  SUPER^();                                  (* the base body: calls + 1 *)
  calls := calls + 10;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Puppy EXTENDS Dog
  METHOD Speak : STRING
    Speak := CONCAT('yip+', SUPER^.Speak());
  END_METHOD
  SUPER^();
  legs := 3;
END_FUNCTION_BLOCK
"""


def test_inheritance_overrides_virtual_dispatch_and_super():
    plc = run(
        ANIMALS
        + """
PROGRAM main
  VAR a : Animal; d : Dog; p : Puppy; s1, s2, s3, s4 : STRING; END_VAR
  a(); d(); p();
  s1 := a.Describe();
  s2 := d.Describe();
  s3 := p.Describe();
  s4 := d.Speak();
END_PROGRAM
"""
    )
    assert [plc[f"main.s{i}"] for i in (1, 2, 3, 4)] == [
        "generic!",
        "woof/generic!",
        "yip+woof/generic!",
        "woof/generic",
    ]
    assert (plc["main.d.calls"], plc["main.d.barks"], plc["main.p.calls"], plc["main.p.legs"], plc["main.p.barks"]) == (
        11,
        2,
        11,
        3,
        1,
    )
    assert plc["main.a.legs"] == 4 and plc["main.a.calls"] == 1


@pytest.mark.parametrize(
    "src, message",
    [
        ("FUNCTION_BLOCK B EXTENDS Nope END_FUNCTION_BLOCK", "B extends 'Nope', which is not declared"),
        (
            "FUNCTION_BLOCK A EXTENDS B END_FUNCTION_BLOCK FUNCTION_BLOCK B EXTENDS A END_FUNCTION_BLOCK",
            "extends itself through",
        ),
        (
            "FUNCTION_BLOCK FINAL A END_FUNCTION_BLOCK FUNCTION_BLOCK B EXTENDS A END_FUNCTION_BLOCK",
            "'A' is FINAL and cannot be extended",
        ),
        (
            "FUNCTION F : INT F := 1; END_FUNCTION FUNCTION_BLOCK B EXTENDS F END_FUNCTION_BLOCK",
            "B can only extend a FUNCTION_BLOCK; 'F' is a FUNCTION",
        ),
        (
            """FUNCTION_BLOCK A METHOD FINAL M : INT M := 1; END_METHOD END_FUNCTION_BLOCK
        FUNCTION_BLOCK B EXTENDS A METHOD M : INT M := 2; END_METHOD END_FUNCTION_BLOCK""",
            "method M of A is FINAL and cannot be overridden",
        ),
        (
            """FUNCTION_BLOCK A METHOD M : INT VAR_INPUT x : INT; END_VAR M := x; END_METHOD END_FUNCTION_BLOCK
        FUNCTION_BLOCK B EXTENDS A METHOD M : DINT VAR_INPUT x : INT; END_VAR M := x; END_METHOD
        END_FUNCTION_BLOCK""",
            "method M overrides A.M with a different signature",
        ),
        (
            """FUNCTION_BLOCK A VAR x : INT; END_VAR METHOD x : INT x := 1; END_METHOD END_FUNCTION_BLOCK""",
            "'x' is declared twice in A",
        ),
        (
            """FUNCTION_BLOCK A VAR_OUTPUT q : INT; END_VAR METHOD M : INT M := 1; END_METHOD END_FUNCTION_BLOCK
        PROGRAM main VAR a : A; v : INT; END_VAR v := a.M; END_PROGRAM""",
            "'M' is a method; call it: M()",
        ),
        (
            """FUNCTION_BLOCK A METHOD M M := 1; END_METHOD END_FUNCTION_BLOCK""",
            "METHOD M has no return type but assigns a result",
        ),
        (
            """FUNCTION_BLOCK A VAR_OUTPUT q : INT; END_VAR END_FUNCTION_BLOCK
        PROGRAM main VAR a : A; END_VAR a.Nope(); END_PROGRAM""",
            "A has no method, action or instance 'Nope'",
        ),
        (
            """PROGRAM main VAR x : INT; END_VAR x := SUPER^.x; END_PROGRAM""",
            "SUPER exists only inside a function block that EXTENDS another",
        ),
    ],
)
def test_object_oriented_errors_are_located(src, message):
    text = errors(src)
    assert message in text and "oop.st:" in text


def test_a_method_variable_hiding_an_instance_variable_is_a_warning():
    cp = compile_text(
        """FUNCTION_BLOCK A VAR_OUTPUT x : INT; END_VAR
      METHOD M : INT VAR x : INT; END_VAR x := 5; M := x; END_METHOD
      x := M() + 1;
      END_FUNCTION_BLOCK
      PROGRAM main VAR a : A; END_VAR a(); END_PROGRAM""",
        "oop.st",
        use_cache=False,
    )
    assert [(d.code, d.span.line) for d in cp.diagnostics] == [("W006", 2)]
    plc = PLC(cp)
    plc.scan()
    assert plc["main.a.x"] == 6  # the method's own x, the instance's untouched by it


SHAPES = """
INTERFACE I_Shape
  METHOD Area : REAL
  END_METHOD
  METHOD Scale
    VAR_INPUT k : REAL; END_VAR
  END_METHOD
END_INTERFACE
INTERFACE I_Named EXTENDS I_Shape
  METHOD Name : STRING
  END_METHOD
END_INTERFACE
FUNCTION_BLOCK Square IMPLEMENTS I_Named
  VAR_INPUT side : REAL := 1.0; END_VAR
  METHOD Area : REAL
    Area := side * side;
  END_METHOD
  METHOD Scale
    VAR_INPUT k : REAL; END_VAR
    side := side * k;
  END_METHOD
  METHOD Name : STRING
    Name := 'square';
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Circle IMPLEMENTS I_Shape
  VAR_INPUT r : REAL := 1.0; END_VAR
  METHOD Area : REAL
    Area := 3.0 * r * r;
  END_METHOD
  METHOD Scale
    VAR_INPUT k : REAL; END_VAR
    r := r * k;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Ring EXTENDS Circle          (* implements I_Shape through its base *)
  METHOD Area : REAL
    Area := 3.0 * r * r - 3.0;
  END_METHOD
END_FUNCTION_BLOCK
"""


def test_polymorphic_dispatch_through_an_interface_array():
    plc = run(
        SHAPES
        + """
PROGRAM main
  VAR
    sq : Square := (side := 2.0);
    c : Circle;
    rg : Ring := (r := 2.0);
    shapes : ARRAY[1..4] OF I_Shape;
    named : I_Named;
    total : REAL;
    i : INT;
    nm : STRING;
    unset : BOOL;
    same : BOOL;
  END_VAR
  shapes[1] := sq;
  shapes[2] := c;
  shapes[3] := rg;
  named := sq;
  total := 0.0;
  FOR i := 1 TO 4 DO
    IF shapes[i] <> NULL THEN
      shapes[i].Scale(k := 2.0);
      total := total + shapes[i].Area();
    END_IF;
  END_FOR;
  nm := named.Name();
  unset := shapes[4] = NULL;
  same := shapes[1] = named;
END_PROGRAM
"""
    )
    # square 2 → 4: 16; circle 1 → 2: 12; ring 2 → 4: 48 − 3 = 45
    assert plc["main.total"] == 73.0 and plc["main.nm"] == "square"
    assert plc["main.sq.side"] == 4.0 and plc["main.rg.r"] == 4.0  # the instances themselves changed
    assert plc["main.unset"] is True and plc["main.same"] is True
    assert plc.variables()["main.shapes"] == ["Square", "Circle", "Ring", None]


def test_a_call_through_a_null_interface_is_a_null_fault_with_the_line():
    from st import PLCFaultError

    plc = PLC(
        compile_text(
            SHAPES
            + """
PROGRAM main
  VAR s : I_Shape; a : REAL; END_VAR
  a := s.Area();
END_PROGRAM
""",
            "oop.st",
        )
    )
    with pytest.raises(PLCFaultError) as e:
        plc.scan()
    assert e.value.fault.kind == "NULL" and e.value.fault.line == SHAPES.count("\n") + 4
    assert plc.state == "FAULT"


@pytest.mark.parametrize(
    "src, message",
    [
        (
            SHAPES + "PROGRAM main VAR s : I_Named; c : Circle; END_VAR s := c; END_PROGRAM",
            "cannot assign Circle to I_Named: Circle does not implement I_Named",
        ),
        (
            """INTERFACE I METHOD M : INT END_METHOD END_INTERFACE
        FUNCTION_BLOCK B IMPLEMENTS I VAR x : INT; END_VAR END_FUNCTION_BLOCK""",
            "B does not implement method M of interface I",
        ),
        (
            """INTERFACE I METHOD M : INT END_METHOD END_INTERFACE
        FUNCTION_BLOCK B IMPLEMENTS I METHOD M : DINT M := 1; END_METHOD END_FUNCTION_BLOCK""",
            "method M of B does not match I.M",
        ),
        (
            """FUNCTION_BLOCK A END_FUNCTION_BLOCK FUNCTION_BLOCK B IMPLEMENTS A END_FUNCTION_BLOCK""",
            "B IMPLEMENTS: 'A' is a FUNCTION BLOCK, not an INTERFACE",
        ),
        ("""FUNCTION_BLOCK B IMPLEMENTS Nope END_FUNCTION_BLOCK""", "B IMPLEMENTS: 'Nope' is not declared"),
        ("""INTERFACE I METHOD M : INT M := 1; END_METHOD END_INTERFACE""", "a method of INTERFACE I has no body"),
        ("""INTERFACE I EXTENDS J END_INTERFACE INTERFACE J EXTENDS I END_INTERFACE""", "extends itself"),
        (
            """INTERFACE I METHOD M : INT END_METHOD END_INTERFACE
        PROGRAM main VAR s : I; x : INT; END_VAR x := s.Nope(); END_PROGRAM""",
            "I has no method 'Nope'",
        ),
    ],
)
def test_interface_errors_are_located(src, message):
    text = errors(src)
    assert message in text and "oop.st:" in text


MOTOR = """
FUNCTION_BLOCK Motor
  VAR _speed : REAL; sets : INT; END_VAR
  PROPERTY Speed : REAL
    GET
      Speed := _speed;
    END_GET
    SET
      VAR lim : REAL := 100.0; END_VAR        (* fresh in every call, as a method's *)
      sets := sets + 1;
      IF Speed > lim THEN _speed := lim; ELSE _speed := Speed; END_IF;
    END_SET
  END_PROPERTY
  PROPERTY Running : BOOL
    GET
      Running := _speed > 0.0;
    END_GET
  END_PROPERTY
  Speed := Speed + 1.0;                         (* this instance's property, GET then SET *)
END_FUNCTION_BLOCK
"""


def test_properties_get_and_set():
    plc = run(
        MOTOR
        + """
PROGRAM main
  VAR m : Motor; v, w : REAL; r0, r1 : BOOL; END_VAR
  r0 := m.Running;
  m.Speed := 50.0;
  m();
  v := m.Speed;
  m.Speed := 150.0;                           (* limited to 100 by the SET *)
  w := m.Speed;
  r1 := m.Running;
END_PROGRAM
"""
    )
    assert (plc["main.r0"], plc["main.v"], plc["main.w"], plc["main.r1"]) == (False, 51.0, 100.0, True)
    assert plc["main.m.sets"] == 3


def test_properties_through_an_interface():
    plc = run("""
INTERFACE I_Level
  PROPERTY Level : INT
    GET END_GET
    SET END_SET
  END_PROPERTY
END_INTERFACE
FUNCTION_BLOCK Tank IMPLEMENTS I_Level
  VAR v : INT; END_VAR
  PROPERTY Level : INT
    GET Level := v; END_GET
    SET v := LIMIT(0, Level, 100); END_SET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main
  VAR t : Tank; i : I_Level; a : INT; END_VAR
  i := t;
  i.Level := 130;
  a := i.Level;
END_PROGRAM
""")
    assert plc["main.a"] == 100 and plc["main.t.v"] == 100


@pytest.mark.parametrize(
    "src, message",
    [
        (
            MOTOR + "PROGRAM main VAR m : Motor; END_VAR m.Running := TRUE; END_PROGRAM",
            "property Running has no SET: it cannot be written",
        ),
        (
            """FUNCTION_BLOCK A VAR x : INT; END_VAR PROPERTY P : INT SET x := P; END_SET END_PROPERTY
        END_FUNCTION_BLOCK PROGRAM main VAR a : A; y : INT; END_VAR y := a.P; END_PROGRAM""",
            "property P has no GET: it cannot be read",
        ),
        (
            """INTERFACE I PROPERTY P : INT GET END_GET END_PROPERTY END_INTERFACE
        FUNCTION_BLOCK B IMPLEMENTS I PROPERTY P : DINT GET P := 1; END_GET END_PROPERTY END_FUNCTION_BLOCK""",
            "B does not implement property P of interface I",
        ),
        (
            """FUNCTION_BLOCK A VAR P : INT; END_VAR PROPERTY P : INT GET P := 1; END_GET END_PROPERTY
        END_FUNCTION_BLOCK""",
            "'P' is declared twice in A",
        ),
    ],
)
def test_property_errors_are_located(src, message):
    text = errors(src)
    assert message in text and "oop.st:" in text


ABSTRACT_BASE = """
FUNCTION_BLOCK ABSTRACT Base
  VAR_OUTPUT n : INT; END_VAR
  METHOD ABSTRACT Step : INT
  END_METHOD
  METHOD PRIVATE Secret : INT
    Secret := 42;
  END_METHOD
  METHOD PROTECTED Helper : INT
    Helper := Secret() + 1;
  END_METHOD
  METHOD Run : INT
    Run := Step() + Helper();
  END_METHOD
END_FUNCTION_BLOCK
"""
IMPL = """
FUNCTION_BLOCK Impl EXTENDS Base
  METHOD OVERRIDE Step : INT
    Step := Helper() * 2;              (* PROTECTED: usable in a derived block *)
  END_METHOD
END_FUNCTION_BLOCK
"""


def test_abstract_base_protected_and_private_methods():
    plc = run(
        ABSTRACT_BASE
        + IMPL
        + """
PROGRAM main
  VAR i : Impl; r : INT; END_VAR
  r := i.Run();
END_PROGRAM
"""
    )
    assert plc["main.r"] == 129  # (42 + 1) * 2 + (42 + 1)


@pytest.mark.parametrize(
    "src, message",
    [
        (
            ABSTRACT_BASE + "PROGRAM main VAR b : Base; END_VAR END_PROGRAM",
            "'Base' is ABSTRACT and cannot be instantiated",
        ),
        (
            ABSTRACT_BASE + "FUNCTION_BLOCK Lazy EXTENDS Base END_FUNCTION_BLOCK",
            "Lazy does not implement the ABSTRACT method Step of Base",
        ),
        (
            ABSTRACT_BASE + IMPL + "PROGRAM main VAR i : Impl; r : INT; END_VAR r := i.Secret(); END_PROGRAM",
            "method Secret of Base is PRIVATE",
        ),
        (
            ABSTRACT_BASE + IMPL + "PROGRAM main VAR i : Impl; r : INT; END_VAR r := i.Helper(); END_PROGRAM",
            "method Helper of Base is PROTECTED",
        ),
        (
            ABSTRACT_BASE
            + """FUNCTION_BLOCK Impl2 EXTENDS Base
        METHOD Step : INT Step := Secret(); END_METHOD END_FUNCTION_BLOCK""",
            "method Secret of Base is PRIVATE",
        ),
        (
            ABSTRACT_BASE
            + """FUNCTION_BLOCK Impl3 EXTENDS Base
        METHOD Step : INT Step := SUPER^.Step(); END_METHOD END_FUNCTION_BLOCK""",
            "method Step of Base is ABSTRACT: it has no implementation to call",
        ),
        (
            """FUNCTION_BLOCK A METHOD OVERRIDE M : INT M := 1; END_METHOD END_FUNCTION_BLOCK""",
            "method M is marked OVERRIDE but A inherits no method of that name",
        ),
        (
            """FUNCTION_BLOCK A METHOD ABSTRACT M : INT END_METHOD END_FUNCTION_BLOCK""",
            "ABSTRACT method M in A, which is not ABSTRACT",
        ),
        (
            """FUNCTION_BLOCK A VAR x : INT; END_VAR PROPERTY PRIVATE P : INT GET P := x; END_GET END_PROPERTY
        END_FUNCTION_BLOCK PROGRAM main VAR a : A; y : INT; END_VAR y := a.P; END_PROGRAM""",
            "property P of A is PRIVATE",
        ),
    ],
)
def test_access_and_abstract_errors(src, message):
    text = errors(src)
    code = "E061" if "ABSTRACT" in message else "E047" if "OVERRIDE" in message else "E043"
    assert f"error[{code}]: {message}" in text and "oop.st:" in text


def test_classes_and_query_interface():
    plc = run("""
INTERFACE I_A METHOD A : INT END_METHOD END_INTERFACE
INTERFACE I_B METHOD B : INT END_METHOD END_INTERFACE
CLASS Both IMPLEMENTS I_A, I_B
  VAR k : INT := 7; END_VAR
  METHOD A : INT A := k; END_METHOD
  METHOD B : INT B := k * 2; END_METHOD
END_CLASS
FUNCTION_BLOCK OnlyA IMPLEMENTS I_A
  METHOD A : INT A := 1; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR both : Both; oa : OnlyA; a1, a2, none : I_A; b : I_B; ok1, ok2, ok3 : BOOL; r : INT; END_VAR
  a1 := both; a2 := oa;
  ok1 := __QUERYINTERFACE(a1, b);
  IF ok1 THEN r := b.B() + a1.A(); END_IF;
  ok2 := __QUERYINTERFACE(a2, b);          (* OnlyA has no I_B: b keeps the instance it had *)
  ok3 := __QUERYINTERFACE(none, b);
END_PROGRAM
""")
    assert (plc["main.ok1"], plc["main.r"], plc["main.ok2"], plc["main.ok3"]) == (True, 21, False, False)
    assert plc.variables()["main.b"] == "Both"


@pytest.mark.parametrize(
    "src, message",
    [
        ("CLASS C VAR x : INT; END_VAR x := 1; END_CLASS", "a CLASS has no body; put the code in a METHOD of C"),
        (
            "CLASS C METHOD M : INT M := 1; END_METHOD END_CLASS PROGRAM main VAR c : C; END_VAR c(); END_PROGRAM",
            "an instance of the CLASS C has no body; call its methods",
        ),
        (
            """INTERFACE I METHOD M : INT END_METHOD END_INTERFACE
        PROGRAM main VAR i : I; x : INT; ok : BOOL; END_VAR ok := __QUERYINTERFACE(i, x); END_PROGRAM""",
            "__QUERYINTERFACE needs an interface variable to fill, not INT",
        ),
    ],
)
def test_class_errors(src, message):
    text = errors(src)
    assert message in text and "oop.st:" in text


def test_references_pointers_adr_sizeof():
    plc = run("""
TYPE Pt : STRUCT x : SINT; y : DINT; END_STRUCT; END_TYPE
PROGRAM main
  VAR
    a : INT := 5; b : INT := 9;
    r : REFERENCE TO INT;
    p : Pt;
    rx : REFERENCE TO DINT;
    ptr : POINTER TO INT;
    v1, v2, v3 : INT;
    arr : ARRAY[1..3] OF INT;
    valid0, valid1 : BOOL;
    s_arr, s_pt, s_str, s_lreal : DINT;
  END_VAR
  valid0 := __ISVALIDREF(r);
  r REF= a;
  valid1 := __ISVALIDREF(r);
  r := r + 1;                  (* writes a *)
  v1 := r * 10;
  r REF= b;
  r := 0;                      (* writes b *)
  rx REF= p.y;
  rx := 42;
  ptr := ADR(arr[2]);
  ptr^ := 7;
  v2 := arr[2];
  v3 := DINT_TO_INT(p.y);
  s_arr := SIZEOF(arr);
  s_pt := SIZEOF(Pt);          (* SINT, 3 bytes of padding, DINT *)
  s_str := SIZEOF(STRING);
  s_lreal := SIZEOF(LREAL);
END_PROGRAM
""")
    assert (plc["main.a"], plc["main.b"], plc["main.v1"], plc["main.v2"], plc["main.v3"]) == (6, 0, 60, 7, 42)
    assert (plc["main.valid0"], plc["main.valid1"]) == (False, True)
    assert (plc["main.s_arr"], plc["main.s_pt"], plc["main.s_str"], plc["main.s_lreal"]) == (6, 8, 81, 8)


def test_an_unbound_reference_is_a_null_fault_with_the_line():
    from st import PLCFaultError

    plc = PLC(
        compile_text(
            """PROGRAM main
  VAR r : REFERENCE TO INT; x : INT; END_VAR
  x := r + 1;
END_PROGRAM""",
            "oop.st",
        )
    )
    with pytest.raises(PLCFaultError) as e:
        plc.scan()
    assert e.value.fault.kind == "NULL" and e.value.fault.line == 3


@pytest.mark.parametrize(
    "src, message",
    [
        ("PROGRAM main VAR x : INT; y : INT; END_VAR x REF= y; END_PROGRAM", "REF= binds a REFERENCE TO variable"),
        (
            "PROGRAM main VAR r : REFERENCE TO INT; y : REAL; END_VAR r REF= y; END_PROGRAM",
            "REF= needs a INT variable, not REAL",
        ),
        ("PROGRAM main VAR r : REFERENCE TO INT; END_VAR r REF= 3; END_PROGRAM", "REF= needs a variable to refer to"),
        (
            "PROGRAM main VAR x : INT; ok : BOOL; END_VAR ok := __ISVALIDREF(x); END_PROGRAM",
            "__ISVALIDREF needs a reference, not INT",
        ),
    ],
)
def test_reference_errors(src, message):
    text = errors(src)
    assert message in text and "oop.st:" in text


# ---------------------------------------------------------------------------- dialect presets


def test_dialect_presets_accept_and_refuse_constructs():
    oop = """FUNCTION_BLOCK A METHOD M : INT M := 1; END_METHOD END_FUNCTION_BLOCK
PROGRAM main VAR a : A; x : INT; END_VAR x := a.M(); END_PROGRAM"""
    vendor = """PROGRAM main VAR x : INT; r : REFERENCE TO INT; p : POINTER TO INT; n : DINT; END_VAR
r REF= x; p := ADR(x); n := SIZEOF(x); END_PROGRAM"""
    for d in ("iec", "codesys", "twincat", None):
        plc = PLC(compile_text(oop, "oop.st", dialect=d))
        plc.scan()
        assert plc["main.x"] == 1
    for d in ("codesys", "twincat", None):
        plc = PLC(compile_text(vendor, "oop.st", dialect=d))
        plc.scan()
        assert plc["main.n"] == 2
    with pytest.raises(CompileError) as e:
        compile_text(oop, "oop.st", dialect="openplc")
    assert "E044" in str(e.value) and "METHOD is not part of the openplc dialect" in str(e.value)
    with pytest.raises(CompileError) as e:
        compile_text(vendor, "oop.st", dialect="iec")
    text = str(e.value)
    for what in ("REFERENCE TO", "POINTER TO", "REF=", "ADR", "SIZEOF"):
        assert f"{what} is not part of the iec dialect" in text


def test_a_dialect_pragma_in_the_file_and_the_openplc_switches():
    src = """{dialect 'openplc'}
PROGRAM main VAR t : DINT; END_VAR t := TIME_TO_DINT(T#2500ms); END_PROGRAM"""
    cp = compile_text(src, "oop.st", use_cache=False)
    assert [d.code for d in cp.diagnostics] == []  # the dialect pragma is not an "ignored pragma"
    plc = PLC(cp)
    plc.scan()
    assert plc["main.t"] == 2  # MatIEC counts seconds
    plc = PLC(compile_text(src, "oop.st", dialect="iec"))  # the explicit choice wins
    plc.scan()
    assert plc["main.t"] == 2500


def test_attribute_pragmas_are_quiet_in_codesys_and_twincat():
    src = """{attribute 'qualified_only'}
PROGRAM main VAR x : INT; END_VAR x := 1; END_PROGRAM"""
    assert [d.code for d in compile_text(src, "oop.st", use_cache=False, dialect="codesys").diagnostics] == []
    assert [d.code for d in compile_text(src, "oop.st", use_cache=False, dialect="iec").diagnostics] == ["W001"]


def test_method_var_inst_and_new_delete():
    plc = run("""
FUNCTION_BLOCK Tally
  METHOD Next : INT
    VAR_INST n : INT; END_VAR          (* kept in the instance between calls *)
    VAR tmp : INT; END_VAR             (* fresh in every call *)
    n := n + 1;
    tmp := tmp + 1;
    Next := n * 10 + tmp;
  END_METHOD
END_FUNCTION_BLOCK
TYPE Pt : STRUCT x, y : INT; END_STRUCT; END_TYPE
PROGRAM main
  VAR a, b : Tally; r1, r2, r3 : INT; p : POINTER TO Pt; q : POINTER TO INT; t : POINTER TO Tally;
      px, qv, tv : INT; gone : BOOL; END_VAR
  r1 := a.Next(); r2 := a.Next(); r3 := b.Next();
  p := __NEW(Pt); p^.x := 3; px := p^.x;
  q := __NEW(INT); q^ := 41; q^ := q^ + 1; qv := q^;
  t := __NEW(Tally); tv := t^.Next();
  __DELETE(p);
  gone := p = NULL;
END_PROGRAM
""")
    assert [plc[f"main.{k}"] for k in ("r1", "r2", "r3", "px", "qv", "tv", "gone")] == [11, 21, 11, 3, 42, 11, True]


CODESYS_STYLE = """
{attribute 'qualified_only'}
{attribute 'strict'}
TYPE E_State : (IDLE := 0, RUNNING := 1, FAULTED := 2); END_TYPE

INTERFACE I_Axis
  METHOD MoveTo : BOOL
    VAR_INPUT fTarget : LREAL; END_VAR
  END_METHOD
  PROPERTY fPosition : LREAL
    GET END_GET
  END_PROPERTY
END_INTERFACE

{attribute 'no_explicit_call' := 'do not call this POU directly'}
FUNCTION_BLOCK ABSTRACT FB_AxisBase IMPLEMENTS I_Axis
  VAR
    _fPos : LREAL;
    _eState : E_State := E_State.IDLE;
  END_VAR
  VAR_OUTPUT
    nMoves : UDINT;
  END_VAR
  METHOD PUBLIC MoveTo : BOOL
    VAR_INPUT fTarget : LREAL; END_VAR
    IF THIS^._eState = E_State.FAULTED THEN
      MoveTo := FALSE;
      RETURN;
    END_IF
    _fPos := THIS^.Clamp(fTarget);
    nMoves := nMoves + 1;
    MoveTo := TRUE;
  END_METHOD
  METHOD PROTECTED ABSTRACT Clamp : LREAL
    VAR_INPUT f : LREAL; END_VAR
  END_METHOD
  PROPERTY PUBLIC fPosition : LREAL
    GET
      fPosition := _fPos;
    END_GET
  END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_LinearAxis EXTENDS FB_AxisBase
  VAR_INPUT fMin : LREAL := 0.0; fMax : LREAL := 100.0; END_VAR
  METHOD PROTECTED Clamp : LREAL
    VAR_INPUT f : LREAL; END_VAR
    Clamp := LIMIT(fMin, f, fMax);
  END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_RotaryAxis EXTENDS FB_AxisBase
  METHOD PROTECTED Clamp : LREAL
    VAR_INPUT f : LREAL; END_VAR
    Clamp := f - 360.0 * DINT_TO_LREAL(LREAL_TO_DINT(f / 360.0 - 0.5));
  END_METHOD
  METHOD PUBLIC MoveTo : BOOL
    VAR_INPUT fTarget : LREAL; END_VAR
    MoveTo := SUPER^.MoveTo(fTarget := fTarget);
  END_METHOD
END_FUNCTION_BLOCK

PROGRAM MAIN
  VAR
    fbX : FB_LinearAxis := (fMax := 50.0);
    fbC : FB_RotaryAxis;
    aAxes : ARRAY[0..1] OF I_Axis;
    i : INT;
    bOk : BOOL := TRUE;
    fSum : LREAL;
  END_VAR
  aAxes[0] := fbX;
  aAxes[1] := fbC;
  fSum := 0;
  FOR i := 0 TO 1 DO
    bOk := bOk AND aAxes[i].MoveTo(fTarget := 725.0);
    fSum := fSum + aAxes[i].fPosition;
  END_FOR
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", ["codesys", "twincat"])
def test_a_codesys_style_source_with_methods_properties_and_interfaces(dialect):
    cp = compile_text(CODESYS_STYLE, "oop.st", dialect=dialect, use_cache=False)
    assert cp.diagnostics == []
    plc = PLC(cp)
    plc.scan(2)
    assert plc["MAIN.bOk"] is True
    assert plc["MAIN.fbX.nMoves"] == 2 and plc["MAIN.fbC.nMoves"] == 2
    assert plc["MAIN.fSum"] == 50.0 + 5.0  # 725 limited to 50; 725 mod 360 = 5


def test_var_stat_is_shared_by_every_instance_and_call():
    plc = run(
        """
FUNCTION_BLOCK Widget
  VAR_STAT created : INT; END_VAR
  VAR_OUTPUT id : INT; END_VAR
  IF id = 0 THEN created := created + 1; id := created; END_IF;
END_FUNCTION_BLOCK
FUNCTION NextTicket : INT
  VAR_STAT counter : INT := 100; END_VAR
  counter := counter + 1;
  NextTicket := counter;
END_FUNCTION
PROGRAM main
  VAR a, b, c : Widget; t1, t2 : INT; END_VAR
  a(); b(); c(); a();
  t1 := NextTicket(); t2 := NextTicket();
END_PROGRAM
""",
        2,
    )
    assert [plc[f"main.{k}"] for k in ("a.id", "b.id", "c.id", "t1", "t2")] == [1, 2, 3, 103, 104]
    assert "id" in plc.variables()["main.a"] and "created" not in plc.variables()["main.a"]
    assert plc.globals() == {"Widget.created": 3, "NextTicket.counter": 104}


def test_var_stat_in_a_method_is_shared_by_instances():
    plc = run(
        """
FUNCTION_BLOCK Widget
  METHOD Next : INT
    VAR_STAT n : INT; END_VAR
    n := n + 1; Next := n;
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR a, b : Widget; x, y : INT; END_VAR
  x := a.Next(); y := b.Next();
END_PROGRAM
""",
        2,
    )
    assert (plc["main.x"], plc["main.y"]) == (3, 4)
    assert plc.globals() == {"Widget.Next.n": 4}


def test_var_stat_in_a_program_is_one_located_error_without_a_cascade():
    msg = errors("""
PROGRAM main
  VAR_STAT g : INT; END_VAR
  g := g + 1;
END_PROGRAM
""")
    assert "oop.st:3:3: error[E003]: VAR_STAT is not allowed in a PROGRAM" in msg
    assert msg.count("error[") == 1


ATTEMPT = """
INTERFACE I_Move METHOD Go : INT END_METHOD END_INTERFACE
INTERFACE I_Light METHOD On : BOOL END_METHOD END_INTERFACE
FUNCTION_BLOCK Base IMPLEMENTS I_Move
  METHOD Go : INT Go := 1; END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Lamp EXTENDS Base IMPLEMENTS I_Light
  METHOD Go : INT Go := 2; END_METHOD
  METHOD On : BOOL On := TRUE; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR
    b : Base; l : Lamp;
    mv : I_Move; li : I_Light;
    rb : REF_TO Base; rl : REF_TO Lamp;
    found : ARRAY[0..3] OF BOOL; got : INT;
  END_VAR
  mv := b;  li ?= mv; found[0] := li <> NULL;       (* Base is no I_Light: NULL *)
  mv := l;  li ?= mv; found[1] := li <> NULL;       (* Lamp is *)
  rb := REF(l);                                     (* a reference to a derived block is one to its base *)
  rl ?= rb; found[2] := rl <> NULL; got := rl^.Go();
  rb := REF(b); rl ?= rb; found[3] := rl <> NULL;   (* a Base is no Lamp: NULL *)
  rl ?= li;                                         (* interface to reference: the Lamp behind it *)
  IF rl <> NULL THEN got := got * 10 + rl^.Go(); END_IF;
END_PROGRAM
"""


def test_assignment_attempt_casts_interfaces_and_references_at_run_time():
    plc = run(ATTEMPT)
    assert [plc[f"main.found[{i}]"] for i in range(4)] == [False, True, True, False]
    assert plc["main.got"] == 22
    assert plc["main.li"] == "Lamp"


def test_assignment_attempt_needs_an_interface_or_reference_on_the_left():
    msg = errors(ATTEMPT.replace("found[3] := rl <> NULL;", "found[3] := rl <> NULL; got ?= mv;"))
    assert "?= needs an interface or a REF_TO a function block on the left, not INT" in msg
    assert "error[E055]" in msg


def test_a_reference_to_a_base_block_is_not_one_to_a_derived_block():
    msg = errors(ATTEMPT.replace("rl ?= rb; found[2]", "rl := rb; found[2]"))
    assert "oop.st:21:9: error[E013]: type mismatch: cannot assign REF_TO Base to REF_TO Lamp" in msg


VAR_ACCESS = """
FUNCTION_BLOCK Tank
  VAR PRIVATE secret : INT := 7; END_VAR
  VAR PROTECTED level : INT := 3; END_VAR
  VAR PUBLIC shown : INT := 1; END_VAR
  METHOD Peek : INT Peek := secret + level; END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK BigTank EXTENDS Tank
  METHOD Twice : INT Twice := level * 2; END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR t : BigTank; a, b, c : INT; END_VAR
  a := t.Peek(); b := t.Twice(); c := t.shown;
END_PROGRAM
"""


def test_var_sections_with_access_specifiers():
    plc = run(VAR_ACCESS)
    assert (plc["main.a"], plc["main.b"], plc["main.c"]) == (10, 6, 1)


@pytest.mark.parametrize(
    "change, where, message",
    [
        (
            "c := t.shown;",
            "13:41",
            "variable level of Tank is PROTECTED: only Tank and the blocks that extend it may use it",
        ),
        ("Twice := level * 2;", "9:31", "variable secret of Tank is PRIVATE: only Tank itself may use it"),
    ],
)
def test_var_access_violations_are_located(change, where, message):
    replacement = {"c := t.shown;": "c := t.level;", "Twice := level * 2;": "Twice := secret * 2;"}[change]
    msg = errors(VAR_ACCESS.replace(change, replacement))
    assert f"oop.st:{where}: error[E043]: {message}" in msg


def test_access_specifiers_belong_to_var_sections_of_blocks():
    msg = errors("PROGRAM main VAR PRIVATE x : INT; END_VAR x := 1; END_PROGRAM")
    assert "error[E003]: PRIVATE applies to the VAR sections of function blocks and classes" in msg


ABSTRACT_PROPERTY = """
FUNCTION_BLOCK ABSTRACT Sensor
  PROPERTY ABSTRACT Value : REAL
    GET END_GET
  END_PROPERTY
  METHOD Scaled : REAL
    Scaled := Value * 2.0;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Temp EXTENDS Sensor
  VAR raw : REAL := 21.5; END_VAR
  PROPERTY Value : REAL
    GET Value := raw; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main
  VAR t : Temp; r : REAL; END_VAR
  r := t.Scaled();
END_PROGRAM
"""


def test_an_abstract_property_is_provided_by_the_derived_block():
    assert run(ABSTRACT_PROPERTY)["main.r"] == 43.0


def test_an_abstract_property_must_be_implemented():
    msg = errors(ABSTRACT_PROPERTY + "FUNCTION_BLOCK Bad EXTENDS Sensor\nEND_FUNCTION_BLOCK\n")
    assert "oop.st:20:16: error[E061]: Bad does not implement the ABSTRACT property Value of Sensor" in msg
    msg = errors(ABSTRACT_PROPERTY.replace("    GET END_GET", "    GET Value := 1.0; END_GET"))
    assert "oop.st:3:21: error[E061]: ABSTRACT property Value has a body" in msg


RELINK = """
INTERFACE I_Count METHOD Bump : INT END_METHOD END_INTERFACE
FUNCTION_BLOCK Counter IMPLEMENTS I_Count
  VAR_OUTPUT n : INT; END_VAR
  METHOD Bump : INT n := n + 1; Bump := n; END_METHOD
END_FUNCTION_BLOCK
TYPE Box : STRUCT v : INT; END_STRUCT END_TYPE
VAR_GLOBAL gc : Counter; gi : I_Count; gr : REF_TO INT; END_VAR
PROGRAM main
  VAR_EXTERNAL gc : Counter; gi : I_Count; gr : REF_TO INT; END_VAR
  VAR
    c : Counter; arr : ARRAY[0..1] OF Counter; b : Box;
    it : I_Count; its : ARRAY[0..1] OF I_Count;
    rb : REF_TO INT; pc : POINTER TO Counter; rr : REFERENCE TO INT;
    init : BOOL; last : INT;
  END_VAR
  IF NOT init THEN
    it := c; its[0] := arr[1]; its[1] := gc; gi := c;
    rb := REF(b.v); pc := ADR(arr[0]); rr REF= b.v; gr := REF(c.n);
    init := TRUE;
  END_IF
  last := it.Bump() + its[0].Bump() + its[1].Bump() + gi.Bump();
  rb^ := rb^ + 1; pc^.Bump(); rr := rr + 1; gr^ := gr^ + 100;
END_PROGRAM
"""


def test_online_change_points_interfaces_and_references_at_the_new_instances():
    plc = PLC(compile_text(RELINK, "v1.st"))
    plc.scan(2)
    before = (plc["main.c.n"], plc["main.arr[1].n"], plc["main.arr[0].n"], plc["gc.n"], plc["main.b.v"])
    assert before == (204, 2, 2, 2, 4)  # c: it and gi bump it (2 per scan), gr adds 100
    plc.online_change(compile_text(RELINK.replace("n := n + 1;", "n := n + 10;"), "v2.st"))
    plc.scan()
    # every link now reaches the new objects: the new code (+10) changes the carried-over values
    assert (plc["main.c.n"], plc["main.arr[1].n"], plc["main.arr[0].n"], plc["gc.n"], plc["main.b.v"]) == (
        204 + 20 + 100,
        12,
        12,
        12,
        6,
    )
    assert plc["main.last"] == 214 + 12 + 12 + 224


def test_a_method_named_like_a_standard_function():
    src = """
FUNCTION_BLOCK S
  VAR_INPUT txt : STRING(50); END_VAR
  METHOD Len : INT
    Len := LEN(txt) * 2;          (* arguments the method does not take: the standard LEN *)
  END_METHOD
  METHOD Abs : INT
    VAR_INPUT v : INT; END_VAR
    Abs := v + 1;
  END_METHOD
  METHOD Twice : INT
    VAR_INPUT v : INT; END_VAR
    Twice := ABS(v) * 2;          (* the method Abs: W007 *)
  END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
  VAR s : S; a, b : INT; END_VAR
  s.txt := 'abc';
  a := s.Len(); b := s.Twice(-4);
END_PROGRAM
"""
    plc = run(src)
    assert (plc["main.a"], plc["main.b"]) == (6, -6)
    d = compile_text(src, "oop.st").diagnostics[0]
    assert (d.code, d.span.line, d.span.col) == ("W007", 13, 14)
    assert d.message == "'ABS' calls the method Abs of S, not the function of that name"


def test_references_read_and_dump_as_the_path_they_designate():
    plc = run("""
TYPE Pt : STRUCT x, y : INT; END_STRUCT END_TYPE
VAR_GLOBAL g : INT; END_VAR
FUNCTION_BLOCK F VAR_OUTPUT q : INT; END_VAR END_FUNCTION_BLOCK
PROGRAM main
  VAR_EXTERNAL g : INT; END_VAR
  VAR
    m : ARRAY[1..2, 0..2] OF INT; pts : ARRAY[1..2] OF Pt; f : F;
    r1, r2, r4 : REF_TO INT; r3 : REF_TO Pt; p : POINTER TO INT; rr : REF_TO REF_TO INT; none : REF_TO INT;
    fresh : POINTER TO INT;
  END_VAR
  r1 := REF(m[2, 1]); r2 := REF(f.q); r3 := REF(pts[2]); r4 := REF(g); p := ADR(pts[1].y); rr := REF(r1);
  fresh := __NEW(INT);
END_PROGRAM
""")
    assert [plc[f"main.{n}"] for n in ("r1", "r2", "r3", "r4", "p", "rr", "none", "fresh")] == [
        "REF(main.m[2, 1])",
        "REF(main.f.q)",
        "REF(main.pts[2])",
        "REF(g)",
        "REF(main.pts[1].y)",
        "REF(main.r1)",
        None,
        "REF(__NEW)",
    ]
    assert plc.variables()["main.r1"] == "REF(main.m[2, 1])"


def test_a_method_var_inst_bound_by_ref_or_addressed_stays_in_the_instance():
    """struckig's Otg.Calculate: `p REF= _profiles[dof]` with p and dof a method's VAR_INST (they were
    boxed as locals that did not exist: a NameError fault)."""
    src = """
TYPE Prof : STRUCT p : ARRAY[0..2] OF LREAL; END_STRUCT END_TYPE
FUNCTION_BLOCK Fb
VAR profs : ARRAY[0..1] OF Prof; total : LREAL; seen : INT; END_VAR
METHOD Calc
VAR_INST
  dof : INT;
  p : REFERENCE TO Prof;
  q : POINTER TO INT;
  k : INT := 5;
END_VAR
FOR dof := 0 TO 1 DO
  p REF= profs[dof];
  p.p[2] := dof + 1.5;
  total := total + p.p[2];
END_FOR
q := ADR(k);
q^ := q^ + 1;
seen := k;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR f : Fb; END_VAR
f.Calc();
f.Calc();
END_PROGRAM
"""
    plc = run(src, dialect="twincat")
    assert plc["main.f.total"] == 8.0 and plc["main.f.profs"][1] == {"p": [0.0, 0.0, 2.5]} and plc["main.f.seen"] == 7
