"""The native tier (`--native`): loop bodies compiled to C by Cython, the rest unchanged.

Pure CPython spends most of an integer loop on dispatch and boxing; this tier takes the
`_body` of every PROGRAM and FUNCTION_BLOCK that has a loop, as the code generator printed it,
gives its BOOL/integer/REAL locals C types where that computes exactly what Python computes
(kinds.py, typer.py), and builds all of them into one extension module per program
(pyx.py, toolchain.py) that the runtime binds to each PLC (st/runtime/native.py). Semantics,
faults (with their ST lines), the watchdog and online change are the same as on the Python tier.

It needs Cython, a C compiler and Python's headers when the program is compiled; without them
the program compiles and runs as Python, with warning W012.
"""

from __future__ import annotations

import ast as py

from ...diagnostics import DiagnosticSink
from ...model.compiled import NativeModule
from ...model.program import Project
from ...source import Span
from .kinds import element_kind, of_type
from .pyx import module_text
from .toolchain import ToolchainError, build, missing
from .typer import NotEligible, Typed, type_body

# what the runtime rebinds in a namespace while the program runs (st.runtime)
RUNTIME_VOLATILE = frozenset({"_now", "_wd_armed", "_plc_log", "_cov"})
_SECTIONS = ("VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_TEMP")


def build_native(
    modules: list[tuple[str, py.Module]], project: Project, sink: DiagnosticSink, where: Span
) -> tuple[list[NativeModule], dict[str, str]]:
    """The native module of a program's generated `modules`, and {POU: why its body stays Python}."""
    why = missing()
    if why is not None:
        sink.warning("W012", where, f"the native tier is not available: {why}", "the program runs as Python")
        return [], {}
    volatile = RUNTIME_VOLATILE | _rebound_globals(modules)
    by_class = {p.pyname: p for p in project.pous.values() if p.pyname}
    bodies: list[tuple[str, str, str, Typed]] = []
    skipped: dict[str, str] = {}
    for path, mod in modules:
        for node in mod.body:
            if not isinstance(node, py.ClassDef):
                continue
            pou = by_class.get(node.name)
            if pou is None or pou.pou_kind not in ("PROGRAM", "FUNCTION_BLOCK"):
                continue
            fn = next((s for s in node.body if isinstance(s, py.FunctionDef) and s.name == "_body"), None)
            if fn is None:
                continue
            fields, arrays = {}, {}
            for v in pou.vars.values():
                if v.section in _SECTIONS and v.pyname:
                    fields[v.pyname] = of_type(v.type)
                    arrays[v.pyname] = element_kind(v.type)
            try:
                bodies.append((node.name, path, pou.name, type_body(fn, fields, arrays, volatile)))
            except NotEligible as e:
                skipped[pou.name] = str(e)
    if not bodies:
        return [], skipped
    text, lines = module_text(bodies)
    try:
        name, so, _built = build(text)
    except ToolchainError as e:
        sink.warning("W012", where, f"the native tier could not build this program: {e}", "the program runs as Python")
        return [], skipped
    return [NativeModule(name, str(so), name + ".pyx", tuple(c for c, _, _, _ in bodies), lines)], skipped


def _rebound_globals(modules: list[tuple[str, py.Module]]) -> frozenset[str]:
    """Module-level names that code assigns after start-up (VAR_GLOBALs, directly addressed
    variables): a body must read them from the namespace at each use."""
    out: set[str] = set()
    for _path, mod in modules:
        for node in mod.body:
            if isinstance(node, (py.Assign, py.AugAssign, py.AnnAssign)):
                targets = node.targets if isinstance(node, py.Assign) else [node.target]
                out.update(n.id for t in targets for n in py.walk(t) if isinstance(n, py.Name))
        for sub in py.walk(mod):
            if isinstance(sub, py.Global):
                out.update(sub.names)
    return frozenset(out)
