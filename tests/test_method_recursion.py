"""Recursion through methods, property accessors, actions and block bodies is found as a
FUNCTION's is (issue 32), wherever the declarations show which body a call runs: E032 under the
iec and openplc presets (the detection tests use iec), W013 under codesys, twincat and the default,
which run it as CODESYS does; docs/oop.md ("Recursion") lists what the check follows and what it
cannot see."""

from __future__ import annotations

from functools import partial

import pytest

from st.api import compile_text

import helpers

run = partial(helpers.run, name="rec.st")
fault = partial(helpers.fault, name="rec.st")
NOT_IEC = "(recursion is not allowed in IEC 61131-3)"
AS_CODESYS = "(recursion runs as in CODESYS; IEC 61131-3 does not allow it)"


def found(src: str, dialect: str | None = "iec") -> list[tuple[str, int, int, str]]:
    """The errors (and W013 warnings) of rec.st as (code, line, column, message), in the order reported."""
    result = compile_text(src, "rec.st", dialect=dialect, use_cache=False, raise_on_error=False)
    return [(d.code, d.span.line, d.span.col, d.message) for d in result.diagnostics if d.is_error or d.code == "W013"]


def main(calls: str, decls: str) -> str:
    return f"PROGRAM main\nVAR {decls} x : DINT; END_VAR\n{calls}\nEND_PROGRAM\n"


DIRECT = """FUNCTION_BLOCK FB_A
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
M := THIS^.M(n + 1);
END_METHOD
METHOD M2 : DINT
VAR_INPUT n : DINT; END_VAR
IF n > 0 THEN M2 := M2(n - 1); END_IF;
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := a.M(0) + a.M2(3);", "a : FB_A;")


def test_a_method_calling_itself_through_this_or_by_its_name():
    assert found(DIRECT) == [
        ("E032", 4, 6, f"method FB_A.M calls itself {NOT_IEC}"),
        ("E032", 8, 21, f"method FB_A.M2 calls itself {NOT_IEC}"),
    ]


def test_this_dot_m_of_the_third_edition_is_the_same_call():
    src = DIRECT.replace("THIS^.M(", "THIS.M(")
    assert found(src, "iec") == [
        ("E032", 4, 6, f"method FB_A.M calls itself {NOT_IEC}"),
        ("E032", 8, 21, f"method FB_A.M2 calls itself {NOT_IEC}"),
    ]


MUTUAL = """FUNCTION_BLOCK FB_A
METHOD Ping : DINT
VAR_INPUT n : DINT; END_VAR
Ping := Pong(n);
END_METHOD
METHOD Pong : DINT
VAR_INPUT n : DINT; END_VAR
Pong := THIS^.Ping(n - 1);
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := a.Ping(3);", "a : FB_A;")


def test_methods_of_one_block_calling_each_other():
    # one error for each method, at the call that closes its circle (errors come in line order)
    assert found(MUTUAL) == [
        ("E032", 4, 9, f"method FB_A.Pong calls itself through method FB_A.Ping {NOT_IEC}"),
        ("E032", 8, 9, f"method FB_A.Ping calls itself through method FB_A.Pong {NOT_IEC}"),
    ]


SUPER_CHAIN = """FUNCTION_BLOCK FB_Base
METHOD Run : DINT
Run := THIS^.Hook();
END_METHOD
METHOD Hook : DINT
Hook := 0;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Derived EXTENDS FB_Base
METHOD Hook : DINT
Hook := SUPER^.Run() + 1;
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := d.Run();", "d : FB_Derived;")


def test_super_calls_that_come_back_through_a_virtual_call_of_the_base():
    # FB_Derived.Hook -> SUPER^.Run (FB_Base's) -> THIS^.Hook(), which on an FB_Derived is Hook again
    assert found(SUPER_CHAIN) == [
        ("E032", 3, 8, f"method FB_Derived.Hook calls itself through method FB_Base.Run {NOT_IEC}"),
        ("E032", 11, 9, f"method FB_Base.Run calls itself through method FB_Derived.Hook {NOT_IEC}"),
    ]


def test_super_calls_that_do_not_come_back_are_fine():
    src = SUPER_CHAIN.replace("Run := THIS^.Hook();", "Run := 7;").replace("d.Run()", "d.Hook()")
    assert found(src) == [] and run(src)["main.x"] == 8


PROPERTIES = """FUNCTION_BLOCK FB_P
VAR v : DINT; END_VAR
PROPERTY Level : DINT
GET
Level := THIS^.Level + 1;
END_GET
SET
THIS^.Level := Level;
END_SET
END_PROPERTY
PROPERTY Total : DINT
GET
Total := Sum();
END_GET
END_PROPERTY
METHOD Sum : DINT
Sum := v + Total;
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := p.Level + p.Total;\np.Level := 3;", "p : FB_P;")


