"""The checker's parts, made and wired together for one run."""

from __future__ import annotations

from .calls import Calls
from .constants import Constants
from .context import CheckContext
from .declarations import Declarations
from .expressions import Expressions
from .statements import Statements
from .tests import TestStatements


class Semantics:
    """Declarations, constants, expressions, calls, statements and test statements of one run."""

    def __init__(self, ctx: CheckContext) -> None:
        self.ctx = ctx
        self.decls = Declarations(ctx)
        self.consts = Constants(ctx)
        self.exprs = Expressions(ctx)
        self.calls = Calls(ctx)
        self.stmts = Statements(ctx)
        self.tests = TestStatements(ctx)
        for part in (self.decls, self.consts, self.exprs, self.calls, self.stmts, self.tests):
            part.wire(self)
