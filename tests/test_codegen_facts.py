"""What the code generator records beside each function it prints, for the native tier
(codegen/facts.py): the locals holding ST variables with their IEC types, the loop guards, the
runtime helpers called and what for, FOR counters' intervals, proven intervals, and the calls of
block bodies and FUNCTIONs."""

from __future__ import annotations

import ast as py

from st.api import libraries
from st.compiler.codegen import ModuleGen
from st.compiler.codegen.facts import WATCHDOG_ARMED, BodyFacts, Helper, Local, facts_of
from st.compiler.driver import check_sources
from st.compiler.intervals import Interval
from st.compiler.lower import lower
from st.diagnostics import DiagnosticSink
from st.model import types as T
from st.source import SourceFile

SRC = """\
FUNCTION sq : DINT
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT twice : DINT; END_VAR
VAR_IN_OUT hits : DINT; END_VAR
VAR k : SINT; END_VAR
sq := INT_TO_DINT(a) * a;
twice := sq * 2;
hits := hits + 1;
END_FUNCTION
FUNCTION_BLOCK cnt
VAR_INPUT go : BOOL; END_VAR
VAR_OUTPUT n : INT; END_VAR
IF go THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK
FUNCTION_BLOCK tool
VAR x : DINT; END_VAR
METHOD twice : DINT
VAR_INPUT v : DINT; END_VAR
twice := v * 2;
END_METHOD
x := THIS^.twice(x);
END_FUNCTION_BLOCK
PROGRAM main
VAR
  a : ARRAY[1..10] OF DINT;
  i : INT;
  d : DINT := 3;
  s : DINT;
  f : REAL;
  c : cnt;
  t : TON;
  h : DINT;
  tw : DINT;
END_VAR
VAR_TEMP j : INT; END_VAR
FOR i := 1 TO 10 DO
  a[i] := a[i] + i;
END_FOR;
WHILE s < 5 DO
  s := s + 1;
END_WHILE;
s := a[d] / d + s MOD 7;
f := f / 3.0 + DINT_TO_REAL(s);
c(go := TRUE);
t(IN := c.n > 2, PT := T#1s);
s := sq(i, twice => tw, hits := h);
j := i + 1;
END_PROGRAM
"""


def _generated(src: str) -> dict[str, py.FunctionDef]:
    """Every function the code generator printed for `src`, by 'class.function' or 'function'."""
    project, diagnostics = check_sources([SourceFile("facts.st", src)], libraries())
    assert not [d for d in diagnostics if d.is_error], diagnostics
    inline = frozenset(path for lib in libraries() if lib.inline_blocks for path, _ in lib.sources)
    modules = ModuleGen(lower(project), DiagnosticSink(), inline_files=inline).generate()
    out: dict[str, py.FunctionDef] = {}
    for _path, mod in modules:
        for node in mod.body:
            if isinstance(node, py.FunctionDef):
                out[node.name] = node
            elif isinstance(node, py.ClassDef):
                out.update((f"{node.name}.{f.name}", f) for f in node.body if isinstance(f, py.FunctionDef))
    return out


GEN = _generated(SRC)


def _type_name(t: T.Type) -> str:
    u = T.unalias(t)
    return u.name if isinstance(u, T.ElemType) else type(u).__name__


def _facts(name: str) -> BodyFacts:
    facts = facts_of(GEN[name])
    assert facts is not None, name
    return facts


def test_a_blocks_body_records_its_cached_variables_with_their_iec_types():
    facts = _facts("_prg_main._body")
    assert facts.kind == "body"
    local = {name: (_type_name(t), s) for name, (t, s) in facts.locals.items() if not name.startswith("_t")}
    assert local == {
        "a": ("ArrayType", "VAR"),
        "i": ("INT", "VAR"),
        "d": ("DINT", "VAR"),
        "s": ("DINT", "VAR"),
        "f": ("REAL", "VAR"),
        "c": ("POUType", "VAR"),
        "t": ("POUType", "VAR"),
        "j": ("INT", "VAR_TEMP"),
    }  # h and tw, passed to sq by reference, stay the instance's attributes
    # TON's body, copied into the call (codegen/inline.py): its locals, renamed, with TON's types
    inlined = {name.split("_", 2)[2]: local for name, local in facts.locals.items() if name.startswith("_t")}
    assert inlined["IN"] == Local(T.BOOL, "VAR_INPUT") and inlined["Q"] == Local(T.BOOL, "VAR_OUTPUT")


def test_loop_guards_helpers_and_calls_are_the_nodes_codegen_printed():
    fn, facts = GEN["_prg_main._body"], _facts("_prg_main._body")
    loops = [n for n in py.walk(fn) if isinstance(n, (py.For, py.While))]
    assert len(loops) == 2 and [loop.body[0] for loop in loops] == facts.guards
    assert all(
        isinstance(g, py.If) and isinstance(g.test, py.Name) and g.test.id == WATCHDOG_ARMED for g in facts.guards
    )
    # every runtime helper the body calls, by what it computes
    assert facts.helpers == {
        "_range": Helper.RANGE,
        "_ix": Helper.INDEX,  # a[d]: d may be any DINT
        "_idiv": Helper.DIV,
        "_f32": Helper.ROUND,
        "_fdiv": Helper.REAL_DIV,
        "_float": Helper.TO_REAL,
    }
    called = {n.func.id for n in py.walk(fn) if isinstance(n, py.Call) and isinstance(n.func, py.Name)}
    assert set(facts.helpers) <= called
    (body_call,) = facts.body_calls  # c(go := TRUE); TON's body is inlined: no call
    assert body_call.cls == "_fb_cnt" and isinstance(body_call.node.func, py.Attribute)
    assert any(body_call.node is n for n in py.walk(fn))
    (fcall,) = facts.function_calls
    assert fcall.name == "_fn_sq" and any(fcall.node is n for n in py.walk(fn))


def test_for_counters_intervals_and_wraps_are_recorded():
    fn, facts = GEN["_prg_main._body"], _facts("_prg_main._body")
    (loop,) = facts.loops
    assert loop.counter == "i" and loop.values == Interval(1, 10) and isinstance(loop.node, py.For)
    assert any(loop.node is n for n in py.walk(fn))
    # a[i] inside the loop needs no index check: its index's interval is a fact
    assert Interval(1, 10) in [r.values for r in facts.ranges]
    # `s := s + 1` wraps to DINT: the wrap's result is within DINT
    dint = Interval(T.DINT.lo, T.DINT.hi)
    assert dint in [r.values for r in facts.ranges]


def test_a_function_records_its_parameters_and_locals():
    facts = _facts("_fn_sq")
    assert facts.kind == "function"
    assert facts.params == [("a", T.INT), ("_r_twice", None), ("_r_hits", None)]
    assert facts.locals == {
        "a": Local(T.INT, "VAR_INPUT"),
        "twice": Local(T.DINT, "VAR_OUTPUT"),
        "hits": Local(T.DINT, "VAR_IN_OUT"),
        "k": Local(T.SINT, "VAR"),
        "sq": Local(T.DINT, "RESULT"),
    }
    assert [a.arg for a in GEN["_fn_sq"].args.args] == [name for name, _ in facts.params]


def test_a_method_and_a_block_without_cached_variables_have_facts_too():
    method = _facts("_fb_tool._m_twice")
    assert method.kind == "method" and method.params == [("v", T.DINT)]
    assert method.locals == {"v": Local(T.DINT, "VAR_INPUT"), "twice": Local(T.DINT, "RESULT")}
    body = _facts("_fb_tool._body")  # THIS^ in the body: its variables stay attributes
    assert body.kind == "body" and body.locals == {}
