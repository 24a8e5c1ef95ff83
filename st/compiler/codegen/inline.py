"""Small standard function blocks (TON, R_TRIG, CTU, …) inlined at their call sites.

A call of a block costs a Python frame, about a third of what the call of R_TRIG does in all. A
body of the IEC library that can neither fault nor act (no call, no index, no loop, no division
by a variable: `inlinable`) is copied into the caller instead, with `self` the instance and its
locals renamed apart: the same statements on the same instance, so the same values and the same
instance variables after the call. Only where the instance is exactly of that block (a variable
of its type, not an in-out or a reference that may hold a derived block), and only for blocks of
a library that says its ST bodies are what runs (`Library.inline_blocks`: not the PLCopen
library, whose bodies are native), and not in a compilation with TEST blocks (a MOCK replaces an
instance's body while the test runs) or coverage probes.
"""

from __future__ import annotations

import ast as py
import copy

from ...model import types as T
from .. import ast as A
from .facts import current, facts_of
from .pyast import _set_lines

_ALLOWED = (
    py.Assign,
    py.If,
    py.Try,
    py.Pass,
    py.Expr,
    py.Compare,
    py.BinOp,
    py.UnaryOp,
    py.BoolOp,
    py.IfExp,
    py.NamedExpr,
    py.Attribute,
    py.Name,
    py.Constant,
    py.expr_context,
    py.operator,
    py.unaryop,
    py.boolop,
    py.cmpop,
)


def inlinable(fn: py.FunctionDef) -> bool:
    """Can this `_body` be copied into a caller: only assignments, IFs, the try/finally of its
    cached variables, and expressions that cannot raise (a division only by a nonzero constant)?"""
    for n in py.walk(py.Module(body=fn.body, type_ignores=[])):
        if isinstance(n, py.Module):
            continue
        if not isinstance(n, _ALLOWED):
            return False
        if isinstance(n, py.Try) and (n.handlers or n.orelse):
            return False
        if isinstance(n, py.Expr) and not isinstance(n.value, py.Constant):
            return False
        if isinstance(n, py.BinOp) and isinstance(n.op, (py.Div, py.FloorDiv, py.Mod, py.Pow)):
            if not (isinstance(n.right, py.Constant) and type(n.right.value) is int and n.right.value > 0):
                return False
    return True


def exact_instance(e) -> bool:
    """Is the called instance a variable of exactly its block: a name or a member of one, each a
    plain variable (not an in-out, a reference, a pointer's target or an array element)?"""
    if isinstance(e, A.Field):
        return _plain_var(e.sym) and exact_instance(e.base)
    return isinstance(e, A.Name) and _plain_var(e.sym)


def _plain_var(sym) -> bool:
    return isinstance(sym, T.VarSym) and sym.section != "VAR_IN_OUT" and not isinstance(T.unalias(sym.type), T.RefType)


def inline_body(fn: py.FunctionDef, inst: str, prefix: str, line: int) -> list[py.stmt]:
    """The body's statements for the instance named `inst`: its locals renamed with `prefix`, every
    position the call's line (a fault cannot happen in it; line marks show the call). The body's
    facts (facts.py) join those of the caller being generated."""
    memo: dict[int, object] = {}
    body = copy.deepcopy(fn.body, memo)
    own, caller = facts_of(fn), current()
    if own is not None and caller is not None:
        caller.add_inlined(own, memo, prefix)
    local = {n.id for n in py.walk(fn) if isinstance(n, py.Name) and isinstance(n.ctx, py.Store)}
    for stmt in body:
        for n in py.walk(stmt):
            if "lineno" in n._attributes:
                n.lineno = n.end_lineno = None  # type: ignore[attr-defined]
            if isinstance(n, py.Name):
                if n.id == "self":
                    n.id = inst
                elif n.id in local:
                    n.id = prefix + n.id
        _set_lines(stmt, line)
    return body
