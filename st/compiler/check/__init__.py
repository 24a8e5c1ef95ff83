"""Semantic analysis: declarations → types and symbols; bodies → typed, checked AST.

The checker never raises on bad input: every problem becomes a diagnostic
and checking goes on, so one run reports all errors. Expression nodes get
their type in `.ty`; names get their symbol in `.sym`; calls get `.target`.

`Checker.run` applies ordered passes (`passes/`) to one explicit `CheckContext`;
the parts that check declarations, constants, expressions, calls and statements
refer to each other (`Semantics`) and are used by the passes. Each rule the parts
and passes apply is a module of `rules/`, naming the diagnostic codes it raises.
"""

from __future__ import annotations

from collections.abc import Callable
from threading import Event
from typing import Any

from ...diagnostics import DiagnosticSink
from ...model.program import Project
from .. import ast as A
from ..library import Library
from ..options import CompileOptions
from .common import _NULL, STEP, Scope, StepType
from .context import CheckCancelled, CheckContext
from .memo import TreeMemo
from .passes.bodies import check_bodies
from .passes.collect import collect
from .passes.configuration import check_configurations
from .passes.cycles import check_cycles
from .passes.globals import declare_globals
from .passes.namespaces import resolve_namespaces
from .passes.oop import check_oop_rules
from .passes.tests import check_tests
from .passes.types import resolve_types
from .rules.storage_limits import check_storage_limits
from .rules.unused import warn_unused
from .semantics import Semantics
from .targets import (
    BODY_CALLS,
    ActionCall,
    Binding,
    BoundCall,
    CallTarget,
    DeleteCall,
    FbCall,
    FunctionCall,
    IsValidRefCall,
    MethodCall,
    NativeCall,
    NewCall,
    QueryItfCall,
    RefCall,
    SizeofCall,
    TestCall,
)

__all__ = [
    "Checker",
    "CheckCancelled",
    "TreeMemo",
    "STEP",
    "StepType",
    "Scope",
    "_NULL",
    "BODY_CALLS",
    "ActionCall",
    "Binding",
    "BoundCall",
    "CallTarget",
    "DeleteCall",
    "FbCall",
    "FunctionCall",
    "IsValidRefCall",
    "MethodCall",
    "NativeCall",
    "NewCall",
    "QueryItfCall",
    "RefCall",
    "SizeofCall",
    "TestCall",
]


class Checker:
    def __init__(self, sink: DiagnosticSink, libraries: list[Library], options: CompileOptions | None = None):
        self.sink = sink
        self.libraries = libraries
        self.options = options or CompileOptions()
        self.strict_enums: set = set(self.options.strict_types)  # {attribute 'strict'} enumerations (lower-case names)
        self.dialect = self.options.dialect

    def run(
        self, units: list[A.Unit], library_units: set[str], memo: TreeMemo | None = None, stop: Event | None = None
    ) -> Project:
        """Check the units. `memo`, `stop`: see CheckContext (the language server's); a stopped
        check raises CheckCancelled."""
        ctx = CheckContext(
            self.sink,
            self.libraries,
            Project(libraries=self.libraries),
            self.dialect,
            library_units=library_units,
            strict_enums=self.strict_enums,
            memo=memo,
            stop=stop,
        )
        sem = Semantics(ctx)
        resolve_namespaces(ctx, units)
        collect(ctx, units)
        steps: tuple[tuple[Callable[[Any], None], Any], ...] = (
            (resolve_types, sem),
            (check_oop_rules, ctx),
            (declare_globals, sem),
            (check_storage_limits, ctx),
            (check_bodies, sem),
            (check_tests, sem),
            (check_cycles, ctx),
            (check_configurations, sem),
            (warn_unused, ctx),
        )
        for step, on in steps:
            ctx.cancel_point()
            step(on)
        return ctx.project