def test_property_accessors_reading_writing_or_reaching_themselves():
    assert found(PROPERTIES) == [
        ("E032", 5, 10, f"property FB_P.Level (GET) calls itself {NOT_IEC}"),
        ("E032", 8, 1, f"property FB_P.Level (SET) calls itself {NOT_IEC}"),
        ("E032", 13, 10, f"method FB_P.Sum calls itself through property FB_P.Total (GET) {NOT_IEC}"),
        ("E032", 17, 12, f"property FB_P.Total (GET) calls itself through method FB_P.Sum {NOT_IEC}"),
    ]


ACTIONS = """FUNCTION_BLOCK FB_Act
VAR n : DINT; END_VAR
ACTION Up:
n := n + 1;
IF n < 10 THEN Down(); END_IF;
END_ACTION
ACTION Down:
Up();
END_ACTION
ACTION Self:
Self();
END_ACTION
END_FUNCTION_BLOCK
""" + main("a.Up();\na.Self();", "a : FB_Act;")


def test_actions_calling_each_other_or_themselves():
    assert found(ACTIONS) == [
        ("E032", 5, 16, f"action FB_Act.Down calls itself through action FB_Act.Up {NOT_IEC}"),
        ("E032", 8, 1, f"action FB_Act.Up calls itself through action FB_Act.Down {NOT_IEC}"),
        ("E032", 11, 1, f"action FB_Act.Self calls itself {NOT_IEC}"),
    ]


THROUGH_FUNCTION = """FUNCTION F : DINT
VAR_INPUT n : DINT; END_VAR
VAR h : FB_H; END_VAR
F := h.Go(n);
END_FUNCTION
FUNCTION_BLOCK FB_H
METHOD Go : DINT
VAR_INPUT n : DINT; END_VAR
Go := F(n - 1);
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Body
VAR_OUTPUT q : DINT; END_VAR
q := G();
END_FUNCTION_BLOCK
FUNCTION G : DINT
VAR b : FB_Body; END_VAR
b();
G := b.q;
END_FUNCTION
""" + main("x := F(3) + G();", "")


def test_a_method_or_a_block_body_and_a_function_through_an_instance_held_by_value():
    assert found(THROUGH_FUNCTION) == [
        ("E032", 4, 6, f"method FB_H.Go calls itself through F {NOT_IEC}"),
        ("E032", 9, 7, f"F calls itself through method FB_H.Go {NOT_IEC}"),
        ("E032", 14, 6, f"G calls itself through function block FB_Body {NOT_IEC}"),
        ("E032", 18, 1, f"function block FB_Body calls itself through G {NOT_IEC}"),
    ]


ONE_IMPLEMENTATION = """INTERFACE I_Rec
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Rec IMPLEMENTS I_Rec
VAR me : I_Rec; END_VAR
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
me := THIS^;
M := me.M(n + 1);
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := r.M(0);", "r : FB_Rec;")


def test_through_an_interface_that_one_block_implements():
    assert found(ONE_IMPLEMENTATION) == [("E032", 11, 6, f"method FB_Rec.M calls itself {NOT_IEC}")]


LINKED_LIST = """CLASS Node
VAR val : INT; next : POINTER TO Node; END_VAR
METHOD SumAll : INT
IF next = 0 THEN SumAll := val; ELSE SumAll := val + next^.SumAll(); END_IF;
END_METHOD
END_CLASS
FUNCTION_BLOCK FB_Peer2
METHOD Ask : DINT
VAR_IN_OUT other : FB_Peer2; END_VAR
Ask := other.Ask(other);
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := n.SumAll() + p.Ask(p);", "n : Node; p : FB_Peer2;")


def test_through_a_pointer_or_an_in_out_whose_type_has_one_body():
    assert found(LINKED_LIST, "codesys") == [  # pointers: a vendor extension; codesys warns
        ("W013", 4, 54, f"method Node.SumAll calls itself {AS_CODESYS}"),
        ("W013", 10, 8, f"method FB_Peer2.Ask calls itself {AS_CODESYS}"),
    ]


TWO_IMPLEMENTATIONS = """INTERFACE I_Two
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_X IMPLEMENTS I_Two
VAR_INPUT other : I_Two; END_VAR
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
M := other.M(n + 1);
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Y IMPLEMENTS I_Two
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
M := n;
END_METHOD
END_FUNCTION_BLOCK
"""


