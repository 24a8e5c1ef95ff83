"""What each stage of the pipeline hands the next (driver.py runs them in this order).

    sources ─parse─► Parsed ─check─► Checked ─lower─► LoweredProgram (lower/) ─generate─► Generated
            ─(native)─► NativeBuild ─artefact─► CompiledProgram (st.model.compiled)

Each result is a small frozen record of what its stage made, so a stage says by its signature
what it needs. A stage may consume what it is given: the lowering rewrites the checked bodies in
place (a checked project is built for one compilation), so a `Checked` is lowered once.
"""

from __future__ import annotations

import ast as py
from dataclasses import dataclass, field
from types import CodeType
from typing import TYPE_CHECKING

from ..model.compiled import NativeModule
from ..model.program import Project
from .library import Library

if TYPE_CHECKING:
    from . import ast as A


@dataclass(frozen=True, slots=True)
class Parsed:
    """The syntax of the libraries in use (first) and of the user's files, as parsed."""

    units: list[A.Unit]
    library_paths: frozenset[str]  # the files that belong to a library (its own rules apply)
    libraries: list[Library]  # the libraries in use (some step aside for the project's own types)


@dataclass(frozen=True, slots=True)
class Checked:
    """The checked project: every name resolved, every expression typed (`Expr.ty`), the model of
    POUs, types, globals, configurations and tests, still holding its syntax (st.model.syntax)."""

    project: Project
    libraries: list[Library]


@dataclass(frozen=True, slots=True)
class Generated:
    """The compiled code: one code object per ST file and per file of TEST blocks, the Python
    modules they came from (for the native tier and `--emit python`) and the coverage probes."""

    modules: list[tuple[str, CodeType]]
    test_modules: list[tuple[str, CodeType]]
    python_modules: list[tuple[str, py.Module]]
    python_text: dict[str, str] = field(default_factory=dict)  # file → source, with --emit python
    coverage_points: list[tuple[object, ...]] | None = None  # with --coverage


@dataclass(frozen=True, slots=True)
class NativeBuild:
    """The native tier's modules and, per body left as Python, why (empty without --native)."""

    modules: list[NativeModule] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
