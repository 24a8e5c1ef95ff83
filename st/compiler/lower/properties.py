"""Properties: every use of a PROPERTY becomes a call of its accessor.

`inst.P` and, inside the block, `P` read through GET; as an assignment's target (`:=`, and
`S=`/`R=`, which set it only when their condition holds) they write through SET. SUPER^.P
calls the base block's accessor on this instance, not the most derived one.
"""

from __future__ import annotations

from typing import TypeGuard

from ...model import types as T
from .. import ast as A
from .walk import is_super, walk_stmts


def property_targets(body: list) -> None:
    """A property as an assignment's target (`:=`, `S=`/`R=`) in `body`, nested statements included,
    becomes the `AccessorCall` of its SET (its reads: `property_read`)."""
    for s in walk_stmts(body):
        if isinstance(s, A.Assign) and _is_property(s.target):
            s.target = _call(s.target, s.target.sym.set)


def property_read(e):
    """The rewrite of one expression: a property read becomes the `AccessorCall` of its GET."""
    return _call(e, e.sym.get) if _is_property(e) else e


def _is_property(e: A.Expr) -> TypeGuard[A.Name | A.Field]:
    return isinstance(e, (A.Name, A.Field)) and isinstance(e.sym, T.PropSym)


def _call(e, accessor: T.POUType) -> A.AccessorCall:
    obj = e.base if isinstance(e, A.Field) else None
    out = A.AccessorCall(e.span, obj, accessor, is_super(obj))
    out.ty = e.ty
    return out
