"""Initial values that name other variables have an order that computes them (CODESYS, TwinCAT:
`b : FB_B(specs := aSpecs);`, `itf : I_State := fbOff;` above `fbOff`, a method's
`n : UDINT := SIZEOF(Block) * dofs;`): each is evaluated once what it reads has its own initial
value, in declaration order otherwise; an instance named only for what it is (an interface or a
REFERENCE TO bound to it, its ADR or REF) only needs to exist, and an instance whose FB_init
arguments read its own variables is created (its declared values set) before they are read. Initial
values that need each other's value (`a : INT := b; b : INT := a + 1;`) have no such order: an
error. Under the presets that allow such initial values at all (codesys, twincat, the default).

Codes: E029.
"""

from __future__ import annotations

from dataclasses import dataclass

from ....diagnostics import Code
from ....model import types as T
from ....model.syntax import Syntax
from ... import ast as A
from ..context import CheckContext
from ..targets import RefCall


@dataclass(frozen=True, slots=True)
class Step:
    """One step of a POU's initialisation: `var` initialised whole ("all"), or an instance whose
    FB_init arguments name variables created with its declared values ("create") and later
    constructed, its FB_init run with those arguments ("construct")."""

    var: T.VarSym
    part: str = "all"


def names_variables(init) -> bool:
    """Does the initializer `init` read a variable (not a constant), name THIS or take an address
    (ADR, REF: of a variable's storage, a constant's too)?"""
    for x in A.walk_nodes(init):
        if isinstance(x, A.Name) and (x.name.upper() == "THIS" or _is_variable(x.sym)):
            return True
        if isinstance(x, A.Call) and isinstance(x.target, RefCall):
            return True
    return False


def late_default(p: T.VarSym) -> bool:
    """Is `p` an input of a FUNCTION or METHOD whose default names variables (TwinCAT:
    `inB : Builder(specs := tmp);` with `tmp` a local of the method)? An omitted argument is then
    computed by the callee, in its initialisation order, not by the caller."""
    owner = p.owner
    return (
        p.section == "VAR_INPUT"
        and p.init is not None
        and isinstance(owner, T.POUType)
        and (owner.pou_kind == "FUNCTION" or owner.owner_fb is not None)
        and names_variables(p.init)
    )


def _is_variable(sym) -> bool:
    return isinstance(sym, T.VarSym) and not (sym.global_ref or sym).constant


def _split(v: T.VarSym) -> bool:
    """Is `v` an instance created first and constructed later (its FB_init arguments name variables)?"""
    return isinstance(v.init, A.CtorInit) and any(names_variables(val) for _n, _sp, val in v.init.args)


def _uses(init, t: T.Type | None, members: dict) -> list[tuple[T.VarSym, bool]]:
    """The variables of `members` (id → VarSym) the initializer `init` of a `t` reads: (variable,
    whether only its identity is needed: an instance, a reference bound to it, its address)."""
    out: list[tuple[T.VarSym, bool]] = []
    if isinstance(init, A.CtorInit):
        bt = T.unalias(t) if t is not None else None
        mt = bt.methods.get("fb_init") if isinstance(bt, T.POUType) else None
        for name, _sp, val in init.args:
            p = mt.vars.get(name.lower()) if mt is not None else None
            out += _uses(val, p.type if p is not None else None, members)
        if init.inner is not None:
            out += _uses(init.inner, t, members)
        return out
    if isinstance(init, A.StructInit):
        bt = T.unalias(t) if t is not None else None
        fields = bt.members if isinstance(bt, T.StructType) else bt.vars if isinstance(bt, T.POUType) else {}
        for name, _sp, val in init.fields:
            m = fields.get(name.lower())
            out += _uses(val, m.type if m is not None else None, members)
        return out
    if isinstance(init, A.ArrayInit):
        at = T.unalias(t) if t is not None else None
        elem = at.element if isinstance(at, T.ArrayType) else None
        for item in init.items:
            for sub in item.items if isinstance(item, A.RepeatInit) else [item]:
                out += _uses(sub, elem, members)
        return out
    if not isinstance(init, A.Expr):
        return out
    ut = T.unalias(t) if t is not None else None
    if (T.is_reference(t) or (isinstance(ut, T.POUType) and ut.pou_kind == "INTERFACE")) and _is_path(init):
        return _path_uses(init, members)  # bound to the variable, or the instance itself
    return _reads(init, members)


