"""The compiled artefact: the checked program as an AST-free value, built as a copy.

The checker's model holds syntax that code generation reads (a POU's declaration, initial-value
expressions, ACTION bodies, SFC conditions, configuration connections, TEST bodies). The
artefact that a compile returns, that the cache stores and that the runtime receives is the
same model through `CompiledProgram.to_bytes`, with that syntax replaced (`ast_free_state`) by
the small values of st.model.summaries. The compiler's own objects are never changed, and a
cached and an uncached compile give the same value.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

from ..model import types as T
from ..model.compiled import CompiledProgram
from ..model.program import ConfigModel, InstanceModel, Project, StepModel, TestModel, TransitionModel
from ..model.summaries import InitialValue, LibraryInfo, PouInfo
from . import ast as A


def artefact(draft: CompiledProgram) -> CompiledProgram:
    """The AST-free copy of a compile's result: what loading its bytes gives, as a cache hit does
    (coverage probes are the build's own and are kept)."""
    copy = CompiledProgram.from_bytes(draft.to_bytes(ast_free_state), sources=draft.sources, helpers=draft.helpers)
    return replace(copy, coverage_points=draft.coverage_points, coverage_hits=draft.coverage_hits)


def libraries_only(libraries: list[Any]) -> Project:
    """The model of a program that does not check: the libraries it was compiled with, nothing else."""
    return Project(libraries=[_library(lib) for lib in libraries])


def ast_free_state(obj: Any) -> dict | None:
    """The state `obj` has in the artefact, or None when it has no syntax to drop."""
    rule = _RULES.get(type(obj))
    if rule is None:
        return None
    state = dict(obj.__dict__)
    rule(state)
    return state


def initial_value(init: Any) -> InitialValue | None:
    """A literal initial value as data; an expression (code) as None."""
    if isinstance(init, A.Literal):
        return InitialValue(init.value)
    return init if isinstance(init, InitialValue) else None


def _declaration(decl: Any) -> PouInfo | None:
    if decl is None or isinstance(decl, PouInfo):
        return decl
    return PouInfo(decl.span, getattr(decl, "kind", type(decl).__name__.upper()), decl.name)


def _action(decl: Any) -> PouInfo | None:
    if decl is None or isinstance(decl, PouInfo):
        return decl
    return PouInfo(decl.span, "ACTION", decl.name)


def _library(lib: Any) -> LibraryInfo:
    if isinstance(lib, LibraryInfo):
        return lib
    return LibraryInfo(lib.name, lib.version, tuple((p, t) for p, t in lib.sources))


def _pou(s: dict) -> None:
    s["decl"] = _declaration(s["decl"])
    s["actions"] = {k: _action(a) for k, a in s["actions"].items()}


def _init(s: dict) -> None:
    s["init"] = initial_value(s["init"])


def _project(s: dict) -> None:
    s["test_blocks"] = []
    s["libraries"] = [_library(lib) for lib in s["libraries"]]


def _config(s: dict) -> None:
    # the declared type is syntax (a type spec); the variable's own type is found from its path
    s["var_config"] = [(path, loc, initial_value(init), None, span) for path, loc, init, _, span in s["var_config"]]


def _instance(s: dict) -> None:
    s["args"] = [(param, None, is_output) for param, _, is_output in s["args"]]


def _step(s: dict) -> None:
    s["actions"] = [(name, qualifier, None) for name, qualifier, _ in s["actions"]]


def _transition(s: dict) -> None:
    s["cond"] = None


def _test(s: dict) -> None:
    s.update(pou=None, setup=[], body=[], teardown=[])


_RULES: dict[type, Callable[[dict], None]] = {
    T.POUType: _pou,
    T.VarSym: _init,
    T.Member: _init,
    T.AliasType: _init,
    Project: _project,
    ConfigModel: _config,
    InstanceModel: _instance,
    StepModel: _step,
    TransitionModel: _transition,
    TestModel: _test,
}
