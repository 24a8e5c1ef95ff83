"""The compiler pipeline: sources → parse → check → generate → code objects → the compiled
artefact (artefact.py), cached (cache.py).

`compile_sources` is the one entry point; the CLI, the PLC API and the tests
all go through it (st.api builds its libraries and CompileOptions).
"""

from __future__ import annotations

import gc
import os
import pickle
import sys
import threading
from collections.abc import Collection, Sequence
from pathlib import Path
from types import CodeType
from typing import TYPE_CHECKING, Any

from ..diagnostics import Code, CompileError, Diagnostic, DiagnosticSink, Severity
from ..model.compiled import CompiledProgram
from ..model.program import Project
from ..source import SourceFile, Span
from . import cache, libpath
from .library import Library
from .options import CompileOptions
from .stages import Checked, Generated, NativeBuild, Parsed

# The stages' modules are imported where they run: a compile answered from the cache (`st check`
# of an unchanged file, every `st run` after the first) loads neither the grammar nor the checker,
# the code generator or the native tier.
if TYPE_CHECKING:
    from . import ast as A
    from .lower import LoweredProgram

_parser_lock = threading.Lock()
_parser = None
_builder = None


def _get_parser():
    global _parser, _builder
    if _parser is None:
        from ..grammar.parser import StParser
        from .build import AstBuilder

        _builder = AstBuilder("")
        _parser = StParser(_builder)
    return _parser, _builder


# (path, text) of a library source → its freshly parsed unit, pickled, and the parse's diagnostics
_library_units: dict[tuple[str, str], tuple[bytes, list[Diagnostic]]] = {}


def parse_library_source(path: str, text: str, sink: DiagnosticSink) -> A.Unit | None:
    """A library source's unit: parsed once per process, then a fresh copy for each compilation
    (the checker and the lowering change the tree they are given). Unpickling the copy costs a
    fraction of parsing the text again, and every compilation parses the standard libraries."""
    key = (path, text)
    got = _library_units.get(key)
    if got is None:
        own = DiagnosticSink()
        unit = parse_source(SourceFile(path, text), own)
        got = (pickle.dumps(unit, pickle.HIGHEST_PROTOCOL), list(own.items))
        _library_units[key] = got
    blob, diags = got
    for d in diags:
        sink.add(d)
    return pickle.loads(blob)


def parse_source(
    src: SourceFile, sink: DiagnosticSink, nested_comments: bool | None = True, vendor_names: bool = False
) -> A.Unit | None:
    """Parse one file; every problem becomes a diagnostic of that file (never an exception).
    `nested_comments`: see grammar.comments.strip_comments; `vendor_names`: R_EDGE, F_EDGE,
    CONFIGURATION and RESOURCE may be names (CODESYS, TwinCAT, the default)."""
    from .build import VENDOR_NAMES

    with _parser_lock:
        parser, builder = _get_parser()
        builder.path = src.path
        builder.errors = []
        builder.names_allowed = VENDOR_NAMES if vendor_names else frozenset()
        try:
            unit, diags = parser.parse(src, nested_comments)
        except RecursionError:
            sink.error(
                Code.TOO_DEEP,
                Span(src.path, 1, 1),
                "this file is nested too deeply to parse",
                "split deeply nested expressions or statements",
            )
            return None
        except Exception as exc:  # a parser bug must still not show the user a traceback
            if os.environ.get("ST_DEBUG"):
                raise
            sink.error(
                Code.INTERNAL,
                Span(src.path, 1, 1),
                f"internal compiler error while parsing: {type(exc).__name__}: {exc}",
                "please report this with the source file; set ST_DEBUG=1 to see the traceback",
            )
            return None
        errors = list(builder.errors)
    for d in diags:
        sink.add(d)
    for e in errors:
        sink.error(e.code, e.span, e.message)
    if unit is not None:
        unit.path = src.path
    return unit


def compile_sources(
    sources: list[SourceFile],
    libraries: list[Library],
    options: CompileOptions | None = None,
    *,
    raise_on_error: bool = True,
) -> CompiledProgram:
    """Compile ST sources with the given libraries and options (st.api builds both)."""
    options = options or CompileOptions()
    # The compiler allocates millions of small objects that all live until the end:
    # the cyclic GC would rescan them again and again (a third of the time on 20k lines).
    enabled = gc.isenabled()
    gc.disable()
    # long operator chains (a + b + ... thousands of terms) nest deeply in the AST
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 20000))
    try:
        return _compile_sources(sources, libraries, options, raise_on_error=raise_on_error)
    finally:
        sys.setrecursionlimit(limit)
        if enabled:
            gc.enable()


