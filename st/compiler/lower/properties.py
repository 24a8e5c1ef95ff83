"""Properties: every use of a PROPERTY becomes a call of its accessor.

`inst.P` and, inside the block, `P` read through GET; as an assignment's target (`:=`, and
`S=`/`R=`, which set it only when their condition holds) they write through SET. SUPER^.P
calls the base block's accessor on this instance, not the most derived one.
"""

from __future__ import annotations

from typing import TypeGuard

from ...model import types as T
from .. import ast as A
from .walk import is_super, rewrite_exprs, rewrite_outside_bodies, walk_stmts


def accessor_calls(body: list) -> None:
    """Rewrite every property access in `body` (nested statements included) into an `AccessorCall`."""
    for s in walk_stmts(body):
        if isinstance(s, A.Assign) and _is_property(s.target):
            s.target = _call(s.target, s.target.sym.set)
    rewrite_exprs(body, _read)


def accessor_calls_outside_bodies(project) -> None:
    """The same in what is not a statement (SFC conditions, configuration arguments)."""
    rewrite_outside_bodies(project, _read)


def _read(e):
    return _call(e, e.sym.get) if _is_property(e) else e


def _is_property(e: A.Expr) -> TypeGuard[A.Name | A.Field]:
    return isinstance(e, (A.Name, A.Field)) and isinstance(e.sym, T.PropSym)


def _call(e, accessor: T.POUType) -> A.AccessorCall:
    obj = e.base if isinstance(e, A.Field) else None
    out = A.AccessorCall(e.span, obj, accessor, is_super(obj))
    out.ty = e.ty
    return out
