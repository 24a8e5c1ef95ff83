"""Semantic analysis: declarations → types and symbols; bodies → typed, checked AST.

The checker never raises on bad input: every problem becomes a diagnostic
and checking goes on, so one run reports all errors. Expression nodes get
their type in `.ty`; names get their symbol in `.sym`; calls get `.target`.
"""
from __future__ import annotations

from ...diagnostics import DiagnosticSink
from ...model import types as T
from ...model.program import Project
from ...source import Span
from .. import ast as A
from ..library import Library
from ..options import CompileOptions
from .calls import CallsMixin
from .common import _NULL, STEP, CallTarget, Scope, StepType
from .configuration import ConfigurationMixin
from .declarations import DeclarationsMixin
from .expressions import ExpressionsMixin
from .limits import check_storage_limits
from .statements import StatementsMixin
from .tests import TestsMixin

__all__ = ["Checker", "CallTarget", "STEP", "StepType", "Scope", "_NULL"]


class Checker(DeclarationsMixin, StatementsMixin, ExpressionsMixin, CallsMixin, ConfigurationMixin, TestsMixin):
    def __init__(self, sink: DiagnosticSink, libraries: list[Library], options: CompileOptions | None = None):
        self.sink = sink
        self.libraries = libraries
        self.p = Project(libraries=libraries)
        self._resolving: set = set()
        self._decl_span: dict = {}
        self._unit_library: dict = {}
        self._pending_types: dict = {}
        self._raw_const_busy: set = set()
        self._deferred_inits: list = []
        self._calls: dict = {}         # caller lower name → [(callee lower name, span)]
        self._configs: list = []
        self._global_blocks: list = []
        self.options = options or CompileOptions()
        self.strict_enums: set = set(self.options.strict_types)  # {attribute 'strict'} enumerations (lower-case names)
        self.dialect = self.options.dialect

    # ================================================================ entry
    def run(self, units: list[A.Unit], library_units: set[str]) -> Project:
        self.library_units = library_units
        for u in units:
            self._collect(u)
        for key, (decl, lib) in list(self._pending_types.items()):
            self._resolve_named_type(key, decl.span)
        for pou in list(self.p.pous.values()):
            self._resolve_interface(pou)
        self._resolve_globals()
        check_storage_limits(self.p, self.err, lambda span: span.file in self.library_units)
        for pou in list(self.p.pous.values()):
            if pou.decl is not None:
                self._check_body(pou)
        self._check_tests()
        self._check_cycles()
        for cfg_decl in self._configs:
            self._check_configuration(cfg_decl)
        if not self.p.configs:
            self._implicit_configuration()
        self._warn_unused()
        return self.p

    # ================================================================ helpers
    def err(self, code: str, span: Span, msg: str, hint: str = "") -> None:
        self.sink.error(code, span, msg, hint)

    def warn(self, code: str, span: Span, msg: str, hint: str = "") -> None:
        if span is not None and span.file in self.library_units:
            return
        self.sink.warning(code, span, msg, hint)

    def enum_as_int(self, t) -> bool:
        """May this enumeration's values be read as integers (codesys/twincat, not 'strict')?"""
        return self.dialect is not None and self.dialect.enum_as_int and isinstance(t, T.EnumType) \
            and t.name.lower() not in self.strict_enums

    def feature(self, kind: str, span: Span, what: str) -> bool:
        """Is this construct part of the chosen dialect? (No preset: everything is.) Reports E044 if not."""
        d = self.dialect
        if d is None or (span is not None and span.file in self.library_units):
            return True
        if (kind == "oop" and d.oop) or (kind == "vendor" and d.vendor_extensions):
            return True
        others = [n for n, p in __import__("st.compiler.dialect", fromlist=["PRESETS"]).PRESETS.items()
                  if (p.oop if kind == "oop" else p.vendor_extensions)]
        self.err("E044", span, f"{what} is not part of the {d.name} dialect",
                 f"choose --dialect {' or '.join(others)} (or a {{dialect '…'}} pragma) to use it")
        return False

    def _lib_of(self, span: Span) -> str:
        return "lib" if span is not None and span.file in self.library_units else ""
