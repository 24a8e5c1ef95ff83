"""Object-oriented rules, checked once every POU interface is resolved (rules/inheritance.py,
rules/access.py, rules/abstract.py): overrides keep the signature and the access of what they
override, FINAL is not overridden, ABSTRACT methods and properties are implemented, interfaces are
implemented with their signatures."""

from __future__ import annotations

from ....model import types as T
from ... import ast as A
from ...syntax import declared
from ..common import CONSTRUCTION
from ..context import CheckContext
from ..rules import abstract, access, inheritance


def check_oop_rules(ctx: CheckContext) -> None:
    for fb in list(ctx.project.pous.values()):
        d = declared(fb)
        if not isinstance(d, A.POU) or d.kind != "FUNCTION_BLOCK":
            continue
        base = fb.base
        if base is not None:
            _check_overrides(ctx, fb, base)
        if d.implements:
            _check_implements(ctx, fb)
        for mt in fb.methods.values():
            if mt.owner_fb is fb:
                inheritance.check_override_marker(ctx, fb, mt, base)
            abstract.check_method(ctx, fb, mt)
        for ps in fb.properties.values():
            abstract.check_property(ctx, fb, ps)


def _check_overrides(ctx: CheckContext, fb: T.POUType, base: T.POUType) -> None:
    """What `fb` declares again of its base's properties and methods."""
    for k, bp in base.properties.items():
        inheritance.check_property_override(ctx, fb, base, fb.properties[k], bp)
    for k, bm in base.methods.items():
        mine = fb.methods[k]
        # each block's FB_init has its own inputs
        if mine is not bm and mine.owner_fb is fb and k not in CONSTRUCTION:
            if inheritance.check_method_override(ctx, mine, bm):
                access.check_override_access(ctx, mine, bm)


def _check_implements(ctx: CheckContext, fb: T.POUType) -> None:
    """FUNCTION_BLOCK … IMPLEMENTS I1, I2: every method and property of each interface, with its signature."""
    for itf in fb.interfaces:
        for k, ip in itf.properties.items():
            inheritance.check_interface_property(ctx, fb, itf, k, ip)
        for k, im in itf.methods.items():
            mine = inheritance.check_interface_method(ctx, fb, itf, k, im)
            if mine is not None:
                access.check_implementation_access(ctx, fb, mine, itf, im)
