"""ABSTRACT function blocks, methods and properties: an ABSTRACT block is not instantiated
(declared, or made with __NEW); an ABSTRACT method or property stands only in an ABSTRACT block,
has no body, is implemented by every block that extends it and is not ABSTRACT itself, and is
never called through SUPER^ (it has no implementation). Under the presets with object-oriented
ST (iec, codesys, twincat, the default).

Codes: E061.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ...syntax import decl_of
from ..context import CheckContext


def _is_abstract(t) -> bool:
    return isinstance(t, T.POUType) and t.decl is not None and "ABSTRACT" in decl_of(t).modifiers


def check_declared_instance(ctx: CheckContext, t: T.Type, section: str, span: Span) -> None:
    """A variable of type `t` declared in a `section`: an instance, unless it only refers to one."""
    if (
        isinstance(t, T.POUType)
        and t.pou_kind == "FUNCTION_BLOCK"
        and _is_abstract(t)
        and section not in ("VAR_IN_OUT", "VAR_EXTERNAL")
    ):
        ctx.err(
            Code.ABSTRACT,
            span,
            f"'{t.name}' is ABSTRACT and cannot be instantiated; declare an instance of a block that EXTENDS it",
        )


def check_new_instance(ctx: CheckContext, t: T.Type, span: Span) -> None:
    """__NEW(t)."""
    if _is_abstract(t):
        ctx.err(Code.ABSTRACT, span, f"'{t.name}' is ABSTRACT and cannot be instantiated")


def check_super_call(ctx: CheckContext, c: A.Call, mt: T.POUType, obj) -> None:
    """`c` calls the method `mt` on `obj` (None: this instance): SUPER^.M() runs the base's own M."""
    if (
        "ABSTRACT" in decl_of(mt).modifiers
        and isinstance(obj, A.Deref)
        and isinstance(obj.base, A.Name)
        and getattr(obj.base.sym, "kind", "") == "super"
    ):
        ctx.err(
            Code.ABSTRACT,
            c.span,
            f"method {mt.name} of {mt.block.name} is ABSTRACT: it has no implementation to call",
        )


def check_method(ctx: CheckContext, fb: T.POUType, mt: T.POUType) -> None:
    """The method `mt` of the block `fb` (its own, or inherited)."""
    mods = decl_of(mt).modifiers
    abstract_fb = "ABSTRACT" in decl_of(fb).modifiers
    if "ABSTRACT" not in mods:
        return
    if mt.owner_fb is not fb:
        if not abstract_fb:
            ctx.err(
                Code.ABSTRACT,
                decl_of(fb).span,
                f"{fb.name} does not implement the ABSTRACT method {mt.name} of {mt.block.name}",
            )
        return
    if not abstract_fb:
        ctx.err(Code.ABSTRACT, decl_of(mt).span, f"ABSTRACT method {mt.name} in {fb.name}, which is not ABSTRACT")
    if decl_of(mt).body:
        ctx.err(Code.ABSTRACT, decl_of(mt).span, f"ABSTRACT method {mt.name} has a body")


def check_property(ctx: CheckContext, fb: T.POUType, ps: T.PropSym) -> None:
    """The property `ps` of the block `fb` (its own, or inherited)."""
    acc = ps.get or ps.set
    if acc is None or acc.decl is None or "ABSTRACT" not in decl_of(acc).modifiers:
        return
    abstract_fb = "ABSTRACT" in decl_of(fb).modifiers
    if ps.owner is fb:
        if not abstract_fb:
            ctx.err(Code.ABSTRACT, ps.span, f"ABSTRACT property {ps.name} in {fb.name}, which is not ABSTRACT")
        if any(a is not None and decl_of(a).body for a in (ps.get, ps.set)):
            ctx.err(Code.ABSTRACT, ps.span, f"ABSTRACT property {ps.name} has a body")
    elif not abstract_fb:
        ctx.err(
            Code.ABSTRACT,
            decl_of(fb).span,
            f"{fb.name} does not implement the ABSTRACT property {ps.name} of {ps.owner.name}",
        )
