"""The lowering stage (compiler/lower): what code generation receives to print."""

from __future__ import annotations

from st.api import libraries
from st.compiler import ast as A
from st.compiler.driver import check_sources
from st.compiler.lower import inheritance, lower
from st.compiler.lower.walk import walk_stmts
from st.source import SourceFile

LOOPS = """
FUNCTION_BLOCK Fb
VAR c, k, s : DINT; END_VAR
FOR k := 10 TO 1 BY s DO c := c + 1; END_FOR;
FOR k := 1 TO 10 DO k := k + 1; END_FOR;
FOR k := 1 TO 10 BY 2 DO
  WHILE c > 0 DO c := c - 1; IF c = 5 THEN CONTINUE; END_IF; END_WHILE;
END_FOR;
REPEAT c := c + 1; UNTIL c > 10 END_REPEAT;
END_FUNCTION_BLOCK
PROGRAM main
VAR f : Fb; END_VAR
f();
END_PROGRAM
"""


def _project(src: str):
    """The checked model of `src`, lowered (what code generation prints)."""
    project, diagnostics = check_sources([SourceFile("lowering.st", src)], libraries())
    assert not [d for d in diagnostics if d.is_error], diagnostics
    lower(project)
    return project


def _loops(body):
    return [s for s in walk_stmts(body) if isinstance(s, (A.For, A.CountedFor, A.While, A.Repeat))]


def test_every_loop_starts_with_one_guard_and_no_for_is_left():
    project = _project(LOOPS)
    body = project.pous["fb"].decl.body
    loops = _loops(body)
    assert [type(s).__name__ for s in loops] == ["CountedFor", "CountedFor", "CountedFor", "While", "Repeat"]
    for s in loops:
        assert isinstance(s.body[0], A.LoopGuard) and s.body[0].span.line == s.span.line
        assert not any(isinstance(x, A.LoopGuard) for x in s.body[1:])


def test_a_for_that_writes_its_counter_is_a_while_form_and_stays_guarded():
    fors = [s for s in _loops(_project(LOOPS).pous["fb"].decl.body) if isinstance(s, A.CountedFor)]
    assert [(s.form, s.step_value) for s in fors] == [("range", None), ("while", 1), ("range", 2)]
    assert isinstance(fors[1].body[0], A.LoopGuard)


def test_lowering_twice_changes_nothing():
    project = _project(LOOPS)
    lower(project)
    for s in _loops(project.pous["fb"].decl.body):
        assert sum(isinstance(x, A.LoopGuard) for x in s.body) == 1


def test_the_loops_of_unit_tests_are_guarded_too():
    project = _project(
        "PROGRAM main\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n"
        "TEST 'loops'\nVAR uut : main; i : INT; END_VAR\n"
        "FOR i := 1 TO 3 DO uut(); END_FOR;\nASSERT_EQ(uut.x, 3);\nEND_TEST\n"
    )
    loops = [s for t in project.tests for s in _loops(t.body)]
    assert len(loops) == 1 and isinstance(loops[0].body[0], A.LoopGuard)


PROPS = """
FUNCTION_BLOCK Base
VAR v : INT; END_VAR
PROPERTY P : INT
GET P := v; END_GET
SET v := P; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
PROPERTY P : INT
GET P := SUPER^.P + 1; END_GET
SET SUPER^.P := P; END_SET
END_PROPERTY
P := 3;
END_FUNCTION_BLOCK
PROGRAM main
VAR d : Derived; r : INT; END_VAR
d.P := 7;
r := d.P;
d();
END_PROGRAM
"""


def test_property_uses_become_accessor_calls():
    project = _project(PROPS)
    main = project.pous["main"].decl.body
    set_, get = main[0], main[1]
    assert isinstance(set_.target, A.AccessorCall)
    assert set_.target.accessor is project.pous["derived"].properties["p"].set
    assert isinstance(get.value, A.AccessorCall) and get.value.accessor is project.pous["derived"].properties["p"].get
    assert not get.value.nonvirtual
    inner = project.pous["derived"].decl.body[0]  # P := 3 inside the block: this instance's SET
    assert isinstance(inner.target, A.AccessorCall) and inner.target.obj is None


def test_super_property_is_the_base_accessor_not_virtual():
    derived = _project(PROPS).pous["derived"]
    getter = derived.properties["p"].get.decl.body[0]
    call = getter.value.left
    assert isinstance(call, A.AccessorCall) and call.nonvirtual
    assert call.accessor.owner_fb.name == "Base"


OOP = """
INTERFACE I
METHOD M : INT END_METHOD
END_INTERFACE
FUNCTION_BLOCK Base IMPLEMENTS I
VAR_INPUT id : INT; END_VAR
METHOD M : INT M := id; END_METHOD
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; nId : INT := 4; END_VAR
id := nId;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
VAR extra : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; nId : INT; END_VAR
extra := nId * 2;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR d : Derived(nId := 5); END_VAR
d();
END_PROGRAM
"""


def test_a_derived_block_is_flattened_and_knows_what_it_is():
    project = _project(OOP)
    blocks = inheritance.blocks(project)
    d = blocks[project.pous["derived"]]
    assert d.kinds == ("base", "derived", "i")
    assert [v.name for v in d.variables] == ["id", "extra"]
    assert {m.name.lower() for m in d.methods} == {"m", "fb_init"}
    assert project.pous["i"] not in blocks


def test_the_fb_init_chain_is_one_constructor_base_first():
    project = _project(OOP)
    ctor = inheritance.blocks(project)[project.pous["derived"]].constructor
    assert [c.method.owner_fb.name for c in ctor.calls] == ["Base", "Derived"]
    assert [a if isinstance(a, bool) else a.name for a in ctor.calls[0].args] == [True, False, "nId"]
    assert set(ctor.inputs) == {"binitretains", "bincopycode", "nid"}
    assert inheritance.blocks(project)[project.pous["main"]].constructor is None


SUPER = """
FUNCTION_BLOCK Animal
VAR_OUTPUT calls : INT; END_VAR
METHOD Speak : STRING Speak := 'generic'; END_METHOD
calls := calls + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Dog EXTENDS Animal
METHOD Speak : STRING Speak := CONCAT('woof/', SUPER^.Speak()); END_METHOD
SUPER^();
END_FUNCTION_BLOCK
PROGRAM main
VAR d : Dog; s : STRING; END_VAR
d();
s := d.Speak();
END_PROGRAM
"""


def test_super_calls_run_the_base_and_other_calls_are_virtual():
    project = _project(SUPER)
    dog, animal = project.pous["dog"], project.pous["animal"]
    assert dog.decl.body[0].call.target.nonvirtual is animal  # SUPER^()
    speak = dog.methods["speak"].decl.body[0].value.target.args[1].value  # SUPER^.Speak()
    assert speak.target.nonvirtual is animal
    main = project.pous["main"].decl.body
    assert main[0].call.target.nonvirtual is None and main[1].value.target.nonvirtual is None
