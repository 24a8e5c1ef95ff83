"""The unit-test statements (ASSERT_*, ADVANCE_TIME, MOCK, MOCK_FUNCTION, MOCK_VERIFY_*) stand
only inside a TEST, SETUP or TEARDOWN block, under every preset.

Codes: E033.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....source import Span
from ..common import Scope
from ..context import CheckContext


def check_test_only(ctx: CheckContext, span: Span, what: str, scope: Scope) -> bool:
    """The test statement `what` at `span` in `scope`: allowed there (else reported: False)?"""
    if getattr(scope, "test", False):
        return True
    ctx.err(Code.TEST_STATEMENT_OUTSIDE_TEST, span, f"{what} is only allowed inside a TEST, SETUP or TEARDOWN block")
    return False
