"""Unit tests: each TEST block → a Python function `_test_<n>()` in its file's module.

The SETUP and TEST variables are the function's locals (fresh per call), the
SETUP statements run first and TEARDOWN in a `finally`. Test statements become
calls of helpers the test runner puts into the namespace (`st.testing.runner`):
`_t_fail`, `_t_advance`, `_t_mock`, `_t_mock_function`, `_t_verify`.
"""

from __future__ import annotations

import ast as py

from ...model import types as T
from ...model.program import TestModel
from ..syntax import test_pou
from .expressions import InitGen
from .pyast import _args, _call, _const, _name, _set_lines
from .statements import StmtGen, _by_ref_names

_PYCMP = {
    "ASSERT_EQ": py.Eq,
    "ASSERT_NEQ": py.NotEq,
    "ASSERT_GT": py.Gt,
    "ASSERT_LT": py.Lt,
    "ASSERT_GE": py.GtE,
    "ASSERT_LE": py.LtE,
}


class TestGen(StmtGen):
    def __init__(self, mod, test: TestModel):
        super().__init__(mod, test.pou)
        self.test = test
        self.self_name = None
        self.result_name = ""  # a test has no result: RETURN returns nothing

    def function(self) -> py.FunctionDef:
        t = self.test
        everything = t.setup + t.body + t.teardown
        by_ref = _by_ref_names(everything)
        self.boxed = {
            v
            for v in test_pou(t).vars.values()
            if (v in by_ref or v.address_taken) and not T.unalias(v.type).is_aggregate
        }
        init = InitGen(self.mod)
        main: list[py.stmt] = []
        for v in test_pou(t).vars.values():
            val = init.initial(v.type, v.init)
            node = py.Assign([_name(v.pyname, py.Store())], py.List([val], py.Load()) if v in self.boxed else val)
            main.append(_set_lines(node, v.span.line))
        body = self.stmts(t.setup) + self.stmts(t.body)
        teardown = self.stmts(t.teardown)
        if teardown:
            main.append(_set_lines(py.Try(body or [py.Pass()], [], [], teardown), t.span.line))
        else:
            main.extend(body)
        gl = sorted(self.globals_written)
        if gl:
            main.insert(0, py.Global(gl))
        fn = py.FunctionDef(t.pyname, _args([]), main or [py.Pass()], [], None, None)
        return _set_lines(fn, t.span.line)

    # ------------------------------------------------------------------ test statements
    def test_call(self, tgt) -> list:
        info, op = tgt.info, tgt.op
        idx = _const(info.index)
        vals = [self.expr(v) for v in tgt.operands]
        msg = self.expr(tgt.msg) if tgt.msg is not None else _const(None)
        if op == "advance_time":
            return [py.Expr(_call("_t_advance", vals[0]))]
        if op == "mock_verify_called":
            return [py.Expr(_call("_t_verify", idx, self._mock_target(tgt.operands[0], vals[0]), _const(None)))]
        if op == "mock_verify_call_count":
            return [py.Expr(_call("_t_verify", idx, self._mock_target(tgt.operands[0], vals[0]), vals[1]))]
        a, b = self.new_tmp(), self.new_tmp()
        test: py.expr
        store: list[py.stmt]
        if op in ("assert_true", "assert_false"):
            test = _name(a) if op == "assert_true" else py.UnaryOp(py.Not(), _name(a))
            store = [py.Assign([_name(a, py.Store())], vals[0])]
            fail_args = [_name(a), _const(op == "assert_true")]
        elif op == "assert_near":
            tol = self.new_tmp()
            store = [
                py.Assign(
                    [py.Tuple([_name(a, py.Store()), _name(b, py.Store()), _name(tol, py.Store())], py.Store())],
                    py.Tuple(vals, py.Load()),
                )
            ]
            diff = py.BinOp(_name(a), py.Sub(), _name(b))
            test = py.Compare(py.UnaryOp(py.USub(), _name(tol)), [py.LtE(), py.LtE()], [diff, _name(tol)])
            fail_args = [_name(a), _name(b), _name(tol)]
        else:
            store = [
                py.Assign(
                    [py.Tuple([_name(a, py.Store()), _name(b, py.Store())], py.Store())], py.Tuple(vals, py.Load())
                )
            ]
            test = py.Compare(_name(a), [_PYCMP[info.kind]()], [_name(b)])
            fail_args = [_name(a), _name(b)]
        fail = py.Expr(_call("_t_fail", idx, msg, *fail_args))
        return store + [py.If(_negate(test), [fail], [])]

    def _mock_target(self, e, value):
        """A mocked FUNCTION is named by its generated Python name; an instance is itself."""
        if isinstance(e.sym, T.POUType) and e.sym.pou_kind == "FUNCTION":
            return _const(e.sym.pyname)
        return value

    def s_Mock(self, s) -> list:
        return [py.Expr(_call("_t_mock", self.expr(s.target)))]

    def s_MockFunction(self, s) -> list:
        value = self.coerce(self.expr(s.value), s.value, s.pou.return_type)
        return [py.Expr(_call("_t_mock_function", _const(s.pou.pyname), value))]


def _negate(test: py.expr) -> py.expr:
    if isinstance(test, py.UnaryOp) and isinstance(test.op, py.Not):
        return test.operand
    return py.UnaryOp(py.Not(), test)
