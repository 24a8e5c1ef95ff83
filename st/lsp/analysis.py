"""One project checked as `st check` checks it, again after every edit, with its index.

A file whose text did not change keeps its tree from the last parse (the checker gives the same
answers on a tree it checked before: tests/test_lsp.py checks that on every fixture), so an edit
re-parses the edited file and re-checks the project; what the checker works out from a tree alone
is kept with it (st/compiler/check/memo.py). A file that does not parse keeps the declarations
the error is not in (tolerant.py). Code generation is not run: the diagnostics are the parser's
and the checker's, which is what `st check` reports for a program that compiles.

The cyclic garbage collector is off during an analysis (as during a compilation: the checker
makes millions of objects that live until it ends); the server collects between analyses
(server.py says when).
"""

from __future__ import annotations

import gc
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from ..compiler import ast as A
from ..compiler.check import CheckCancelled, TreeMemo
from ..compiler.driver import check, parse, parse_settings, parse_source
from ..compiler.options import CompileOptions
from ..diagnostics import Code, CompileError, Diagnostic, DiagnosticSink, Severity
from ..model.program import Project
from ..source import SourceFile, Span
from .index import Index, build_index
from .tolerant import Tolerant, parse_tolerant


@dataclass
class Analysis:
    sources: dict[str, SourceFile]
    user_files: set[str]
    diagnostics: dict[str, list[Diagnostic]]  # every user file, with [] when it has none
    project: Project | None
    units: list[Any] = field(default_factory=list)
    seconds: float = 0.0
    all_sources: dict[str, SourceFile] = field(default_factory=dict)  # the libraries' too
    cuts: dict[str, list[tuple[int, int]]] = field(default_factory=dict)  # tolerant.py's, per file
    _index: Index | None = None
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def scope_at(self, file: str, line: int) -> Any:
        """The POU (or method) whose code `line` (0-based) is in. In lines cut out of a file that
        does not parse (tolerant.py), the one declared at the cut's start: its old tree ends where
        the old text ended, the new text may be longer."""
        index = self.index
        for a, b in self.cuts.get(file, ()):
            if a <= line <= b:
                inside = [s for s in index.scopes if s.file == file and a <= s.first <= line]
                if inside:
                    return max(inside, key=lambda s: s.first)
        return index.scope_at(file, line)

    @property
    def has_index(self) -> bool:
        return self._index is not None

    @property
    def index(self) -> Index:
        """Every name's definition and references: built on first use (the diagnostics are
        published before it, so a keystroke's errors show without waiting for it)."""
        self.build_index()
        assert self._index is not None
        return self._index

    def build_index(self, stop: threading.Event | None = None) -> bool:
        """Build the index unless it is built; False when `stop` was set before it was done
        (the server's: an edit came, the next analysis's index is the one wanted)."""
        with self._lock:
            if self._index is None:
                if self.project is None:
                    self._index = Index()
                else:
                    try:
                        self._index = build_index(self.project, self.units, self.all_sources, self.user_files, stop)
                    except CheckCancelled:
                        return False
                    except Exception:  # noqa: BLE001 - an index that cannot be built: no navigation, no crash
                        self._index = Index()
            return True


class Analyzer:
    """Checks one project again and again; keeps each file's parse while its text is the same."""

    def __init__(self) -> None:
        self._units: dict[str, Any] = {}
        self._last_tree: dict[str, A.Unit] = {}  # each file's last tree (tolerant.py's `last`)
        self._cuts: dict[str, Tolerant] = {}  # files read tolerantly, with what was cut out
        self.memo = TreeMemo()

    def analyze(self, sources: list[SourceFile], stop: threading.Event | None = None) -> Analysis:
        """Check the project. `stop`: set when the answer is no longer wanted; then CheckCancelled
        is raised (the kept trees stay good for the next analysis)."""
        enabled = gc.isenabled()
        gc.disable()
        try:
            return self._analyze(sources, stop)
        finally:
            if enabled:
                gc.enable()

    def _parse_tolerantly(self, sources: list[SourceFile], options: CompileOptions) -> None:
        """Parse the files whose text changed, a file that does not parse as far as it can."""
        nested, vendor_names = parse_settings(options)
        for s in sources:
            key = (s.text, nested, vendor_names)
            kept = self._units.get(s.path)
            if kept is not None and kept[0] == key:
                continue
            own = DiagnosticSink()
            unit = parse_source(s, own, nested, vendor_names)
            self._cuts.pop(s.path, None)
            if unit is None:
                errors = [d for d in own.items if d.severity == Severity.ERROR]
                t = parse_tolerant(s, errors, self._last_tree.get(s.path), nested, vendor_names)
                if t.unit is not None:
                    unit = t.unit
                    self._cuts[s.path] = t
            if unit is not None:
                self._last_tree[s.path] = unit
            self._units[s.path] = (key, unit, list(own.items))

    def _analyze(self, sources: list[SourceFile], stop: threading.Event | None) -> Analysis:
        t0 = time.perf_counter()
        by_path = {s.path: s for s in sources}
        user = set(by_path)
        sink = DiagnosticSink()
        try:
            options = CompileOptions.for_sources(sources)
        except CompileError as e:
            return self._refused(e.diagnostics, by_path, user, t0)
        from ..api import libraries

        libs = libraries(options)
        lib_paths = {path for lib in libs for path, _ in lib.sources}
        for path in [p for p in self._units if p not in by_path and p not in lib_paths]:
            del self._units[path]  # a file that left the project (or a library it no longer uses)
            self._last_tree.pop(path, None)
            self._cuts.pop(path, None)
        project = None
        units: list[Any] = []
        all_sources = dict(by_path)
        try:
            self._parse_tolerantly(sources, options)
            parsed = parse(sources, libs, options, sink, self._units)
            units = parsed.units
            checked = check(parsed, options, sink, self.memo, stop)
            project = checked.project
            self.memo.sweep()
            for lib in parsed.libraries:
                for path, text in lib.sources:
                    all_sources.setdefault(path, SourceFile(path, text))
        except CheckCancelled:
            raise
        except RecursionError:
            first = sources[0].path if sources else "<input>"
            sink.error(Code.TOO_DEEP, Span(first, 1, 1), "this code is nested too deeply to check")
            project = None
        except Exception as exc:  # noqa: BLE001 - a checker bug must not end the server
            first = sources[0].path if sources else "<input>"
            sink.error(Code.INTERNAL, Span(first, 1, 1), f"internal compiler error: {type(exc).__name__}: {exc}")
            project = None
        out: dict[str, list[Diagnostic]] = {p: [] for p in user}
        parser_said = {id(d) for p in user if p in self._cuts for d in self._units[p][2]}
        for d in sink.sorted():
            if d.span.file in out:
                t = self._cuts.get(d.span.file)
                if t is not None and id(d) not in parser_said and t.hides(d):
                    continue
                out[d.span.file].append(d)
        cuts = {p: t.cut for p, t in self._cuts.items() if p in user}
        return Analysis(dict(by_path), user, out, project, units, time.perf_counter() - t0, all_sources, cuts)

    def _refused(self, diags: list[Diagnostic], by_path: dict, user: set[str], t0: float) -> Analysis:
        out: dict[str, list[Diagnostic]] = {p: [] for p in user}
        for d in diags:
            out.setdefault(d.span.file, []).append(d)
        return Analysis(by_path, user, out, None, [], time.perf_counter() - t0)
