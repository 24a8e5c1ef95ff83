"""An assignment attempt (dest ?= src) works on instances: dest is an interface variable or a
REF_TO a function block or interface, src an interface, a function block instance, a reference
to one, or NULL. Under the presets with object-oriented ST (E044 under openplc).

Codes: E055.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..common import _NULL
from ..context import CheckContext


def attempt(ctx: CheckContext, s: A.Assign, dest: T.Type, src: T.Type) -> tuple[str, bool, bool] | None:
    """What `s` (dest ?= src) tests at run time: (the kind dest needs, src is a reference, dest is
    one), or None after reporting an operand it cannot work on."""
    kind, dest_ref = _instance_kind(dest)
    if kind is None or (not dest_ref and kind.pou_kind != "INTERFACE"):
        ctx.err(
            Code.BAD_ASSIGNMENT_ATTEMPT,
            s.target.span,
            f"?= needs an interface or a REF_TO a function block on the left, not {dest}",
        )
        return None
    if src is _NULL:
        return (kind.name.lower(), False, dest_ref)
    got, src_ref = _instance_kind(src)
    if got is None:
        ctx.err(
            Code.BAD_ASSIGNMENT_ATTEMPT,
            s.value.span,
            f"?= needs an interface, a function block instance or a reference to one on the right, not {src}",
        )
        return None
    return (kind.name.lower(), src_ref, dest_ref)


def _instance_kind(t: T.Type) -> tuple[T.POUType | None, bool]:
    """(the block or interface type `t` is or refers to, whether through a reference); (None, False)
    for anything else."""
    u = T.unalias(t)
    if isinstance(u, T.RefType):
        target = T.unalias(u.target)
        if isinstance(target, T.POUType) and target.pou_kind in ("FUNCTION_BLOCK", "INTERFACE"):
            return target, True
    if isinstance(u, T.POUType) and u.pou_kind in ("FUNCTION_BLOCK", "INTERFACE"):
        return u, False
    return None, False
