"""TEST blocks: each TEST is checked as a pseudo-POU of kind TEST whose variables are its file's
SETUP variables, its own and TEARDOWN's; its statements may use the test statements."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ....diagnostics import Code
from ....model import types as T
from ....model.program import TestModel
from ... import ast as A
from ...syntax import test_blocks
from ..common import Scope
from ..context import CheckContext

if TYPE_CHECKING:
    from ..semantics import Semantics


def check_tests(sem: Semantics) -> None:
    ctx = sem.ctx
    by_file: dict = {}
    for tb in test_blocks(ctx.project):
        by_file.setdefault(tb.span.file, []).append(tb)
    for _path, blocks in by_file.items():
        setup = _single_block(ctx, blocks, "SETUP")
        teardown = _single_block(ctx, blocks, "TEARDOWN")
        seen: dict = {}
        for tb in blocks:
            if tb.kind != "TEST":
                continue
            if tb.name in seen:
                ctx.err(
                    Code.DECLARED_TWICE,
                    tb.span,
                    f"a TEST named '{tb.name}' already exists in this file (line {seen[tb.name].line})",
                )
                continue
            seen[tb.name] = tb.span
            _check_test(sem, tb, setup, teardown)


def _single_block(ctx: CheckContext, blocks: list[A.TestBlock], kind: str) -> A.TestBlock | None:
    found = [b for b in blocks if b.kind == kind]
    for extra in found[1:]:
        ctx.err(
            Code.DECLARED_TWICE,
            extra.span,
            f"a file may have one {kind} block (the first is at line {found[0].span.line})",
        )
    return found[0] if found else None


def _check_test(sem: Semantics, tb: A.TestBlock, setup, teardown) -> None:
    ctx = sem.ctx
    index = len(ctx.project.tests)
    pou = T.POUType(f"TEST '{tb.name}'", "TEST", decl=None)
    pou.pyname = f"_test_{index}"
    scope = Scope(pou, pou.vars)
    scope.test = True
    for block in (setup.var_blocks if setup else []) + tb.var_blocks + (teardown.var_blocks if teardown else []):
        sem.decls.declare_block(block, pou.vars, scope, pou)
    parts = []
    for block in (setup, tb, teardown):
        body = block.body if block is not None else []
        sem.stmts.stmt_list(body, scope)
        parts.append(body)
    ctx.project.tests.append(TestModel(tb.name, tb.span, pou.pyname, pou, parts[0], parts[1], parts[2]))
