"""The Lark LALR parser for ST, and syntax errors turned into diagnostics.

`StParser(callbacks)` parses one file at a time with the given Lark
Transformer running inside the parser (no intermediate tree). Syntax errors
become `Diagnostic`s with a location and, for the usual slips, a hint. After
an error the parser recovers and goes on, so that one run reports the syntax
errors of every POU of a file:

- a missing ';' is inserted, and the file still yields its AST (it is checked);
- otherwise the one-token repair after which the parser gets furthest is made:
  insert THEN, DO, ')', END_IF, …, delete a stray token, put ':=' for '=' or
  IF for another keyword, insert END_VAR before a statement in a declaration
  section;
- otherwise the parser skips to a statement or POU boundary (the token after a
  ';' or an END_*, a statement or POU keyword) and goes on in the innermost
  enclosing list on its stack (statements, declarations, POUs) that accepts the
  tokens there, never inside a construct whose opening keyword it skipped.

Each way on is tried first on a view of the parser's stack (`_Cursor`: no
callbacks, the contextual lexer as the parser uses it), and taken only if the
parser then accepts the next tokens, so a recovered statement brings no
follow-on errors. A file that needed any recovery but a ';' yields no AST:
only its errors are reported.
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
from collections.abc import Iterable
from copy import copy
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from lark import Lark, Token
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError
from lark.lexer import ContextualLexer, LexerState
from lark.parsers.lalr_analysis import Shift

from ..diagnostics import Diagnostic, Severity
from ..source import SourceFile, Span
from .comments import strip_comments

GRAMMAR_PATH = Path(__file__).with_name("st.lark")

# How a message names a terminal whose pattern is not its ST spelling (every other terminal is a
# fixed string, shown quoted: 'END_IF', ':=', '..').
_PRETTY = {
    "IDENT": "an identifier",
    "INTEGER": "an integer",
    "BASED_INT": "an integer",
    "REAL_LIT": "a real number",
    "STRING_LIT": "a string",
    "WSTRING_LIT": "a wide string",
    "TIME_LIT": "a time literal",
    "DATE_LIT": "a date literal",
    "TOD_LIT": "a time-of-day literal",
    "DT_LIT": "a date-and-time literal",
    "TYPED_PREFIX": "a typed literal",
    "DIRECT_VAR": "a located address",
    "PARTIAL_ACCESS": "a partial access such as %X0",
    "VAR_KIND": "'VAR'",
    "STRING_KW": "'STRING'",
    "SET_ASSIGN": "'S='",
    "RESET_ASSIGN": "'R='",
    "REF_ASSIGN": "'REF='",
    "ACCESS_DIRECTION": "'READ_ONLY'",
    "WS": "white space",
    "$END": "end of file",
}
# all of these accepted: an expression may start here
_EXPR_START = frozenset({"IDENT", "INTEGER", "REAL_LIT", "LPAR", "MINUS", "NOT", "TRUE", "FALSE", "STRING_LIT"})
# what "an expression" stands for in a list of expected tokens
_EXPR_ONLY = _EXPR_START | {
    "BASED_INT",
    "WSTRING_LIT",
    "TIME_LIT",
    "DATE_LIT",
    "TOD_LIT",
    "DT_LIT",
    "TYPED_PREFIX",
    "DIRECT_VAR",
    "PLUS",
}
# what "a literal" stands for (a CASE label)
_LITERALS = frozenset(
    {
        "INTEGER",
        "BASED_INT",
        "REAL_LIT",
        "STRING_LIT",
        "WSTRING_LIT",
        "TIME_LIT",
        "DATE_LIT",
        "TOD_LIT",
        "DT_LIT",
        "TYPED_PREFIX",
        "TRUE",
        "FALSE",
    }
)

# ------------------------------------------------------------------ recovery
_MAX_ERRORS = 50  # syntax errors reported per file; the parse stops at that many
_WINDOW = 3  # tokens the parser must accept where it resumes after skipping
_REPAIR_WINDOW = 10  # tokens over which one-token repairs are compared
_REPAIR_MIN = 4  # tokens a one-token repair must let the parser accept after it
_MAX_TRIALS = 4000  # trial parses per file: bounded work on any input
_MAX_CANDIDATES = 24  # enclosing lists a resynchronisation considers

# A state where one of these may begin is a list the parser can resume in.
_RECOVERY_RULES = frozenset(
    {
        "statement",
        "var_decl",
        "var_block",
        "struct_member",
        "type_item",
        "_element",
        "_fb_part",
        "_pou_part",
        "_config_part",
        "_resource_part",
        "method_decl",
        "property_decl",
        "property_accessor",
        "action_assoc",
        "task_decl",
        "program_config",
        "case_labels",
    }
)
# keywords that open a construct an END_* closes (reserved words)
_HARD_OPENERS = {
    "IF": "END_IF",
    "CASE": "END_CASE",
    "FOR": "END_FOR",
    "WHILE": "END_WHILE",
    "REPEAT": "END_REPEAT",
    "TRY": "END_TRY",
    "VAR_KIND": "END_VAR",
    "STRUCT": "END_STRUCT",
    "UNION": "END_UNION",
    "TYPE": "END_TYPE",
    "FUNCTION": "END_FUNCTION",
    "FUNCTION_BLOCK": "END_FUNCTION_BLOCK",
    "PROGRAM": "END_PROGRAM",
    "CONFIGURATION": "END_CONFIGURATION",
    "RESOURCE": "END_RESOURCE",
    "INITIAL_STEP": "END_STEP",
}
# the same for words that may be names too: counted only where the parser read them as keywords
_SOFT_OPENERS = {
    "METHOD": "END_METHOD",
    "PROPERTY": "END_PROPERTY",
    "GET": "END_GET",
    "SET": "END_SET",
    "ACTION": "END_ACTION",
    "STEP": "END_STEP",
    "TRANSITION": "END_TRANSITION",
    "INTERFACE": "END_INTERFACE",
    "CLASS": "END_CLASS",
    "TEST": "END_TEST",
    "SETUP": "END_SETUP",
    "TEARDOWN": "END_TEARDOWN",
}
_OPENERS = {**_HARD_OPENERS, **_SOFT_OPENERS}
# a PROGRAM inside these configures an instance: nothing to close
_CONFIG_CLOSERS = frozenset({"END_CONFIGURATION", "END_RESOURCE"})
# tokens to resume at (and any token after a ';' or an END_*)
_SYNC = frozenset(
    {"IF", "CASE", "FOR", "WHILE", "REPEAT", "EXIT", "CONTINUE", "RETURN", "ELSE", "ELSIF", "UNTIL", "TASK"}
    | set(_OPENERS)
)
# POU keywords that stand only between POUs: the POU before them is over, closed or not
_TOP_LEVEL = frozenset({"FUNCTION", "FUNCTION_BLOCK", "PROGRAM", "TYPE", "CONFIGURATION"})
# the END_* after which a POU may begin
_TOP_CLOSERS = frozenset(
    {
        "END_PROGRAM",
        "END_FUNCTION",
        "END_FUNCTION_BLOCK",
        "END_TYPE",
        "END_CONFIGURATION",
        "END_INTERFACE",
        "END_CLASS",
        "END_TEST",
        "END_SETUP",
        "END_TEARDOWN",
        "END_METHOD",
        "END_PROPERTY",
        "END_ACTION",
    }
)
# the sections that stand between POUs (VAR, VAR_INPUT, … there: a POU header is missing)
_TOP_SECTIONS = frozenset({"VAR_GLOBAL", "VAR_CONFIG"})
# tokens a one-token repair may insert, or put for the unexpected token (and every END_*)
_INSERTABLE = ("SEMICOLON", "THEN", "DO", "OF", "RPAR", "RSQB", "COLON", "ASSIGN", "TO", "COMMA")
# keywords a repair may put for another keyword
_STATEMENT_WORDS = frozenset(
    {"IF", "ELSIF", "ELSE", "CASE", "FOR", "BY", "WHILE", "REPEAT", "UNTIL", "EXIT", "CONTINUE", "RETURN"}
)
# where one of these follows a name in a declaration section, END_VAR is missing before it
_STATEMENT_SIGNS = frozenset(
    {
        "ASSIGN",
        "SET_ASSIGN",
        "RESET_ASSIGN",
        "REF_ASSIGN",
        "ATTEMPT_ASSIGN",
        "IF",
        "CASE",
        "FOR",
        "WHILE",
        "REPEAT",
        "RETURN",
        "EXIT",
        "CONTINUE",
    }
)
# characters no token starts with: skipped in one step while looking for a place to resume
_NO_TOKEN = re.compile(r"[^A-Za-z0-9_\s'\"%().,:;=<>+\-*/&^\[\]?#]+")


@dataclass(frozen=True, slots=True)
class _Repair:
    """A one-token repair: insert `terminal` before the unexpected token, delete that token, put
    `terminal` for it, or (`before`) insert `terminal` before the construct being read, from
    `at` = (offset, line, column) on, after cutting the stacks back to `depth` states."""

    kind: str  # insert | delete | replace | before
    terminal: str = ""
    depth: int = 0
    at: tuple[int, int, int] | None = None

    @property
    def semicolon(self) -> bool:
        return self.kind == "insert" and self.terminal == "SEMICOLON"


def _spelling(name: str, kind: str, value: str) -> str:
    if name in _PRETTY:
        return _PRETTY[name]
    if kind == "str":
        return f"'{value}'"
    return "a " + name.lower().replace("_", " ")  # a regex terminal _PRETTY misses (a test rejects it)


@dataclass(frozen=True, slots=True)
class _Tables:
    """What recovery needs to know of the grammar, worked out once per parser."""

    states: dict[Any, dict[str, tuple[Any, Any]]]  # the LALR table
    end_state: Any
    lexer: ContextualLexer
    recovery: frozenset  # states of a list the parser may resume in
    name_states: frozenset  # states right after a word read as a name
    top: frozenset  # states between two POUs
    closers: frozenset[str]  # END_* terminals
    insertable: tuple[str, ...]
    text: dict[str, str]  # the source text of each fixed-string terminal
    keywords: frozenset[str]  # words (upper case) a trial does not take for a name
    reserved: frozenset[str]  # words (upper case) that are never a name


class _Cursor:
    """A trial parse on a view of the parser's state stack (its first `depth` states): no
    callbacks run, the stack itself is not touched."""

    __slots__ = ("states", "end_state", "base", "lo", "top")

    def __init__(self, t: _Tables, base: list, depth: int):
        self.states = t.states
        self.end_state = t.end_state
        self.base = base
        self.lo = depth
        self.top: list = []

    def state(self):
        return self.top[-1] if self.top else self.base[self.lo - 1]

    def copy(self) -> _Cursor:
        other = copy(self)
        other.top = list(self.top)
        return other

    def _reduce(self, rule) -> None:
        size = len(rule.expansion)
        top = self.top
        n = min(size, len(top))
        if n:
            del top[-n:]
        self.lo -= size - n
        top.append(self.states[self.state()][rule.origin.name][1])

    def reduce_for(self, ttype: str):
        """Reduce as the parser does before it shifts `ttype`; the state it shifts to (None: the
        token is an error here)."""
        states = self.states
        while True:
            act = states[self.state()].get(ttype)
            if act is None:
                return None
            action, arg = act
            if action is Shift:
                return arg
            self._reduce(arg)

    def feed(self, ttype: str) -> bool:
        target = self.reduce_for(ttype)
        if target is None:
            return False
        self.top.append(target)
        return True

    def feed_end(self) -> bool:
        while True:
            act = self.states[self.state()].get("$END")
            if act is None or act[0] is Shift:
                return False
            self._reduce(act[1])
            if self.state() == self.end_state:
                return True


@dataclass(slots=True)
class _Recovery:
    """One parse's recovery: what it reported and tried, and where it skipped or made up input."""

    builder_errors: list | None  # the builder's error list, if it keeps one
    reported: int = 0
    last_pos: int = -1  # text offset of the last error
    trials: int = 0
    ast_kept: bool = True  # no recovery but inserted ';': the AST is the program as written
    gaps: list[int] = field(default_factory=list)  # value-stack positions of skipped or made-up input
    wrapped: bool = False  # the callbacks know about gaps


