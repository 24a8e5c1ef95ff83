"""The state one checker run works on, passed explicitly to every pass and part of the checker."""

from __future__ import annotations

from dataclasses import dataclass, field
from threading import Event
from typing import Any

from ...diagnostics import Code, DiagnosticSink
from ...model import types as T
from ...model.program import Project
from ...source import Span
from .. import ast as A
from ..dialect import Dialect
from ..library import FuncSig, Library
from ..names import mangle
from .memo import TreeMemo
from .rules import dialect_features


class CheckCancelled(Exception):  # noqa: N818 - not a failure: the answer is not wanted any more
    """The check was stopped (`CheckContext.stop`). Its trees may be checked again: every change a
    check makes to a tree is one a later check finds made and leaves."""


@dataclass
class CheckContext:
    sink: DiagnosticSink
    """Where every diagnostic goes (the checker never raises on bad input)."""
    libraries: list[Library]
    """The libraries of the compilation: their native functions are looked up here."""
    project: Project
    """What the checker builds: POUs, types, globals, configurations, tests."""
    dialect: Dialect | None = None
    """The dialect preset whose switches the checker consults (None: every construct is allowed)."""
    library_units: set[str] = field(default_factory=set)
    """The file names of library sources: no warnings there, no dialect restrictions."""
    strict_enums: set[str] = field(default_factory=set)
    """{attribute 'strict'} enumerations (lower-case names): never read as integers."""
    pending_types: dict[str, tuple[A.TypeDecl, str]] = field(default_factory=dict)
    """TYPE declarations collected and not necessarily resolved yet: lower name → (declaration, library)."""
    decl_span: dict[str, Span] = field(default_factory=dict)
    """Where each type and POU is declared (lower name), for 'declared twice' and 'contains itself'."""
    resolving: set[str] = field(default_factory=set)
    """Named types being resolved right now: meeting one again means it is defined in terms of itself."""
    raw_const_busy: set[str] = field(default_factory=set)
    """Global constants being evaluated before the globals are declared (a cycle yields no value)."""
    deferred_inits: list[tuple[A.VarDecl, T.Type]] = field(default_factory=list)
    """Initial values of globals, checked once every global is declared (they may name each other)."""
    deferred_pou_inits: list[tuple[A.VarDecl, T.Type, Any, bool]] = field(default_factory=list)
    """Initial values of POU variables met before the globals are declared (they may name global
    constants: `h : HANDLE := RTS_INVALID_HANDLE`), checked right after; (declaration, type, scope,
    whether it may name variables: Declarations.check_initializer)."""
    globals_declared: bool = False
    configs: list[A.Configuration] = field(default_factory=list)
    """CONFIGURATION declarations collected, checked after the bodies."""
    global_blocks: list[tuple[str, A.VarBlock]] = field(default_factory=list)
    gvl_of_block: dict[int, str] = field(default_factory=dict)
    """A VAR_GLOBAL block of a named global variable list (TwinCAT's .TcGVL): id(block) → the list's name."""
    gvls: dict[str, dict[str, T.VarSym]] = field(default_factory=dict)
    """Named global variable lists: lower list name → lower variable name → symbol (`GVL_Main.x`)."""
    """VAR_GLOBAL blocks: (scope prefix, block); the prefix is '' or a configuration/resource path."""
    qualified_only: set[int] = field(default_factory=set)
    """Globals of a {attribute 'qualified_only'} list (ids of their symbols): reachable only as GVL.x
    (but by their plain names in their own list's initial values: `current_gvl`)."""
    gvl_of_decl: dict[int, str] = field(default_factory=dict)
    """id(VarDecl) of a named list's variable → the list's lower name."""
    current_gvl: str | None = None
    """The named list whose initial values are being checked, if any."""
    namespaces: dict[str, str] = field(default_factory=dict)
    """Library and project namespaces, lower name → name: `Tc2_Standard.TON` is TON (passes/namespaces.py)."""
    program_instances: dict[str, T.VarSym] = field(default_factory=dict)
    """The one instance of each PROGRAM used by name (CODESYS, TwinCAT: `Prg.x`, `Prg()`,
    `Prg.M()`), lower program name → its global symbol; a task of the configuration runs that same
    instance (`InstanceModel.singleton`)."""
    called_programs: set[str] = field(default_factory=set)
    """PROGRAMs another POU calls by name (lower names): the implicit configuration's task does
    not run them itself (they run where they are called, as under a TwinCAT task calling MAIN)."""
    memo: TreeMemo | None = None
    """Answers kept from the last check of the same trees (the language server's; memo.py)."""
    stop: Event | None = None
    """Set when the check's answer is no longer wanted (an edit came): `Checker.run` raises
    `CheckCancelled` between passes and `check_bodies` between bodies."""

    def cancel_point(self) -> None:
        """Raise CheckCancelled if the check was stopped."""
        if self.stop is not None and self.stop.is_set():
            raise CheckCancelled

    # ---------------------------------------------------------------- reporting
    def err(self, code: Code, span: Span, msg: str, hint: str = "") -> None:
        self.sink.error(code, span, msg, hint)

    def warn(self, code: Code, span: Span, msg: str, hint: str = "") -> None:
        if span is not None and span.file in self.library_units:
            return
        self.sink.warning(code, span, msg, hint)

    def lib_of(self, span: Span | None) -> str:
        """'lib' for a span in a library source, else ''."""
        return "lib" if span is not None and span.file in self.library_units else ""

    def program_instance(self, pou: T.POUType) -> T.VarSym:
        """The instance of the PROGRAM `pou` that its name stands for, made when first used."""
        key = pou.name.lower()
        sym = self.program_instances.get(key)
        if sym is None:
            span = pou.decl.span if isinstance(pou.decl, (A.POU, A.Method, A.Interface)) else Span("<programs>", 1, 1)
            sym = T.VarSym(pou.name, pou, "VAR_GLOBAL", span, pyname="_pgi_" + mangle(pou.name), is_global=True)
            self.program_instances[key] = sym
            self.project.globals["<program> " + key] = sym
            self.project.global_names.setdefault(key, []).append(sym)  # `Prg.x` for the runtime's paths too
        return sym

    # ---------------------------------------------------------------- dialect
    def feature(self, kind: str, span: Span, what: str) -> bool:
        """Is this construct part of the chosen dialect? (No preset: everything is.) Reports E044 if not
        (rules/dialect_features.py)."""
        return dialect_features.check_feature(self, kind, span, what)

    def feature_quiet(self, kind: str) -> bool:
        """`feature` without a report: does the dialect allow oop / vendor constructs?"""
        return dialect_features.allows(self.dialect, kind)

    def bits_as_numbers(self) -> bool:
        """May bit strings and numbers convert implicitly where the value is kept (codesys, twincat,
        and the default, which accepts what any preset accepts)?"""
        return self.dialect is None or self.dialect.bits_as_numbers

    def enum_as_int(self, t) -> bool:
        """May this enumeration's values be read as integers (codesys/twincat, not 'strict')?"""
        return (
            self.dialect is not None
            and self.dialect.enum_as_int
            and isinstance(t, T.EnumType)
            and t.name.lower() not in self.strict_enums
        )

    def enum_read_as_int(self, t) -> bool:
        """May this enumeration's value be kept in an integer (assigned to one, passed to an integer
        input)? codesys/twincat: yes, 'strict' too (it forbids arithmetic and integers INTO the
        enumeration, not reading it as its number: Beckhoff's attribute 'strict')."""
        return self.dialect is not None and self.dialect.enum_as_int and isinstance(t, T.EnumType)

    # ---------------------------------------------------------------- libraries
    def native(self, key: str) -> FuncSig | None:
        """The signature of a library's native function of this (lower-case) name, or None."""
        for lib in self.libraries:
            sig = lib.lookup(key)
            if sig is not None:
                return sig
        return None
