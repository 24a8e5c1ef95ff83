"""A file that does not parse, read as far as it can be: while a statement is half typed, the
rest of the file still declares its POUs.

The parser reports every syntax error of a file but yields no tree for a file that needed any
repair (st/grammar/parser.py). For the language server that would drop every POU of the file
from the project while one statement is unfinished: the other files would show errors for names
the file declares, and completion in the POU being edited would know none of its variables. So
the declarations holding the errors are blanked (their lines kept, so every position stays) and
the rest is parsed again; the declarations cut out are taken from the file's last tree that had
them. The diagnostics are those of the whole text; the checker's inside what was cut out are
dropped (they would be about the old text).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from ..compiler import ast as A
from ..compiler.driver import parse_source
from ..diagnostics import Diagnostic, DiagnosticSink
from ..grammar.comments import strip_comments
from ..source import SourceFile

MAX_CUTS = 8  # regions blanked before giving up on a file

# A declaration that never nests in another (meeting one closes what is still open) and one that
# does (inside a function block, an interface, a configuration).
_OUTER = "PROGRAM FUNCTION_BLOCK FUNCTION CLASS INTERFACE TYPE CONFIGURATION TEST SETUP TEARDOWN NAMESPACE".split()
_INNER = "METHOD PROPERTY ACTION RESOURCE VAR_GLOBAL".split()
_WORDS = "|".join(sorted(_OUTER + _INNER, key=len, reverse=True))
_WORD = re.compile(rf"\b(END_)?({_WORDS}|VAR)\b", re.I)
_PROGRAM_CONFIG = re.compile(r"\s+\w+\s*(WITH\b|:)", re.I)  # `PROGRAM p WITH t : main;` in a RESOURCE


@dataclass
class Region:
    kind: str
    first: int  # 0-based lines, both included
    last: int


@dataclass
class Tolerant:
    """A unit made of what parses and what was cut out (from the last tree), and where the cuts are."""

    unit: A.Unit | None
    cut: list[tuple[int, int]] = field(default_factory=list)  # 0-based line ranges, both included
    kept_old: list[Any] = field(default_factory=list)  # declarations taken from the last tree

    def hides(self, d: Diagnostic) -> bool:
        """Is d the checker's, about lines that were cut out?"""
        line = d.span.line - 1
        return any(a <= line <= b for a, b in self.cut)


def regions(text: str) -> list[Region]:
    """The declarations of a text (comments already blanked) as line ranges, nested ones too; one
    without its END_ ends where the next outer declaration starts (or at the end)."""
    out: list[Region] = []
    open_: list[Region] = []
    n_lines = text.count("\n") + 1
    line_starts = [0]
    line_starts += [m.end() for m in re.finditer("\n", text)]

    def line_of(pos: int) -> int:
        lo, hi = 0, len(line_starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if line_starts[mid] <= pos:
                lo = mid
            else:
                hi = mid - 1
        return lo

    for m in _WORD.finditer(text):
        end, word = bool(m.group(1)), m.group(2).upper()
        if word == "PROGRAM" and not end and _PROGRAM_CONFIG.match(text, m.end()):
            continue
        line = line_of(m.start(2))
        if end:
            want = "VAR_GLOBAL" if word == "VAR" else word
            if any(r.kind == want for r in open_):
                while open_:
                    r = open_.pop()
                    r.last = line
                    if r.kind == want:
                        break
            continue
        if word == "VAR":
            continue
        if word in _OUTER:
            while open_:  # an outer declaration before the last one's END_: that one ends here
                open_.pop().last = line - 1
        r = Region(word, line, n_lines - 1)
        open_.append(r)
        out.append(r)
    return out


def innermost(rs: list[Region], line: int) -> Region | None:
    best = None
    for r in rs:
        if r.first <= line <= r.last and (best is None or r.first >= best.first):
            best = r
    return best


def _key(item: Any) -> tuple | None:
    """What names a top-level declaration across two versions of a file (None: nothing does)."""
    if isinstance(item, A.TypeBlock):
        return ("TYPE", *sorted(getattr(t, "name", "").lower() for t in item.types))
    name = getattr(item, "name", None)
    if isinstance(name, str) and name:
        return (type(item).__name__, getattr(item, "kind", ""), name.lower())
    return None


def parse_tolerant(
    src: SourceFile,
    errors: list[Diagnostic],
    last: A.Unit | None,
    nested: bool | None,
    vendor_names: bool,
) -> Tolerant:
    """src did not parse (its syntax errors: `errors`). Blank the innermost declaration around each
    error, parse again (at most MAX_CUTS times) and add the declarations of `last` (the file's last
    tree) that the cut text no longer has."""
    stripped = strip_comments(src.text, nested)[0]
    rs = regions(stripped)
    lines = src.text.split("\n")
    cut: list[tuple[int, int]] = []
    todo = [d.span.line - 1 for d in errors]
    unit = None
    for _ in range(MAX_CUTS):
        fresh = [line for line in todo if not any(a <= line <= b for a, b in cut)]
        if not fresh:
            return Tolerant(None)
        r = innermost(rs, fresh[0])
        if r is None:
            return Tolerant(None)
        cut.append((r.first, r.last))
        for i in range(r.first, min(r.last, len(lines) - 1) + 1):
            lines[i] = " " * len(lines[i])
        sink = DiagnosticSink()
        unit = parse_source(SourceFile(src.path, "\n".join(lines)), sink, nested, vendor_names)
        if unit is not None:
            break
        todo = [d.span.line - 1 for d in sink.items if d.code.startswith("E00")]
    if unit is None:
        return Tolerant(None)
    kept: list[Any] = []
    if last is not None:
        have = {_key(x) for x in unit.items}
        for x in last.items:
            k = _key(x)
            if k is None:
                line = x.span.line - 1 if getattr(x, "span", None) is not None else -1
                if any(a <= line <= b for a, b in cut):
                    kept.append(x)
            elif k not in have:
                kept.append(x)
        unit.items.extend(kept)
    return Tolerant(unit, cut, kept)