def _is_path(e) -> bool:
    while isinstance(e, (A.Field, A.Index)):
        e = e.base
    return isinstance(e, A.Name) or (isinstance(e, A.Deref) and isinstance(e.base, A.Name))


def _path_uses(e, members: dict) -> list[tuple[T.VarSym, bool]]:
    """A variable path used for what it is: its root (x, THIS^.x) only needs to exist; its indexes are read."""
    out: list[tuple[T.VarSym, bool]] = []
    while isinstance(e, (A.Field, A.Index)):
        if isinstance(e, A.Index):
            for i in e.indices:
                out += _reads(i, members)
        elif id(e.sym) in members and isinstance(e.base, A.Deref):  # THIS^.x
            return out + [(e.sym, True)]
        e = e.base
    if isinstance(e, A.Name) and id(e.sym) in members:
        out.append((e.sym, True))
    return out


_ATTACHED = frozenset(("span", "name_span", "end_span", "ty", "const", "sym", "pou", "target"))


def _reads(e, members: dict) -> list[tuple[T.VarSym, bool]]:
    """The variables of `members` an expression reads (x, inst.x, THIS^.x); the argument of ADR or
    REF only needs to exist."""
    out: list[tuple[T.VarSym, bool]] = []
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, (list, tuple)):
            stack.extend(x)
            continue
        if not isinstance(x, Syntax):
            continue
        if isinstance(x, A.Call) and isinstance(x.target, RefCall):
            out += _path_uses(x.target.arg, members)
            continue
        if isinstance(x, (A.Name, A.Field)) and id(x.sym) in members:
            out.append((x.sym, False))
        stack.extend(getattr(x, f) for f in x.__dataclass_fields__ if f not in _ATTACHED)
    return out


def plan(variables: list[T.VarSym]) -> tuple[list[Step], list[T.VarSym]]:
    """The order in which `variables` (in declaration order) get their initial values, and the
    variables of a cycle of initial values that need each other (empty when there is none)."""
    members = {id(v): v for v in variables}
    done: set = set()  # (id, part) of steps taken
    busy: list[T.VarSym] = []  # the variables being ordered (the path of the depth-first walk)
    steps: list[Step] = []
    cycle: list[T.VarSym] = []

    def need(v: T.VarSym, part: str) -> None:
        nonlocal cycle
        if part == "all" and _split(v):
            part = "construct"  # its values as declared, then its FB_init
        if cycle or (id(v), part) in done:
            return
        if part == "create":  # nothing to read: the instance with its declared values
            done.add((id(v), "create"))
            steps.append(Step(v, "create"))
            return
        at = next((i for i, b in enumerate(busy) if b is v), None)
        if at is not None:
            cycle = busy[at:]
            return
        busy.append(v)
        split = _split(v)
        if split:
            need(v, "create")
        for u, identity in _uses(v.init, v.type, members):
            if u is v and split:
                continue  # its own variables, as declared: it exists already
            need(u, "create" if identity and _split(u) else "all")
        busy.pop()
        if cycle:
            return
        done.add((id(v), part))
        steps.append(Step(v, part))

    for v in variables:
        need(v, "all")
        if cycle:
            return [Step(x) for x in variables], cycle
    return steps, []


def check_initialization_order(ctx: CheckContext) -> None:
    """Every block's instance variables and every FUNCTION's and METHOD's locals: no cycle."""
    reported: set = set()
    for pou in list(ctx.project.pous.values()):
        if pou.decl is None or pou.pou_kind == "INTERFACE":
            continue
        tables = [pou.vars] + [mt.vars for mt in pou.methods.values() if mt.owner_fb is pou]
        for table in tables:
            variables = [v for v in table.values() if v.init is not None and v.section != "VAR_EXTERNAL"]
            if not any(names_variables(v.init) for v in variables):
                continue
            _steps, cycle = plan(variables)
            key = frozenset(id(v) for v in cycle)
            if cycle and key not in reported:
                reported.add(key)
                first = min(cycle, key=lambda v: (v.span.line, v.span.col))
                names = " → ".join(v.name for v in cycle + cycle[:1])
                ctx.err(
                    Code.NOT_CONSTANT,
                    first.span,
                    f"the initial values of {names} need each other's values",
                    "initialise one of them in the code instead",
                )
