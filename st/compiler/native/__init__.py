"""The native tier (`--native`): block bodies compiled to C by Cython, with the same semantics.

Pure CPython spends most of a scan on dispatch and boxing; this tier takes the `_body` of
every PROGRAM and FUNCTION_BLOCK of the project, and every user FUNCTION, as the code generator
printed them, with the facts it recorded beside each (codegen/facts.py: which locals hold which
ST variables, the loop guards, the helpers and what for, the intervals it proved), gives their
BOOL/integer/REAL locals C types where that computes exactly what Python computes, reaches
instance variables at their slots' offsets (kinds.py, typer.py), and builds all of them into
one extension module per program
(pyx.py, toolchain.py) that the runtime binds to each PLC (st/runtime/native.py). Semantics,
faults (with their ST lines), the watchdog and online change are the same as on the Python tier.

It needs Cython, a C compiler and Python's headers when the program is compiled; without them
the program compiles and runs as Python, with warning W012.
"""

from __future__ import annotations

import ast as py
from typing import Any

from ...diagnostics import Code, DiagnosticSink
from ...model import types as T
from ...model.compiled import NativeModule
from ...model.program import Project
from ...source import Span
from ..codegen.facts import WATCHDOG_ARMED, facts_of
from .kinds import Inst, ctype, of_type
from .pyx import module_text
from .toolchain import ToolchainError, build, missing
from .typer import ClassInfo, FuncInfo, NotEligible, Typed, type_body

# what the runtime rebinds in a namespace while the program runs (st.runtime)
RUNTIME_VOLATILE = frozenset({"_now", WATCHDOG_ARMED, "_plc_log", "_cov"})
_SECTIONS = ("VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_TEMP")


def build_native(
    modules: list[tuple[str, py.Module]], project: Project, sink: DiagnosticSink, where: Span
) -> tuple[list[NativeModule], dict[str, str]]:
    """The native module of a program's generated `modules`, and {POU: why its body stays Python}."""
    why = missing()
    if why is not None:
        sink.warning(
            Code.NATIVE_UNAVAILABLE, where, f"the native tier is not available: {why}", "the program runs as Python"
        )
        return [], {}
    volatile = RUNTIME_VOLATILE | _rebound_globals(modules)
    by_class = {p.pyname: p for p in project.pous.values() if p.pyname}
    structs = {t.pyname: t for t in _struct_types(project)}
    classes: dict[str, ClassInfo] = {}
    found: list[tuple[str, py.ClassDef, Any]] = []
    for path, mod in modules:
        for node in mod.body:
            if not isinstance(node, py.ClassDef):
                continue
            st = structs.get(node.name)
            if st is not None:  # its members read and written at their slots, as a block's variables
                kinds = {m.pyname or m.name: of_type(m.type) for m in st.members.values()}
                classes[node.name] = ClassInfo(_slots(node), {k: v for k, v in kinds.items() if v is not None})
                continue
            pou = by_class.get(node.name)
            if pou is None or pou.pou_kind not in ("PROGRAM", "FUNCTION_BLOCK"):
                continue
            kinds = {v.pyname: of_type(v.type) for v in pou.vars.values() if v.section in _SECTIONS and v.pyname}
            # a VAR_IN_OUT block or STRUCT is the caller's instance itself (an elementary one is a reference)
            kinds.update(
                (v.pyname, k)
                for v in pou.vars.values()
                if v.section == "VAR_IN_OUT" and v.pyname and isinstance(k := of_type(v.type), Inst)
            )
            classes[node.name] = ClassInfo(_slots(node), {k: v for k, v in kinds.items() if v is not None})
            found.append((path, node, pou))
    funcs, fdefs = _functions(modules, project)
    bodies: list[tuple[str, str, str, Typed]] = []
    skipped: dict[str, str] = {}
    for path, fdef, pou in fdefs:
        if fdef.name not in funcs:
            skipped[pou.name] = "the code generator recorded no facts for its parameters"
            continue
        try:
            bodies.append((fdef.name, path, pou.name, type_body(fdef, fdef.name, classes, volatile, funcs)))
        except NotEligible as e:
            skipped[pou.name] = str(e)
    for path, node, pou in found:
        if pou.library:
            continue  # a library's bodies stay Python (most are small; the block calls into them are compiled)
        fn = next((s for s in node.body if isinstance(s, py.FunctionDef) and s.name == "_body"), None)
        if fn is None:
            continue
        try:
            bodies.append((node.name, path, pou.name, type_body(fn, node.name, classes, volatile, funcs)))
        except NotEligible as e:
            skipped[pou.name] = str(e)
    if not bodies:
        return [], skipped
    text, lines = module_text(bodies)
    try:
        name, _so, _built = build(text)
    except ToolchainError as e:
        sink.warning(
            Code.NATIVE_UNAVAILABLE,
            where,
            f"the native tier could not build this program: {e}",
            "the program runs as Python",
        )
        return [], skipped
    blocks = tuple(c for c, _, _, t in bodies if t.function is None)
    functions = tuple(c for c, _, _, t in bodies if t.function is not None)
    return [NativeModule(name, name + ".pyx", blocks, lines, functions)], skipped


def _functions(
    modules: list[tuple[str, py.Module]], project: Project
) -> tuple[dict[str, FuncInfo], list[tuple[str, py.FunctionDef, Any]]]:
    """The user FUNCTIONs as the code generator printed them (module-level `def`s): {name: the
    kinds of its parameters and result}, and [(file, def, POU)]. A parameter that receives no
    value of a C kind (its facts say: a VAR_IN_OUT's or VAR_OUTPUT's reference, a box) stays an
    object."""
    by_name = {p.pyname: p for p in project.pous.values() if p.pyname and p.pou_kind == "FUNCTION" and not p.library}
    infos: dict[str, FuncInfo] = {}
    defs = []
    for path, mod in modules:
        for node in mod.body:
            pou = by_name.get(node.name) if isinstance(node, py.FunctionDef) else None
            if pou is None:
                continue
            assert isinstance(node, py.FunctionDef)
            facts = facts_of(node)
            if facts is not None and [a.arg for a in node.args.args] == [name for name, _ in facts.params]:
                params = [of_type(t) if t is not None else None for _, t in facts.params]
                infos[node.name] = FuncInfo([k if ctype(k) else None for k in params], of_type(pou.return_type))
            defs.append((path, node, pou))
    return infos, defs


def _struct_types(project: Project) -> list[T.StructType]:
    """The project's STRUCT types (a UNION, whose members share bytes, is not one)."""
    return [t for t in project.types.values() if isinstance(t, T.StructType) and t.kind == "struct" and t.pyname]


def _slots(cls: py.ClassDef) -> frozenset[str]:
    """The names in a generated class's `__slots__` (its own; an EXTENDS block's are all declared again)."""
    for s in cls.body:
        if isinstance(s, py.Assign) and any(isinstance(t, py.Name) and t.id == "__slots__" for t in s.targets):
            if isinstance(s.value, py.Tuple):
                return frozenset(
                    e.value for e in s.value.elts if isinstance(e, py.Constant) and isinstance(e.value, str)
                )
    return frozenset()


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
