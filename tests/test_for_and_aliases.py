"""A FOR counter written while the body runs, and the other choices code generation makes from
who writes what (issue 31): lower/loops.py's form, codegen's cached instance variables, the
interval of a counter, the native tier.

CODESYS and TwinCAT test the value the body left (the codesys/twincat presets and the default do
the same); IEC 61131-3 and MatIEC forbid writing the counter (iec/openplc: E052, located). Each
case is checked against the value CODESYS computes, on both tiers, and against a build that makes
none of these choices (every FOR re-tests its counter, no variable is kept in a Python local):
the choices may change speed, never a value.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from st import PLC
from st.api import compile_text
from st.compiler.lower import loops, writes
from st.compiler.native import toolchain
from st.diagnostics import CompileError
from st.runtime.faults import PLCFaultError

ALIASES = """
FUNCTION_BLOCK AddTen
  VAR_IN_OUT v : INT; END_VAR
  v := v + 10;
END_FUNCTION_BLOCK

FUNCTION AddTenF : INT
  VAR_IN_OUT v : INT; END_VAR
  v := v + 10;
  AddTenF := v;
END_FUNCTION

FUNCTION_BLOCK OutTen
  VAR_INPUT x : INT; END_VAR
  VAR_OUTPUT y : INT; END_VAR
  y := x + 10;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Helper
  METHOD AddTen
    VAR_IN_OUT v : INT; END_VAR
    v := v + 10;
  END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK SelfBump
  VAR_OUTPUT n, i : INT; END_VAR
  METHOD Bump
    i := i + 10;
  END_METHOD
  n := 0;
  FOR i := 1 TO 30 DO n := n + 1; Bump(); END_FOR
END_FUNCTION_BLOCK

(* an instance held by a VAR_GLOBAL, which a function its body calls writes: its counter, and a
   variable the body reads in the loop *)
FUNCTION_BLOCK GlobalTouched
  VAR_OUTPUT n, y, i, x : INT; END_VAR
  x := 1; y := 0; n := 0;
  FOR i := 1 TO 30 DO n := n + 1; y := y + x; Poke(); END_FOR
END_FUNCTION_BLOCK

FUNCTION Poke : BOOL
  VAR_EXTERNAL g_touched : GlobalTouched; END_VAR
  g_touched.i := g_touched.i + 10;
  g_touched.x := 100;
  Poke := TRUE;
END_FUNCTION

(* no loop: the variables of a straight-line body are kept in locals only where nothing reaches them *)
FUNCTION_BLOCK Straight
  VAR_OUTPUT a, b, c : INT; END_VAR
  a := 1; b := a + a + a; Nudge(); c := a + a + a + b;
END_FUNCTION_BLOCK

FUNCTION Nudge : BOOL
  VAR_EXTERNAL g_straight : Straight; END_VAR
  g_straight.a := 5;
  Nudge := TRUE;
END_FUNCTION

VAR_GLOBAL g_touched : GlobalTouched; g_straight : Straight; END_VAR

PROGRAM main
  VAR
    add : AddTen; outb : OutTen; h : Helper; sb : SelfBump;
    i1, n1, i2, n2, i3, n3, i4, n4, i5, n5, i6, n6, i7, n7, i8, n8, i9, n9 : INT;
    p : POINTER TO INT; r : REFERENCE TO INT; x : INT;
  END_VAR
  n1 := 0; FOR i1 := 1 TO 30 DO n1 := n1 + 1; add(v := i1); END_FOR;
  n2 := 0; FOR i2 := 1 TO 30 DO n2 := n2 + 1; x := AddTenF(i2); END_FOR;
  n3 := 0; FOR i3 := 1 TO 30 DO n3 := n3 + 1; outb(x := i3, y => i3); END_FOR;
  n4 := 0; FOR i4 := 1 TO 30 DO n4 := n4 + 1; h.AddTen(i4); END_FOR;
  n5 := 0; FOR i5 := 1 TO 30 DO n5 := n5 + 1; p := ADR(i5); p^ := p^ + 10; END_FOR;
  r REF= i6;
  n6 := 0; FOR i6 := 1 TO 30 DO n6 := n6 + 1; r := r + 10; END_FOR;
  n7 := 0; FOR i7 := 1 TO 30 DO n7 := n7 + 1; i7 := i7 + 10; END_FOR;
  n8 := 0; FOR i8 := 1 TO 30 DO n8 := n8 + 1; FOR i8 := i8 TO i8 + 9 DO x := x; END_FOR; END_FOR;
  n9 := 0; FOR i9 := 1 TO 30 DO n9 := n9 + 1; AddTenF(v := i9); END_FOR;
  sb();
  g_touched();
  g_straight();
