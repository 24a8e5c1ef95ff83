"""The compiler's view of the syntax the model holds while a program compiles.

st.model types its syntax fields as the opaque `Syntax` (it does not import the compiler); these
accessors narrow them to the AST classes the checker put there, so the rest of the compiler reads
typed nodes. A field that holds something else (an artefact's summary, or nothing: a native
library POU) is a compiler bug, reported as one (E099).
"""

from __future__ import annotations

from ..model import types as T
from ..model.program import Project, TestModel
from . import ast as A

# what a POUType's `decl` holds while compiling: a POU, a METHOD (or a property's accessor) or an
# INTERFACE
Declaration = A.POU | A.Method | A.Interface


def decl_of(pou: T.POUType) -> Declaration:
    """The declaration `pou` was made from."""
    d = pou.decl
    if not isinstance(d, (A.POU, A.Method, A.Interface)):
        raise TypeError(f"{pou.name} has no declaration while compiling (it holds {type(d).__name__})")
    return d


def block_decl(pou: T.POUType) -> A.POU:
    """The declaration of a FUNCTION, FUNCTION_BLOCK or PROGRAM (not a METHOD or INTERFACE)."""
    d = pou.decl
    if not isinstance(d, A.POU):
        raise TypeError(f"{pou.name} is not declared as a POU while compiling (it holds {type(d).__name__})")
    return d


def action_of(pou: T.POUType, key: str) -> A.ActionDecl:
    """The ACTION `key` (lower case) of `pou`."""
    a = pou.actions[key]
    if not isinstance(a, A.ActionDecl):
        raise TypeError(f"action {key} of {pou.name} has no declaration while compiling")
    return a


def declared(pou: T.POUType) -> Declaration | None:
    """The declaration `pou` was made from, or None for a block implemented in Python."""
    return None if pou.decl is None else decl_of(pou)


def interface_decl(pou: T.POUType) -> A.Interface:
    """The declaration of an INTERFACE."""
    d = pou.decl
    if not isinstance(d, A.Interface):
        raise TypeError(f"{pou.name} is not declared as an INTERFACE while compiling (it holds {type(d).__name__})")
    return d


def test_blocks(project: Project) -> list[A.TestBlock]:
    """The TEST, SETUP and TEARDOWN blocks as parsed."""
    out = [tb for tb in project.test_blocks if isinstance(tb, A.TestBlock)]
    if len(out) != len(project.test_blocks):
        raise TypeError("a test block holds no syntax while compiling")
    return out


def test_pou(test: TestModel) -> T.POUType:
    """The pseudo-POU holding a TEST block's variables (with its SETUP's)."""
    if test.pou is None:
        raise TypeError(f"TEST {test.name!r} has no variables while compiling")
    return test.pou
