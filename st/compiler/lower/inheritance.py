"""Inheritance: what a block's class holds once EXTENDS is resolved.

A derived block's class is flattened: it holds every variable of its bases (the checker has
already put them into `POUType.vars`) and gets every method, property accessor and action it
has, its own and the inherited ones it does not override, so a base may be declared after its
derived blocks or in another file. `kinds` names what an instance is (the block, its bases and
every interface they provide) for `?=` and __QUERYINTERFACE.

Every call of a method or a block gets `nonvirtual` on its call target: None for a Python
method call (the instance's most derived implementation runs), else the block whose method
or body runs on this instance: the base, for SUPER^.M(…) and SUPER^().
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ...model import types as T
from .. import ast as A
from ..check import FbCall, MethodCall
from .fb_init import Constructor, constructor
from .walk import is_super


@dataclass(slots=True)
class Block:
    pou: T.POUType
    kinds: tuple  # sorted lower-case names
    variables: list  # [VarSym] an instance holds (VAR_EXTERNAL, VAR_TEMP, VAR_STAT are elsewhere)
    method_variables: list  # [VarSym] its methods' VAR_INST, kept in the instance
    actions: list  # [ast.ActionDecl]
    methods: list  # [POUType]
    accessors: list  # [POUType] GET and SET of its properties
    constructor: Constructor | None


def blocks(project) -> dict:
    """POUType → Block for every FUNCTION_BLOCK, PROGRAM and CLASS with a body to generate."""
    out = {}
    for pou in project.pous.values():
        if pou.decl is None or pou.pou_kind in ("INTERFACE", "FUNCTION"):
            continue
        out[pou] = Block(
            pou,
            tuple(sorted(kinds_of(pou))),
            [v for v in pou.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_TEMP", "VAR_STAT")],
            [v for mt in pou.methods.values() for v in mt.vars.values() if v.section == "VAR_INST"],
            list(pou.actions.values()),
            list(pou.methods.values()),
            [acc for ps in pou.properties.values() for acc in (ps.get, ps.set) if acc is not None],
            constructor(pou),
        )
    return out


def dispatch(e):
    """The rewrite of one expression: for a method or block call, which implementation runs (a
    SUPER^ call runs the base's, not the most derived one)."""
    if isinstance(e, A.Call):
        match e.target:
            case MethodCall(obj=obj) as tgt:
                e.target = replace(tgt, nonvirtual=obj.base.ty.target if is_super(obj) else None)
            case FbCall(pou=pou) as tgt:
                e.target = replace(tgt, nonvirtual=pou if is_super(e.callee) else None)
    return e


def kinds_of(pou: T.POUType) -> set:
    """Lower-case names of what an instance is: its block, the blocks it extends and every
    interface they provide (for __QUERYINTERFACE and ?=)."""
    out: set[str] = set()
    todo: list[T.POUType | None] = [pou]
    while todo:
        x = todo.pop()
        if x is None or x.name.lower() in out:
            continue
        out.add(x.name.lower())
        todo.extend(x.interfaces)
        todo.append(x.base)
    return out