def _compile_sources(
    sources: list[SourceFile], libraries: list[Library], options: CompileOptions, *, raise_on_error: bool
) -> CompiledProgram:
    all_sources = {s.path: s for s in sources}
    lib_sources = [SourceFile(path, text) for lib in libraries for path, text in lib.sources]
    all_sources.update((src.path, src) for src in lib_sources)
    helpers = {}
    for lib in libraries:
        helpers.update(lib.helpers)
    key = cache.cache_key(sources, libraries, options)
    cached = options.use_cache and not options.coverage and not any(s.load_diagnostics for s in sources)
    cdir = cache.cache_dir() if cached else None
    if cdir is not None:
        hit = cache.load(cdir, key, sources=all_sources, helpers=helpers)
        if hit is not None:
            return hit
    from .artefact import artefact, libraries_only
    from .lower import lower
    from .native import build_native

    sink = DiagnosticSink()
    parsed = parse(sources, libraries, options, sink)
    project = Project()
    generated: Generated | None = None
    native = NativeBuild()
    try:
        checked = check(parsed, options, sink)
        project = checked.project
        _attach_test_texts(project, all_sources)
        if not sink.has_errors:
            generated = generate(lower(project), checked, options, sink)
            if not sink.has_errors and options.native and not options.coverage and not project.tests:
                where = Span(sources[0].path if sources else "<input>", 1, 1)
                native = NativeBuild(*build_native(generated.python_modules, project, sink, where))
    except RecursionError as exc:
        first = sources[0].path if sources else "<input>"
        sink.error(
            Code.TOO_DEEP,
            getattr(exc, "st_span", None) or Span(first, 1, 1),
            "this statement is nested too deeply to compile",
            "split the expression into several assignments",
        )
    except SyntaxError as exc:  # Python's own limits, e.g. more than 20 nested loops
        sink.error(
            Code.TOO_DEEP,
            Span(exc.filename or (sources[0].path if sources else "<input>"), exc.lineno or 1, 1),
            f"this code is nested too deeply to compile ({exc.msg})",
            "move inner loops into a FUNCTION",
        )
    except Exception as exc:  # a compiler bug must still not show the user a traceback
        first = sources[0].path if sources else "<input>"
        sink.error(
            Code.INTERNAL,
            getattr(exc, "st_span", None) or Span(first, 1, 1),
            f"internal compiler error: {type(exc).__name__}: {exc}",
            "please report this with the source file; set ST_DEBUG=1 to see the traceback",
        )
        if os.environ.get("ST_DEBUG"):
            raise
    diags = sink.sorted()
    draft = CompiledProgram(
        generated.modules if generated is not None else [],
        project,
        diags,
        all_sources,
        helpers,
        generated.python_text if generated is not None else {},
        test_modules=generated.test_modules if generated is not None else [],
        native=native.modules,
        native_skipped=native.skipped,
    )
    if generated is not None and generated.coverage_points is not None:
        draft.coverage_points = generated.coverage_points
        draft.coverage_hits = bytearray(len(generated.coverage_points))
    result = None
    if not any(d.is_error for d in diags):
        try:
            result = artefact(draft)
        except Exception as exc:  # a compiler object left in the model: a compiler bug, reported as one
            if os.environ.get("ST_DEBUG"):
                raise
            sink.error(
                Code.INTERNAL,
                Span(sources[0].path if sources else "<input>", 1, 1),
                f"internal compiler error: {type(exc).__name__}: {exc}",
                "please report this with the source file; set ST_DEBUG=1 to see the traceback",
            )
            draft.diagnostics = diags = sink.sorted()
    if result is None:
        if raise_on_error:
            raise CompileError(diags, all_sources)
        draft.project = libraries_only(libraries)
        return artefact(draft)
    if cdir is not None:
        cache.store(cdir, key, result)
    return result


def parse_settings(options: CompileOptions) -> tuple[bool | None, bool]:
    """How the options' dialect reads a file: (nested comments, vendor names); parse_source's."""
    nested = options.dialect.nested_comments if options.dialect is not None else None
    return nested, options.dialect is None or options.dialect.vendor_extensions


