"""The base of the checker's mutually recursive parts (declarations, constants, expressions, calls,
statements, test statements): each holds the context and its peers as explicit fields."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...diagnostics import Code
from ...model.program import Project
from ...source import Span
from .context import CheckContext

if TYPE_CHECKING:
    from .calls import Calls
    from .constants import Constants
    from .declarations import Declarations
    from .expressions import Expressions
    from .semantics import Semantics
    from .statements import Statements
    from .tests import TestStatements


class Part:
    ctx: CheckContext
    decls: Declarations
    consts: Constants
    exprs: Expressions
    calls: Calls
    stmts: Statements
    tests: TestStatements

    def __init__(self, ctx: CheckContext) -> None:
        self.ctx = ctx

    def wire(self, sem: Semantics) -> None:
        """Meet the other parts (they refer to each other: an expression holds a call, a call's
        arguments are expressions, a declaration's initial value is one...)."""
        self.decls, self.consts, self.exprs = sem.decls, sem.consts, sem.exprs
        self.calls, self.stmts, self.tests = sem.calls, sem.stmts, sem.tests

    @property
    def p(self) -> Project:
        return self.ctx.project

    def err(self, code: Code, span: Span, msg: str, hint: str = "") -> None:
        self.ctx.err(code, span, msg, hint)

    def warn(self, code: Code, span: Span, msg: str, hint: str = "") -> None:
        self.ctx.warn(code, span, msg, hint)

    def feature(self, kind: str, span: Span, what: str) -> bool:
        return self.ctx.feature(kind, span, what)
