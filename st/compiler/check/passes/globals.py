"""Globals: every VAR_GLOBAL (of the files, the configurations and their resources) declared under
its scope's name, their initial values checked once all are known, VAR_EXTERNALs bound to them."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...names import qualified
from ..common import same_type

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
    for prefix, block in ctx.global_blocks:
        table: dict = {}
        if block.kind == "VAR_CONFIG":
            continue
        sem.decls.declare_block(block, table, None, None)
        for key, sym in table.items():
            sym.section = "VAR_GLOBAL"
            sym.is_global = True
            scope = prefix.split(".") if prefix else []
            sym.pyname = "_g_" + qualified(*scope, sym.name)
            uniq = sym.pyname.lower()
            other = declared.get(uniq)
            if other is not None and ctx.lib_of(other.span) and not ctx.lib_of(sym.span):
                # a user global of a library constant's name (ADSLOG_MSGTYPE_ERROR) is the one used
                ctx.project.global_names[key].remove(other)
                other = None
            if other is not None:
                ctx.err(
                    "E011",
                    sym.span,
                    f"global '{sym.name}' is declared twice (first at {other.span.file}:{other.span.line})",
                )
                continue
            declared[uniq] = sym
            ctx.project.globals[sym.pyname] = sym
            ctx.project.global_names.setdefault(key, []).append(sym)
            gvl = ctx.gvl_of_block.get(id(block))
            if gvl:
                if gvl.endswith("!"):  # {attribute 'qualified_only'}
                    gvl = gvl[:-1]
                    ctx.qualified_only.add(id(sym))
                ctx.gvls.setdefault(gvl.lower(), {})[key] = sym
    # global initializers may name other globals: check them once all are declared; so may the
    # initial values of the POUs' variables met so far
    ctx.globals_declared = True
    for decl, t in ctx.deferred_inits:
        sem.decls.check_initializer(decl.init, t, None)
    ctx.deferred_inits = []
    for decl, t, scope in ctx.deferred_pou_inits:
        sem.decls.check_initializer(decl.init, t, scope)
    ctx.deferred_pou_inits = []
    # bind VAR_EXTERNAL declarations (of POUs, their methods and property accessors)
    owners = []
    for pou in ctx.project.pous.values():
        owners.append(pou)
        owners += [m for m in pou.methods.values() if m.owner_fb is pou]
        owners += [a for ps in pou.properties.values() if ps.owner is pou for a in (ps.get, ps.set) if a]
    for pou in owners:
        for sym in pou.vars.values():
            if sym.section == "VAR_EXTERNAL":
                cands = ctx.project.global_names.get(sym.name.lower())
                if not cands:
                    ctx.err("E010", sym.span, f"VAR_EXTERNAL '{sym.name}' has no matching VAR_GLOBAL")
                    continue
                g = cands[0]
                sym.global_ref = g
                sym.pyname = g.pyname
                if not same_type(g.type, sym.type):
                    ctx.err(
                        "E013",
                        sym.span,
                        f"VAR_EXTERNAL '{sym.name}' is declared {sym.type} but the VAR_GLOBAL is {g.type}",
                    )
