"""Unit tests (STruC++ syntax): TEST / SETUP / TEARDOWN blocks, assertions, time and mocks.

A TEST is checked like a POU of its own (kind TEST) whose variables are the
file's SETUP variables followed by the TEST's: both are fresh for every test.
Its statements may use the test statements below; everywhere else they are
E033. What codegen and the test runner need is kept in `model.TestModel` and
`model.AssertInfo`.
"""

from __future__ import annotations

from typing import cast

from ...diagnostics import Code
from ...model import types as T
from ...model.program import AssertInfo
from .. import ast as A
from .common import Scope
from .part import Part
from .rules import call_without_value, result_without_type, unit_test_only
from .targets import TestCall

# name → (minimum, maximum) number of arguments, the message included
TEST_CALLS = {
    "assert_eq": (2, 3),
    "assert_neq": (2, 3),
    "assert_true": (1, 2),
    "assert_false": (1, 2),
    "assert_gt": (2, 3),
    "assert_lt": (2, 3),
    "assert_ge": (2, 3),
    "assert_le": (2, 3),
    "assert_near": (3, 4),
    "advance_time": (1, 1),
    "mock_verify_called": (1, 1),
    "mock_verify_call_count": (2, 2),
}
_CMP_OF = {
    "assert_eq": "=",
    "assert_neq": "<>",
    "assert_gt": ">",
    "assert_lt": "<",
    "assert_ge": ">=",
    "assert_le": "<=",
}


