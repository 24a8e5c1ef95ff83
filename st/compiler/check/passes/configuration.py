"""Configurations: tasks, program instances and their connections, VAR_CONFIG, VAR_ACCESS; without a
CONFIGURATION, an implicit one runs every PROGRAM in one task."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....diagnostics import Code
from ....model import types as T
from ....model.addresses import canonical
from ....model.program import AccessPath, ConfigModel, InstanceModel, TaskModel
from ... import ast as A
from ...syntax import decl_of
from ..common import _SECTIONS_PARAM, Scope
from ..rules import declaration_mismatch

if TYPE_CHECKING:
    from ..semantics import Semantics


def check_configurations(sem: Semantics) -> None:
    for cfg_decl in sem.ctx.configs:
        _check_configuration(sem, cfg_decl)
    if not sem.ctx.project.configs:
        _implicit_configuration(sem)
    for cm in sem.ctx.project.configs:  # a task runs the instance that `Prg` names in code
        for im in cm.instances:
            sym = sem.ctx.program_instances.get(im.type.name.lower())
            if sym is not None and im.name.lower() == im.type.name.lower():
                im.singleton = sym.pyname


def _check_configuration(sem: Semantics, cfg: A.Configuration) -> None:
    ctx = sem.ctx
    cm = ConfigModel(cfg.name)
    scope = Scope(None, {})
    for res in cfg.resources:
        for td in res.tasks:
            tm = TaskModel(td.name, span=td.span)
            for k, v in td.params.items():
                _task_parameter(sem, tm, k, v, scope)
            if any(t.name.lower() == td.name.lower() for t in cm.tasks):
                ctx.err(Code.DECLARED_TWICE, td.span, f"task '{td.name}' is declared twice")
            cm.tasks.append(tm)
        for pc in res.programs:
            im = _program_instance(sem, cm, res, pc, scope)
            if im is not None:
                cm.instances.append(im)
    configured: dict[str, T.Type] = {}  # %address → the type of the variable VAR_CONFIG places there
    for b in cfg.var_blocks:
        if b.kind == "VAR_CONFIG":
            for d in b.decls:
                t = _config_path_type(sem, cm, d)
                if t is not None:
                    cm.var_config.append((d.path or [], d.location, d.init, d.type, d.span))
                    if d.location:
                        configured[canonical(d.location)] = t
    for b in cfg.var_blocks + [b for r in cfg.resources for b in r.var_blocks]:
        if b.kind == "VAR_ACCESS":
            for d in b.decls:
                _access_path(sem, cfg, cm, configured, d)
    ctx.project.configs.append(cm)


def _access_path(sem: Semantics, cfg: A.Configuration, cm: ConfigModel, configured: dict, d: A.AccessDecl) -> None:
    """`name : [R.]inst.var : T [READ_ONLY|READ_WRITE];` (or a global, or a %address): registered in
    the project's access paths when its variable is found and has the declared type."""
    ctx = sem.ctx
    name = d.names[0][0]
    path = list(d.path)
    shown = ".".join(path)
    if len(path) > 1 and any(r.name.lower() == path[0].lower() for r in cfg.resources):
        path = path[1:]  # the resource's name: its instances and globals are the configuration's here
    taken = any(i.name.lower() == name.lower() for i in cm.instances) or ctx.project.global_names.get(name.lower())
    if name.lower() in ctx.project.access_paths or taken:
        ctx.err(Code.DECLARED_TWICE, d.span, f"'{name}' is declared twice (an access path's name must be new)")
        return
    t: T.Type | None
    if path[0].startswith("%"):
        found = (configured.get(canonical(path[0])) or _located(ctx, canonical(path[0]))) if len(path) == 1 else None
        if found is None:
            ctx.err(Code.UNDECLARED, d.span, f"VAR_ACCESS: no located variable at {shown}")
            return
        t, target = found, canonical(path[0])
    else:
        inst = next((i for i in cm.instances if i.name.lower() == path[0].lower()), None)
        gs = ctx.project.global_names.get(path[0].lower()) if inst is None else None
        if inst is None and not gs:
            ctx.err(Code.UNDECLARED, d.span, f"VAR_ACCESS: {shown}: no program instance or global named '{path[0]}'")
            return
        t = inst.type if inst is not None else gs[0].type if gs else T.INT
        for part in path[1:]:
            ut = T.unalias(t)
            member: T.VarSym | T.Member | None = None
            if isinstance(ut, T.POUType):
                sym = ut.vars.get(part.lower())
                member = sym if sym is not None and sym.section != "VAR_TEMP" else None
            elif isinstance(ut, T.StructType):
                member = ut.members.get(part.lower())
            else:
                member = None
            if member is None:
                ctx.err(Code.UNDECLARED, d.span, f"VAR_ACCESS: {shown}: '{part}' is not a variable of {ut}")
                return
            t = member.type
        target = ".".join(path)
    want = sem.decls.resolve_type(d.type, None)
    if want is None or not declaration_mismatch.check_access_entry(ctx, d, want, t):
        return
    ctx.project.access_paths[name.lower()] = AccessPath(name, target, t, d.read_only, d.span)


