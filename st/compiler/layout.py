"""ST text laid out at the lines and columns of another file (an XML project), so that every
diagnostic of the ST names that file at the place the code came from.

A `Layout` starts as the file's lines, all blank; code and generated keywords are placed at
(line, column). Pieces on one line are written in column order; a piece that would overlap the
one before it (or touch it, unless both are code taken from the file) is pushed right, one space
after it. Used by twincat.py and plcopen_xml.py.
"""

from __future__ import annotations


class Layout:
    """The output: as many lines as `source`, blank, with pieces placed at lines and columns."""

    def __init__(self, source: str):
        self.starts = [0]
        for i, c in enumerate(source):
            if c == "\n":
                self.starts.append(i + 1)
        self.pieces: list[list[tuple[int, str, bool]]] = [[] for _ in self.starts]  # (column, text, code?)

    def where(self, offset: int) -> tuple[int, int]:
        """The 0-based (line, column) of an offset of the source."""
        lo, hi = 0, len(self.starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if self.starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo, offset - self.starts[lo]

    def place(self, line: int, col: int, text: str, code: bool = False) -> None:
        """`text` at the 0-based `line` and `col`; its further lines (if any) start at column 0
        of the lines below. Blank parts are left out (they would only push others right). `code`:
        text of the file itself, which may touch the code before it (a CDATA split in pieces)."""
        for k, part in enumerate(text.split("\n")):
            if part.strip() and 0 <= line + k < len(self.pieces):
                self.pieces[line + k].append((col if k == 0 else 0, part, code))

    def code(self, offset: int, text: str) -> None:
        """Text starting at `offset` of the source, kept at its lines and columns."""
        self.place(*self.where(offset), text, code=True)

    def keyword(self, offset: int, text: str) -> None:
        line, col = self.where(offset)
        self.pieces[line].append((col, text, False))

    def text(self) -> str:
        lines = []
        for pieces in self.pieces:
            out = ""
            after_code = False
            for col, part, code in sorted(pieces, key=lambda p: p[0]):
                gap = 0 if not out or (code and after_code) else 1
                if col < len(out) + gap:
                    col = len(out) + gap  # a piece pushed right of what precedes it
                out += " " * (col - len(out)) + part
                after_code = code
            lines.append(out)
        return "\n".join(lines)
