"""Pass 1, collect: every TYPE, POU, INTERFACE, CONFIGURATION, global block and TEST block of the
units, by name, before anything is resolved (so declarations may come in any order)."""

from __future__ import annotations

import re

from ....model import types as T
from ....source import Span
from ... import ast as A
from ...names import mangle
from ..context import CheckContext


def collect(ctx: CheckContext, units: list[A.Unit]) -> None:
    for u in units:
        _collect(ctx, u)


def _collect(ctx: CheckContext, u: A.Unit) -> None:
    for item in u.items:
        if isinstance(item, A.TypeBlock):
            for td in item.types:
                key = td.name.lower()
                if _replaces_library(ctx, key, td.span):
                    pass  # a user type of a library type's name (T_MaxString) is the one used
                elif key in ctx.pending_types or key in ctx.project.pous:
                    _dup(ctx, td.name, td.span)
                    continue
                if key in T.ELEMENTARY:
                    ctx.err("E011", td.span, f"'{td.name}' is an elementary type and cannot be redefined")
                    continue
                ctx.pending_types[key] = (td, ctx.lib_of(td.span))
                ctx.decl_span[key] = td.span
        elif isinstance(item, (A.POU, A.Interface)):
            _oop_features(ctx, item)
            key = item.name.lower()
            if key in ctx.pending_types and _replaces_library(ctx, key, item.span):
                pass
            elif key in ctx.project.pous or key in ctx.pending_types:
                old = ctx.project.pous.get(key)
                if (
                    old is not None
                    and old.library
                    and not ctx.lib_of(item.span)
                    and old.pou_kind != item.kind
                    and _used_by_library(ctx, old)
                ):
                    # the library's own code uses it as what it is: another kind cannot stand in for it
                    kinds = {
                        "FUNCTION": "function",
                        "FUNCTION_BLOCK": "function block",
                        "PROGRAM": "program",
                        "INTERFACE": "interface",
                    }
                    ctx.err(
                        "E011",
                        item.span,
                        f"'{item.name}' is a {kinds.get(old.pou_kind, old.pou_kind)} of the "
                        f"standard library; a {item.kind} cannot replace it",
                        f"rename it, or declare it as a {old.pou_kind} to replace the library's",
                    )
                    continue
                if old is not None and old.library and not ctx.lib_of(item.span):
                    # a user POU replaces a library POU of the same name
                    ctx.warn("W004", item.span, f"'{item.name}' replaces the standard library's {item.name}")
                else:
                    _dup(ctx, item.name, item.span)
                    continue
            pt = T.POUType(item.name, item.kind, decl=item, library=ctx.lib_of(item.span))
            pt.pyname = {"FUNCTION": "_fn_", "FUNCTION_BLOCK": "_fb_", "PROGRAM": "_prg_", "INTERFACE": "_itf_"}[
                item.kind
            ] + mangle(item.name)
            ctx.project.pous[key] = pt
            ctx.decl_span[key] = item.span
        elif isinstance(item, A.Configuration):
            ctx.configs.append(item)
        elif isinstance(item, A.VarBlock):
            if item.kind != "VAR_GLOBAL":
                ctx.err("E003", item.span, f"{item.kind} is not allowed outside a POU")
                continue
            ctx.global_blocks.append(("", item))
            gvl = _gvl_name(u)
            if gvl:
                ctx.gvl_of_block[id(item)] = gvl
                if any(_QUALIFIED_ONLY.fullmatch(p.text) for p in u.pragmas):
                    ctx.gvl_of_block[id(item)] = gvl + "!"  # its variables only as GVL.x
        elif isinstance(item, A.TestBlock):
            ctx.project.test_blocks.append(item)


_QUALIFIED_ONLY = re.compile(r"\{\s*attribute\s+'qualified_only'\s*\}", re.I)
_GVL = re.compile(r"\{\s*gvl\s+'([A-Za-z_][A-Za-z0-9_]*)'\s*\}", re.I)


def _gvl_name(u: A.Unit) -> str:
    """The name of the global variable list a file is (`{gvl 'GVL_Main'}`, from a .TcGVL), or ''."""
    for p in u.pragmas:
        m = _GVL.fullmatch(p.text)
        if m:
            return m.group(1)
    return ""


def _replaces_library(ctx: CheckContext, key: str, span: Span) -> bool:
    """A user declaration of a library TYPE's name takes its place (the library's is dropped),
    unless library code uses that type; then it is a duplicate."""
    old = ctx.pending_types.get(key)
    if old is None or not old[1] or ctx.lib_of(span):
        return False
    td = old[0]
    probe = T.POUType(td.name, "TYPE", decl=None, library="lib")
    if _used_by_library(ctx, probe, td.span):
        return False
    del ctx.pending_types[key]
    return True


_END = re.compile(r"^\s*END_(FUNCTION_BLOCK|FUNCTION|PROGRAM|INTERFACE|CLASS)\b", re.I | re.M)


def _used_by_library(ctx: CheckContext, pou: T.POUType, own_type: Span | None = None) -> bool:
    """Does library code other than `pou`'s own declaration name it? Then a user POU of another
    kind cannot stand in for it (the standard library's F_TRIG uses R_TRIG, PID uses INTEGRAL);
    a library POU nothing else uses may be replaced by anything."""
    name = re.compile(rf"\b{re.escape(pou.name)}\b", re.I)
    own = pou.decl.span if pou.decl is not None else None
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


def _oop_features(ctx: CheckContext, item) -> None:
    if isinstance(item, A.Interface):
        ctx.feature("oop", item.span, "INTERFACE")
        return
    if "CLASS" in item.modifiers:
        ctx.feature("oop", item.span, "CLASS")
    if item.extends:
        ctx.feature("oop", item.span, "EXTENDS")
    if item.implements:
        ctx.feature("oop", item.span, "IMPLEMENTS")
    for m in item.methods:
        ctx.feature("oop", m.span, "METHOD")
    for pr in item.properties:
        ctx.feature("oop", pr.span, "PROPERTY")


def _dup(ctx: CheckContext, name: str, span: Span) -> None:
    prev = ctx.decl_span.get(name.lower())
    where = f" (first declared at {prev.file}:{prev.line})" if prev else ""
    ctx.err("E011", span, f"'{name}' is declared twice{where}")
