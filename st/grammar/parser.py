"""The Lark LALR parser for ST, and syntax errors turned into diagnostics.

`StParser(callbacks)` parses one file at a time with the given Lark
Transformer running inside the parser (no intermediate tree). Syntax errors
become `Diagnostic`s with a location and, for the usual slips, a hint; a
missing ';' is repaired so that the rest of the file is still checked.
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
from pathlib import Path

from lark import Lark, Token
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from ..diagnostics import Diagnostic, Severity
from ..source import SourceFile, Span
from .comments import strip_comments

GRAMMAR_PATH = Path(__file__).with_name("st.lark")

_PRETTY = {
    "IDENT": "an identifier",
    "INTEGER": "an integer",
    "REAL_LIT": "a real number",
    "STRING_LIT": "a string",
    "WSTRING_LIT": "a wide string",
    "TIME_LIT": "a time literal",
    "DIRECT_VAR": "a located address",
    "TYPED_PREFIX": "a typed literal",
    "VAR_KIND": "VAR",
    "BASED_INT": "an integer",
    "$END": "end of file",
    "STRING_KW": "STRING",
}
_EXPR_START = {"IDENT", "INTEGER", "REAL_LIT", "LPAR", "MINUS", "NOT", "TRUE", "FALSE", "STRING_LIT"}


def _cache_dir() -> Path:
    base = os.environ.get("ST_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "st"
    )
    try:
        Path(base).mkdir(parents=True, exist_ok=True)
        return Path(base)
    except OSError:
        return Path(tempfile.gettempdir())


class StParser:
    def __init__(self, callbacks):
        text = GRAMMAR_PATH.read_text()
        digest = hashlib.sha256(text.encode()).hexdigest()[:16]
        cache = _cache_dir() / f"grammar-{digest}.lark.pickle"
        self.callbacks = callbacks
        self.lark = Lark(
            text,
            parser="lalr",
            lexer="contextual",
            start="start",
            transformer=callbacks,
            cache=str(cache),
            maybe_placeholders=False,
        )
        self._pretty = {}
        for t in self.lark.terminals:
            if t.name in _PRETTY:
                self._pretty[t.name] = _PRETTY[t.name]
            elif t.pattern.type == "str":
                self._pretty[t.name] = f"'{t.pattern.value}'"
            else:
                self._pretty[t.name] = t.name

    # ------------------------------------------------------------------ errors
    def _expected(self, names) -> str:
        names = sorted(set(names))
        if _EXPR_START <= set(names):
            names = [
                n
                for n in names
                if n not in _EXPR_START
                and n
                not in (
                    "BASED_INT",
                    "WSTRING_LIT",
                    "TIME_LIT",
                    "DATE_LIT",
                    "TOD_LIT",
                    "DT_LIT",
                    "TYPED_PREFIX",
                    "DIRECT_VAR",
                    "PLUS",
                )
            ] + ["EXPR"]
        shown = []
        for n in names:
            if n == "EXPR":
                shown.append("an expression")
            elif n in self._pretty:
                shown.append(self._pretty[n])
            else:
                shown.append(n)
        shown = sorted(set(shown))
        if len(shown) > 8:
            return ", ".join(shown[:8]) + ", …"
        return ", ".join(shown)

    def _describe(self, tok: Token) -> str:
        if tok.type == "$END":
            return "end of file"
        return f"'{tok}'"

    def _hint(self, src: SourceFile, tok: Token, expected: set, semicolon_fixes: bool) -> str:
        t = tok.type
        if t == "EQ" and "ASSIGN" in expected:
            return "use ':=' to assign a value; '=' compares"
        if semicolon_fixes:
            return "a ';' is missing here"
        if "END_IF" in expected and re.search(r"\bELSE\s+IF\b", src.text, re.I):
            return "'ELSE IF' opens a nested IF that needs its own END_IF; did you mean ELSIF?"
        if t == "$END":
            ends = [e for e in expected if e.startswith("END_")]
            if ends:
                return f"{ends[0]} is missing"
        if t == "ASSIGN" and "EQ" in expected:
            return "':=' assigns; use '=' to compare"
        return ""

    def _semicolon_fixes(self, ip, tok) -> bool:
        """Would inserting ';' before this token let the parse go on?"""
        if ip is None or tok.type == "$END":
            return False
        found = getattr(self.callbacks, "errors", None)  # the builder's, if it keeps any
        errors = found if isinstance(found, list) else None
        mark = len(errors) if errors is not None else 0
        try:
            trial = ip.copy()
            trial.feed_token(Token("SEMICOLON", ";"))
            trial.feed_token(tok)
            return True
        except (UnexpectedInput, RecursionError):  # RecursionError: copying a very deep partial tree
            return False
        finally:
            if errors is not None:
                del errors[mark:]  # what the trial reduced is not the program

    # ------------------------------------------------------------------ parse
    def parse(self, src: SourceFile, nested_comments: bool | None = True):
        """Returns (result or None, diagnostics). `nested_comments`: see `strip_comments`."""
        text, pragmas, comment_errors = strip_comments(src.text, nested_comments)
        diags: list[Diagnostic] = []
        for ce in comment_errors:
            diags.append(Diagnostic("E002", Severity.ERROR, src.span_at(ce.offset), ce.message))
        seen_pragmas = set()
        for p in pragmas:
            if p.embedded_code:
                diags.append(
                    Diagnostic(
                        "W009",
                        Severity.WARNING,
                        src.span_at(p.offset),
                        "embedded C code {{ ... }} is skipped: st does not run it",
                        hint="OpenPLC compiles it into its C output; write what it does in ST to have it run here",
                    )
                )
                continue
            if p.text not in seen_pragmas:
                seen_pragmas.add(p.text)
                diags.append(
                    Diagnostic(
                        "W001",
                        Severity.WARNING,
                        src.span_at(p.offset),
                        f"pragma {p.text[:60]!r} is ignored",
                        data=(("pragma", p.name),),
                    )
                )

        def on_error(e: UnexpectedInput) -> bool:
            if isinstance(e, UnexpectedCharacters):
                pos = e.pos_in_stream
                assert pos is not None  # the lexer's error: it knows where it stopped
                ch = text[pos] if pos < len(text) else "?"
                diags.append(
                    Diagnostic("E001", Severity.ERROR, Span(src.path, e.line, e.column), f"unexpected character {ch!r}")
                )
                return False
            if isinstance(e, UnexpectedToken):
                tok = e.token
                expected = set(e.accepts or e.expected)
                ip = e.interactive_parser
                fixes = "SEMICOLON" in expected and self._semicolon_fixes(ip, tok)
                hint = self._hint(src, tok, expected, fixes)
                if tok.type == "$END":
                    span = Span(src.path, src.text.count("\n") + 1, 1)
                elif fixes:
                    # point just after the previous token: where the ';' belongs
                    i = tok.start_pos - 1
                    while i >= 0 and text[i].isspace():
                        i -= 1
                    line, col = src.position(i + 1)
                    span = Span(src.path, line, col)
                    if line < tok.line:
                        hint = f"a ';' is missing at the end of line {line}"
                else:
                    span = Span(
                        src.path,
                        tok.line,
                        tok.column,
                        getattr(tok, "end_line", 0) or 0,
                        getattr(tok, "end_column", 0) or 0,
                    )
                msg = f"syntax error: unexpected {self._describe(tok)}; expected {self._expected(expected)}"
                diags.append(Diagnostic("E001", Severity.ERROR, span, msg, hint))
                # repair a missing ';' and go on, so that later errors are reported too
                if fixes and len(diags) < 50:
                    ip.feed_token(
                        Token(
                            "SEMICOLON",
                            ";",
                            start_pos=tok.start_pos,
                            line=tok.line,
                            column=tok.column,
                            end_line=tok.line,
                            end_column=tok.column,
                        )
                    )
                    ip.feed_token(tok)
                    return True
                return False
            return False

        try:
            result = self.lark.parse(text, on_error=on_error)
        except UnexpectedEOF as e:
            if not any(d.code == "E001" for d in diags):
                diags.append(
                    Diagnostic(
                        "E001",
                        Severity.ERROR,
                        Span(src.path, src.text.count("\n") + 1, 1),
                        f"syntax error: unexpected end of file; expected {self._expected(e.expected)}",
                    )
                )
            return None, diags
        except UnexpectedInput:
            if not any(d.code == "E001" for d in diags):  # pragma: no cover - defensive
                diags.append(Diagnostic("E001", Severity.ERROR, Span(src.path, 1, 1), "syntax error"))
            return None, diags
        except VisitError as e:  # an exception inside a builder callback
            orig = e.orig_exc
            span = getattr(orig, "span", None) or Span(src.path, 1, 1)
            diags.append(
                Diagnostic(getattr(orig, "code", "E003"), Severity.ERROR, span, getattr(orig, "message", str(orig)))
            )
            return None, diags
        if result is not None and hasattr(result, "pragmas"):
            result.pragmas = [p for p in pragmas if not p.embedded_code]
        return result, diags
