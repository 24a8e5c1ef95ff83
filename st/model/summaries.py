"""What the compiled model keeps of things the compiler holds as syntax.

The checker fills the model with its AST (a POU's declaration, initial-value expressions, an
ACTION's body); code generation needs them, the compiled artefact does not. The artefact holds
these small values in their place, so it carries no AST node and loads without the compiler.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..source import Span


@dataclass(frozen=True)
class PouInfo:
    """A POU, METHOD or ACTION declaration: where it is and what it is (`POUType.decl`, `.actions`).
    `kind`: FUNCTION, FUNCTION_BLOCK, PROGRAM, INTERFACE, ACTION, ... as the source said."""

    span: Span
    kind: str
    name: str


@dataclass(frozen=True)
class InitialValue:
    """A literal initial value (`x : TIME := T#2s`) as the Python value the runtime stores (2e9 ns).
    Initial values that are expressions are code, not data: the artefact has None for them."""

    value: Any


@dataclass(frozen=True)
class LibraryInfo:
    """A library a program was compiled with: its name, version and ST sources [(path, text)]."""

    name: str
    version: str
    sources: tuple[tuple[str, str], ...] = ()