def parse(
    sources: list[SourceFile],
    libraries: list[Library],
    options: CompileOptions,
    sink: DiagnosticSink,
    units_of: dict[str, tuple[tuple[str, bool | None, bool], A.Unit | None, list[Diagnostic]]] | None = None,
) -> Parsed:
    """Parse the libraries' sources and the user's. `units_of` (the language server's): a file's
    unit kept from the last parse while its text is the same (the checker gives the same answers
    on a tree it checked before), filled as files are parsed; a library source's too."""
    lib_units: list[tuple[Library, A.Unit]] = []
    for lib in libraries:
        for path, text in lib.sources:
            if units_of is None:
                u = parse_library_source(path, text, sink)
            else:
                kept = units_of.get(path)
                if kept is None or kept[0] != (text, None, False):
                    own = DiagnosticSink()
                    kept = units_of[path] = ((text, None, False), parse_library_source(path, text, own), own.items)
                u = kept[1]
                for d in kept[2]:
                    sink.add(d)
            if u is not None:
                lib_units.append((lib, u))
    units: list[A.Unit] = []
    nested, vendor_names = parse_settings(options)
    for s in sources:
        for d in s.load_diagnostics:
            sink.add(d)
        if units_of is None:
            u = parse_source(s, sink, nested, vendor_names)
        else:
            key = (s.text, nested, vendor_names)
            kept = units_of.get(s.path)
            if kept is None or kept[0] != key:
                own = DiagnosticSink()
                kept = units_of[s.path] = (key, parse_source(s, own, nested, vendor_names), list(own.items))
            u = kept[1]
            for d in kept[2]:
                sink.add(d)
        if u is not None:
            units.append(u)
    in_use = _libraries_in_use(libraries, lib_units, units, sink)
    lib_paths = {path for lib in in_use for path, _ in lib.sources}
    units = [u for lib, u in lib_units if lib in in_use] + units
    # pragmas a dialect knows are not "ignored" news: {dialect '…'} always, {attribute '…'} in codesys/twincat,
    # {attribute 'symbol' := …} everywhere (the OPC UA server's symbol configuration: st/opcua/symbols.py)
    known = {"dialect", "gvl", "namespace"}
    if options.dialect is not None and options.dialect.attribute_pragmas:
        known.add("attribute")
    every_lib_path = {path for lib in libraries for path, _ in lib.sources}
    sink.items = [
        d
        for d in sink.items
        if not (
            d.code == Code.IGNORED_PRAGMA
            and (d.datum("pragma") in known or d.datum("attribute") == "symbol" or d.span.file in every_lib_path)
        )
    ]
    return Parsed(units, frozenset(lib_paths), in_use)


def check(parsed: Parsed, options: CompileOptions, sink: DiagnosticSink, memo: Any = None, stop: Any = None) -> Checked:
    """Check the parsed units (every problem a diagnostic in `sink`). `memo`, `stop`: the
    language server's (check/context.py's CheckContext says what they are)."""
    from .check import Checker

    project = Checker(sink, parsed.libraries, options).run(parsed.units, set(parsed.library_paths), memo, stop)
    return Checked(project, parsed.libraries)


def generate(lowered: LoweredProgram, checked: Checked, options: CompileOptions, sink: DiagnosticSink) -> Generated:
    """Python modules and their code objects (none if code generation reported an error)."""
    inline_files = frozenset(path for lib in checked.libraries if lib.inline_blocks for path, _ in lib.sources)
    from .codegen import ModuleGen
    from .codegen.source import python_text

    gen = ModuleGen(lowered, sink, coverage=options.coverage, inline_files=inline_files)
    py_modules = gen.generate()
    coverage = gen.cov_points if options.coverage else None
    if sink.has_errors:
        return Generated([], [], py_modules, coverage_points=coverage)
    modules: list[tuple[str, CodeType]] = []
    test_modules: list[tuple[str, CodeType]] = []
    pysrc: dict[str, str] = {}
    for out, group in ((modules, py_modules), (test_modules, gen.test_modules())):
        for path, mod in group:
            if options.emit_python:
                pysrc[path] = (pysrc[path] + "\n\n" if path in pysrc else "") + python_text(mod)
            out.append((path, compile(mod, path, "exec")))
    return Generated(modules, test_modules, py_modules, pysrc, coverage)


def _type_names(units, with_pous: bool = False) -> dict[str, A.TypeDecl | A.POU | A.Interface]:
    """The TYPEs the units declare by (lower) name, and their POUs and interfaces if asked."""
    from . import ast as A

    names: dict[str, A.TypeDecl | A.POU | A.Interface] = {}
    for u in units:
        for item in u.items:
            if isinstance(item, A.TypeBlock):
                names.update((td.name.lower(), td) for td in item.types)
            elif with_pous and isinstance(item, (A.POU, A.Interface)):
                names[item.name.lower()] = item
    return names


def _libraries_in_use(
    libraries: list[Library], lib_units: list[tuple[Library, A.Unit]], units: list[A.Unit], sink: DiagnosticSink
) -> list[Library]:
    """The libraries minus those that yield to the project's own types (Library.yields_to_own_types),
    each left out with a warning at the first of the project's types that made it step aside."""
    own = _type_names(units, with_pous=True)
    kept = []
    for lib in libraries:
        clash = sorted(
            (own[k] for k in _type_names(u for owner, u in lib_units if owner is lib) if k in own),
            key=lambda td: (td.span.file, td.span.line, td.span.col),
        )
        if lib.yields_to_own_types and clash:
            td = clash[0]
            more = f" and {len(clash) - 1} more of its types" if len(clash) > 1 else ""
            sink.warning(
                Code.OWN_MOTION_LIBRARY,
                td.span,
                f"the project declares its own {td.name}{more}: st's {lib.name} library is left out",
                f"the project's own blocks are used; rename {td.name} to use st's {lib.name} blocks",
            )
            continue
        kept.append(lib)
    return kept


