"""The compiler pipeline: sources → parse → check → generate → code objects (cached).

`compile_sources` is the one entry point; the CLI, the PLC API and the tests
all go through it.
"""
from __future__ import annotations

import gc
import hashlib
import marshal
import os
import pickle
import sys
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from ..diagnostics import CompileError, Diagnostic, DiagnosticSink, Severity
from ..source import SourceFile, Span
from . import ast as A
from .build import AstBuilder
from .check import Checker
from .codegen import ModuleGen
from .codegen.source import python_text
from .lower import lower
from .dialect import strict_types
from .library import Library
from .model import Project

COMPILER_VERSION = "0.1.0-9"
_parser_lock = threading.Lock()
_parser = None
_builder = None


def _get_parser():
    global _parser, _builder
    if _parser is None:
        from ..grammar.parser import StParser
        _builder = AstBuilder("")
        _parser = StParser(_builder)
    return _parser, _builder


@dataclass
class CompiledProgram:
    """Everything the runtime needs: code objects and the checked model."""

    modules: list                      # [(filename, code object)]
    project: Project
    diagnostics: list
    sources: dict                      # path → SourceFile (for rendering diagnostics)
    helpers: dict = field(default_factory=dict)
    python_source: dict = field(default_factory=dict)   # path → Python text (emit python)
    from_cache: bool = False
    coverage_points: list = field(default_factory=list)  # [(file, line, kind, label, target)] (coverage builds)
    coverage_hits: Optional[bytearray] = None            # one byte per point, shared by every PLC of this build
    test_modules: list = field(default_factory=list)     # [(filename, code)]: `_test_<n>` functions (TEST blocks)


def parse_source(src: SourceFile, sink: DiagnosticSink) -> Optional[A.Unit]:
    """Parse one file; every problem becomes a diagnostic of that file (never an exception)."""
    with _parser_lock:
        parser, builder = _get_parser()
        builder.path = src.path
        builder.errors = []
        try:
            unit, diags = parser.parse(src)
        except RecursionError:
            sink.error("E041", Span(src.path, 1, 1), "this file is nested too deeply to parse",
                       "split deeply nested expressions or statements")
            return None
        except Exception as exc:  # a parser bug must still not show the user a traceback
            if os.environ.get("ST_DEBUG"):
                raise
            sink.error("E099", Span(src.path, 1, 1), f"internal compiler error while parsing: {type(exc).__name__}: {exc}",
                       "please report this with the source file; set ST_DEBUG=1 to see the traceback")
            return None
        errors = list(builder.errors)
    for d in diags:
        sink.add(d)
    for e in errors:
        sink.error(e.code, e.span, e.message)
    if unit is not None:
        unit.path = src.path
    return unit


def _cache_dir() -> Optional[Path]:
    if os.environ.get("ST_NO_CACHE"):
        return None
    base = os.environ.get("ST_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "st")
    p = Path(base) / "compiled"
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return p


_toolchain_digest: Optional[str] = None


def _toolchain() -> str:
    """A digest of the compiler's own code: a new compiler never reuses old cached output."""
    global _toolchain_digest
    if _toolchain_digest is None:
        h = hashlib.sha256(COMPILER_VERSION.encode())
        root = Path(__file__).resolve().parents[1]
        for sub in ("grammar", "compiler", "stdlib", "runtime"):
            for f in sorted((root / sub).rglob("*")):
                if f.suffix in (".py", ".lark", ".st"):
                    h.update(f.read_bytes())
        _toolchain_digest = h.hexdigest()
    return _toolchain_digest


def _cache_key(sources: list[SourceFile], libraries: list[Library], emit_python: bool) -> str:
    h = hashlib.sha256()
    h.update(_toolchain().encode())
    h.update(sys.version.encode())
    h.update(b"py" if emit_python else b"-")
    for lib in libraries:
        h.update(lib.name.encode() + lib.version.encode())
        for path, text in lib.sources:
            h.update(text.encode())
    for s in sources:
        h.update(s.path.encode() + b"\0" + s.text.encode() + b"\0")
    return h.hexdigest()


def compile_sources(sources: list[SourceFile], libraries: list[Library], *, emit_python: bool = False,
                    use_cache: bool = True, raise_on_error: bool = True, coverage: bool = False) -> CompiledProgram:
    """Compile ST sources with the given libraries; `coverage` adds line and branch probes (not cached)."""
    # The compiler allocates millions of small objects that all live until the end:
    # the cyclic GC would rescan them again and again (a third of the time on 20k lines).
    enabled = gc.isenabled()
    gc.disable()
    # long operator chains (a + b + ... thousands of terms) nest deeply in the AST
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 20000))
    try:
        return _compile_sources(sources, libraries, emit_python=emit_python, use_cache=use_cache and not coverage,
                                raise_on_error=raise_on_error, coverage=coverage)
    finally:
        sys.setrecursionlimit(limit)
        if enabled:
            gc.enable()


