"""A POU of the program may replace a standard library POU of the same name: a warning that it
does (W004), under every preset; but where the library's own code uses that POU as what it is
(F_TRIG uses R_TRIG, PID uses INTEGRAL), one of another kind cannot stand in for it (E011).

Codes: W004, E011.
"""

from __future__ import annotations

import re

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ...syntax import decl_of
from ..context import CheckContext

_KINDS = {"FUNCTION": "function", "FUNCTION_BLOCK": "function block", "PROGRAM": "program", "INTERFACE": "interface"}


def check_library_replacement(ctx: CheckContext, item: A.POU | A.Interface, old: T.POUType) -> bool:
    """The user's POU `item` has the name of the library's `old`: does it replace it (warned), or
    is it refused (reported: False)?"""
    if old.pou_kind != item.kind and used_by_library(ctx, old):
        # the library's own code uses it as what it is: another kind cannot stand in for it
        ctx.err(
            Code.DECLARED_TWICE,
            item.span,
            f"'{item.name}' is a {_KINDS.get(old.pou_kind, old.pou_kind)} of the "
            f"standard library; a {item.kind} cannot replace it",
            f"rename it, or declare it as a {old.pou_kind} to replace the library's",
        )
        return False
    ctx.warn(Code.REPLACES_LIBRARY_POU, item.span, f"'{item.name}' replaces the standard library's {item.name}")
    return True


_END = re.compile(r"^\s*END_(FUNCTION_BLOCK|FUNCTION|PROGRAM|INTERFACE|CLASS)\b", re.I | re.M)


def used_by_library(ctx: CheckContext, pou: T.POUType, own_type: Span | None = None) -> bool:
    """Does library code other than `pou`'s own declaration name it? Then a user POU of another
    kind cannot stand in for it (the standard library's F_TRIG uses R_TRIG, PID uses INTEGRAL);
    a library POU nothing else uses may be replaced by anything."""
    name = re.compile(rf"\b{re.escape(pou.name)}\b", re.I)
    own = decl_of(pou).span if pou.decl is not None else None
    for lib in ctx.libraries:
        for path, text in lib.sources:
            if own_type is not None and path == own_type.file:  # a TYPE: all but its own line
                lines = text.split("\n")
                text = "\n".join(lines[: own_type.line - 1] + lines[own_type.line :])
            if own is not None and path == own.file:
                start = sum(len(line) + 1 for line in text.split("\n")[: own.line - 1])
                end = _END.search(text, start)
                text = text[:start] + text[end.end() if end else len(text) :]
            if name.search(_COMMENTS.sub("", text)):
                return True
    return False


_COMMENTS = re.compile(r"\(\*.*?\*\)|//[^\n]*", re.S)