def check_sources(
    sources: list[SourceFile], libraries: list[Library], options: CompileOptions | None = None
) -> tuple[Project, list[Diagnostic]]:
    """The front end alone: parse and check, (the checked model with its AST, the diagnostics).
    For tools and tests that look at what the compiler works on; `compile_sources` returns the
    AST-free artefact instead."""
    options = options or CompileOptions()
    sink = DiagnosticSink()
    return check(parse(sources, libraries, options, sink), options, sink).project, sink.sorted()


def _attach_test_texts(project: Project, sources: dict) -> None:
    """Each test statement's source text, for failure reports (`ASSERT_EQ(uut.count, 3)`)."""
    for info in project.test_asserts:
        src = sources.get(info.span.file)
        if src is not None:
            info.text = src.text_of(info.span)


def _read_text(p: str) -> str:
    try:
        return _decoded(Path(p).read_bytes())
    except OSError as e:
        raise CompileError(
            [Diagnostic(Code.UNREADABLE_FILE, Severity.ERROR, Span(str(p), 0, 0), f"cannot read file: {e.strerror}")],
            {},
        ) from None


def _decoded(raw: bytes) -> str:
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    if text.startswith("\ufeff"):
        text = text[1:]
    return text.replace("\r\n", "\n").replace("\r", "\n")


def load_files(paths: list[str], lib_path: Sequence[str] = (), provided: Collection[str] = ()) -> list[SourceFile]:
    """The sources: .st files as they are; TwinCAT's .TcPOU/.TcDUT/.TcGVL/.TcIO and PLCopen XML
    projects (plc.xml) as their ST laid out at the XML's lines (diagnostics point into the XML file,
    and the problems of reading it are the source's `load_diagnostics`); a .plcproj as the files it
    compiles, and the library projects it references (libpath.py: found among the projects named and
    in the search path `lib_path` + ST_LIBPATH, transitively, each once; `provided`: lower-case
    names of the libraries st stands in for, never searched for)."""
    from . import twincat

    paths = [str(p) for p in paths]
    projects = [p for p in paths if p.lower().endswith(twincat.PROJECT_SUFFIX)]
    found = libpath.resolve(projects, lib_path, provided) if projects else libpath.Resolution()
    out: list[SourceFile] = []
    for p in paths + found.libraries:
        if p.lower().endswith(twincat.PROJECT_SUFFIX):
            out += _load_project(p, found, tasks=p in projects)
        else:
            out.append(_load_file(p))
    return out


def _load_file(p: str) -> SourceFile:
    from . import plcopen_xml, twincat

    text = _read_text(p)
    problems: list[Diagnostic] = []
    if twincat.is_twincat(p):
        text = twincat.twincat_source(text)
    elif plcopen_xml.handles(p, text):
        text, problems = plcopen_xml.plcopen_source(text, p)
    return SourceFile(p, text, load_diagnostics=problems)


def _load_project(p: str, found: libpath.Resolution, tasks: bool = False) -> list[SourceFile]:
    """A .plcproj's files, then the project itself as a source of pragmas (its namespaces and those
    its library references give) that carries what went wrong reading it: a <Compile> file missing
    (E000 at the element, its name matched ignoring case first, as on Windows), a library not found
    (W014 at the reference); with `tasks` (a project named, not a library found), the CONFIGURATION
    its .TcTTO task files mean (twincat_tasks.py), after the XML's last line."""
    from . import twincat, twincat_tasks

    xml = _read_text(p)
    out = []
    problems = list(found.warnings.get(p, []))
    for item in twincat.compile_items(p, xml):
        reason = "no such file, nor one whose name differs only in case"
        if item.found:
            try:
                out.append(_load_file(item.path))
                continue
            except CompileError as e:
                reason = e.diagnostics[0].message.removeprefix("cannot read file: ")
        problems.append(
            Diagnostic(
                Code.UNREADABLE_FILE,
                Severity.ERROR,
                Span(p, item.line, item.col),
                f"cannot read file '{item.include}' of this project: {reason}",
            )
        )
    pragmas = twincat.project_namespaces(xml) + "".join(
        "{namespace '" + n + "'}\n" for n in found.namespaces.get(p, []) if n.isidentifier()
    )
    text = twincat.project_source(xml, pragmas, [d.span.line for d in problems])
    if tasks:
        text += "\n" + twincat_tasks.project_configuration(p, xml)
    return out + [SourceFile(p, text, load_diagnostics=problems)]
