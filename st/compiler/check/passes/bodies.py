"""Bodies: every POU's statements, its methods' and property accessors', its actions and its SFC
network, typed and checked (the recursion check, passes/cycles.py, reads the calls' targets after)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....model import types as T
from ....model.program import SfcModel, StepModel, TransitionModel
from ... import ast as A
from ..common import Scope

if TYPE_CHECKING:
    from ..semantics import Semantics


def check_bodies(sem: Semantics) -> None:
    for pou in list(sem.ctx.project.pous.values()):
        if pou.decl is not None:
            _check_body(sem, pou)


def _check_body(sem: Semantics, pou: T.POUType) -> None:
    ctx = sem.ctx
    d = pou.decl
    if pou.pou_kind == "INTERFACE":
        return
    if "CLASS" in getattr(d, "modifiers", ()) and d.body:
        ctx.err("E003", d.body[0].span, f"a CLASS has no body; put the code in a METHOD of {pou.name}")
    scope = Scope(pou, pou.vars, library=pou.library)
    if pou.pou_kind in ("FUNCTION_BLOCK", "PROGRAM"):
        scope.fb = pou
    for mt in pou.methods.values():
        if mt.owner_fb is pou:
            _check_method(sem, pou, mt)
    for ps in pou.properties.values():
        if ps.owner is pou:
            for acc in (ps.get, ps.set):
                if acc is not None:
                    _check_method(sem, pou, acc)
    if d.steps or d.transitions:
        _check_sfc(sem, pou, scope)
    for act in d.actions:
        scope.actions[act.name.lower()] = act
    sem.stmts.stmt_list(d.body, scope)
    for act in d.actions:
        sem.stmts.stmt_list(act.body, scope)
    if (
        pou.pou_kind == "FUNCTION"
        and pou.return_type is None
        and pou.name.lower() not in pou.vars  # a variable of its name is that variable (TwinCAT)
        and _assigns_name(d.body, pou.name)
    ):
        ctx.err("E013", d.span, f"FUNCTION {pou.name} has no return type but assigns a result")


def _check_method(sem: Semantics, fb: T.POUType, mt: T.POUType) -> None:
    """A METHOD's body: its own variables first, then the instance's."""
    ctx = sem.ctx
    names = dict(fb.vars)
    names.update(mt.vars)
    scope = Scope(mt, names, library=fb.library)
    scope.fb = fb
    sem.stmts.stmt_list(mt.decl.body, scope)
    if (
        mt.pyname.startswith("_m_")
        and mt.return_type is None
        and mt.name.lower() not in names
        and _assigns_name(mt.decl.body, mt.name)
    ):
        ctx.err("E013", mt.decl.span, f"METHOD {mt.name} has no return type but assigns a result")


def _check_sfc(sem: Semantics, pou: T.POUType, scope: Scope) -> None:
    ctx = sem.ctx
    d = pou.decl
    steps: list[StepModel] = []
    index = {}
    for s in d.steps:
        key = s.name.lower()
        if key in index:
            ctx.err("E011", s.span, f"step '{s.name}' is declared twice")
            continue
        if key in pou.vars:
            ctx.err("E011", s.span, f"step '{s.name}' has the name of a variable")
        index[key] = len(steps)
        steps.append(StepModel(s.name, len(steps), s.initial, [], s.span))
    initial = [s for s in steps if s.initial]
    if len(initial) != 1:
        ctx.err("E030", d.span, f"an SFC needs exactly one INITIAL_STEP (found {len(initial)})")
    scope.steps = index
    actions: dict = {}
    for act in d.actions:
        actions[act.name.lower()] = act
    action_names: list = []
    action_index: dict = {}
    for s, sm in zip(d.steps, steps):
        for aa in s.actions:
            key = aa.action.lower()
            if key not in actions:
                sym = pou.vars.get(key)
                if sym is None or not T.base_of(sym.type).is_bool:
                    ctx.err("E030", aa.span, f"'{aa.action}' is neither an ACTION of {pou.name} nor a BOOL variable")
                    continue
                sym.used = sym.written = True
            q = aa.qualifier
            if q not in ("N", "R", "S", "P", "L", "D", "SD", "DS", "SL", "P0", "P1"):
                ctx.err("E030", aa.span, f"unknown action qualifier '{q}'")
                continue
            if q in ("L", "D", "SD", "DS", "SL"):
                if aa.time is None:
                    ctx.err("E030", aa.span, f"qualifier {q} needs a time, e.g. {aa.action}({q}, T#1s)")
                    continue
                tt = sem.exprs.expr(aa.time, scope, T.TIME)
                if tt is not None and not T.base_of(tt).is_time:
                    ctx.err("E013", aa.time.span, f"the time of qualifier {q} must be a TIME, not {tt}")
            if key not in action_index:
                action_index[key] = len(action_names)
                action_names.append(key)
            sm.actions.append((key, q, aa.time))
    transitions = []
    for i, t in enumerate(d.transitions):
        srcs: list[int] = []
        dsts: list[int] = []
        for names, out in ((t.sources, srcs), (t.targets, dsts)):
            for n, sp in names:
                if n.lower() not in index:
                    ctx.err("E030", sp, f"unknown step '{n}'")
                else:
                    out.append(index[n.lower()])
        prio = 0
        if t.priority is not None:
            c = sem.consts.value(t.priority, scope)
            prio = c if isinstance(c, int) else 0
        if t.cond is not None:
            ct = sem.exprs.expr(t.cond, scope, T.BOOL)
            if ct is not None and not T.base_of(ct).is_bool:  # None: reported already
                ctx.err("E015", t.cond.span, f"a transition condition must be BOOL, not {ct}")
            cond = t.cond
        else:
            cond = None
            sem.stmts.stmt_list(t.body or [], scope)
        transitions.append(TransitionModel(i, srcs, dsts, cond, prio, t.span))
    ctx.project.sfc[pou.name.lower()] = SfcModel(steps, transitions, action_names, action_index)


def _assigns_name(body: list, name: str) -> bool:
    key = name.lower()
    for s in body:
        if isinstance(s, A.Assign) and isinstance(s.target, A.Name) and s.target.name.lower() == key:
            return True
    return False
