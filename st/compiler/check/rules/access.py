"""Access specifiers: a PRIVATE method, property or variable is used only inside its own block, a
PROTECTED one there and in the blocks that extend it; an override keeps the base's access or
widens it; a method that implements an interface's is PUBLIC. Under the presets with
object-oriented ST (iec, codesys, twincat, the default).

Codes: E043.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ...syntax import decl_of
from ..common import Scope
from ..context import CheckContext


def check_access(ctx: CheckContext, mods, owner: T.POUType | None, what: str, scope: Scope, span: Span) -> None:
    """`what` (a member of `owner` with the modifiers `mods`) used in `scope` (a global has no owner
    and no access modifier)."""
    if owner is None:
        return
    if "PRIVATE" in mods and scope.fb is not owner:
        ctx.err(Code.NOT_ACCESSIBLE, span, f"{what} of {owner.name} is PRIVATE: only {owner.name} itself may use it")
    elif "PROTECTED" in mods and (scope.fb is None or not T.implements(scope.fb, owner)):
        ctx.err(
            Code.NOT_ACCESSIBLE,
            span,
            f"{what} of {owner.name} is PROTECTED: only {owner.name} and the blocks that extend it may use it",
        )


def _rank(mods) -> int:
    """PUBLIC/INTERNAL 0 < PROTECTED 1 < PRIVATE 2."""
    return 2 if "PRIVATE" in mods else 1 if "PROTECTED" in mods else 0


def check_override_access(ctx: CheckContext, mine: T.POUType, theirs: T.POUType) -> None:
    """The method `mine` overrides `theirs`: no narrower access."""
    m = decl_of(mine)
    if _rank(m.modifiers) > _rank(decl_of(theirs).modifiers):
        ctx.err(
            Code.NOT_ACCESSIBLE,
            m.span,
            f"method {m.name} overrides {theirs.block.name}.{m.name} with a narrower "
            f"access (an override keeps the base's access or widens it)",
        )


def check_implementation_access(ctx: CheckContext, fb: T.POUType, mine: T.POUType, itf: T.POUType, im) -> None:
    """The method `mine` of `fb` implements `im` of the interface `itf`: it is PUBLIC."""
    if {"PRIVATE", "PROTECTED"} & set(decl_of(mine).modifiers):
        ctx.err(
            Code.NOT_ACCESSIBLE,
            decl_of(mine).span,
            f"method {mine.name} of {fb.name} implements {itf.name}.{im.name}: it must be PUBLIC",
        )
