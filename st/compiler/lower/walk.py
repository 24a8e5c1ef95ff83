"""Where the statements are: every body code generation prints, and walking nested statements."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import fields as dataclass_fields
from dataclasses import replace
from typing import TypeGuard

from ...model import types as T
from ...model.program import Project
from .. import ast as A
from ..check import CallTarget
from ..syntax import action_of, decl_of

# fields of a call target that are declarations (a POU, a type, a signature), never rewritten
_TARGET_DECLS = frozenset(("pou", "nonvirtual", "block", "sig", "type", "itf", "info", "arg_types", "value"))


def bodies(project: Project) -> Iterator[tuple[list, T.POUType | None]]:
    """(statements, block) for every statement list of a checked project: POU bodies, actions,
    methods, property accessors (a block's inherited ones are the base's own lists, so a list may
    come twice) and the unit tests' SETUP, TEST and TEARDOWN statements. `block`: the function
    block or program whose instance the statements run on (None for a FUNCTION and a test)."""
    for pou in project.pous.values():
        if pou.decl is None:
            continue
        block = pou if pou.pou_kind in ("FUNCTION_BLOCK", "PROGRAM") else None
        yield getattr(pou.decl, "body", None) or [], block
        for key in pou.actions:
            yield action_of(pou, key).body, block
        for mt in pou.methods.values():
            if mt.decl is not None:
                yield decl_of(mt).body, mt.owner_fb or block
        for ps in pou.properties.values():
            for acc in (ps.get, ps.set):
                if acc is not None and acc.decl is not None:
                    yield decl_of(acc).body, ps.owner or block
    for test in project.tests:
        yield test.setup, None
        yield test.body, None
        yield test.teardown, None


def inner_bodies(s) -> Iterator[list]:
    """The statement lists directly inside one statement."""
    if isinstance(s, A.If):
        for _, b in s.branches:
            yield b
        if s.orelse:
            yield s.orelse
    elif isinstance(s, A.Case):
        for br in s.branches:
            yield br.body
        if s.orelse:
            yield s.orelse
    elif isinstance(s, (A.For, A.CountedFor, A.While, A.Repeat)):
        yield s.body
    elif isinstance(s, A.Try):
        yield s.body
        if s.handler is not None:
            yield s.handler
        if s.final is not None:
            yield s.final


def walk_stmts(body: list) -> Iterator:
    """Every statement of `body`, nested ones included, in source order."""
    for s in body:
        yield s
        for inner in inner_bodies(s):
            yield from walk_stmts(inner)


def rewrite_outside_bodies(project: Project, fn: Callable) -> None:
    """`rewrite_exprs` for the expressions that are not in a statement: SFC transition
    conditions and action durations, a configuration's program arguments."""

    def one(e):
        if e is None:
            return None
        holder = [e]
        rewrite_exprs(holder, fn)
        return holder[0]

    for sfc in project.sfc.values():
        for t in sfc.transitions:
            t.cond = one(t.cond)
        for st in sfc.steps:
            st.actions = [(act, q, one(texpr)) for act, q, texpr in st.actions]
    for cfg in project.configs:
        for im in cfg.instances:
            im.args = [(p, one(value), is_out) for p, value, is_out in im.args]


def is_super(e: object) -> TypeGuard[A.Deref]:
    """SUPER^ (the instance as its base block)."""
    return isinstance(e, A.Deref) and isinstance(e.base, A.Name) and getattr(e.base.sym, "kind", "") == "super"


def rewrite_exprs(body: list, fn: Callable) -> None:
    """Replace in place every expression of `body` by `fn(expression)`, innermost first: in
    nested statements, call arguments and what a call resolved to (`Call.target`), so that
    every place code generation reads an expression from sees the rewritten one."""
    memo: dict = {}

    def expr(e):
        if id(e) in memo:
            return memo[id(e)]
        memo[id(e)] = e  # the same node reached again while rewriting its parts
        fields(e)
        out = memo[id(e)] = fn(e)
        return out

    def value(v):
        if isinstance(v, A.Expr):
            return expr(v)
        if isinstance(v, list):
            v[:] = [value(x) for x in v]
        elif isinstance(v, tuple):
            return tuple(value(x) for x in v)
        elif isinstance(v, dict):
            for k in v:
                v[k] = value(v[k])
        elif isinstance(v, (A.Stmt, A.Arg, A.CaseBranch, A.CtorInit, A.StructInit, A.ArrayInit, A.RepeatInit)):
            fields(v)  # (initializers: FB_init arguments of __NEW, initial values that name variables)
        elif isinstance(v, CallTarget):  # frozen: a target whose expressions changed is made anew
            changed = {}
            for f in dataclass_fields(v):
                if f.name in _TARGET_DECLS:
                    continue
                x = getattr(v, f.name)
                y = value(x)
                if y is not x:
                    changed[f.name] = y
            return replace(v, **changed) if changed else v
        return v

    def fields(node):
        for name in node.__dataclass_fields__:
            if name in ("ty", "const", "sym", "span", "name_span", "pou"):
                continue
            setattr(node, name, value(getattr(node, name)))

    value(body)
