"""Source files and spans: where every token, node and diagnostic comes from."""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class Span:
    """A position in a source file: 1-based line and column."""

    file: str
    line: int
    col: int
    end_line: int = 0
    end_col: int = 0

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


NO_SPAN = Span("<builtin>", 0, 0)


@dataclass(slots=True)
class SourceFile:
    """The text of one file, with fast offset → line/column mapping."""

    path: str
    text: str
    _line_starts: list[int] = field(default_factory=list, repr=False)
    # diagnostics found while reading the file (a PLCopen XML body in FBD, malformed XML), reported
    # with the compile's (st.diagnostics.Diagnostic objects; this module cannot name the class)
    load_diagnostics: list = field(default_factory=list, repr=False)

    def _starts(self) -> list[int]:
        if not self._line_starts:
            starts = [0]
            find = self.text.find
            i = find("\n")
            while i >= 0:
                starts.append(i + 1)
                i = find("\n", i + 1)
            self._line_starts = starts
        return self._line_starts

    def position(self, offset: int) -> tuple[int, int]:
        starts = self._starts()
        line = bisect.bisect_right(starts, offset)
        return line, offset - starts[line - 1] + 1

    def span_at(self, offset: int) -> Span:
        line, col = self.position(offset)
        return Span(self.path, line, col)

    def offset(self, line: int, col: int) -> int:
        starts = self._starts()
        return starts[min(max(line, 1), len(starts)) - 1] + col - 1

    def text_of(self, span: Span) -> str:
        """The source text a span covers (one line's rest when the span has no end)."""
        if not span.end_line:
            return self.line_text(span.line)[span.col - 1 :].strip()
        return self.text[self.offset(span.line, span.col) : self.offset(span.end_line, span.end_col)]

    def line_text(self, line: int) -> str:
        starts = self._starts()
        if line < 1 or line > len(starts):
            return ""
        start = starts[line - 1]
        end = self.text.find("\n", start)
        return self.text[start:] if end < 0 else self.text[start:end]


_COMMENT = re.compile(r"\(\*(.*?)\*\)|//(.*)$|/\*(.*?)\*/")


def comment_beside(lines: list[str], line: int, col: int) -> str:
    """The comment written after a declaration on its line (after its `;`), else a comment alone
    on the line above: what a declaration says about itself ("" when nothing). 1-based line, col."""
    if not 0 < line <= len(lines):
        return ""
    text = lines[line - 1]
    semi = text.find(";", max(col - 1, 0))
    if semi >= 0:
        m = _COMMENT.search(text, semi)
        if m:
            return " ".join(next(g for g in m.groups() if g is not None).split())
    if line >= 2:
        m = _COMMENT.fullmatch(lines[line - 2].strip())
        if m:
            return " ".join(next(g for g in m.groups() if g is not None).split())
    return ""
