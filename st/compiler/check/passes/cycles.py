"""Self-containment and recursion, once the bodies are checked (they fill the call graph): a type
may not contain itself, and POUs may not call themselves (IEC forbids recursion)."""

from __future__ import annotations

from ....model import types as T
from ....source import Span
from ..context import CheckContext


def check_cycles(ctx: CheckContext) -> None:
    """A type may not contain itself, and POUs may not call themselves (IEC forbids recursion)."""

    def members(t):
        t = T.unalias(t)
        if isinstance(t, T.ArrayType):
            return members(t.element)
        if isinstance(t, T.StructType):
            return [m.type for m in t.members.values()]
        if isinstance(t, T.POUType) and t.pou_kind != "FUNCTION":
            return [v.type for v in t.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_IN_OUT")]
        return []

    def leaf(t):
        t = T.unalias(t)
        while isinstance(t, T.ArrayType):
            t = T.unalias(t.element)
        return t if isinstance(t, (T.StructType, T.POUType)) else None

    for t in list(ctx.project.types.values()) + list(ctx.project.pous.values()):
        start = leaf(t)
        if start is None:
            continue
        seen, stack = set(), [leaf(m) for m in members(start)]
        while stack:
            x = stack.pop()
            if x is None or id(x) in seen:
                continue
            if x is start:
                span = ctx.decl_span.get(start.name.lower())
                ctx.err("E046", span or Span("<types>", 0, 0), f"'{start.name}' contains itself")
                break
            seen.add(id(x))
            stack.extend(leaf(m) for m in members(x))
    # calls
    for pou in ctx.project.pous.values():
        seen, stack = set(), list(ctx.calls.get(pou.name.lower(), ()))
        while stack:
            name, span = stack.pop()
            if name == pou.name.lower():
                ctx.err("E032", span, f"{pou.name} calls itself (recursion is not allowed in IEC 61131-3)")
                break
            if name in seen:
                continue
            seen.add(name)
            stack.extend(ctx.calls.get(name, ()))