def _task_parameter(sem: Semantics, tm: TaskModel, k: str, v: A.Expr, scope: Scope) -> None:
    """TASK t (INTERVAL := T#20ms, SINGLE := trigger, PRIORITY := 1): one of them."""
    ctx = sem.ctx
    if k == "INTERVAL":
        tt = sem.exprs.expr(v, scope, T.TIME)
        c = sem.consts.value(v, scope)
        if tt is None or not T.base_of(tt).is_time or not isinstance(c, int):
            ctx.err(Code.TYPE_MISMATCH, v.span, "INTERVAL must be a TIME constant, e.g. T#20ms")
        elif c <= 0:
            ctx.err(Code.NOT_CONSTANT, v.span, "INTERVAL must be positive")
        else:
            tm.interval = c
    elif k == "PRIORITY":
        c = sem.consts.value(v, scope)
        if not isinstance(c, int):
            ctx.err(Code.NOT_CONSTANT, v.span, "PRIORITY must be an integer constant")
        else:
            tm.priority = c
    elif k == "SINGLE":
        if not isinstance(v, A.Name):
            ctx.err(Code.TYPE_MISMATCH, v.span, "SINGLE must name a BOOL variable")
            return
        gs = ctx.project.global_names.get(v.name.lower())
        if not gs:
            ctx.err(Code.UNDECLARED, v.span, f"SINGLE refers to unknown variable '{v.name}'")
        else:
            tm.single = gs[0].pyname
    else:
        ctx.err(Code.BAD_PARAMETER, v.span, f"unknown task parameter '{k}' (INTERVAL, SINGLE, PRIORITY)")


def _program_instance(sem: Semantics, cm: ConfigModel, res, pc, scope: Scope) -> InstanceModel | None:
    """PROGRAM inst WITH task : Type (in := a, out => b): None after an error."""
    ctx = sem.ctx
    pou = ctx.project.pous.get(pc.type_name.lower())
    if pou is None or pou.pou_kind != "PROGRAM":
        ctx.err(Code.BAD_CONFIGURATION, pc.span, f"'{pc.type_name}' is not a PROGRAM")
        return None
    if pc.task and not any(t.name.lower() == pc.task.lower() for t in cm.tasks):
        ctx.err(Code.BAD_CONFIGURATION, pc.span, f"unknown task '{pc.task}'")
        return None
    if any(i.name.lower() == pc.instance.lower() for i in cm.instances):
        ctx.err(Code.DECLARED_TWICE, pc.span, f"program instance '{pc.instance}' is declared twice")
        return None
    im = InstanceModel(pc.instance, pou, pc.task, res.name, [], pc.span)
    for a in pc.args:
        p = pou.vars.get(a.name.lower())
        if p is None or p.section not in _SECTIONS_PARAM:
            ctx.err(Code.BAD_PARAMETER, a.span, f"{pou.name} has no parameter '{a.name}'")
            continue
        if a.output:
            sem.exprs.expr(a.value, scope)
        else:
            vt = sem.exprs.expr(a.value, scope, p.type)
            sem.stmts.assignable(a.value, vt, p.type, a.value.span, "pass")
        im.args.append((p, a.value, a.output))
    return im


def _located(ctx, address: str) -> T.Type | None:
    """The type of a variable located at `address` (a global's, or a program's or block's own)."""
    for sym in list(ctx.project.globals.values()) + [v for p in ctx.project.user_pous() for v in p.vars.values()]:
        if sym.location and canonical(sym.location) == address:
            return sym.type
    return None


def _config_path_type(sem: Semantics, cm: ConfigModel, d: A.VarDecl):
    """Check a VAR_CONFIG entry `inst.fb.var AT %QX0.0 : T := v;`; its variable's type or None."""
    ctx = sem.ctx
    path = d.path or []
    inst = next((i for i in cm.instances if path and i.name.lower() == path[0].lower()), None)
    if inst is None:
        ctx.err(Code.UNDECLARED, d.span, f"VAR_CONFIG: no program instance named '{path[0] if path else ''}'")
        return None
    t: T.Type = inst.type
    for name in path[1:]:
        ut = T.unalias(t)
        sym = ut.vars.get(name.lower()) if isinstance(ut, T.POUType) else None
        if sym is None:
            ctx.err(Code.UNDECLARED, d.span, f"VAR_CONFIG: {'.'.join(path)}: '{name}' is not a variable of {ut}")
            return None
        t = sym.type
    want = sem.decls.resolve_type(d.type, None)
    if not declaration_mismatch.check_config_entry(ctx, d, path, want, t):
        return None
    if d.location:
        sem.decls.check_location(d.location, t, d.span)
    if d.init is not None:
        sem.decls.check_initializer(d.init, t, None)
    return t


def _implicit_configuration(sem: Semantics) -> None:
    ctx = sem.ctx
    progs = [
        p
        for p in ctx.project.pous.values()
        if p.pou_kind == "PROGRAM" and not p.library and p.name.lower() not in ctx.called_programs
    ]
    cm = ConfigModel("", implicit=True)
    cm.tasks.append(TaskModel("main", 0, 0))
    for p in progs:
        cm.instances.append(InstanceModel(p.name, p, "main", "", [], decl_of(p).span if p.decl else None))
    ctx.project.configs.append(cm)
