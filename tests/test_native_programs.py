"""Every example program and benchmark workload on the native tier (issue 33): each body of the
program's own blocks and FUNCTIONs is compiled, with a C type for every variable it holds in a
Python local whose IEC type has one, or stays Python for one of the documented reasons, and the
set of those is exactly the one expected for that program."""

from __future__ import annotations

import ast as py
import re
from pathlib import Path

import pytest

from st.api import compile_text
from st.compiler.native import toolchain
from st.compiler.native.kinds import ctype, of_type

ROOT = Path(__file__).resolve().parents[1]
needs_toolchain = pytest.mark.skipif(toolchain.missing() is not None, reason=f"native tier: {toolchain.missing()}")

# a program's tests (TEST blocks) have no native build: a MOCK replaces a body while a test runs
PROGRAMS = [
    p
    for p in [
        *sorted((ROOT / "programs").glob("*.st")),
        *sorted((ROOT / "programs" / "thesis").glob("*.st")),
        *sorted((ROOT / "bench" / "workloads").glob("*.st")),
    ]
    if not p.name.startswith("test_")
]

# why a body stays Python (st/compiler/native: typer.NotEligible, build_native; docs/native.md)
DOCUMENTED = (
    "it writes a global variable",
    "it uses the name ",  # "…, which C or Cython reserve"
    "it contains a ",  # a Yield, an Await, a Lambda, a ClassDef, a nested function
    "an expression is nested more than ",
    "its parameters are not plain positional ones",
)

# {program: {POU: why its body stays Python}}; a program not named here has every body compiled
EXPECTED_PYTHON: dict[str, dict[str, str]] = {}


def _c_locals(pyx: str) -> dict[str, set[str]]:
    """{class or FUNCTION: the locals its compiled body declares with a C type}."""
    out: dict[str, set[str]] = {}
    current = None
    for line in pyx.splitlines():
        m = re.match(r"cdef \w+ _k_impl(\w+)\(", line)
        if m:
            current = out.setdefault(m.group(1), set())
        elif current is not None and line.startswith("    cdef ") and "_k_wd" not in line:
            current.update(n.strip() for n in line.split(None, 2)[2].split(","))
        elif current is not None and not line.startswith("    cdef "):
            current = None
    return out


def _held_in_locals(fn: py.FunctionDef, names: set[str]) -> set[str]:
    """Which of `names` the generated function holds in a Python local of their own (stored as a
    plain name, never as a one-element box)."""
    stores: dict[str, list[py.expr | None]] = {}
    for node in py.walk(fn):
        if isinstance(node, py.Assign):
            for t in node.targets:
                for n in py.walk(t):
                    if isinstance(n, py.Name) and isinstance(n.ctx, py.Store):
                        stores.setdefault(n.id, []).append(node.value if t is n else None)
        elif isinstance(node, py.For) and isinstance(node.target, py.Name):
            stores.setdefault(node.target.id, []).append(None)
    return {n for n in names & set(stores) if not any(isinstance(v, py.List) for v in stores[n])}


@pytest.mark.slow  # a native build per program (2-3 s each the first time)
@needs_toolchain
@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: p.name)
def test_every_user_body_is_compiled_with_c_types(path):
    compiled = compile_text(path.read_text(), path.name, native=True, emit_python=True)
    assert not [d for d in compiled.diagnostics if d.code == "W012"]
    own = {
        p.pyname: p
        for p in compiled.project.pous.values()
        if not p.library and p.pou_kind in ("PROGRAM", "FUNCTION_BLOCK", "FUNCTION") and p.pyname
    }
    (module,) = compiled.native
    done = {*module.classes, *module.functions}
    assert {own[c].name for c in done if c in own} | set(compiled.native_skipped) == {p.name for p in own.values()}
    assert compiled.native_skipped == EXPECTED_PYTHON.get(path.name, {})
    assert all(why.startswith(DOCUMENTED) for why in compiled.native_skipped.values())
    # every ST variable of the POU that the generated body holds in a Python local, and whose IEC
    # type has a C type, is a C variable of the compiled body (a parameter is one of its signature)
    declared = _c_locals(module.file.with_name(module.pyx).read_text())
    tree = py.parse(compiled.python_source[path.name])
    defs = {n.name: n for n in tree.body if isinstance(n, (py.ClassDef, py.FunctionDef))}
    for name in done:
        pou = own[name]
        node = defs[name]
        fn = (
            node
            if isinstance(node, py.FunctionDef)
            else next(s for s in node.body if getattr(s, "name", "") == "_body")
        )
        params = {a.arg for a in fn.args.args}
        typed = {
            v.pyname
            for v in pou.vars.values()
            if v.section in ("VAR", "VAR_TEMP", "VAR_INPUT", "VAR_OUTPUT") and ctype(of_type(v.type)) and v.pyname
        }
        if pou.pou_kind == "FUNCTION" and ctype(of_type(pou.return_type)):
            typed.add(pou.name)  # the FUNCTION's own result variable
        want = _held_in_locals(fn, typed) - params
        assert want <= declared[name], f"{pou.name}: {sorted(want - declared[name])} stay Python objects"
        assert want or pou.pou_kind != "PROGRAM" or not typed, f"{pou.name} holds no variable in a C local"