def _cache_dir() -> Path:
    base = os.environ.get("ST_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "st"
    )
    try:
        Path(base).mkdir(parents=True, exist_ok=True)
        return Path(base)
    except OSError:
        return Path(tempfile.gettempdir())


def _move(ls: LexerState, pos: int, line: int, column: int, last: Token | None = None) -> None:
    """Put a lexer state at a position of its text (line and column of that position)."""
    lc = ls.line_ctr
    lc.char_pos = pos
    lc.line = line
    lc.column = column
    lc.line_start_pos = pos - column + 1
    ls.last_token = last


def _at_start(like: LexerState, tok: Token) -> LexerState:
    ls = copy(like)
    _move(ls, tok.start_pos or 0, tok.line or 1, tok.column or 1)
    return ls


def _at_end(like: LexerState, tok: Token) -> LexerState:
    ls = copy(like)
    _move(ls, tok.end_pos or 0, tok.end_line or 1, tok.end_column or 1, tok)
    return ls


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
        self._pretty = {t.name: _spelling(t.name, t.pattern.type, t.pattern.value) for t in self.lark.terminals}
        self._pretty["$END"] = _PRETTY["$END"]
        self._tables: _Tables | None = None

    def spelling(self, terminal: str) -> str:
        """How a syntax error names a terminal of the grammar: its ST text quoted ('END_IF', ':=',
        'REF='), or what it stands for ('an identifier')."""
        return self._pretty.get(terminal, terminal)

    def _tables_of(self, ip) -> _Tables | None:
        if self._tables is None:
            lexer = ip.lexer_thread.lexer
            if not isinstance(lexer, ContextualLexer):  # pragma: no cover - the parser is built contextual
                return None
            conf = ip.parser_state.parse_conf
            states = conf.states
            reductions = [arg for acts in states.values() for a, arg in acts.values() if a is not Shift]
            # the words `name` accepts (ON, STEP, METHOD, …); R_EDGE and F_EDGE are names in some dialects
            names = {r.expansion[0].name for r in reductions if r.origin.name == "name"} | {"R_EDGE", "F_EDGE"}
            text = {t.name: t.pattern.value for t in self.lark.terminals if t.pattern.type == "str"}
            words = {n: v.upper() for n, v in text.items() if v.isidentifier()}
            closers = frozenset(n for n in text if n.startswith("END_"))
            self._tables = _Tables(
                states=states,
                end_state=conf.end_state,
                lexer=lexer,
                recovery=frozenset(s for s, acts in states.items() if not _RECOVERY_RULES.isdisjoint(acts)),
                name_states=frozenset(
                    s
                    for s, acts in states.items()
                    if acts and all(a is not Shift and arg.origin.name == "name" for a, arg in acts.values())
                ),
                top=frozenset(s for s, acts in states.items() if "_element" in acts),
                closers=closers,
                insertable=_INSERTABLE + tuple(sorted(closers)),
                text=text,
                keywords=frozenset(words.values())
                | {"STRING", "WSTRING", "VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_GLOBAL"},
                reserved=frozenset(w for n, w in words.items() if n not in names),
            )
        return self._tables

    # ------------------------------------------------------------------ messages
    def _accepts(self, t: _Tables, stack: list) -> set[str]:
        """The terminals the parser can go on with. Words it would read only as a name are left
        out when an identifier is accepted: they are one."""
        out: set[str] = set()
        names: set[str] = set()
        for k in t.states[stack[-1]]:
            if not k.isupper():
                continue
            cur = _Cursor(t, stack, len(stack))
            if k == "$END":
                if cur.feed_end():
                    out.add(k)
            elif cur.feed(k):
                out.add(k)
                if cur.state() in t.name_states:
                    names.add(k)
        if "IDENT" in out:
            out -= names - {"IDENT"}
        return out

    def _expected(self, names: Iterable[str]) -> str:
        wanted = set(names)
        if "$END" in wanted:
            wanted.discard("SEMICOLON")  # between declarations a stray ';' is allowed, not wanted
        shown = set()
        if _EXPR_START <= wanted:
            wanted -= _EXPR_ONLY
            shown.add("an expression")
        elif len(wanted & _LITERALS) >= 3:
            wanted -= _LITERALS
            shown.add("a literal")
        shown |= {self.spelling(n) for n in wanted}
        # what stands for many tokens first, then the words and symbols
        items = sorted(s for s in shown if not s.startswith("'")) + sorted(s for s in shown if s.startswith("'"))
        if len(items) > 8:
            return ", ".join(items[:8]) + ", …"
        return ", ".join(items)

    def _describe(self, tok: Token) -> str:
        if tok.type == "$END":
            return "end of file"
        text = str(tok)
        if len(text) > 40:
            text = text[:30] + "…"
        if tok.type in ("STRING_LIT", "WSTRING_LIT"):
            return f"string {text}"
        return f"'{text}'"

    def _word(self, terminal: str) -> str:
        """A terminal as a hint names it: a keyword as it is (END_IF), a symbol quoted (')')."""
        shown = self.spelling(terminal)
        return shown[1:-1] if shown[1:-1].isidentifier() else shown

    def _hint(self, src: SourceFile, tok: Token, expected: set, semicolon_fixes: bool) -> str:
        t = tok.type
        if t == "EQ" and "ASSIGN" in expected:
            return "use ':=' to assign a value; '=' compares"
        if semicolon_fixes:
            return "a ';' is missing here"
        if "END_IF" in expected and re.search(r"\bELSE\s+IF\b", src.text, re.I):
            return "'ELSE IF' opens a nested IF that needs its own END_IF; did you mean ELSIF?"
        if t == "$END":
            ends = sorted(e for e in expected if e.startswith("END_"))
            if ends:
                return f"{ends[0]} is missing"
        if t == "ASSIGN" and "EQ" in expected:
            return "':=' assigns; use '=' to compare"
        return ""

    def _repair_hint(self, tok: Token, repair: _Repair | None, opened: list[str], expected: set) -> str:
        if opened and opened[-1] == "END_VAR" and tok.type in _STATEMENT_SIGNS:
            return "END_VAR is missing before this statement"
        if repair is not None:
            kind, terminal = repair.kind, repair.terminal
            if kind == "insert" and terminal == "IDENT":
                what = "an expression" if "INTEGER" in expected else "a type" if "ARRAY" in expected else "a name"
                return f"{what} is missing before {self._describe(tok)}"
            if kind == "insert":
                return f"{self._word(terminal)} is missing before {self._describe(tok)}"
            if kind == "before":
                return f"{self._word(terminal)} is missing before this line"
            if kind == "replace":
                return f"did you mean {self._word(terminal)}?"
            return ""
        if opened and tok.type in _TOP_LEVEL:
            return f"{opened[0]} is missing before {self._describe(tok)}"
        return ""

    # ------------------------------------------------------------------ trials
    def _trial(
        self,
        ctx: _Recovery,
        t: _Tables,
        stack: list,
        depth: int,
        pre: list[str],
        ls: LexerState,
        window: int,
        lenient: bool = False,
        boundary: bool = False,
    ) -> int:
        """How far the parser gets from the first `depth` states of `stack`: after the tokens
        `pre`, how many tokens of the text from `ls` on it accepts, at most `window` (`window` if
        it reaches the end of the file); -1: not even `pre`. `lenient`: a ';' missing among those
        tokens does not stop it (the parser will insert it there). `boundary`: `window` only once
        it has also accepted a ';' or an END_* (at most 4 * `window` tokens); window - 1 if it
        fails between the two."""
        ctx.trials += 1
        cur = _Cursor(t, stack, depth)
        for ttype in pre:
            if not cur.feed(ttype):
                return -1
        ls = copy(ls)
        lexers = t.lexer.lexers
        for n in range(window * 4 if boundary else window):
            try:
                tok = lexers[cur.state()].next_token(ls)
            except EOFError:
                return window if cur.feed_end() else min(n, window - 1)
            except UnexpectedCharacters:  # no token this state takes: what is there? (as the parser does)
                try:
                    tok = t.lexer.root_lexer.next_token(ls)
                except (UnexpectedCharacters, EOFError):
                    return min(n, window - 1)
            if tok.type == "IDENT" and tok.upper() in t.keywords:
                return min(n, window - 1)  # a keyword read as a name, where no keyword fits: no way on
            before = cur.copy() if lenient else cur
            target = cur.reduce_for(tok.type)
            if target is None:
                if not lenient or tok.type == "SEMICOLON":
                    return min(n, window - 1)
                cur = before.copy()
                if not (cur.feed("SEMICOLON") and cur.feed(tok.type)):
                    return min(n, window - 1)
            elif tok.type == "VAR_KIND" and cur.state() in t.top and tok.upper() not in _TOP_SECTIONS:
                return min(n, window - 1)  # VAR, VAR_INPUT, … between POUs: a POU header was skipped
            else:
                cur.top.append(target)
            if boundary and n + 1 >= window and (tok.type == "SEMICOLON" or tok.type in t.closers):
                return window
        return window

    def _local_repair(
        self, ctx: _Recovery, t: _Tables, ip, src: SourceFile, tok: Token, ls: LexerState, accepts: set
    ) -> _Repair | None:
        """The one-token repair after which the parser gets furthest, if at least _REPAIR_MIN
        tokens (a ';': fewer): insert a token before `tok`, insert END_VAR (VAR, …) before the
        construct being read (`VAR … x := 1;`), delete tok, or put another token for it. `ls`: the
        text after tok."""
        sstack = ip.parser_state.state_stack
        depth = len(sstack)
        after = [] if tok.type == "$END" else [tok.type]
        choices = [x for x in t.insertable if x in accepts]
        # in order of preference, where two get as far
        cands = [(_Repair("insert", x, depth), [x, *after]) for x in choices]
        opening = self._construct_start(t, ip, src, ls.text.text, tok)
        if opening is not None:
            d, at = opening
            state = t.states[sstack[d - 1]]
            cands += [(_Repair("before", x, d, at), [x]) for x in (*sorted(t.closers), "VAR_KIND") if x in state]
        if tok.type != "$END":
            cands.append((_Repair("delete"), []))
            if tok.type in t.text:  # a keyword or a symbol for another (a name or a literal: never)
                cands += [(_Repair("replace", x, depth), [x]) for x in choices if x != tok.type]
                if tok.type in t.closers or tok.type in _STATEMENT_WORDS or tok.upper() in t.reserved:
                    words = sorted(accepts & _STATEMENT_WORDS - {tok.type})
                    cands += [(_Repair("replace", x, depth), [x]) for x in words]
        if "IDENT" in accepts:  # a made-up name or operand: the last resort
            cands.append((_Repair("insert", "IDENT", depth), ["IDENT", *after]))
        best: _Repair | None = None
        best_score = 0
        for repair, pre in cands:
            if repair.at is not None:
                pos, line, col = repair.at
                from_ls = copy(ls)
                _move(from_ls, pos, line, col)
                score = self._trial(ctx, t, sstack, repair.depth, pre, from_ls, _REPAIR_WINDOW, boundary=True)
            else:
                score = self._trial(ctx, t, sstack, depth, pre, ls, _REPAIR_WINDOW, boundary=True)
            # a missing ';' (the usual slip) needs less evidence: another error may follow closely
            if score > best_score and score >= (_WINDOW - 1 if repair.semicolon else _REPAIR_MIN):
                best, best_score = repair, score
                if score == _REPAIR_WINDOW:
                    break
        if best is None and "SEMICOLON" in choices:
            # a ';' is missing here and again further on: the parser will insert that one too
            if self._trial(ctx, t, sstack, depth, ["SEMICOLON", *after], ls, _REPAIR_WINDOW, True, True) >= _REPAIR_MIN:
                best = _Repair("insert", "SEMICOLON", depth)
        return best

    def _construct_start(
        self, t: _Tables, ip, src: SourceFile, text: str, tok: Token
    ) -> tuple[int, tuple[int, int, int]] | None:
        """The innermost list on the stack, a few states down, and where the text the parser has
        read since begins, if that is one statement or declaration (no ';' in it) before `tok`:
        (depth, (offset, line, column))."""
        sstack = ip.parser_state.state_stack
        vstack = ip.parser_state.value_stack
        for d in range(len(sstack) - 1, max(len(sstack) - 8, 1), -1):
            if sstack[d - 1] not in t.recovery:
                continue
            v = vstack[d - 1]
            if isinstance(v, Token):
                if v.start_pos is None or v.line is None or v.column is None:
                    return None
                at = (v.start_pos, v.line, v.column)
            else:
                span = getattr(v, "span", None)
                if not isinstance(span, Span) or span.line < 1 or span.col < 1:
                    return None
                at = (src.offset(span.line, span.col), span.line, span.col)
            end = tok.start_pos if tok.type != "$END" and tok.start_pos is not None else len(text)
            if not at[0] < end or ";" in text[at[0] : end]:
                return None
            return d, at
        return None

    def _keyword_read_as_name(self, t: _Tables, ip) -> Token | None:
        """A reserved word the parser has just taken for a name: where no keyword fits, the
        contextual lexer reads FUNCTION_BLOCK as an identifier, and the error shows one token
        later. Taken back off the stacks and returned as the keyword it is."""
        sstack = ip.parser_state.state_stack
        vstack = ip.parser_state.value_stack
        v = vstack[-1] if vstack else None
        if not isinstance(v, Token) or v.type != "IDENT" or v.upper() not in t.reserved or len(sstack) < 2:
            return None
        try:
            kw = t.lexer.root_lexer.next_token(_at_start(ip.lexer_thread.state, v))
        except (UnexpectedCharacters, EOFError):  # pragma: no cover - it was read once
            return None
        if kw.type == "IDENT" or kw.end_pos != v.end_pos:  # pragma: no cover - the same text
            return None
        del sstack[-1]
        del vstack[-1]
        return kw

    def _open_constructs(self, t: _Tables, ip) -> list[tuple[int, str]]:
        """(value-stack index, END_*) of each construct open on the parser's stack, outermost
        first: the opening keywords the parser has shifted as keywords (not read as names)."""
        sstack = ip.parser_state.state_stack
        vstack = ip.parser_state.value_stack
        states = t.states
        out: list[tuple[int, str]] = []
        for i, v in enumerate(vstack):
            if not isinstance(v, Token):
                continue
            closer = _OPENERS.get(v.type)
            if closer is None or sstack[i + 1] in t.name_states:
                continue
            if states[sstack[i]].get(v.type) != (Shift, sstack[i + 1]):
                continue
            if v.type == "PROGRAM" and out and out[-1][1] in _CONFIG_CLOSERS:
                continue
            out.append((i, closer))
        return out

    # ------------------------------------------------------------------ recovery
    def _mark_gap(self, ctx: _Recovery, ip, at: int) -> None:
        """Input was skipped or made up at value-stack position `at`: the AST is not the program,
        and what the builder says about the constructs around the gap is not about the file."""
        ctx.ast_kept = False
        if not ctx.wrapped:
            ctx.wrapped = True
            self._wrap_callbacks(ctx, ip)
        ctx.gaps[:] = [g for g in ctx.gaps if g < at] + [at]

    def _wrap_callbacks(self, ctx: _Recovery, ip) -> None:
        """From the first gap on, a rule reduced across a gap runs with its builder errors (and
        exceptions) dropped."""
        conf = ip.parser_state.parse_conf
        vstack = ip.parser_state.value_stack
        gaps = ctx.gaps
        errors = ctx.builder_errors

        def wrap(rule, fn):
            # a list (of statements, of POUs, …) the parser resumed in spans the gap before its first
            # item: the items it skipped were its own
            first = 0 if rule.origin.name.startswith("__") or rule.origin.name == "start" else 1

            def call(children):
                low = len(vstack)  # the children are off the stack already
                high = low + len(children)
                if not any(low + first <= g <= high for g in gaps):
                    return fn(children)
                gaps[:] = [g for g in gaps if g <= low] + [low + 1]
                mark = len(errors) if errors is not None else 0
                try:
                    return fn(children)
                except Exception:  # noqa: BLE001 - built from made-up input: the AST is not used
                    return None
                finally:
                    if errors is not None:
                        del errors[mark:]

            return call

        conf.callbacks = {k: (wrap(k, f) if hasattr(k, "expansion") else f) for k, f in conf.callbacks.items()}

    def _apply(self, ctx: _Recovery, t: _Tables, ip, tok: Token, repair: _Repair) -> None:
        """Make a one-token repair on the parser itself (its callbacks run); the lexer is past tok."""
        kind = repair.kind
        if repair.at is not None:  # the text from the construct's start is read again
            del ip.parser_state.state_stack[repair.depth :]
            del ip.parser_state.value_stack[repair.depth - 1 :]
            pos, line, col = repair.at
            _move(ip.lexer_thread.state, pos, line, col)
        if not repair.semicolon:
            self._mark_gap(ctx, ip, len(ip.parser_state.value_stack))
        if kind == "delete":
            return
        at = repair.at or (tok.start_pos or 0, tok.line or 1, tok.column or 1)
        ip.feed_token(
            Token(
                repair.terminal,
                t.text.get(repair.terminal, "VAR" if repair.terminal == "VAR_KIND" else ""),
                start_pos=at[0],
                line=at[1],
                column=at[2],
                end_line=at[1],
                end_column=at[2],
                end_pos=at[0],
            )
        )
        if kind == "insert" and tok.type != "$END":
            ip.feed_token(tok)

    def _resynchronise(self, ctx: _Recovery, t: _Tables, ip, ls: LexerState, first_is_error: bool) -> bool:
        """Skip the text from `ls` on to a statement or POU boundary where a list open on the stack
        accepts the next tokens, cut the stacks back to that list and resume there. A list inside
        a construct whose END_* has been skipped, or whose opening keyword has, is no place to
        resume: the skipped keywords are counted."""
        text = ls.text.text
        sstack = ip.parser_state.state_stack
        depth = len(sstack)
        opened = self._open_constructs(t, ip)
        on_stack = [c for _, c in opened]
        candidates: list[tuple[int, int]] = []  # (depth, constructs open below it), innermost first
        for d in range(depth, 1, -1):
            if sstack[d - 1] in t.recovery:
                candidates.append((d, sum(1 for i, _ in opened if i < d - 1)))
                if len(candidates) >= _MAX_CANDIDATES:
                    break
        candidates.append((1, 0))  # the file's list of POUs
        root = t.lexer.root_lexer
        states = t.states
        k = len(on_stack)  # the constructs of the stack not closed by a skipped END_*
        skipped: list[str] = []  # the END_* of constructs opened in the skipped text
        prev: str | None = None
        first = first_is_error
        scan = copy(ls)
        while ctx.trials < _MAX_TRIALS:
            lc = scan.line_ctr
            pos = lc.char_pos
            try:
                tok = root.next_token(scan)
            except EOFError:
                return False
            except UnexpectedCharacters:
                m = _NO_TOKEN.match(text, pos)
                lc.feed(text[pos : m.end()] if m else text[pos])
                prev = None
                first = False
                continue
            ttype = tok.type
            in_config = ttype == "PROGRAM" and any(c in _CONFIG_CLOSERS for c in on_stack[:k] + skipped)
            if prev == "SEMICOLON" or prev in t.closers or ttype in _SYNC:
                word = ttype == "IDENT" or ttype in t.text and t.text[ttype].isidentifier()
                for d, below in candidates:
                    if first and d == depth:
                        continue  # where the parser stood at this very token
                    if d == 1:  # between POUs: at a POU keyword, or after the END_* of one
                        if not ((ttype in _TOP_LEVEL and not in_config) or (prev in _TOP_CLOSERS and k == 0)):
                            continue
                        if skipped and ttype not in _TOP_LEVEL:
                            continue
                    elif skipped or k != below:
                        continue
                    acts = states[sstack[d - 1]]
                    if ttype not in acts and not (word and "IDENT" in acts):
                        continue
                    if self._trial(ctx, t, sstack, d, [], _at_start(ls, tok), _WINDOW) >= _WINDOW:
                        del sstack[d:]
                        del ip.parser_state.value_stack[d - 1 :]
                        self._mark_gap(ctx, ip, d - 1)
                        _move(ip.lexer_thread.state, tok.start_pos or 0, tok.line or 1, tok.column or 1, tok)
                        return True
            # what the skipped token opens or closes
            closer = _HARD_OPENERS.get(ttype)
            if closer is not None:
                if not in_config:
                    skipped.append(closer)
            elif ttype in t.closers:
                if ttype in skipped:
                    del skipped[len(skipped) - 1 - skipped[::-1].index(ttype) :]
                elif ttype in on_stack[:k]:
                    k = k - 1 - on_stack[:k][::-1].index(ttype)
                    skipped = []
            prev = ttype
            first = False
        return False

    def _on_token(self, ctx: _Recovery, src: SourceFile, text: str, e: UnexpectedToken, diags: list) -> bool:
        """Report an unexpected token; recover if possible (True: the parse goes on)."""
        ip = e.interactive_parser
        t = self._tables_of(ip) if ip is not None else None
        tok = e.token
        repair: _Repair | None = None
        ls_after = ip.lexer_thread.state if ip is not None else None  # the text after tok
        if t is None or ls_after is None:  # pragma: no cover - the parser always gives its state
            t = None
            expected = set(e.expected)
        else:
            kw = self._keyword_read_as_name(t, ip)
            if kw is not None:
                tok = kw
                ls_after = _at_end(ls_after, kw)
            expected = self._accepts(t, ip.parser_state.state_stack)
            repair = self._local_repair(ctx, t, ip, src, tok, ls_after, expected)
        fixes = repair is not None and repair.semicolon
        hint = self._hint(src, tok, expected, fixes)
        if not hint and t is not None:
            hint = self._repair_hint(tok, repair, [c for _, c in self._open_constructs(t, ip)], expected)
        if tok.type == "$END":
            span = Span(src.path, src.text.count("\n") + 1, 1)
        elif fixes:
            # point just after the previous token: where the ';' belongs
            i = (tok.start_pos or 0) - 1
            while i >= 0 and text[i].isspace():
                i -= 1
            line, col = src.position(i + 1)
            span = Span(src.path, line, col)
            if line < (tok.line or 0):
                hint = f"a ';' is missing at the end of line {line}"
        else:
            span = Span(src.path, tok.line or 1, tok.column or 1, tok.end_line or 0, tok.end_column or 0)
        msg = f"syntax error: unexpected {self._describe(tok)}; expected {self._expected(expected)}"
        diags.append(Diagnostic("E001", Severity.ERROR, span, msg, hint))
        ctx.reported += 1
        if t is None or ctx.reported >= _MAX_ERRORS:
            return False
        if repair is not None:
            ip.lexer_thread.state = ls_after
            self._apply(ctx, t, ip, tok, repair)
            return True
        if tok.type == "$END" or ls_after is None:
            return False
        return self._resynchronise(ctx, t, ip, _at_start(ls_after, tok), first_is_error=True)

    def _on_character(self, ctx: _Recovery, src: SourceFile, text: str, e: UnexpectedCharacters, diags: list) -> bool:
        """Report a character no token begins with; skip it, or resynchronise."""
        pos = e.pos_in_stream
        assert pos is not None  # the lexer's error: it knows where it stopped
        ch = text[pos] if pos < len(text) else "?"
        diags.append(
            Diagnostic("E001", Severity.ERROR, Span(src.path, e.line, e.column), f"unexpected character {ch!r}")
        )
        ctx.reported += 1
        ip = e.interactive_parser
        t = self._tables_of(ip) if ip is not None else None
        if t is None or ctx.reported >= _MAX_ERRORS:
            return False
        ls = ip.lexer_thread.state  # at the character
        after = copy(ls)
        after.line_ctr.feed(text[pos])
        stack = ip.parser_state.state_stack
        if self._trial(ctx, t, stack, len(stack), [], after, _WINDOW) >= _WINDOW:  # a stray character
            ls.line_ctr = after.line_ctr
            return True
        return self._resynchronise(ctx, t, ip, after, first_is_error=False)

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
                        data=(("pragma", p.name), ("attribute", p.attribute)),
                    )
                )

        found = getattr(self.callbacks, "errors", None)
        ctx = _Recovery(found if isinstance(found, list) else None)

        def on_error(e: UnexpectedInput) -> bool:
            if ctx.reported >= _MAX_ERRORS:
                return False
            # every recovery lets the parser past the error: one at or before the last is a
            # follow-on error (a safety net: it stops the parse, unreported)
            tok = getattr(e, "token", None)
            pos = len(text) + 1 if tok is not None and tok.type == "$END" else e.pos_in_stream
            if pos is None or pos <= ctx.last_pos:
                return False
            ctx.last_pos = pos
            if isinstance(e, UnexpectedCharacters):
                return self._on_character(ctx, src, text, e, diags)
            if isinstance(e, UnexpectedToken):
                return self._on_token(ctx, src, text, e, diags)
            return False  # pragma: no cover - the LALR parser raises no other

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
        if not ctx.ast_kept:
            return None, diags
        if result is not None and hasattr(result, "pragmas"):
            result.pragmas = [p for p in pragmas if not p.embedded_code]
        return result, diags