END_PROGRAM
"""

# CODESYS: each round writes 10 more into the counter, so 1 → 11, 12 → 22, 23 → 33, 34 ends it
EXPECTED = {f"main.{v}{k}": (34 if v == "i" else 3) for k in range(1, 10) for v in "in"}
EXPECTED.update({"main.sb.n": 3, "main.sb.i": 34})
EXPECTED.update({"g_touched.n": 3, "g_touched.i": 34, "g_touched.y": 1 + 100 + 100, "g_touched.x": 100})
EXPECTED.update({"g_straight.a": 5, "g_straight.b": 3, "g_straight.c": 18})


def _values(compiled) -> dict:
    plc = PLC(compiled)
    plc.scan()
    return {k: plc[k] for k in EXPECTED}


def _without_choices(monkeypatch):
    """Every FOR re-tests its counter and no variable is kept in a Python local."""
    monkeypatch.setattr(loops, "may_write_counter", lambda *a: True)
    monkeypatch.setattr(writes.Writes, "shared", lambda self, body, block: True)


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat"])
def test_a_counter_written_while_the_body_runs_is_tested_as_codesys_does(dialect):
    assert _values(compile_text(ALIASES, "aliases.st", dialect=dialect, use_cache=False)) == EXPECTED


def test_the_same_without_any_choice_made_from_who_writes_what(monkeypatch):
    _without_choices(monkeypatch)
    assert _values(compile_text(ALIASES, "aliases.st", use_cache=False)) == EXPECTED


@pytest.mark.skipif(toolchain.missing() is not None, reason=f"native tier: {toolchain.missing()}")
def test_the_same_on_the_native_tier():
    compiled = compile_text(ALIASES, "aliases.st", native=True)
    assert compiled.native  # at least the program's body is compiled
    assert _values(compiled) == EXPECTED


def test_each_loop_takes_the_form_its_writers_need():
    compiled = compile_text(ALIASES, "aliases.st", emit_python=True, use_cache=False)
    text = "\n".join(compiled.python_source.values())
    # none of the nine counters of main, nor SelfBump's or GlobalTouched's, runs as a Python `for`;
    # the inner FOR over i8 does (its body leaves i8 alone; the outer loop re-tests what it left)
    assert [f"for i{k} in" in text for k in range(1, 10)] == [False] * 7 + [True, False]
    assert "for i in " not in text and "_range(1, 31)" not in text


PLAIN = """
FUNCTION_BLOCK Worker
  VAR_INPUT k : INT; END_VAR
  VAR_OUTPUT s : DINT; END_VAR
  s := s + k;
END_FUNCTION_BLOCK
PROGRAM main
  VAR i, j : INT; w : Worker; total : DINT; a : ARRAY[1..10] OF INT; END_VAR
  FOR i := 1 TO 10 DO w(k := i); a[i] := i; END_FOR;
  FOR j := 1 TO 10 DO total := total + a[j]; END_FOR;
END_PROGRAM
"""


def test_a_counter_nothing_else_can_reach_stays_a_python_for_and_is_cached():
    text = "\n".join(compile_text(PLAIN, "plain.st", emit_python=True, use_cache=False).python_source.values())
    assert text.count("for i in _range(1, 11)") == 1 and text.count("for j in _range(1, 11)") == 1
    assert "i = self.i" in text  # kept in a local during the body
    plc = PLC(compile_text(PLAIN, "plain.st"))
    plc.scan()
    assert (plc["main.i"], plc["main.j"], plc["main.total"], plc["main.w.s"]) == (11, 11, 55, 55)


INDEX = """
FUNCTION_BLOCK AddTen
  VAR_IN_OUT v : INT; END_VAR
  v := v + 10;
END_FUNCTION_BLOCK
PROGRAM main
  VAR i : INT; add : AddTen; arr : ARRAY[1..10] OF INT; END_VAR
  FOR i := 1 TO 10 DO
    add(v := i);
    arr[i] := 1;
  END_FOR;
END_PROGRAM
"""


@pytest.mark.parametrize("native", [False, True])
def test_an_index_by_a_counter_the_body_moved_out_of_bounds_is_checked(native):
    """The counter's interval 1..10 does not hold once a call wrote 11 into it: the index check stays."""
    if native and toolchain.missing() is not None:
        pytest.skip(f"native tier: {toolchain.missing()}")
    plc = PLC(compile_text(INDEX, "index.st", native=native))
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    assert info.value.fault.kind == "INDEX" and info.value.fault.line == 10


