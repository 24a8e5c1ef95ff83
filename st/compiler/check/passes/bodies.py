"""Bodies: every POU's statements, its methods' and property accessors', its actions and its SFC
network, typed and checked (the recursion check, passes/cycles.py, reads the calls' targets after)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....diagnostics import Code
from ....model import types as T
from ....model.program import SfcModel, StepModel, TransitionModel
from ...syntax import decl_of
from ..common import Scope
from ..rules import conditions, result_without_type

if TYPE_CHECKING:
    from ..semantics import Semantics


def check_bodies(sem: Semantics) -> None:
    for pou in list(sem.ctx.project.pous.values()):
        if pou.decl is not None:
            sem.ctx.cancel_point()
            _check_body(sem, pou)


def _check_body(sem: Semantics, pou: T.POUType) -> None:
    ctx = sem.ctx
    d = decl_of(pou)
    if pou.pou_kind == "INTERFACE":
        return
    if "CLASS" in getattr(d, "modifiers", ()) and d.body:
        ctx.err(Code.MISPLACED_SECTION, d.body[0].span, f"a CLASS has no body; put the code in a METHOD of {pou.name}")
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
    if pou.pou_kind == "FUNCTION":  # (a variable of its name is that variable: TwinCAT)
        result_without_type.check_assigned_result(ctx, pou, "FUNCTION", d.body, pou.vars, d.span)


def _check_method(sem: Semantics, fb: T.POUType, mt: T.POUType) -> None:
    """A METHOD's body: its own variables first, then the instance's."""
    ctx = sem.ctx
    names = dict(fb.vars)
    names.update(mt.vars)
    scope = Scope(mt, names, library=fb.library)
    scope.fb = fb
    sem.stmts.stmt_list(decl_of(mt).body, scope)
    if mt.pyname.startswith("_m_"):
        result_without_type.check_assigned_result(ctx, mt, "METHOD", decl_of(mt).body, names, decl_of(mt).span)


def _check_sfc(sem: Semantics, pou: T.POUType, scope: Scope) -> None:
    ctx = sem.ctx
    d = decl_of(pou)
    steps, index = _sfc_steps(ctx, pou)
    initial = [s for s in steps if s.initial]
    if len(initial) != 1:
        ctx.err(Code.SFC, d.span, f"an SFC needs exactly one INITIAL_STEP (found {len(initial)})")
    scope.steps = index
    actions = {act.name.lower(): act for act in d.actions}
    action_names: list = []
    action_index: dict = {}
    for s, sm in zip(d.steps, steps):
        for aa in s.actions:
            key = aa.action.lower()
            if not _step_action(sem, pou, aa, key in actions, scope):
                continue
            if key not in action_index:
                action_index[key] = len(action_names)
                action_names.append(key)
            sm.actions.append((key, aa.qualifier, aa.time))
    transitions = [_transition(sem, i, t, index, scope) for i, t in enumerate(d.transitions)]
    ctx.project.sfc[pou.name.lower()] = SfcModel(steps, transitions, action_names, action_index)


def _sfc_steps(ctx, pou: T.POUType) -> tuple[list[StepModel], dict]:
    """The steps of an SFC, in order, and their index by lower-case name."""
    steps: list[StepModel] = []
    index: dict = {}
    for s in decl_of(pou).steps:
        key = s.name.lower()
        if key in index:
            ctx.err(Code.DECLARED_TWICE, s.span, f"step '{s.name}' is declared twice")
            continue
        if key in pou.vars:
            ctx.err(Code.DECLARED_TWICE, s.span, f"step '{s.name}' has the name of a variable")
        index[key] = len(steps)
        steps.append(StepModel(s.name, len(steps), s.initial, [], s.span))
    return steps, index


def _step_action(sem: Semantics, pou: T.POUType, aa, is_action: bool, scope: Scope) -> bool:
    """A step's action association `aa`: an ACTION (or a BOOL variable) with a known qualifier and,
    for a timed one, its time (False after an error)."""
    ctx = sem.ctx
    if not is_action:
        sym = pou.vars.get(aa.action.lower())
        if sym is None or not T.base_of(sym.type).is_bool:
            ctx.err(Code.SFC, aa.span, f"'{aa.action}' is neither an ACTION of {pou.name} nor a BOOL variable")
            return False
        sym.used = sym.written = True
    q = aa.qualifier
    if q not in ("N", "R", "S", "P", "L", "D", "SD", "DS", "SL", "P0", "P1"):
        ctx.err(Code.SFC, aa.span, f"unknown action qualifier '{q}'")
        return False
    if q in ("L", "D", "SD", "DS", "SL"):
        if aa.time is None:
            ctx.err(Code.SFC, aa.span, f"qualifier {q} needs a time, e.g. {aa.action}({q}, T#1s)")
            return False
        tt = sem.exprs.expr(aa.time, scope, T.TIME)
        if tt is not None and not T.base_of(tt).is_time:
            ctx.err(Code.TYPE_MISMATCH, aa.time.span, f"the time of qualifier {q} must be a TIME, not {tt}")
    return True


def _transition(sem: Semantics, i: int, t, index: dict, scope: Scope) -> TransitionModel:
    ctx = sem.ctx
    srcs: list[int] = []
    dsts: list[int] = []
    for names, out in ((t.sources, srcs), (t.targets, dsts)):
        for n, sp in names:
            if n.lower() not in index:
                ctx.err(Code.SFC, sp, f"unknown step '{n}'")
            else:
                out.append(index[n.lower()])
    prio = 0
    if t.priority is not None:
        c = sem.consts.value(t.priority, scope)
        prio = c if isinstance(c, int) else 0
    if t.cond is not None:
        conditions.check_transition_condition(ctx, t.cond, sem.exprs.expr(t.cond, scope, T.BOOL))
        cond = t.cond
    else:
        cond = None
        sem.stmts.stmt_list(t.body or [], scope)
    return TransitionModel(i, srcs, dsts, cond, prio, t.span)