class TestStatements(Part):
    # ---------------------------------------------------------------- statements
    def _test_only(self, span, what: str, scope: Scope) -> bool:
        return unit_test_only.check_test_only(self.ctx, span, what, scope)

    def mock(self, s: A.Mock, scope: Scope) -> None:
        if not self._test_only(s.span, "MOCK", scope):
            return
        t = self.exprs.expr(s.target, scope)
        if t is None:
            return
        if not _is_instance(t):
            self.err(
                Code.TYPE_MISMATCH,
                s.target.span,
                f"MOCK needs a function block or program instance, not a {t}",
                "functions are mocked with MOCK_FUNCTION name RETURNS value;",
            )

    def mock_function(self, s: A.MockFunction, scope: Scope) -> None:
        if not self._test_only(s.span, "MOCK_FUNCTION", scope):
            return
        pou = self.p.pous.get(s.name.lower())
        if pou is None or pou.pou_kind != "FUNCTION" or pou.decl is None:
            what = "a standard function" if self.ctx.native(s.name.lower()) is not None else "not a FUNCTION"
            self.err(
                Code.NOT_CALLABLE, s.span, f"'{s.name}' is {what}; MOCK_FUNCTION replaces a FUNCTION written in ST"
            )
            self.exprs.expr(s.value, scope)
            return
        s.pou = pou
        vt = self.exprs.expr(s.value, scope, pou.return_type)
        if result_without_type.check_mocked_result(self.ctx, pou, s.value) and vt is not None:
            self.stmts.assignable(s.value, vt, pou.return_type, s.value.span)

    # ---------------------------------------------------------------- calls
    def test_call(self, c: A.Call, key: str, scope: Scope, statement: bool):
        """ASSERT_*, ADVANCE_TIME and MOCK_VERIFY_*: checked here, generated as runtime helper calls."""
        name = cast(A.Name, c.callee).name.upper()
        if not self._test_only(c.span, name, scope):
            return None
        if call_without_value.check_statement_call(self.ctx, c, statement, f"{name} is a statement; it has no value"):
            return None
        lo, hi = TEST_CALLS[key]
        args = c.args
        if any(a.name or a.output for a in args):
            self.err(Code.BAD_PARAMETER, c.span, f"{name} takes positional arguments only")
            return None
        if not lo <= len(args) <= hi:
            want = str(lo) if lo == hi else f"{lo} or {hi}"
            self.err(Code.ARGUMENT_COUNT, c.span, f"{name} takes {want} arguments, not {len(args)}")
            for a in args:
                self.exprs.expr(a.value, scope)
            return None
        values = [a.value for a in args]
        info = AssertInfo(name, c.span)
        msg = None
        if key.startswith("assert_"):
            n_operands = {"assert_true": 1, "assert_false": 1, "assert_near": 3}.get(key, 2)
            if len(values) > n_operands:
                msg = values[n_operands]
                mt = self.exprs.expr(msg, scope)
                if mt is not None and T.base_of(mt).kind not in ("string",):
                    self.err(Code.TYPE_MISMATCH, msg.span, f"the message of {name} must be a STRING, not {mt}")
            values = values[:n_operands]
            ok = self._check_assert(key, name, values, scope, info)
        elif key == "advance_time":
            t = self.exprs.expr(values[0], scope, T.TIME)
            ok = t is not None
            if t is not None:  # (info is kept only when ok)
                if not (T.base_of(t).is_time or T.base_of(t).is_intlike or isinstance(T.base_of(t), T.LiteralType)):
                    self.err(
                        Code.TYPE_MISMATCH,
                        values[0].span,
                        f"ADVANCE_TIME needs a TIME or a number of nanoseconds, not {t}",
                    )
                    ok = False
                info.types = [t]
        else:  # mock_verify_called / mock_verify_call_count
            ok = self._check_verify(key, name, values, scope, info)
        if ok:
            info.index = len(self.p.test_asserts)
            self.p.test_asserts.append(info)
            c.target = TestCall(key, info, values, msg)
        return None

    def _check_assert(self, key, name, values, scope, info) -> bool:
        if key in ("assert_true", "assert_false"):
            t = self.exprs.expr(values[0], scope, T.BOOL)
            info.types = [t]
            if t is not None and not T.base_of(t).is_bool:
                self.err(Code.TYPE_MISMATCH, values[0].span, f"{name} needs a BOOL, not {t}")
                return False
            return t is not None
        if key == "assert_near":
            ts = [self.exprs.expr(v, scope) for v in values]
            info.types = ts
            for v, t in zip(values, ts):
                if t is not None and not (T.base_of(t).is_num or isinstance(T.base_of(t), T.LiteralType)):
                    self.err(Code.TYPE_MISMATCH, v.span, f"{name} compares numbers, not {t}")
                    return False
            return None not in ts
        # a comparison: checked as `a OP b`, so every rule of the operator applies
        probe = A.Binary(values[0].span, _CMP_OF[key], values[0], values[1])
        t = self.exprs.expr(probe, scope)
        info.types = [values[0].ty, values[1].ty]
        if t is None:
            return False
        for v in values:
            ut = T.unalias(v.ty) if v.ty is not None else None
            if ut is not None and ut.is_aggregate:
                self.err(
                    Code.TYPE_MISMATCH,
                    v.span,
                    f"{name} compares elementary values; compare the elements of this {v.ty}",
                )
                return False
        return True

    def _check_verify(self, key, name, values, scope, info) -> bool:
        target = values[0]
        if isinstance(target, A.Name) and self.exprs.lookup(target.name.lower(), scope) is None:
            pou = self.p.pous.get(target.name.lower())
            if pou is not None and pou.pou_kind == "FUNCTION" and pou.decl is not None:
                target.sym = pou
                target.ty = None
                info.types = [pou]
            else:
                self.err(Code.UNDECLARED, target.span, f"'{target.name}' is neither an instance nor a FUNCTION")
                return False
        else:
            t = self.exprs.expr(target, scope)
            if t is None:
                return False
            if not _is_instance(t):
                self.err(Code.TYPE_MISMATCH, target.span, f"{name} needs a mocked instance or FUNCTION, not a {t}")
                return False
            info.types = [t]
        if key == "mock_verify_call_count":
            ct = self.exprs.expr(values[1], scope, T.DINT)
            if ct is not None and not (T.base_of(ct).is_intlike or isinstance(T.base_of(ct), T.LiteralType)):
                self.err(Code.TYPE_MISMATCH, values[1].span, f"the expected call count must be an integer, not {ct}")
                return False
            return ct is not None
        return True


def _is_instance(t) -> bool:
    ut = T.unalias(t)
    return isinstance(ut, T.POUType) and ut.pou_kind in ("FUNCTION_BLOCK", "PROGRAM")