WRITES = """PROGRAM main
  VAR i, n, x : INT; add : AddTen; END_VAR
  FOR i := 1 TO 3 DO
    i := i + 1;
    add(v := i);
    x := AddTenF(i);
    FOR i := 1 TO 2 DO n := n + 1; END_FOR;
  END_FOR;
END_PROGRAM
FUNCTION_BLOCK AddTen
  VAR_IN_OUT v : INT; END_VAR
  v := v + 10;
END_FUNCTION_BLOCK
FUNCTION AddTenF : INT
  VAR_IN_OUT v : INT; END_VAR
  AddTenF := v;
END_FUNCTION
"""


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_iec_and_matiec_refuse_every_write_of_the_counter_the_body_shows(dialect):
    with pytest.raises(CompileError) as info:
        compile_text(WRITES, "writes.st", dialect=dialect, use_cache=False)
    got = [(d.code, d.span.line, d.span.col) for d in info.value.diagnostics]
    assert got == [("E052", 4, 5), ("E052", 5, 14), ("E052", 6, 18), ("E052", 7, 9)]
    first = info.value.diagnostics[0]
    assert first.message == "'i' is the control variable of the FOR on line 3: assigned in its body"
    assert "passed to VAR_IN_OUT 'v'" in info.value.diagnostics[1].message


def test_iec_accepts_a_counter_only_read_in_the_body():
    compile_text(PLAIN, "plain.st", dialect="iec", use_cache=False)


ROOT = Path(__file__).resolve().parents[1]
CORPUS = sorted(
    [p for p in (ROOT / "programs").glob("*.st") if not p.name.startswith("test_")]
    + list((ROOT / "bench" / "workloads").glob("*.st"))
    + list((ROOT / "tests" / "golden").glob("*.st"))
)


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.name)
def test_the_choices_change_no_value_of_the_example_programs(path, monkeypatch):
    """Differential: the project's own programs, with and without the choices, 300 scans."""
    chosen = PLC(compile_text(path.read_text(), str(path), use_cache=False))
    _without_choices(monkeypatch)
    plain = PLC(compile_text(path.read_text(), str(path), use_cache=False))
    for plc in (chosen, plain):
        plc.scan(300)
    assert chosen.variables(all=True) == plain.variables(all=True)  # the blocks' internals too


IN_OUTS = """
FUNCTION ViaGlobal : INT
  VAR_IN_OUT v : INT; END_VAR
  VAR_EXTERNAL g : INT; END_VAR
  v := v + 1;
  g := 100;          (* v names g: CODESYS's reference sees it *)
  ViaGlobal := v;
END_FUNCTION

FUNCTION Twice : INT
  VAR_IN_OUT a, b : INT; END_VAR
  a := a + 1;
  b := b * 10;       (* a and b may name one variable *)
  Twice := a;
END_FUNCTION

FUNCTION Plain : INT
  VAR_IN_OUT v : INT; END_VAR
  v := v + 1;
  Plain := v;
END_FUNCTION

FUNCTION_BLOCK Counter
  VAR_OUTPUT x : INT; END_VAR
  METHOD Add : INT
    VAR_IN_OUT v : INT; END_VAR
    v := v + 1;
    x := 50;         (* the caller passed this very x *)
    Add := v;
  END_METHOD
END_FUNCTION_BLOCK

VAR_GLOBAL g : INT; END_VAR

PROGRAM main
  VAR_EXTERNAL g : INT; END_VAR
  VAR r1, r2, r3, r4, k, q : INT; c : Counter; END_VAR
  g := 1; r1 := ViaGlobal(g);
  k := 1; r2 := Twice(k, k);
  q := 1; r3 := Plain(q);
  r4 := c.Add(c.x);
END_PROGRAM
"""
IN_OUTS_EXPECTED = {"main.r1": 100, "g": 100, "main.r2": 20, "main.k": 20, "main.r3": 2, "main.q": 2}
IN_OUTS_EXPECTED.update({"main.r4": 50, "main.c.x": 50})


@pytest.mark.parametrize("native", [False, True])
def test_a_function_s_in_out_written_another_way_meanwhile_is_seen_as_codesys_does(native):
    if native and toolchain.missing() is not None:
        pytest.skip(f"native tier: {toolchain.missing()}")
    plc = PLC(compile_text(IN_OUTS, "in_outs.st", native=native))
    plc.scan()
    assert {k: plc[k] for k in IN_OUTS_EXPECTED} == IN_OUTS_EXPECTED


def test_an_in_out_nothing_else_can_reach_is_still_copied_in_and_out():
    text = "\n".join(compile_text(IN_OUTS, "in_outs.st", emit_python=True, use_cache=False).python_source.values())
    plain = text[text.index("def _fn_Plain") :]
    assert "v = _r_v.get()" in plain  # a local copy: the fast path stays where it is right
    via = text[text.index("def _fn_ViaGlobal") : text.index("def _fn_Twice")]
    assert "_r_v.get()" not in via and "v[0]" in via  # through the caller's reference
