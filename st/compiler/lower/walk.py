"""Where the statements are: every body code generation prints, and walking nested statements."""
from __future__ import annotations

from typing import Iterator

from .. import ast as A
from ..model import Project


def bodies(project: Project) -> Iterator[list]:
    """Every statement list of a checked project: POU bodies, actions, methods, property
    accessors (a block's inherited ones are the base's own lists, so a list may come twice)
    and the unit tests' SETUP, TEST and TEARDOWN statements."""
    for pou in project.pous.values():
        if pou.decl is None:
            continue
        yield getattr(pou.decl, "body", None) or []
        for act in pou.actions.values():
            if act is not None:
                yield act.body
        for mt in pou.methods.values():
            if mt.decl is not None:
                yield mt.decl.body
        for ps in pou.properties.values():
            for acc in (ps.get, ps.set):
                if acc is not None and acc.decl is not None:
                    yield acc.decl.body
    for test in project.tests:
        yield test.setup
        yield test.body
        yield test.teardown


def inner_bodies(s) -> Iterator[list]:
    """The statement lists directly inside one statement."""
    if isinstance(s, A.If):
        for _, b in s.branches:
            yield b
        if s.orelse:
            yield s.orelse
    elif isinstance(s, A.Case):
        for b in s.branches:
            yield b.body
        if s.orelse:
            yield s.orelse
    elif isinstance(s, (A.For, A.CountedFor, A.While, A.Repeat)):
        yield s.body


def walk_stmts(body: list) -> Iterator:
    """Every statement of `body`, nested ones included, in source order."""
    for s in body:
        yield s
        for inner in inner_bodies(s):
            yield from walk_stmts(inner)
