"""Inheritance and interface contracts: a FINAL block is not extended, a FINAL method not
overridden; an override keeps the signature (parameters and return type) of what it overrides, a
property its type; a method marked OVERRIDE overrides something; a block implements every method
and property of its interfaces with their signatures; an INTERFACE's methods have no body and
agree with those of the interfaces it extends. Under the presets with object-oriented ST.

Codes: E047.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ...syntax import decl_of
from ..common import signature
from ..context import CheckContext


def check_extensible(ctx: CheckContext, pou: T.POUType, base: T.POUType) -> bool:
    """`pou` EXTENDS `base`: not a FINAL one (reported: False)."""
    if "FINAL" in (decl_of(base).modifiers if base.decl is not None else ()):
        ctx.err(Code.INHERITANCE_CONTRACT, decl_of(pou).span, f"'{base.name}' is FINAL and cannot be extended")
        return False
    return True


def check_interface_method_body(ctx: CheckContext, itf: T.POUType, m) -> None:
    """The method declaration `m` of the INTERFACE `itf`: a prototype."""
    if m.body:
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            m.span,
            f"a method of INTERFACE {itf.name} has no body; implement it in a "
            f"FUNCTION_BLOCK that IMPLEMENTS {itf.name}",
        )


def check_interface_extension(ctx: CheckContext, itf: T.POUType, base: T.POUType, mine: T.POUType, theirs) -> None:
    """The method `mine` of `itf` and `theirs` of the interface `base` it extends: one signature."""
    if signature(mine) != signature(theirs):
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            decl_of(mine).span,
            f"method {mine.name} of {itf.name} differs from {base.name}.{theirs.name}",
        )


def check_property_override(ctx: CheckContext, fb: T.POUType, base: T.POUType, mine: T.PropSym, theirs) -> None:
    """The property `mine` of `fb` and `theirs`, of its base `base`, of the same name."""
    if mine is not theirs and mine.owner is fb and str(mine.type) != str(theirs.type):
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            mine.span,
            f"property {mine.name} overrides {base.name}.{theirs.name} with another type",
        )


def check_method_override(ctx: CheckContext, mine: T.POUType, theirs: T.POUType) -> bool:
    """A method that replaces an inherited one keeps its signature; a FINAL one cannot be replaced
    (reported: False, nothing more to check)."""
    m = decl_of(mine)
    if "FINAL" in decl_of(theirs).modifiers:
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            m.span,
            f"method {m.name} of {theirs.block.name} is FINAL and cannot be overridden",
        )
        return False
    if signature(mine) != signature(theirs):
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            m.span,
            f"method {m.name} overrides {theirs.block.name}.{m.name} with a different "
            f"signature (parameters and return type must be the same)",
        )
    return True


def check_override_marker(ctx: CheckContext, fb: T.POUType, mt: T.POUType, base: T.POUType | None) -> None:
    """The own method `mt` of `fb`: marked OVERRIDE only where `base` has a method of its name."""
    if "OVERRIDE" in decl_of(mt).modifiers and (base is None or mt.name.lower() not in base.methods):
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            decl_of(mt).span,
            f"method {mt.name} is marked OVERRIDE but {fb.name} inherits no method of that name",
        )


def check_interface_property(ctx: CheckContext, fb: T.POUType, itf: T.POUType, key: str, ip) -> None:
    """The property `ip` of the interface `itf` that `fb` implements: with its type, GET and SET."""
    mine = fb.properties.get(key)
    if mine is not None and str(mine.type) == str(ip.type):
        if ip.bare or not ((ip.get and not mine.get) or (ip.set and not mine.set)):
            return
    if mine is None and "ABSTRACT" in decl_of(fb).modifiers:
        return
    ctx.err(
        Code.INHERITANCE_CONTRACT,
        decl_of(fb).span,
        f"{fb.name} does not implement property {ip.name} of interface "
        f"{itf.name} (same type, GET and SET as declared there)",
    )


def check_interface_method(ctx: CheckContext, fb: T.POUType, itf: T.POUType, key: str, im) -> T.POUType | None:
    """The method `im` of the interface `itf` that `fb` implements: present (unless `fb` is
    ABSTRACT) and with its signature. Returns `fb`'s method when it is so."""
    mine = fb.methods.get(key)
    if mine is None:
        if "ABSTRACT" not in decl_of(fb).modifiers:
            ctx.err(
                Code.INHERITANCE_CONTRACT,
                decl_of(fb).span,
                f"{fb.name} does not implement method {im.name} of interface {itf.name}",
            )
        return None
    if signature(mine) != signature(im):
        ctx.err(
            Code.INHERITANCE_CONTRACT,
            decl_of(mine).span,
            f"method {mine.name} of {fb.name} does not match "
            f"{itf.name}.{im.name} (parameters and return type must be the same)",
        )
        return None
    return mine
