"""A type is not defined in terms of itself: a structure or function block does not contain
itself (directly, or through its members, arrays of them, the blocks it holds), a named type is
not defined through itself, a function block or an interface does not extend itself. Under every
preset (a REF_TO or POINTER TO itself is fine: it does not contain it).

Codes: E046.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ...syntax import decl_of
from ..context import CheckContext


def report_named_type(ctx: CheckContext, key: str, span: Span) -> None:
    """The named type `key` is met again while it is being resolved."""
    ctx.err(Code.SELF_CONTAINING_TYPE, span, f"type '{key}' is defined in terms of itself")


def check_extends_chain(ctx: CheckContext, pou: T.POUType, base: T.POUType) -> bool:
    """`pou` EXTENDS `base`: the chain of bases does not lead back to `pou` (reported: False)."""
    chain = {pou.name.lower()}
    b: T.POUType | None = base
    while b is not None:
        if b.name.lower() in chain:
            ctx.err(Code.SELF_CONTAINING_TYPE, decl_of(pou).span, f"{pou.name} extends itself through '{b.name}'")
            return False
        chain.add(b.name.lower())
        nxt = b.decl.extends if isinstance(b.decl, A.POU) else ""
        b = ctx.project.pous.get(nxt.lower()) if nxt else None
    return True


def check_interface_extends(ctx: CheckContext, itf: T.POUType, base: T.POUType) -> bool:
    """INTERFACE itf EXTENDS base: base does not already extend itf (reported: False)."""
    if T.implements(base, itf):
        ctx.err(
            Code.SELF_CONTAINING_TYPE, decl_of(itf).span, f"INTERFACE {itf.name} extends itself through '{base.name}'"
        )
        return False
    return True


def check_self_containment(ctx: CheckContext) -> None:
    """Every structure and block of the program, once all are resolved: none contains itself."""
    for t in list(ctx.project.types.values()) + list(ctx.project.pous.values()):
        start = _leaf(t)
        if start is None:
            continue
        seen, stack = set(), [_leaf(m) for m in _members(start)]
        while stack:
            x = stack.pop()
            if x is None or id(x) in seen:
                continue
            if x is start:
                span = ctx.decl_span.get(start.name.lower())
                ctx.err(Code.SELF_CONTAINING_TYPE, span or Span("<types>", 0, 0), f"'{start.name}' contains itself")
                break
            seen.add(id(x))
            stack.extend(_leaf(m) for m in _members(x))


def _members(t) -> list:
    """The types a value of type t holds by value."""
    t = T.unalias(t)
    if isinstance(t, T.ArrayType):
        return _members(t.element)
    if isinstance(t, T.StructType):
        return [m.type for m in t.members.values()]
    if isinstance(t, T.POUType) and t.pou_kind != "FUNCTION":
        return [v.type for v in t.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_IN_OUT")]
    return []


def _leaf(t):
    """The structure or block a type is (through aliases and arrays), or None."""
    t = T.unalias(t)
    while isinstance(t, T.ArrayType):
        t = T.unalias(t.element)
    return t if isinstance(t, (T.StructType, T.POUType)) else None
