"""Remove comments and pragmas before lexing.

ST comments nest in CODESYS and TwinCAT (``(* (* *) *)``), which a regular lexer
cannot follow; in MatIEC (OpenPLC) they do not: ``(* a (* b *)`` is one comment.
OpenPLC's ``(*DBG:...*)`` lines can be megabytes long. This pass blanks every
comment, pragma and embedded C block (``{{ ... }}``, OpenPLC's) with spaces
(keeping newlines), so line and column numbers of everything that remains are
unchanged, and records the pragmas and C blocks it removed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_TOKENS = re.compile(r"\(\*|\*\)|/\*|//|'|\"|\{")
_BLANK = re.compile(r"[^\n]")
_NAME = re.compile(r"\{\s*([A-Za-z_][A-Za-z0-9_]*)")
_ATTRIBUTE = re.compile(r"\{\s*attribute\s+'([^']*)'", re.I)


@dataclass(frozen=True, slots=True)
class Pragma:
    offset: int
    text: str

    @property
    def name(self) -> str:
        """The pragma's first word, lower-case: 'dialect' for `{ dialect 'iec' }`, '' for none."""
        m = _NAME.match(self.text)
        return m.group(1).lower() if m else ""

    @property
    def attribute(self) -> str:
        """The attribute's name, lower-case: 'symbol' for `{attribute 'symbol' := 'read'}`, else ''."""
        m = _ATTRIBUTE.match(self.text)
        return m.group(1).lower() if m else ""

    @property
    def embedded_code(self) -> bool:
        """An embedded C block `{{ ... }}` (OpenPLC): code for MatIEC's C output, not a pragma."""
        return self.text.startswith("{{")


@dataclass(frozen=True, slots=True)
class CommentError:
    offset: int
    message: str


def _blank(text: str) -> str:
    return _BLANK.sub(" ", text)


def strip_comments(text: str, nested: bool | None = True) -> tuple[str, list[Pragma], list[CommentError]]:
    """Return (text with comments blanked, pragmas, errors). `nested`: do `(* *)` comments nest
    (CODESYS, TwinCAT) or end at the first `*)` (MatIEC); None: nest, unless that leaves a comment
    unclosed and reading them MatIEC's way leaves none (a file written for OpenPLC)."""
    if nested is None:
        found = _strip(text, True)
        if found[2] and any("unterminated comment '(*'" in e.message for e in found[2]):
            flat = _strip(text, False)
            if not flat[2]:
                return flat
        return found
    return _strip(text, nested)


def _strip(text: str, nested: bool) -> tuple[str, list[Pragma], list[CommentError]]:
    if "(*" not in text and "//" not in text and "/*" not in text and "{" not in text:
        return text, [], []
    out: list[str] = []
    pragmas: list[Pragma] = []
    errors: list[CommentError] = []
    pos = 0
    n = len(text)
    search = _TOKENS.search
    while True:
        m = search(text, pos)
        if m is None:
            out.append(text[pos:])
            break
        tok = m.group()
        start = m.start()
        if tok == "'" or tok == '"':
            # skip a string literal ($ escapes the next character)
            i = start + 1
            while i < n:
                c = text[i]
                if c == "$":
                    i += 2
                    continue
                if c == tok or c == "\n":
                    break
                i += 1
            end = min(i + 1, n)
            out.append(text[pos:end])
            pos = end
            continue
        out.append(text[pos:start])
        if tok == "//":
            nl = text.find("\n", start)
            end = n if nl < 0 else nl
        elif tok == "/*":
            close = text.find("*/", start + 2)
            if close < 0:
                errors.append(CommentError(start, "unterminated comment '/*'"))
                end = n
            else:
                end = close + 2
        elif tok == "(*" and not nested:
            close = text.find("*)", start + 2)
            if close < 0:
                errors.append(CommentError(start, "unterminated comment '(*'"))
                end = n
            else:
                end = close + 2
        elif tok == "(*":
            depth = 1
            i = start + 2
            while depth:
                opening = text.find("(*", i)
                closing = text.find("*)", i)
                if closing < 0:
                    break
                if 0 <= opening < closing:
                    depth += 1
                    i = opening + 2
                else:
                    depth -= 1
                    i = closing + 2
            if depth:
                errors.append(
                    CommentError(
                        start, "unterminated comment '(*' (comments nest: every '(*' inside it needs its own '*)')"
                    )
                )
                end = n
            else:
                end = i
        elif tok == "{" and text.startswith("{{", start):
            close = text.find("}}", start + 2)
            if close < 0:
                errors.append(CommentError(start, "unterminated embedded code block '{{' (it ends with '}}')"))
                end = n
            else:
                end = close + 2
                pragmas.append(Pragma(start, text[start:end]))
        elif tok == "{":
            close = text.find("}", start + 1)
            if close < 0:
                errors.append(CommentError(start, "unterminated pragma '{'"))
                end = n
            else:
                end = close + 1
                pragmas.append(Pragma(start, text[start:end]))
        else:  # a stray '*)'
            errors.append(
                CommentError(
                    start,
                    "'*)' without a matching '(*'"
                    + ("" if nested else " (comments do not nest here: an inner '*)' ends the whole comment)"),
                )
            )
            end = start + 2
        out.append(_blank(text[start:end]))
        pos = end
    return "".join(out), pragmas, errors
