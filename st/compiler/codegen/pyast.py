"""Small builders for Python `ast` nodes, and value helpers shared by the generators."""

from __future__ import annotations

import ast as py
import struct
from typing import TypeVar

from ...model import types as T
from .facts import note_helper

_F32 = struct.Struct("<f")
DAY_NS = 86_400_000_000_000


def f32(v: float) -> float:
    try:
        return _F32.unpack(_F32.pack(v))[0]
    except OverflowError:
        return float("inf") if v > 0 else float("-inf")


def _name(n: str, ctx=None) -> py.Name:
    return py.Name(n, ctx or py.Load())


def _const(v) -> py.Constant:
    return py.Constant(v)


def _attr(obj: py.expr, name: str, ctx=None) -> py.Attribute:
    return py.Attribute(obj, name, ctx or py.Load())


def _call(fn: str | py.expr, *args) -> py.Call:
    if fn == "_f32" and len(args) == 1 and _rounded(args[0]):
        return args[0]  # REAL rounding is idempotent: `_f32(_f32(x))` is `_f32(x)`
    if isinstance(fn, str):
        note_helper(fn)
        return py.Call(_name(fn), list(args), [])
    return py.Call(fn, list(args), [])


def _rounded(node: py.expr) -> bool:
    """A call whose value is already a single-precision float: `_f32(x)`, or `_abs` of one."""
    if not isinstance(node, py.Call) or not isinstance(node.func, py.Name) or len(node.args) != 1:
        return False
    name = node.func.id
    return name == "_f32" or (name == "_abs" and _rounded(node.args[0]))


def _store(node: py.expr) -> py.expr:
    """Turn a Load expression into a Store target."""
    if isinstance(node, py.Name):
        return py.Name(node.id, py.Store())
    if isinstance(node, py.Attribute):
        return py.Attribute(node.value, node.attr, py.Store())
    if isinstance(node, py.Subscript):
        return py.Subscript(node.value, node.slice, py.Store())
    raise TypeError(node)


_N = TypeVar("_N", bound=py.AST)


def _set_lines(node: _N, line: int) -> _N:
    """Give a node and its children without a position the ST line `line`.

    Children that already have a line (inner statements, placed earlier) are
    not descended into, so placing a whole body costs one pass.
    """
    stack: list[py.AST] = [node]
    pop, push = stack.pop, stack.append
    while stack:
        n = pop()
        if "lineno" in n._attributes:
            if getattr(n, "lineno", None) is not None and n is not node:
                continue
            if getattr(n, "lineno", None) is None:
                # a node that lists "lineno" in its _attributes has all four positions
                n.lineno = n.end_lineno = line  # type: ignore[attr-defined]
                n.col_offset = n.end_col_offset = 0  # type: ignore[attr-defined]
        for f in n._fields:
            v = getattr(n, f, None)
            if isinstance(v, list):
                for x in v:
                    if isinstance(x, py.AST):
                        push(x)
            elif isinstance(v, py.AST):
                push(v)
    return node


def default_value(t: T.Type):
    """The Python value of a scalar type's default, or None for aggregates."""
    t = T.unalias(t)
    if isinstance(t, T.SubrangeType):
        return t.lo  # IEC: a subrange starts at its lower limit
    if isinstance(t, T.ElemType):
        if t.kind == "char":
            return "\0"
        return t.default
    if isinstance(t, T.StringType):
        return ""
    if isinstance(t, T.EnumType):
        return t.default_value
    if isinstance(t, T.RefType):
        return None
    return None


class Unsupported(Exception):
    def __init__(self, span, msg):
        self.span = span
        self.msg = msg


def _args(names: list[str], defaults=None) -> py.arguments:
    return py.arguments([], [py.arg(n) for n in names], None, [], [], None, defaults or [])
