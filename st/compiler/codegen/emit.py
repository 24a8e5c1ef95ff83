"""The code-emitting API for libraries: what a native function's `emit` may build on.

A `FuncSig.emit(ctx, args, arg_types, result_type)` (compiler/library.py) returns a Python
`ast.expr` built from its arguments' expressions; these are the helpers it may use besides
the `ast` node classes themselves. Generated code may only name `_`-prefixed helpers that a
library installs (`Library.helpers`), so `call` takes such a name or an expression.
"""

from __future__ import annotations

import ast as py

from .pyast import _call, _const

__all__ = ["call", "const", "wrap"]


def call(fn: str | py.expr, *args: py.expr) -> py.Call:
    """`fn(*args)`: a call of a helper by name (e.g. "_f32") or of an expression."""
    return _call(fn, *args)


def const(value) -> py.Constant:
    """A Python constant (int, float, str, bool, None, or a tuple of them)."""
    return _const(value)


def wrap(node: py.expr, elem) -> py.expr:
    """`node` wrapped to the width of the integer type `elem` (two's complement when signed)."""
    from .expressions import wrap as _wrap  # (when code is generated: libraries load without it)

    return _wrap(node, elem)
