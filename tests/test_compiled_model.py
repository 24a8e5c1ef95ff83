"""The compiled artefact: AST-free, the same from the cache as from the compiler, a versioned
serialisation, and st/model a leaf package."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

from st import PLC
from st.api import compile_text
from st.compiler import cache
from st.model.compiled import FORMAT, CompiledProgram, FormatError
from st.model.summaries import InitialValue, PouInfo

# a bit of everything the compiler keeps as syntax: initial values, methods and properties,
# SFC steps, transitions and actions, configuration connections, VAR_CONFIG, a TEST block
PROGRAM = """
TYPE Pair : STRUCT a : INT := 7; b : INT := 2 * 3; END_STRUCT; END_TYPE
TYPE Level : INT := 4; END_TYPE
FUNCTION_BLOCK Counter
  VAR_INPUT step : INT := 1; END_VAR
  VAR_OUTPUT count : INT; END_VAR
  VAR _speed : REAL; END_VAR
  METHOD Add : INT
    VAR_INPUT n : INT; END_VAR
    count := count + n * step;
    Add := count;
  END_METHOD
  PROPERTY Speed : REAL
    GET Speed := _speed; END_GET
    SET _speed := Speed; END_SET
  END_PROPERTY
  count := count + step;
END_FUNCTION_BLOCK
PROGRAM P
VAR_INPUT go : BOOL; lim : INT := 3; END_VAR
VAR_OUTPUT lamp : BOOL; level : INT; END_VAR
VAR speed : INT; c : Counter; p : Pair; l : Level; cnt : INT; t : TIME := T#2s; END_VAR
INITIAL_STEP Idle:
END_STEP
TRANSITION FROM Idle TO Work := go AND lim > 0; END_TRANSITION
STEP Work:
  count(P);
  lamp(D, T#20ms);
END_STEP
TRANSITION FROM Work TO Idle := Work.T >= T#30ms; END_TRANSITION
ACTION count: cnt := cnt + c.Add(1); END_ACTION
END_PROGRAM
CONFIGURATION C
  VAR_GLOBAL g_level : INT; g_lim : INT := 21; END_VAR
  RESOURCE R ON PLC
    TASK t(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst WITH t : P (go := %IX0.1, lim := g_lim + 1, lamp => %QX0.2, level => g_level);
  END_RESOURCE
  VAR_CONFIG
    inst.speed : INT := 100;
  END_VAR
END_CONFIGURATION
TEST 'counts'
  VAR c : Counter; END_VAR
  c(step := 2);
  ASSERT_EQ(c.count, 2);
END_TEST
"""


def _compiler_objects(root) -> list:
    """Every object reachable from `root` whose class belongs to the compiler (the AST above all)."""
    seen, found, todo = set(), [], [root]
    while todo:
        x = todo.pop()
        if id(x) in seen or isinstance(x, (str, int, float, bool, bytes, type(None), type)):
            continue
        seen.add(id(x))
        if type(x).__module__.startswith("st.compiler"):
            found.append(x)
            continue
        if isinstance(x, dict):
            todo.extend(x.keys())
            todo.extend(x.values())
        elif isinstance(x, (list, tuple, set, frozenset)):
            todo.extend(x)
        elif hasattr(x, "__dict__"):
            todo.extend(vars(x).values())
    return found


def test_the_artefact_holds_no_compiler_object():
    compiled = compile_text(PROGRAM, "m.st", use_cache=False)
    assert _compiler_objects(compiled.project) == []
    p = compiled.project.pous["p"]
    assert p.decl == PouInfo(p.decl.span, "PROGRAM", "P") and p.decl.span.line == 19
    assert p.actions["count"].kind == "ACTION"
    assert p.vars["t"].init == InitialValue(2_000_000_000)
    assert p.vars["speed"].init is None
    assert compiled.project.configs[0].var_config[0][2] == InitialValue(100)
    assert [lib.name for lib in compiled.project.libraries] == ["iec61131", "plcopen", "vendor"]
    assert [t.name for t in compiled.project.tests] == ["counts"]


def test_a_cached_and_an_uncached_compile_give_the_same_artefact(tmp_path, monkeypatch):
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path))
    first = compile_text(PROGRAM, "m.st")
    second = compile_text(PROGRAM, "m.st")
    uncached = compile_text(PROGRAM, "m.st", use_cache=False)
    assert (first.from_cache, second.from_cache, uncached.from_cache) == (False, True, False)
    assert first.to_bytes() == second.to_bytes() == uncached.to_bytes()
    assert first.sources.keys() == second.sources.keys() and first.helpers.keys() == second.helpers.keys()
    plc = PLC(second)
    plc["%IX0.1"] = True
    plc.scan(3)
    assert plc["inst.cnt"] == 1 and plc["g_level"] == 0


def test_storing_and_loading_change_nothing_they_are_given(tmp_path):
    compiled = compile_text(PROGRAM, "m.st", use_cache=False)
    before = compiled.to_bytes()
    project, decl = compiled.project, compiled.project.pous["p"].decl
    cache.store(tmp_path, "k", compiled)
    assert compiled.to_bytes() == before
    assert compiled.project is project and project.pous["p"].decl is decl and not compiled.from_cache
    loaded = cache.load(tmp_path, "k", sources=compiled.sources, helpers=compiled.helpers)
    again = cache.load(tmp_path, "k", sources=compiled.sources, helpers=compiled.helpers)
    assert loaded is not None and again is not None and loaded.from_cache
    assert loaded.project is not again.project and loaded.project is not compiled.project
    assert loaded.to_bytes() == before


def test_an_old_or_foreign_payload_is_refused_and_the_cache_compiles_again(tmp_path, monkeypatch):
    compiled = compile_text(PROGRAM, "m.st", use_cache=False)
    data = compiled.to_bytes()
    old = data.replace(FORMAT.to_bytes(2, "big"), (FORMAT - 1).to_bytes(2, "big"), 1)
    with pytest.raises(FormatError, match=f"format {FORMAT - 1}, this st reads format {FORMAT}"):
        CompiledProgram.from_bytes(old)
    with pytest.raises(FormatError, match="not a compiled st program"):
        CompiledProgram.from_bytes(b"\x80\x05garbage")
    with pytest.raises(FormatError, match="damaged"):
        CompiledProgram.from_bytes(data[: len(data) // 2])
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path))
    compile_text(PROGRAM, "m.st")
    (entry,) = (tmp_path / "compiled").iterdir()
    entry.write_bytes(old)
    again = compile_text(PROGRAM, "m.st")
    assert not again.from_cache and again.to_bytes() == data
    assert compile_text(PROGRAM, "m.st").from_cache


def test_the_serialisation_lets_no_compiler_object_in():
    compiled = compile_text(PROGRAM, "m.st", use_cache=False)
    from st.compiler import ast as A

    compiled.project.pous["p"].decl = A.Empty(compiled.project.pous["p"].decl.span)
    with pytest.raises(TypeError, match="st.compiler.ast.Empty cannot be part of a compiled program"):
        compiled.to_bytes()


def test_the_model_is_a_leaf_package():
    """st/model imports only the standard library, st.source and st.diagnostics."""
    root = Path(__file__).resolve().parents[1] / "st" / "model"
    allowed = {"source", "diagnostics"}
    for f in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level == 0:
                    assert node.module.split(".")[0] in sys.stdlib_module_names | {"__future__"}, (f.name, node.module)
                elif node.level == 2:
                    assert (node.module or "").split(".")[0] in allowed, (f.name, node.module)
                else:
                    assert node.level == 1, (f.name, node.module)
            elif isinstance(node, ast.Import):
                for a in node.names:
                    assert a.name.split(".")[0] in sys.stdlib_module_names, (f.name, a.name)


def test_a_compiler_object_left_in_the_model_is_an_internal_error(monkeypatch):
    from st.compiler import artefact
    from st.diagnostics import CompileError

    monkeypatch.setattr(artefact, "_RULES", {})  # nothing dropped: the AST stays in the model
    r = compile_text(PROGRAM, "m.st", use_cache=False, raise_on_error=False)
    assert [d.code for d in r.diagnostics if d.is_error] == ["E099"]
    assert "cannot be part of a compiled program" in r.diagnostics[0].message and r.project.pous == {}
    with pytest.raises(CompileError):
        compile_text(PROGRAM, "m.st", use_cache=False)
