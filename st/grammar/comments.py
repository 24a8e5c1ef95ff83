"""Remove comments and pragmas before lexing.

ST comments nest (``(* (* *) *)``), which a regular lexer cannot follow, and
OpenPLC's ``(*DBG:...*)`` lines can be megabytes long. This pass blanks every
comment and pragma with spaces (keeping newlines), so line and column numbers
of everything that remains are unchanged, and records the pragmas it removed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_TOKENS = re.compile(r"\(\*|\*\)|/\*|//|'|\"|\{")
_BLANK = re.compile(r"[^\n]")
_NAME = re.compile(r"\{\s*([A-Za-z_][A-Za-z0-9_]*)")


@dataclass(frozen=True, slots=True)
class Pragma:
    offset: int
    text: str

    @property
    def name(self) -> str:
        """The pragma's first word, lower-case: 'dialect' for `{ dialect 'iec' }`, '' for none."""
        m = _NAME.match(self.text)
        return m.group(1).lower() if m else ""


@dataclass(frozen=True, slots=True)
class CommentError:
    offset: int
    message: str


def _blank(text: str) -> str:
    return _BLANK.sub(" ", text)


def strip_comments(text: str) -> tuple[str, list[Pragma], list[CommentError]]:
    """Return (text with comments blanked, pragmas, errors)."""
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
        elif tok == "{":
            close = text.find("}", start + 1)
            if close < 0:
                errors.append(CommentError(start, "unterminated pragma '{'"))
                end = n
            else:
                end = close + 1
                pragmas.append(Pragma(start, text[start:end]))
        else:  # a stray '*)'
            errors.append(CommentError(start, "'*)' without a matching '(*'"))
            end = start + 2
        out.append(_blank(text[start:end]))
        pos = end
    return "".join(out), pragmas, errors