def _compile_sources(sources, libraries, *, emit_python, use_cache, raise_on_error, coverage) -> CompiledProgram:
    all_sources = {s.path: s for s in sources}
    key = _cache_key(sources, libraries, emit_python)
    cdir = _cache_dir() if use_cache else None
    if cdir is not None:
        hit = _load_cache(cdir / key, all_sources, libraries)
        if hit is not None:
            return hit
    sink = DiagnosticSink()
    units = []
    lib_paths = set()
    for lib in libraries:
        for path, text in lib.sources:
            src = SourceFile(path, text)
            all_sources[path] = src
            lib_paths.add(path)
            u = parse_source(src, sink)
            if u is not None:
                units.append(u)
    for s in sources:
        u = parse_source(s, sink)
        if u is not None:
            units.append(u)
    dialect = next((lib.dialect for lib in libraries if getattr(lib, "dialect", None)), None)
    # pragmas a dialect knows are not "ignored" news: {dialect '…'} always, {attribute '…'} in codesys/twincat
    sink.items = [d for d in sink.items if not (d.code == "W001" and (
        "{dialect" in d.message.lower().replace(" ", "") or
        (dialect is not None and dialect.attribute_pragmas and "{attribute" in d.message.lower())))]
    checker = Checker(sink, libraries)
    checker.strict_enums = strict_types(s.text for s in sources)
    modules = []
    test_modules = []
    pysrc = {}
    project = Project()
    gen = None
    try:
        project = checker.run(units, lib_paths)
        _attach_test_texts(project, all_sources)
        if not sink.has_errors:
            gen = ModuleGen(lower(project), sink, coverage=coverage)
            py_modules = gen.generate()
            if not sink.has_errors:
                for out, group in ((modules, py_modules), (test_modules, gen.test_modules())):
                    for path, mod in group:
                        if emit_python:
                            pysrc[path] = (pysrc[path] + "\n\n" if path in pysrc else "") + python_text(mod)
                        out.append((path, compile(mod, path, "exec")))
    except RecursionError as exc:
        first = sources[0].path if sources else "<input>"
        sink.error("E041", getattr(exc, "st_span", None) or Span(first, 1, 1),
                   "this statement is nested too deeply to compile", "split the expression into several assignments")
    except SyntaxError as exc:       # Python's own limits, e.g. more than 20 nested loops
        sink.error("E041", Span(exc.filename or (sources[0].path if sources else "<input>"), exc.lineno or 1, 1),
                   f"this code is nested too deeply to compile ({exc.msg})", "move inner loops into a FUNCTION")
    except Exception as exc:  # a compiler bug must still not show the user a traceback
        first = sources[0].path if sources else "<input>"
        sink.error("E099", getattr(exc, "st_span", None) or Span(first, 1, 1), f"internal compiler error: {type(exc).__name__}: {exc}",
                   "please report this with the source file; set ST_DEBUG=1 to see the traceback")
        if os.environ.get("ST_DEBUG"):
            raise
    diags = sink.sorted()
    helpers = {}
    for lib in libraries:
        helpers.update(lib.helpers)
    result = CompiledProgram(modules, project, diags, all_sources, helpers, pysrc)
    result.test_modules = test_modules
    if coverage and gen is not None:
        result.coverage_points = gen.cov_points
        result.coverage_hits = bytearray(len(gen.cov_points))
    if any(d.is_error for d in diags):
        if raise_on_error:
            raise CompileError(diags, all_sources)
        return result
    if cdir is not None:
        _store_cache(cdir / key, result)
    return result


