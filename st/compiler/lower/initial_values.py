"""Initial values that name variables: in which order a POU's variables get them.

CODESYS lets an initial value name other variables (`b : FB_B(specs := aSpecs);`, an interface
initialised with an instance declared below it, a method's local computed from its inputs); the
checker accepts them where the preset does and refuses a cycle (check/rules/initialization_order.py).
Here each block, FUNCTION and METHOD with such initial values gets the order of its
initialisation: declaration order, except that a variable whose initial value reads another gets
its value after that one's, and an instance whose FB_init arguments name variables is created
first (its declared values in place) and constructed (FB_init run) where its arguments have their
values. POUs without such initial values are not listed: their variables are initialised in
declaration order, as before.

A block's VAR_IN_OUT whose binding its code tests (`__ISVALIDREF(io)`) starts unbound (NULL), so
the test is FALSE until a call of the instance gives it (`note_unbound_in_out`). Initial values that
name variables are code and are lowered as bodies are (`rewrite_initializers`).
"""

from __future__ import annotations

from ...model import types as T
from .. import ast as A
from ..check import IsValidRefCall
from ..check.rules.initialization_order import late_default, names_variables, plan
from .walk import rewrite_exprs


def initial_orders(project) -> dict:
    """POUType (a block, a FUNCTION, a METHOD) → [Step], for those with initial values that name
    variables: the instance variables of a block, the locals (VAR, VAR_TEMP) of a function or method."""
    out: dict = {}
    for pou in project.pous.values():
        if pou.decl is None or pou.pou_kind == "INTERFACE":
            continue
        if pou.pou_kind == "FUNCTION":
            _add(out, pou, _call_variables(pou))
            continue
        _add(out, pou, [v for v in pou.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_TEMP", "VAR_STAT")])
        for mt in pou.methods.values():
            if mt.owner_fb is pou:
                _add(out, mt, _call_variables(mt))
    return out


def _call_variables(pou: T.POUType) -> list:
    """A FUNCTION's or METHOD's variables initialised at each call: its locals, and its inputs whose
    default names variables (computed when the caller omits them: codegen/pous.py)."""
    return [v for v in pou.vars.values() if v.section in ("VAR", "VAR_TEMP") or late_default(v)]


def _add(out: dict, pou: T.POUType, variables: list) -> None:
    if any(v.init is not None and names_variables(v.init) for v in variables):
        steps, cycle = plan(variables)
        if not cycle:  # (the checker has reported it)
            out[pou] = steps


def note_unbound_in_out(e, out: set) -> None:
    """`e`, an expression of a body: where it is `__ISVALIDREF(io)` of a block's VAR_IN_OUT, that
    in-out starts unbound (`out` collects them; lower/__init__.py calls this in its one walk)."""
    if isinstance(e, A.Call) and isinstance(e.target, IsValidRefCall) and isinstance(e.target.arg, A.Name):
        sym = e.target.arg.sym
        if (
            isinstance(sym, T.VarSym)
            and sym.section == "VAR_IN_OUT"
            and isinstance(sym.owner, T.POUType)
            and sym.owner.pou_kind in ("FUNCTION_BLOCK", "PROGRAM")
        ):
            out.add(sym)


def rewrite_initializers(project, fn) -> None:
    """`rewrite_exprs` for the initial values that name variables (they are code: a property read
    becomes its GET, GVL.x the global), of every POU's, method's and structure-less variable."""
    for pou in project.pous.values():
        if pou.decl is None or pou.pou_kind == "INTERFACE":
            continue
        tables = [pou.vars] + [mt.vars for mt in pou.methods.values() if mt.owner_fb is pou]
        for table in tables:
            for v in table.values():
                if v.owner is not None and v.init is not None and names_variables(v.init):
                    holder = [v.init]
                    rewrite_exprs(holder, fn)
                    v.init = holder[0]
