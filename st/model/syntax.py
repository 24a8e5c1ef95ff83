"""The compiler's syntax as the model sees it: an opaque node.

While a program compiles, the model holds pieces of the compiler's syntax tree (a POU's
declaration, an initial value's expression, an ACTION's body, a transition's condition) that code
generation reads; the compiled artefact holds the AST-free values of st.model.summaries in their
place, or None. Every node of st.compiler.ast derives from `Syntax`, so a model field says what it
holds (`Syntax | InitialValue | None`) without the model importing the compiler, and the compiler
narrows a field to its own node class where it reads one (st.compiler.syntax_of).
"""

from __future__ import annotations


class Syntax:
    """The base of every node of the compiler's syntax tree (st.compiler.ast)."""

    __slots__ = ()
