"""Generated Python as text (`st compile --emit python`): each statement marked with its ST line.

Every generated statement carries the line of the ST statement it came from (`lineno`); the
text shows it as a trailing comment, `x = 1  # st:12`. Built on the standard library's
unparser (Python 3.11's `ast._Unparser`): a statement's first output line gets its mark,
continuation lines (`else:`, `finally:`) none, an `elif` the line of its condition.
"""

from __future__ import annotations

import ast as py


def python_text(module: py.Module) -> str:
    """The module as Python source, each statement's first line ending in `# st:<line>`."""
    return _MarkedUnparser().visit(module)


class _MarkedUnparser(py._Unparser):  # type: ignore[name-defined]  # private, so not in the stdlib's stubs
    def __init__(self):
        super().__init__()
        self._mark = None  # the line of the statement about to start an output line
        self._open = None  # the line of the output line being written
        self._elifs: list = []  # per If being printed: the lines of its elif arms

    def visit(self, node) -> str:
        text = super().visit(node)
        if self._open is not None:
            text += f"  # st:{self._open}"
        return text

    def traverse(self, node):
        if isinstance(node, py.stmt):
            self._mark = getattr(node, "lineno", None)
        super().traverse(node)

    def maybe_newline(self):
        if self._open is not None:
            self.write(f"  # st:{self._open}")
            self._open = None
        super().maybe_newline()

    def fill(self, text=""):
        super().fill(text)
        if text == "elif " and self._elifs and self._elifs[-1]:
            self._mark = self._elifs[-1].pop(0)
        self._open, self._mark = self._mark, None

    def visit_If(self, node):
        lines, n = [], node
        while n.orelse and len(n.orelse) == 1 and isinstance(n.orelse[0], py.If):
            n = n.orelse[0]
            lines.append(getattr(n, "lineno", None))
        self._elifs.append(lines)
        try:
            super().visit_If(node)
        finally:
            self._elifs.pop()
