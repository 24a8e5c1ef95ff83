"""Pass 1, collect: every TYPE, POU, INTERFACE, CONFIGURATION, global block and TEST block of the
units, by name, before anything is resolved (so declarations may come in any order)."""

from __future__ import annotations

import re

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ...names import mangle
from ..context import CheckContext
from ..rules.replaces_library import check_library_replacement, used_by_library


def collect(ctx: CheckContext, units: list[A.Unit]) -> None:
    for u in units:
        _collect(ctx, u)


def _collect(ctx: CheckContext, u: A.Unit) -> None:
    for item in u.items:
        if isinstance(item, A.TypeBlock):
            for td in item.types:
                _collect_type(ctx, td)
        elif isinstance(item, (A.POU, A.Interface)):
            _collect_pou(ctx, item)
        elif isinstance(item, A.Configuration):
            ctx.configs.append(item)
        elif isinstance(item, A.VarBlock):
            _collect_globals(ctx, u, item)
        elif isinstance(item, A.TestBlock):
            ctx.project.test_blocks.append(item)


def _collect_type(ctx: CheckContext, td: A.TypeDecl) -> None:
    key = td.name.lower()
    if _replaces_library(ctx, key, td.span):
        pass  # a user type of a library type's name (T_MaxString) is the one used
    elif key in ctx.pending_types or key in ctx.project.pous:
        _dup(ctx, td.name, td.span)
        return
    if key in T.ELEMENTARY:
        ctx.err(Code.DECLARED_TWICE, td.span, f"'{td.name}' is an elementary type and cannot be redefined")
        return
    ctx.pending_types[key] = (td, ctx.lib_of(td.span))
    ctx.decl_span[key] = td.span


def _collect_pou(ctx: CheckContext, item: A.POU | A.Interface) -> None:
    _oop_features(ctx, item)
    key = item.name.lower()
    if key in ctx.pending_types and _replaces_library(ctx, key, item.span):
        pass
    elif key in ctx.project.pous or key in ctx.pending_types:
        old = ctx.project.pous.get(key)
        if old is None or not old.library or ctx.lib_of(item.span):
            _dup(ctx, item.name, item.span)
            return
        if not check_library_replacement(ctx, item, old):
            return
    pt = T.POUType(item.name, item.kind, decl=item, library=ctx.lib_of(item.span))
    pt.pyname = {"FUNCTION": "_fn_", "FUNCTION_BLOCK": "_fb_", "PROGRAM": "_prg_", "INTERFACE": "_itf_"}[
        item.kind
    ] + mangle(item.name)
    ctx.project.pous[key] = pt
    ctx.decl_span[key] = item.span


def _collect_globals(ctx: CheckContext, u: A.Unit, item: A.VarBlock) -> None:
    if item.kind != "VAR_GLOBAL":
        ctx.err(Code.MISPLACED_SECTION, item.span, f"{item.kind} is not allowed outside a POU")
        return
    ctx.global_blocks.append(("", item))
    gvl = gvl_name(u)
    if gvl:
        ctx.gvl_of_block[id(item)] = gvl
        if any(_QUALIFIED_ONLY.fullmatch(p.text) for p in u.pragmas):
            ctx.gvl_of_block[id(item)] = gvl + "!"  # its variables only as GVL.x


_QUALIFIED_ONLY = re.compile(r"\{\s*attribute\s+'qualified_only'\s*\}", re.I)
_GVL = re.compile(r"\{\s*gvl\s+'([A-Za-z_][A-Za-z0-9_]*)'\s*\}", re.I)


def gvl_name(u: A.Unit) -> str:
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
    if used_by_library(ctx, probe, td.span):
        return False
    del ctx.pending_types[key]
    return True


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
    ctx.err(Code.DECLARED_TWICE, span, f"'{name}' is declared twice{where}")