def test_through_an_interface_several_blocks_implement_it_is_the_runtime_s_recursion_fault():
    plc, info = fault(TWO_IMPLEMENTATIONS + main("a(other := a);\nx := b.M(1) + a.M(0);", "a : FB_X; b : FB_Y;"))
    assert (info.kind, info.line, info.pou, plc["main.x"]) == ("RECURSION", 10, "FB_X", 0)


def test_an_interface_call_that_ends_elsewhere_runs():
    src = TWO_IMPLEMENTATIONS + main("a(other := b);\nx := a.M(4);", "a : FB_X; b : FB_Y;")
    assert run(src)["main.x"] == 5


OVERRIDDEN = """FUNCTION_BLOCK FB_Base
METHOD Step : DINT
VAR_INPUT p : REFERENCE TO FB_Base; END_VAR
Step := p.Step(p);
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Leaf EXTENDS FB_Base
METHOD Step : DINT
VAR_INPUT p : REFERENCE TO FB_Base; END_VAR
Step := 1;
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := b.Step(l);", "b : FB_Base; l : FB_Leaf;")


def test_a_reference_to_a_block_whose_method_is_overridden_is_not_followed():
    # p.Step() runs FB_Base.Step or FB_Leaf.Step, as p refers at run time: not a known body
    assert found(OVERRIDDEN, "codesys") == []
    assert run(OVERRIDDEN, dialect="codesys")["main.x"] == 1


def test_other_blocks_methods_of_the_same_name_are_no_recursion():
    src = """FUNCTION_BLOCK FB_Inner
METHOD M : DINT
M := 5;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Outer
VAR inner : FB_Inner; END_VAR
METHOD M : DINT
M := inner.M() + 1;
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := o.M();", "o : FB_Outer;")
    assert found(src) == [] and run(src)["main.x"] == 6


def test_a_method_named_like_a_function_is_not_that_function():
    # the method Helper calls Other, which calls the FUNCTION Helper: no circle
    src = """FUNCTION Helper : DINT
Helper := 1;
END_FUNCTION
FUNCTION Other : DINT
Other := Helper() + 1;
END_FUNCTION
FUNCTION_BLOCK FB
METHOD Helper : DINT
Helper := Other() + 1;
END_METHOD
END_FUNCTION_BLOCK
""" + main("x := f.Helper();", "f : FB;")
    assert found(src) == [] and run(src)["main.x"] == 3


def test_function_recursion_is_still_reported_with_the_way_round():
    src = (
        "FUNCTION F : INT\nVAR_INPUT n : INT; END_VAR\nF := G(n);\nEND_FUNCTION\n"
        "FUNCTION G : INT\nVAR_INPUT n : INT; END_VAR\nG := F(n - 1);\nEND_FUNCTION\n"
        "FUNCTION H : INT\nVAR_INPUT n : INT; END_VAR\nH := H(n - 1);\nEND_FUNCTION\n"
    )
    assert found(src) == [
        ("E032", 3, 6, f"G calls itself through F {NOT_IEC}"),
        ("E032", 7, 6, f"F calls itself through G {NOT_IEC}"),
        ("E032", 11, 6, f"H calls itself {NOT_IEC}"),
    ]


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_recursion_is_refused_under_iec_and_matiec(dialect):
    src = (
        FACTORIAL[: FACTORIAL.index("FUNCTION_BLOCK")]
        + "PROGRAM main\nVAR a : DINT; END_VAR\na := Fact(3);\nEND_PROGRAM\n"
    )
    assert [d[:3] for d in found(src, dialect)] == [("E032", 3, 27)]
    assert [d[:3] for d in found(DIRECT, "iec")] == [("E032", 4, 6), ("E032", 8, 21)]


FACTORIAL = """FUNCTION Fact : DINT
VAR_INPUT n : DINT; END_VAR
IF n > 1 THEN Fact := n * Fact(n - 1); ELSE Fact := 1; END_IF;
END_FUNCTION
FUNCTION_BLOCK FB_F
METHOD M : DINT
VAR_INPUT n : DINT; END_VAR
IF n > 1 THEN M := n * THIS^.M(n - 1); ELSE M := 1; END_IF;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR f : FB_F; a, b : DINT; END_VAR
a := Fact(10);
b := f.M(6);
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_codesys_twincat_and_the_default_warn_and_run_it(dialect):
    assert [d[:3] for d in found(FACTORIAL, dialect)] == [("W013", 3, 27), ("W013", 8, 24)]
    assert found(FACTORIAL, dialect)[0][3] == f"Fact calls itself {AS_CODESYS}"
    plc = run(FACTORIAL, dialect=dialect)
    assert (plc["main.a"], plc["main.b"]) == (3628800, 720)
