"""Object-oriented rules, checked once every POU interface is resolved: overrides keep the
signature and the access of what they override, FINAL is not overridden, ABSTRACT methods and
properties are implemented, interfaces are implemented with their signatures."""

from __future__ import annotations

from ....model import types as T
from ..common import CONSTRUCTION, signature
from ..context import CheckContext


def check_oop_rules(ctx: CheckContext) -> None:
    for fb in list(ctx.project.pous.values()):
        d = fb.decl
        if d is None or d.kind != "FUNCTION_BLOCK":
            continue
        base = fb.base
        if base is not None:
            for k, bp in base.properties.items():
                my_prop = fb.properties[k]
                if my_prop is not bp and my_prop.owner is fb and str(my_prop.type) != str(bp.type):
                    ctx.err(
                        "E047",
                        my_prop.span,
                        f"property {my_prop.name} overrides {base.name}.{bp.name} with another type",
                    )
            for k, bm in base.methods.items():
                mine = fb.methods[k]
                # each block's FB_init has its own inputs
                if mine is not bm and mine.owner_fb is fb and k not in CONSTRUCTION:
                    _check_override(ctx, fb, mine, bm)
        if d.implements:
            _check_implements(ctx, fb)
        _check_abstract_and_override(ctx, fb, base)


def _access_rank(mods) -> int:
    """PUBLIC/INTERNAL 0 < PROTECTED 1 < PRIVATE 2."""
    return 2 if "PRIVATE" in mods else 1 if "PROTECTED" in mods else 0


def _check_abstract_and_override(ctx: CheckContext, fb: T.POUType, base) -> None:
    d = fb.decl
    abstract_fb = "ABSTRACT" in d.modifiers
    for mt in fb.methods.values():
        mods = mt.decl.modifiers
        if mt.owner_fb is fb:
            if "OVERRIDE" in mods and (base is None or mt.name.lower() not in base.methods):
                ctx.err(
                    "E043",
                    mt.decl.span,
                    f"method {mt.name} is marked OVERRIDE but {fb.name} inherits no method of that name",
                )
            if "ABSTRACT" in mods and not abstract_fb:
                ctx.err("E043", mt.decl.span, f"ABSTRACT method {mt.name} in {fb.name}, which is not ABSTRACT")
            if "ABSTRACT" in mods and mt.decl.body:
                ctx.err("E043", mt.decl.span, f"ABSTRACT method {mt.name} has a body")
        elif "ABSTRACT" in mods and not abstract_fb:
            ctx.err("E043", d.span, f"{fb.name} does not implement the ABSTRACT method {mt.name} of {mt.owner_fb.name}")
    for ps in fb.properties.values():
        acc = ps.get or ps.set
        if acc is None or acc.decl is None or "ABSTRACT" not in acc.decl.modifiers:
            continue
        if ps.owner is fb:
            if not abstract_fb:
                ctx.err("E043", ps.span, f"ABSTRACT property {ps.name} in {fb.name}, which is not ABSTRACT")
            if any(a is not None and a.decl.body for a in (ps.get, ps.set)):
                ctx.err("E043", ps.span, f"ABSTRACT property {ps.name} has a body")
        elif not abstract_fb:
            ctx.err("E043", d.span, f"{fb.name} does not implement the ABSTRACT property {ps.name} of {ps.owner.name}")


def _check_override(ctx: CheckContext, fb: T.POUType, mine: T.POUType, theirs: T.POUType) -> None:
    """A method that replaces an inherited one must keep its signature; FINAL ones cannot be replaced."""
    m = mine.decl
    if "FINAL" in theirs.decl.modifiers:
        ctx.err("E047", m.span, f"method {m.name} of {theirs.owner_fb.name} is FINAL and cannot be overridden")
        return

    if signature(mine) != signature(theirs):
        ctx.err(
            "E047",
            m.span,
            f"method {m.name} overrides {theirs.owner_fb.name}.{m.name} with a different "
            f"signature (parameters and return type must be the same)",
        )
    if _access_rank(m.modifiers) > _access_rank(theirs.decl.modifiers):
        ctx.err(
            "E043",
            m.span,
            f"method {m.name} overrides {theirs.owner_fb.name}.{m.name} with a narrower "
            f"access (an override keeps the base's access or widens it)",
        )


def _check_implements(ctx: CheckContext, fb: T.POUType) -> None:
    """FUNCTION_BLOCK … IMPLEMENTS I1, I2: every method and property of each interface, with its signature."""
    d = fb.decl
    abstract = "ABSTRACT" in d.modifiers
    for itf in fb.interfaces:
        for k, ip in itf.properties.items():
            my_prop = fb.properties.get(k)
            if (
                my_prop is None
                or str(my_prop.type) != str(ip.type)
                or (not ip.bare and ((ip.get and not my_prop.get) or (ip.set and not my_prop.set)))
            ):
                if my_prop is None and abstract:
                    continue
                ctx.err(
                    "E047",
                    d.span,
                    f"{fb.name} does not implement property {ip.name} of interface "
                    f"{itf.name} (same type, GET and SET as declared there)",
                )
        for k, im in itf.methods.items():
            mine = fb.methods.get(k)
            if mine is None:
                if not abstract:
                    ctx.err("E047", d.span, f"{fb.name} does not implement method {im.name} of interface {itf.name}")
            elif signature(mine) != signature(im):
                ctx.err(
                    "E047",
                    mine.decl.span,
                    f"method {mine.name} of {fb.name} does not match "
                    f"{itf.name}.{im.name} (parameters and return type must be the same)",
                )
            elif {"PRIVATE", "PROTECTED"} & set(mine.decl.modifiers):
                ctx.err(
                    "E043",
                    mine.decl.span,
                    f"method {mine.name} of {fb.name} implements {itf.name}.{im.name}: it must be PUBLIC",
                )
