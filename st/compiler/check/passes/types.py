"""Types: every named TYPE resolved, then every POU's interface (variables, methods, properties,
base and interfaces). Resolution is on demand (`Declarations`), so this pass only makes sure that
everything is resolved once, whether or not something else used it first."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..semantics import Semantics


def resolve_types(sem: Semantics) -> None:
    ctx = sem.ctx
    for key, (decl, _lib) in list(ctx.pending_types.items()):
        sem.decls.resolve_named_type(key, decl.span)
    for pou in list(ctx.project.pous.values()):
        sem.decls.resolve_interface(pou)