def _attach_test_texts(project: Project, sources: dict) -> None:
    """Each test statement's source text, for failure reports (`ASSERT_EQ(uut.count, 3)`)."""
    for info in project.test_asserts:
        src = sources.get(info.span.file)
        if src is not None:
            info.text = src.text_of(info.span)


def _strip_for_cache(project: Project) -> None:
    """Drop what only the compiler needed (AST bodies) before pickling."""
    for pou in project.pous.values():
        if pou.decl is not None:
            pou.decl = _PouStub(pou.decl.span, pou.decl.kind, pou.decl.name)
        for v in pou.vars.values():
            if not isinstance(v.init, A.Literal):       # literal initial values serve the Python API
                v.init = None
        pou.actions = {k: None for k in pou.actions}
    for t in project.types.values():
        if hasattr(t, "members") and isinstance(t.members, dict):
            for m in t.members.values():
                if hasattr(m, "init"):
                    m.init = None
        if hasattr(t, "init"):
            t.init = None
    for g in project.globals.values():
        g.init = None
    for sfc in project.sfc.values():
        for t in sfc.transitions:
            t.cond = None
        for st in sfc.steps:
            st.actions = [(a, q, None) for a, q, _ in st.actions]
    project.libraries = []
    project.test_blocks = []
    for t in project.tests:
        t.pou, t.setup, t.body, t.teardown = None, [], [], []
    for cfg in project.configs:
        for inst in cfg.instances:
            inst.args = [(p, None, o) for p, _, o in inst.args]


@dataclass
class _PouStub:
    span: Span
    kind: str
    name: str


def _store_cache(path: Path, result: CompiledProgram) -> None:
    try:
        proj = result.project
        libs = proj.libraries
        _strip_for_cache(proj)
        payload = pickle.dumps({
            "modules": [(p, marshal.dumps(c)) for p, c in result.modules],
            "test_modules": [(p, marshal.dumps(c)) for p, c in result.test_modules],
            "project": proj,
            "diagnostics": result.diagnostics,
            "python": result.python_source,
        }, protocol=pickle.HIGHEST_PROTOCOL)
        proj.libraries = libs
        tmp = path.with_suffix(".tmp%d" % os.getpid())
        tmp.write_bytes(payload)
        os.replace(tmp, path)
    except Exception:  # the cache is an optimisation; never fail a compile for it
        pass


def _load_cache(path: Path, sources: dict, libraries: list[Library]) -> Optional[CompiledProgram]:
    try:
        data = path.read_bytes()
    except OSError:
        return None
    try:
        d = pickle.loads(data)
        modules = [(p, marshal.loads(c)) for p, c in d["modules"]]
        test_modules = [(p, marshal.loads(c)) for p, c in d["test_modules"]]
    except Exception:
        return None
    helpers = {}
    for lib in libraries:
        helpers.update(lib.helpers)
        for p, text in lib.sources:
            sources[p] = SourceFile(p, text)
    d["project"].libraries = libraries
    result = CompiledProgram(modules, d["project"], d["diagnostics"], sources, helpers, d["python"], True)
    result.test_modules = test_modules
    return result


def load_files(paths: list[str]) -> list[SourceFile]:
    out = []
    for p in paths:
        try:
            raw = Path(p).read_bytes()
        except OSError as e:
            raise CompileError([Diagnostic("E000", Severity.ERROR, Span(str(p), 0, 0),
                                           f"cannot read file: {e.strerror}")], {}) from None
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            text = raw.decode("latin-1")
        if text.startswith("\ufeff"):
            text = text[1:]
        out.append(SourceFile(str(p), text.replace("\r\n", "\n").replace("\r", "\n")))
    return out
