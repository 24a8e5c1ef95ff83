"""Globals: every VAR_GLOBAL (of the files, the configurations and their resources) declared under
its scope's name, their initial values checked once all are known, VAR_EXTERNALs bound to them."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....diagnostics import Code
from ... import ast as A
from ...names import qualified
from ..context import CheckContext
from ..rules import declaration_mismatch

if TYPE_CHECKING:
    from ..semantics import Semantics


def declare_globals(sem: Semantics) -> None:
    ctx = sem.ctx
    for cfg in ctx.configs:
        for b in cfg.var_blocks:
            ctx.global_blocks.append((cfg.name, b))
        for r in cfg.resources:
            for b in r.var_blocks:
                ctx.global_blocks.append((cfg.name + "." + r.name, b))
    declared: dict = {}  # scope + lower-case name → symbol (ST names ignore case)
    constants = []  # (declaration, its symbols) of every VAR_GLOBAL CONSTANT
    for prefix, block in ctx.global_blocks:
        if block.kind not in ("VAR_CONFIG", "VAR_ACCESS"):
            table = _declare_block(sem, prefix, block, declared)
            if "CONSTANT" in block.qualifiers:
                constants += [(d, [table[n.lower()] for n, _ in d.names if n.lower() in table]) for d in block.decls]
    # global initializers may name other globals: check them once all are declared; so may the
    # initial values of the POUs' variables met so far
    ctx.globals_declared = True
    for decl, t in ctx.deferred_inits:
        ctx.current_gvl = ctx.gvl_of_decl.get(id(decl))  # its own list's names need no qualifier
        sem.decls.check_initializer(decl.init, t, None)
    ctx.current_gvl = None
    ctx.deferred_inits = []
    for decl, syms in constants:  # their values, for the code that reads them (inlined as literals)
        ctx.current_gvl = ctx.gvl_of_decl.get(id(decl))
        value = sem.consts.value(decl.init, None) if isinstance(decl.init, A.Expr) else None
        for sym in syms:
            sym.const_value = value
    ctx.current_gvl = None
    for decl, t, scope, variables in ctx.deferred_pou_inits:
        sem.decls.check_initializer(decl.init, t, scope, variables)
    ctx.deferred_pou_inits = []
    _bind_externals(ctx)


def _declare_block(sem: Semantics, prefix: str, block, declared: dict) -> dict:
    """The variables of one VAR_GLOBAL block, under its scope's name (`prefix`): {lower name: symbol}."""
    ctx = sem.ctx
    table: dict = {}
    sem.decls.declare_block(block, table, None, None)
    gvl = ctx.gvl_of_block.get(id(block))
    for key, sym in table.items():
        sym.section = "VAR_GLOBAL"
        sym.is_global = True
        scope = prefix.split(".") if prefix else []
        if gvl and gvl.endswith("!"):
            # a qualified_only list's member is its own: beside a library global of its name
            scope.append(gvl[:-1])
        sym.pyname = "_g_" + qualified(*scope, sym.name)
        uniq = sym.pyname.lower()
        other = declared.get(uniq)
        if other is not None and ctx.lib_of(other.span) and not ctx.lib_of(sym.span):
            # a user global of a library constant's name (ADSLOG_MSGTYPE_ERROR) is the one used
            ctx.project.global_names[key].remove(other)
            other = None
        if other is not None:
            ctx.err(
                Code.DECLARED_TWICE,
                sym.span,
                f"global '{sym.name}' is declared twice (first at {other.span.file}:{other.span.line})",
            )
            continue
        declared[uniq] = sym
        ctx.project.globals[sym.pyname] = sym
        ctx.project.global_names.setdefault(key, []).append(sym)
        if gvl:
            ctx.gvl_of_decl.update((id(d), gvl.rstrip("!").lower()) for d in block.decls)
            if gvl.endswith("!"):  # {attribute 'qualified_only'}
                ctx.qualified_only.add(id(sym))
            ctx.gvls.setdefault(gvl.rstrip("!").lower(), {})[key] = sym
    return table


def _bind_externals(ctx: CheckContext) -> None:
    """Bind the VAR_EXTERNAL declarations (of POUs, their methods and property accessors)."""
    owners = []
    for pou in ctx.project.pous.values():
        owners.append(pou)
        owners += [m for m in pou.methods.values() if m.owner_fb is pou]
        owners += [a for ps in pou.properties.values() if ps.owner is pou for a in (ps.get, ps.set) if a]
    for pou in owners:
        for sym in pou.vars.values():
            if sym.section != "VAR_EXTERNAL":
                continue
            cands = ctx.project.global_names.get(sym.name.lower())
            if not cands:
                ctx.err(Code.UNDECLARED, sym.span, f"VAR_EXTERNAL '{sym.name}' has no matching VAR_GLOBAL")
                continue
            g = cands[0]
            sym.global_ref = g
            sym.pyname = g.pyname
            declaration_mismatch.check_external(ctx, sym, g)
