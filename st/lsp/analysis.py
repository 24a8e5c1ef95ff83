"""One project checked as `st check` checks it, again after every edit, with its index.

Parsing is the larger part of a check (st/compiler/driver.py); a file whose text did not change
keeps its tree from the last parse (the checker gives the same answers on a tree it checked
before: tests/test_lsp.py checks that on every fixture), so an edit re-parses the edited file and
re-checks the project. Code generation is not run: the diagnostics are the parser's and the
checker's, which is what `st check` reports for a program that compiles.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any

from ..compiler.driver import check, parse
from ..compiler.options import CompileOptions
from ..diagnostics import Code, CompileError, Diagnostic, DiagnosticSink
from ..model.program import Project
from ..source import SourceFile, Span
from .index import Index, build_index


@dataclass
class Analysis:
    sources: dict[str, SourceFile]
    user_files: set[str]
    diagnostics: dict[str, list[Diagnostic]]  # every user file, with [] when it has none
    project: Project | None
    units: list[Any] = field(default_factory=list)
    seconds: float = 0.0
    all_sources: dict[str, SourceFile] = field(default_factory=dict)  # the libraries' too
    _index: Index | None = None
    _lock: threading.Lock = field(default_factory=threading.Lock)

    @property
    def index(self) -> Index:
        """Every name's definition and references: built on first use (the diagnostics are
        published before it, so a keystroke's errors show without waiting for it)."""
        with self._lock:
            if self._index is None:
                if self.project is None:
                    self._index = Index()
                else:
                    try:
                        self._index = build_index(self.project, self.units, self.all_sources, self.user_files)
                    except Exception:  # noqa: BLE001 - an index that cannot be built: no navigation, no crash
                        self._index = Index()
            return self._index


class Analyzer:
    """Checks one project again and again; keeps each file's parse while its text is the same."""

    def __init__(self) -> None:
        self._units: dict[str, Any] = {}

    def analyze(self, sources: list[SourceFile]) -> Analysis:
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
        for path in [p for p in self._units if p not in by_path]:
            del self._units[path]  # a file that left the project
        project = None
        units: list[Any] = []
        all_sources = dict(by_path)
        try:
            parsed = parse(sources, libs, options, sink, self._units)
            units = parsed.units
            checked = check(parsed, options, sink)
            project = checked.project
            for lib in parsed.libraries:
                for path, text in lib.sources:
                    all_sources.setdefault(path, SourceFile(path, text))
        except RecursionError:
            first = sources[0].path if sources else "<input>"
            sink.error(Code.TOO_DEEP, Span(first, 1, 1), "this code is nested too deeply to check")
            project = None
        except Exception as exc:  # noqa: BLE001 - a checker bug must not end the server
            first = sources[0].path if sources else "<input>"
            sink.error(Code.INTERNAL, Span(first, 1, 1), f"internal compiler error: {type(exc).__name__}: {exc}")
            project = None
        out: dict[str, list[Diagnostic]] = {p: [] for p in user}
        for d in sink.sorted():
            if d.span.file in out:
                out[d.span.file].append(d)
        return Analysis(dict(by_path), user, out, project, units, time.perf_counter() - t0, all_sources)

    def _refused(self, diags: list[Diagnostic], by_path: dict, user: set[str], t0: float) -> Analysis:
        out: dict[str, list[Diagnostic]] = {p: [] for p in user}
        for d in diags:
            out.setdefault(d.span.file, []).append(d)
        return Analysis(by_path, user, out, None, [], time.perf_counter() - t0)
