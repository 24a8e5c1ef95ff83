"""A fuzzer over mutated example programs: no input may crash the compiler or the runtime.

`mutant(seed, index)` is a pure function of (seed, index) and the texts of programs/ (every
`*.st` under it, the thesis's too; a test file is joined to the program it tests): one of them
with one to four mutations: tokens or lines deleted, duplicated or swapped, names replaced by
other names of the program, literals by extreme ones, operators and type names by others,
statements inserted that fault at run time or never end, recursion through a method or an
interface, pragmas, brackets and IFs nested deeply, the text cut short.

`run_one(source)` compiles a mutant as `st check`/`st run` do (`st.api.compile_text`,
`raise_on_error=False`), runs a few scans on virtual time under the watchdog when it compiles,
and says what happened. Acceptable outcomes: `ok`, `diagnostics` (compile errors, each at a
line and column of the mutant), `fault:KIND` (a located PLC fault of a named kind, at start-up or
in a scan). Defects: `internal` (E099, an exception out of the compiler, an error without a
location or in a library file), `start-error` (the PLC refused to start without a located ST
fault), `raw-fault` (a fault of the generic kind FAULT, without a location, or with Python's text
in its message), `crash` (an exception out of the runtime, or the worker process died), `timeout`
(the mutant outlasted the wall-clock timeout of its `Worker`). A defect carries a signature that
groups mutants failing the same way: the exception type and the innermost frame in st/, or the
diagnostic code and the first words of its message.

`Worker` classifies mutants in one long-lived subprocess (replaced after a timeout or a death);
`shrink` reduces a failing mutant while its signature stays the same.
"""

from __future__ import annotations

import os
import pickle
import random
import re
import select
import struct
import subprocess
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = Path(__file__).resolve().parents[1]
ACCEPTABLE = ("ok", "diagnostics", "fault:")
DEFECTS = ("internal", "start-error", "raw-fault", "crash", "timeout")
# the kinds the runtime and the standard library name (runtime/faults.py, runtime/helpers.py,
# stdlib/functions.py, runtime/watchdog.py); FAULT is the generic kind of an unexpected exception
NAMED_KINDS = {"DIV0", "INDEX", "RANGE", "NULL", "LOOP", "WATCHDOG", "CONVERSION", "OVERFLOW", "RECURSION"}
_PYTHON_TEXT = re.compile(
    r"\b[A-Z][A-Za-z]*(?:Error|Exception)\b|Traceback|math domain|invalid literal|"
    r"Exceeds the limit|too large to convert|unsupported operand|NoneType|"
    r"object has no attribute|object is not|can't multiply|int too large|"
    r"cannot convert float|not supported between"
)

# ---------------------------------------------------------------------- the corpus and its tokens

_TOKEN = re.compile(
    r"\(\*.*?\*\)|/\*.*?\*/|//[^\n]*|\{[^{}\n]*\}|'(?:[^'$\n]|\$.)*'|\"(?:[^\"$\n]|\$.)*\"|"
    r"[A-Za-z_][A-Za-z0-9_]*#[A-Za-z0-9_.:+\-#]*|\d+#[0-9A-Fa-f_]+|[A-Za-z_][A-Za-z0-9_]*|"
    r"\d[\d_]*(?:\.\d+)?(?:[eE][+-]?\d+)?|%[IQM][XBWDL]?[\d.*]*|:=|=>|<>|<=|>=|\*\*|\.\.|\s+|\S",
    re.S,
)


def corpus() -> list:
    """(name, text) of every example program under programs/, sorted by path; a test file
    test_X.st is joined to X.st beside it (as `st test` compiles it)."""
    out = []
    for f in sorted((ROOT / "programs").rglob("*.st")):
        text = f.read_text()
        if f.name.startswith("test_"):
            subject = f.with_name(f.name[5:])
            if subject.exists():
                text = subject.read_text() + "\n" + text
        out.append((str(f.relative_to(ROOT)), text))
    return out


def tokens(text: str) -> list:
    """The text as tokens (whitespace and comments included): "".join(tokens(t)) == t."""
    return _TOKEN.findall(text)


def _significant(toks):
    return [i for i, t in enumerate(toks) if not t.isspace() and not t.startswith(("(*", "//", "/*"))]


# ---------------------------------------------------------------------- the dictionaries

_INT_TYPES = ["SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD", "LWORD"]
EXTREMES = {
    "int": [
        "0",
        "-1",
        "1",
        "2147483647",
        "-2147483648",
        "4294967295",
        "18446744073709551615",
        "18446744073709551616",
        "-9223372036854775808",
        "16#FFFFFFFFFFFFFFFF",
        "16#" + "F" * 40,
        "2#" + "1" * 64,
        "2#1" + "0" * 127,
        "8#777",
        "9" * 30,
        "INT#-5",
        "BYTE#300",
        "SINT#-128",
        "UDINT#4294967295",
        "16#" + "F" * 200,
    ],
    "real": [
        "1.0E308",
        "-1.0E308",
        "1.0E-320",
        "0.0",
        "-0.0",
        "3.4E38",
        "1.0E39",
        "1.0E-45",
        "REAL#1.5",
        "LREAL#-1.0E308",
        "1.0E400",
    ],
    "time": [
        "T#-1s",
        "T#106751d",
        "TIME#-106751d",
        "T#0s",
        "LT#1ns",
        "T#1d2h3m4s5ms",
        "T#1.5h",
        "LT#213503d",
        "T#999999999d",
        "T#-0.5ms",
    ],
    "date": [
        "DT#1970-01-01-00:00:00",
        "DT#9999-12-31-23:59:59",
        "D#2024-02-30",
        "D#1970-01-01",
        "TOD#24:00:00",
        "TOD#23:59:59.999",
        "TOD#00:00:00",
        "DT#1969-12-31-23:59:59",
        "D#0001-01-01",
        "LDT#2262-04-11-23:47:16.854775807",
    ],
    "string": [
        "'x'",
        "''",
        "'$N$T$$'",
        "'$FF$00'",
        '"w"',
        '""',
        "'" + "A" * 9000 + "'",
        "'" + "$$" * 200 + "'",
        "'$'",
        "'$Q'",
    ],
    "bool": ["TRUE", "FALSE", "0", "1"],
}
ALL_EXTREMES = [v for vs in EXTREMES.values() for v in vs]
BINARY = [
    "+",
    "-",
    "*",
    "/",
    "MOD",
    "AND",
    "OR",
    "XOR",
    "<",
    ">",
    "=",
    "<>",
    "<=",
    ">=",
    "**",
    "&",
    "AND_THEN",
    "OR_ELSE",
]
OPERATORS = BINARY + ["NOT", ":=", "=>", ".", "^", "#", ",", ";", "(", ")", "[", "]", "..", ":", "?="]
TYPES = _INT_TYPES + [
    "BOOL",
    "REAL",
    "LREAL",
    "STRING",
    "WSTRING",
    "TIME",
    "LTIME",
    "DATE",
    "TOD",
    "DT",
    "CHAR",
    "ARRAY[0..3] OF INT",
    "ARRAY[1..0] OF INT",
    "ARRAY[-5..5, 0..1] OF LREAL",
    "ARRAY[0..100000000] OF BYTE",
    "STRING[1]",
    "STRING[65535]",
    "REF_TO INT",
    "POINTER TO INT",
    "REFERENCE TO INT",
    "TON",
    "CTU",
    "R_TRIG",
    "ANY_INT",
    "ARRAY[*] OF INT",
]
_TYPE_NAMES = {t for t in TYPES if t.isalpha()} | {"TIME_OF_DAY", "DATE_AND_TIME", "LINT", "LREAL"}
# a statement that faults or never ends; {k} makes its variables (DECLS) unique to one insertion
STATEMENTS = [
    "x_f{k} := x_f{k} / 0;",
    "x_f{k} := x_f{k} / d_f{k};",
    "x_f{k} := x_f{k} MOD d_f{k};",
    "u_f{k} := u_f{k} MOD 0;",
    "u_f{k} := u_f{k} / d_f{k};",
    "r_f{k} := r_f{k} / 0.0;",
    "x_f{k} := LREAL_TO_DINT(r_f{k} / 0.0);",
    "t_f{k} := t_f{k} / d_f{k};",
    "WHILE TRUE DO END_WHILE;",
    "FOR i_f{k} := 0 TO 2000000000 DO END_FOR;",
    "REPEAT UNTIL FALSE END_REPEAT;",
    "WHILE x_f{k} > 0 DO x_f{k} := x_f{k} + 1; END_WHILE;",
    "FOR i_f{k} := 10 TO 0 BY 0 DO END_FOR;",
    "FOR i_f{k} := 0 TO 10 BY 0 DO END_FOR;",
    "a_f{k}[i_f{k} + 100] := 1;",
    "a_f{k}[x_f{k} - 100] := 1;",
    "x_f{k} := a_f{k}[x_f{k} * 1000];",
    "w_f{k} := SHL(w_f{k}, -1);",
    "w_f{k} := ROR(w_f{k}, x_f{k} - 100);",
    "r_f{k} := SIN(1.0E308 * 10.0);",
    "x_f{k} := LREAL_TO_DINT(1.0E30);",
    "x_f{k} := MUX(i_f{k} + 99, 1, 2);",
    "s_f{k} := MID(s_f{k}, 2, -5);",
    "x_f{k} := STRING_TO_DINT(s_f{k});",
    "x_f{k} := LEN(LEFT(s_f{k}, -1));",
    "s_f{k} := DELETE(s_f{k}, 9, 99);",
    "r_f{k} := EXPT(10.0, 400.0);",
    "r_f{k} := SQRT(-1.0);",
    "r_f{k} := LN(0.0);",
    "r_f{k} := EXPT(-8.0, 0.5);",
    "x_f{k} := (x_f{k} - 2147483647 - 9) / -1;",
    "t_f{k} := T#106751d + T#106751d;",
    "x_f{k} := TIME_TO_DINT(T#106751d);",
    "x_f{k} := x_f{k} ** 40;",
    "x_f{k} := x_f{k} * x_f{k} * x_f{k} * x_f{k};",
    "r_f{k} := DINT_TO_LREAL(x_f{k}) ** 1000.0;",
    "u_f{k} := -u_f{k};",
    "x_f{k} := DWORD_TO_DINT(w_f{k} - 1);",
    "p_f{k} := 0; x_f{k} := p_f{k}^;",
    "x_f{k} := BCD_TO_DINT(16#FF);",
    "w_f{k} := DINT_TO_BCD_WORD(x_f{k} - 8);",
    "RETURN;",
    "EXIT;",
    "CONTINUE;",
    "CASE x_f{k} OF 1..0: ; END_CASE;",
    "s_f{k} := CONCAT(s_f{k}, s_f{k});",
    "x_f{k} := SEL(TRUE, 1, 2) / (x_f{k} - 7);",
]
DECLS = (
    "VAR x_f{k} : DINT := 7; d_f{k} : DINT; i_f{k} : DINT; r_f{k} : LREAL; s_f{k} : STRING := 'abc'; "
    "a_f{k} : ARRAY[0..3] OF INT; u_f{k} : UDINT := 5; w_f{k} : WORD; t_f{k} : TIME := T#1s; "
    "p_f{k} : REF_TO DINT; END_VAR\n"
)
# recursion the checker cannot see (through a method, an interface) faults at run time; a function
# calling itself is E032. (declarations appended to the file, a variable, the call in a body)
RECURSION = [
    (
        "\nFUNCTION_BLOCK FB_rec{k}\nMETHOD m : DINT\nVAR_INPUT n : DINT; END_VAR\nm := THIS^.m(n + 1);\n"
        "END_METHOD\nEND_FUNCTION_BLOCK\n",
        "VAR rec_f{k} : FB_rec{k}; rx_f{k} : DINT; END_VAR\n",
        "rx_f{k} := rec_f{k}.m(0);",
    ),
    (
        "\nINTERFACE I_rec{k}\nMETHOD m : DINT\nVAR_INPUT n : DINT; END_VAR\nEND_METHOD\nEND_INTERFACE\n"
        "FUNCTION_BLOCK FB_rec{k} IMPLEMENTS I_rec{k}\nVAR me : I_rec{k}; END_VAR\nMETHOD m : DINT\n"
        "VAR_INPUT n : DINT; END_VAR\nme := THIS^;\nm := me.m(n + 1);\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "VAR rec_f{k} : FB_rec{k}; rx_f{k} : DINT; END_VAR\n",
        "rx_f{k} := rec_f{k}.m(0);",
    ),
    (
        "\nFUNCTION F_rec{k} : DINT\nVAR_INPUT n : DINT; END_VAR\nF_rec{k} := F_rec{k}(n + 1);\nEND_FUNCTION\n",
        "VAR rx_f{k} : DINT; END_VAR\n",
        "rx_f{k} := F_rec{k}(0);",
    ),
]
PRAGMAS = [
    "{attribute 'hide'}",
    "{attribute 'x'}",
    "{attribute 'qualified_only'}",
    "{attribute 'pack_mode' := '1'}",
    "{dialect 'codesys'}",
    "{dialect 'iec'}",
    "{dialect 'openplc'}",
    "{dialect 'twincat'}",
    "{dialect 'foo'}",
    "{dialect ''}",
    "{{ raw c }}",
    "{warning 'w'}",
    "{IF defined(x)}",
    "(* unterminated",
    "{",
    "(* (* nested *) *)",
    "/* c */",
    "}",
]
_HEADS = ("PROGRAM", "FUNCTION_BLOCK", "FUNCTION", "METHOD", "TEST", "SETUP")

_LITERAL = re.compile(
    r"\d[\d_]*(?:\.\d+)?(?:[eE][+-]?\d+)?|\d+#[0-9A-Fa-f_]+|[A-Za-z_]\w*#\S+|'.*'|\".*\"|"
    r"TRUE|FALSE",
    re.I | re.S,
)
_KEYWORDS = {
    "PROGRAM",
    "END_PROGRAM",
    "FUNCTION",
    "END_FUNCTION",
    "FUNCTION_BLOCK",
    "END_FUNCTION_BLOCK",
    "VAR",
    "VAR_INPUT",
    "VAR_OUTPUT",
    "VAR_IN_OUT",
    "VAR_GLOBAL",
    "VAR_EXTERNAL",
    "VAR_TEMP",
    "VAR_STAT",
    "VAR_INST",
    "END_VAR",
    "IF",
    "THEN",
    "ELSIF",
    "ELSE",
    "END_IF",
    "CASE",
    "OF",
    "END_CASE",
    "FOR",
    "TO",
    "BY",
    "DO",
    "END_FOR",
    "WHILE",
    "END_WHILE",
    "REPEAT",
    "UNTIL",
    "END_REPEAT",
    "RETURN",
    "EXIT",
    "CONTINUE",
    "TYPE",
    "END_TYPE",
    "STRUCT",
    "END_STRUCT",
    "ARRAY",
    "CONFIGURATION",
    "END_CONFIGURATION",
    "RESOURCE",
    "END_RESOURCE",
    "TASK",
    "WITH",
    "ON",
    "CONSTANT",
    "RETAIN",
    "PERSISTENT",
    "AT",
    "METHOD",
    "END_METHOD",
    "INTERFACE",
    "END_INTERFACE",
    "PROPERTY",
    "END_PROPERTY",
    "EXTENDS",
    "IMPLEMENTS",
    "THIS",
    "SUPER",
    "TEST",
    "END_TEST",
    "SETUP",
    "END_SETUP",
    "TEARDOWN",
    "END_TEARDOWN",
    "INTERVAL",
    "PRIORITY",
    "SINGLE",
    "MOD",
    "AND",
    "OR",
    "XOR",
    "NOT",
    "TRUE",
    "FALSE",
    "REF_TO",
    "REF",
    "POINTER",
    "REFERENCE",
    "GET",
    "SET",
    "PUBLIC",
    "PRIVATE",
    "PROTECTED",
    "INTERNAL",
    "ABSTRACT",
    "FINAL",
    "OVERRIDE",
    "ACTION",
    "END_ACTION",
    "STEP",
    "END_STEP",
    "INITIAL_STEP",
    "TRANSITION",
    "END_TRANSITION",
    "FROM",
    "READ_ONLY",
    "READ_WRITE",
    "VAR_CONFIG",
    "VAR_ACCESS",
    "AND_THEN",
    "OR_ELSE",
}


def _lit_kind(tok: str) -> str | None:
    u = tok.upper()
    if u in ("TRUE", "FALSE"):
        return "bool"
    if tok[:1] in ("'", '"'):
        return "string"
    if re.fullmatch(r"\d[\d_]*|\d+#[0-9A-F_]+", u):
        return "int"
    if re.fullmatch(r"\d[\d_]*(\.\d+)?(E[+-]?\d+)?", u):
        return "real"
    prefix = u.split("#")[0]
    if prefix in ("T", "TIME", "LT", "LTIME"):
        return "time"
    if prefix in ("D", "DATE", "TOD", "TIME_OF_DAY", "DT", "DATE_AND_TIME", "LDT", "LTOD", "LDATE"):
        return "date"
    if prefix in ("REAL", "LREAL"):
        return "real"
    if prefix in _INT_TYPES:
        return "int"
    return None


def _is_name(t: str) -> bool:
    return bool(re.fullmatch(r"[A-Za-z_]\w*", t)) and t.upper() not in _KEYWORDS and t.upper() not in _TYPE_NAMES


def _in_body(toks: list, k: int) -> bool:
    """Is token k after the last END_VAR of its POU (a statement, not a declaration)?"""
    for m in range(k, -1, -1):
        up = toks[m].upper()
        if up == "END_VAR":
            return True
        if up.startswith("VAR") or up in ("TYPE", "STRUCT", "END_STRUCT", "END_TYPE", "CONFIGURATION", "RESOURCE"):
            return False
    return False


def _add_decls(toks: list, before: int, decls: str) -> list:
    """Put `decls` on the line after the header of the POU that contains token `before`."""
    heads = [m for m in range(before) if toks[m].upper() in _HEADS and (m == 0 or toks[m - 1].isspace())]
    if not heads:
        return toks
    end = next((m for m in range(heads[-1], len(toks)) if "\n" in toks[m]), len(toks) - 1)
    return toks[: end + 1] + [decls] + toks[end + 1 :]


_OPEN = {"IF", "CASE", "FOR", "WHILE", "REPEAT"}
_CLOSE = {"END_IF", "END_CASE", "END_FOR", "END_WHILE", "END_REPEAT"}


def _statement_ends(toks: list, sig: list) -> tuple:
    """The ';' of statements in bodies, and those at the top level of a PROGRAM's body (reached
    in every scan, unless an earlier statement returns)."""
    ends, top = [], []
    depth, pou = 0, ""
    for m in sig:
        up = toks[m].upper()
        if up in _HEADS or up == "ACTION":
            depth, pou = 0, up
        elif up in _OPEN:
            depth += 1
        elif up in _CLOSE:
            depth = max(0, depth - 1)
        elif up == ";" and _in_body(toks, m):
            ends.append(m)
            if depth == 0 and pou == "PROGRAM":
                top.append(m)
    return ends, top


def _insert_statement(toks, sig, rng, stmt, decls, tail=""):
    ends, top = _statement_ends(toks, sig)
    bodies = top if top and rng.random() < 0.7 else ends or [rng.choice(sig)]
    k = rng.choice(bodies)
    toks = toks[: k + 1] + ["\n", stmt, "\n"] + toks[k + 1 :]
    toks = _add_decls(toks, k, decls)
    return toks + [tail] if tail else toks


# mutation kinds and their weights: most keep the program compilable, so that the runtime is
# exercised too
MUTATIONS = {
    "delete-token": 2,
    "duplicate-token": 1,
    "swap-tokens": 1,
    "delete-line": 2,
    "duplicate-line": 1,
    "swap-lines": 1,
    "replace-name": 4,
    "extreme-literal": 14,
    "swap-operator": 6,
    "swap-type": 5,
    "fault-statement": 16,
    "recursion": 2,
    "pragma": 2,
    "nest-brackets": 2,
    "nest-ifs": 1,
    "truncate": 1,
}
_KINDS, _WEIGHTS = list(MUTATIONS), list(MUTATIONS.values())


def _mutate_once(toks: list, rng: random.Random, kind: str | None = None) -> list:
    sig = _significant(toks)
    if not sig:
        return toks
    kind = kind or rng.choices(_KINDS, weights=_WEIGHTS)[0]
    i = rng.choice(sig)
    k = rng.randrange(1000)  # suffix of inserted names
    if kind == "delete-token":
        return toks[:i] + toks[i + 1 :]
    if kind == "duplicate-token":
        return toks[: i + 1] + [" ", toks[i]] + toks[i + 1 :]
    if kind == "swap-tokens":
        j = rng.choice(sig)
        toks = list(toks)
        toks[i], toks[j] = toks[j], toks[i]
        return toks
    if kind in ("delete-line", "duplicate-line", "swap-lines"):
        lines = "".join(toks).splitlines(keepends=True)
        a, b = rng.randrange(len(lines)), rng.randrange(len(lines))
        if kind == "delete-line":
            del lines[a]
        elif kind == "duplicate-line":
            lines.insert(a, lines[a] if lines[a].endswith("\n") else lines[a] + "\n")
        else:
            lines[a], lines[b] = lines[b], lines[a]
        return tokens("".join(lines))
    if kind == "replace-name":
        names = [t for t in toks if _is_name(t)]
        spots = [m for m in sig if _is_name(toks[m])]
        if names and spots:
            return _replace(toks, rng.choice(spots), rng.choice(names))
        return toks
    if kind == "extreme-literal":
        spots = [m for m in sig if _LITERAL.fullmatch(toks[m])]
        if not spots:
            return toks
        i = rng.choice(spots)
        lk = _lit_kind(toks[i])
        pool = EXTREMES[lk] if lk and rng.random() < 0.7 else ALL_EXTREMES
        return _replace(toks, i, rng.choice(pool))
    if kind == "swap-operator":
        spots = [m for m in sig if toks[m].upper() in BINARY or toks[m].upper() == "NOT"]
        if not spots:
            return toks
        return _replace(toks, rng.choice(spots), " " + rng.choice(BINARY if rng.random() < 0.8 else OPERATORS) + " ")
    if kind == "swap-type":
        spots = [m for m in sig if toks[m].upper() in _TYPE_NAMES]
        if not spots:
            return toks
        return _replace(toks, rng.choice(spots), rng.choice(TYPES))
    if kind == "fault-statement":
        return _insert_statement(toks, sig, rng, rng.choice(STATEMENTS).format(k=k), DECLS.format(k=k))
    if kind == "recursion":
        tail, decls, call = (s.format(k=k) for s in rng.choice(RECURSION))
        return _insert_statement(toks, sig, rng, call, decls, tail)
    if kind == "pragma":
        p = rng.choice(PRAGMAS)
        if rng.random() < 0.3:  # at the top, where a dialect pragma belongs
            return [p, "\n"] + toks
        starts = [m for m in sig if m == 0 or "\n" in toks[m - 1]]
        i = rng.choice(starts or sig)
        return toks[:i] + [p, " "] + toks[i:]
    if kind == "nest-brackets":
        n = rng.choice([5, 50, 200, 1000, 3000, 10000])
        opener, closer = rng.choice([("(", ")"), ("(", ")"), ("[", "]"), ("-", ""), ("NOT ", ""), ("(", "")])
        spots = [m for m in sig if (_is_name(toks[m]) or _LITERAL.fullmatch(toks[m])) and _in_body(toks, m)]
        i = rng.choice(spots) if spots and rng.random() < 0.8 else i
        return toks[:i] + [opener * n, toks[i], closer * n] + toks[i + 1 :]
    if kind == "nest-ifs":
        n = rng.choice([5, 25, 200, 2000])
        spots = [m for m in sig if toks[m] == ";" and _in_body(toks, m)]
        if not spots:
            return toks
        i = rng.choice(spots)
        return toks[: i + 1] + ["\n", "IF TRUE THEN " * n, "RETURN;", " END_IF;" * n, "\n"] + toks[i + 1 :]
    return toks[: max(i, 1)]  # truncate


def _replace(toks, i, new):
    return toks[:i] + [new] + toks[i + 1 :]


def mutate(text: str, rng: random.Random, n: int | None = None) -> str:
    """One to four mutations (or n) of the text, drawn from rng."""
    toks = tokens(text)
    for _ in range(n if n is not None else rng.randint(1, 4)):
        toks = _mutate_once(toks, rng)
    return "".join(toks)


def mutant(seed: int, index: int, programs: list | None = None) -> tuple:
    """(base program name, mutated text): a pure function of (seed, index) and the corpus."""
    programs = programs if programs is not None else corpus()
    rng = random.Random(f"st-fuzz:{seed}:{index}")
    name, text = programs[rng.randrange(len(programs))]
    return name, mutate(text, rng)


# ---------------------------------------------------------------------- classification


@dataclass
class Outcome:
    cls: str  # ok, diagnostics, fault:KIND, or one of DEFECTS
    signature: str = ""  # for defects: what groups them
    detail: str = ""

    @property
    def defect(self) -> bool:
        return not self.cls.startswith(ACCEPTABLE)


def _norm(text: str, words: int = 8) -> str:
    """The first words of a message, numbers and quoted names blanked (one signature per bug)."""
    text = re.sub(r"'[^']*'|\"[^\"]*\"", "'…'", text)
    text = re.sub(r"\b\d[\d_.eE+]*\b", "N", text)
    return " ".join(text.split()[:words])[:120]


def _frame(exc: BaseException) -> str:
    """The exception's type and the innermost frame of the st package (not this module)."""
    frames = [
        f
        for f in traceback.extract_tb(exc.__traceback__)
        if f.filename.startswith(str(PACKAGE)) and not f.filename.endswith("testing/fuzz.py")
    ]
    if not frames:
        return type(exc).__name__
    f = frames[-1]
    return f"{type(exc).__name__} at {Path(f.filename).relative_to(PACKAGE)}:{f.name}"


def _located(d, name: str, lines: int) -> bool:
    s = d.span
    return s.file == name and 1 <= s.line <= lines + 1 and s.col >= 1


def _fault_outcome(f) -> Outcome:
    if f.kind not in NAMED_KINDS or _PYTHON_TEXT.search(f.message) or not f.file or f.line < 1:
        why = "" if f.file and f.line >= 1 else "unlocated "
        return Outcome("raw-fault", f"{why}[{f.kind}] {_norm(f.message)}", str(f)[:300])
    return Outcome(f"fault:{f.kind}")


def run_one(
    source: str,
    filename: str = "fuzz.st",
    scans: int = 20,
    timeout: float | None = None,
    watchdog="100ms",
    phase: Callable | None = None,
) -> Outcome:
    """Compile `source` as `st check`/`st run` do; if it compiles, start a PLC on virtual time with
    the watchdog budget `watchdog` per job and run `scans` base ticks. With `timeout` (seconds),
    do it in a fresh isolated worker process that is killed after that long (a `timeout` or `crash`
    outcome then); without, in this process. `phase(name)` is told compile / start / scan."""
    if timeout is not None:
        w = Worker(timeout=timeout, watchdog=watchdog, scans=scans)
        try:
            return w.classify(source, filename)
        finally:
            w.close()
    from ..api import compile_text
    from ..runtime.faults import PLCFaultError, PLCStartError
    from ..runtime.plc import PLC

    tell = phase or (lambda p: None)
    tell("compile")
    try:
        compiled = compile_text(source, filename, raise_on_error=False, use_cache=False)
    except Exception as e:
        return Outcome("internal", f"compile: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
    errors = [d for d in compiled.diagnostics if d.is_error]
    internal = [d for d in compiled.diagnostics if d.code == "E099"]
    if internal:
        d = internal[0]
        return Outcome("internal", f"E099 {_norm(d.message)}", f"{d.span}: {d.message}"[:300])
    n_lines = source.count("\n") + 1
    stray = [d for d in errors if not _located(d, filename, n_lines)]
    if stray:
        d = stray[0]
        where = "in a library file" if d.span.file != filename else "unlocated"
        return Outcome("internal", f"{where} {d.code} {_norm(d.message)}", f"{d.span}: {d.message}"[:300])
    if errors:
        return Outcome("diagnostics")
    tell("start")
    try:
        plc = PLC(compiled, watchdog=watchdog)
    except PLCStartError as e:
        f = getattr(e, "fault", None)
        if f is not None:
            out = _fault_outcome(f)
            return out if not out.defect else Outcome("start-error", "start: " + out.signature, out.detail)
        return Outcome("start-error", f"start: {_norm(str(e))}", str(e)[:300])
    except Exception as e:
        return Outcome("crash", f"start: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
    tell("scan")
    try:
        plc.scan(scans)
    except PLCFaultError as e:
        return _fault_outcome(e.fault)
    except Exception as e:
        return Outcome("crash", f"scan: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
    finally:
        try:
            plc.close()
        except Exception:
            pass
    return Outcome("ok")


classify = run_one


# ---------------------------------------------------------------------- isolation
# The worker is a plain `python -c` subprocess (no multiprocessing start method to re-import the
# caller's __main__); messages are length-prefixed pickles on its stdin and stdout.


def _write(f, obj) -> None:
    data = pickle.dumps(obj)
    f.write(struct.pack("<I", len(data)) + data)
    f.flush()


def _read_exact(fd: int, n: int) -> bytes:
    buf = b""
    while len(buf) < n:
        chunk = os.read(fd, n - len(buf))
        if not chunk:
            raise EOFError
        buf += chunk
    return buf


def _worker_main(mem_limit: int) -> None:
    """The worker process: classify the mutants read from stdin, one message per phase and one
    per outcome on the original stdout (stray prints go to stderr)."""
    import resource

    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    import st.api  # noqa: F401 - imports done before the first timeout starts
    import st.runtime.plc  # noqa: F401

    if mem_limit:  # a mutant that allocates gigabytes gets a MemoryError, not the machine's memory
        resource.setrlimit(resource.RLIMIT_AS, (mem_limit, mem_limit))
    fd = sys.stdin.fileno()
    _write(out, ("ready", None))
    while True:
        try:
            (n,) = struct.unpack("<I", _read_exact(fd, 4))
            job = pickle.loads(_read_exact(fd, n))
        except EOFError:
            return
        if job is None:
            return
        source, name, scans, watchdog = job
        try:
            res = run_one(source, name, scans=scans, watchdog=watchdog, phase=lambda p: _write(out, ("phase", p)))
        except BaseException as e:  # what escapes run_one is itself a defect
            res = Outcome("crash", f"classify: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
        _write(out, ("done", res))


class Worker:
    """One long-lived subprocess classifying mutants; a mutant that takes longer than `timeout`
    seconds of wall-clock time is a `timeout`, one that kills the process a `crash` (their
    signature names the phase: compile, start or scan); the worker is then replaced. The worker's
    address space is limited to `mem_limit` bytes."""

    def __init__(self, timeout: float = 10.0, watchdog="100ms", scans: int = 20, mem_limit: int = 3 << 30):
        self.timeout = timeout
        self.watchdog = watchdog
        self.scans = scans
        self.mem_limit = mem_limit
        self.proc: subprocess.Popen | None = None
        self.restarts = 0

    def _start(self) -> None:
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
        self.proc = subprocess.Popen(
            [sys.executable, "-c", f"from st.testing.fuzz import _worker_main; _worker_main({self.mem_limit})"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=env,
            cwd=str(ROOT),
        )
        try:
            msg = self._recv(120)
        except EOFError:
            msg = None
        if msg != ("ready", None):
            self.close()
            raise RuntimeError("the fuzz worker did not start (try: python -c 'import st.testing.fuzz')")

    def _recv(self, timeout: float):
        """The next message, or None after `timeout` seconds; EOFError if the worker died."""
        assert self.proc is not None and self.proc.stdout is not None  # started, stdout=PIPE
        fd = self.proc.stdout.fileno()
        if not select.select([fd], [], [], max(0.0, timeout))[0]:
            return None
        (n,) = struct.unpack("<I", _read_exact(fd, 4))
        return pickle.loads(_read_exact(fd, n))

    def classify(self, source: str, name: str = "fuzz.st", on_phase: Callable[[str], None] | None = None) -> Outcome:
        """The mutant's outcome; `on_phase(phase)` is told each phase the worker enters (compile,
        start, scan) as it reports it."""
        if self.proc is not None and self.proc.poll() is not None:
            self._replace()
        if self.proc is None:
            self._start()
        proc = self.proc
        assert proc is not None  # _start made it
        try:
            _write(proc.stdin, (source, name, self.scans, self.watchdog))
        except OSError:
            pass  # died: seen as EOF below
        deadline = time.monotonic() + self.timeout
        phase = "compile"
        while True:
            try:
                msg = self._recv(deadline - time.monotonic())
            except (EOFError, OSError):
                code = proc.wait(5)
                self._replace()
                return Outcome("crash", f"worker died in {phase} (exit {code})", "")
            if msg is None:
                self._replace()
                return Outcome("timeout", f"timeout in {phase}", f"more than {self.timeout:g} s")
            tag, value = msg
            if tag == "phase":
                phase = value
                if on_phase is not None:
                    on_phase(phase)
                continue
            return value

    def _replace(self) -> None:
        """Kill the worker after a timeout or a death; the next mutant starts a new one."""
        self.restarts += 1
        self.close()

    def close(self) -> None:
        if self.proc is not None:
            try:
                if self.proc.poll() is None:
                    self.proc.kill()
                self.proc.wait(5)
            finally:
                for f in (self.proc.stdin, self.proc.stdout):
                    assert f is not None  # both are pipes
                    try:
                        f.close()
                    except OSError:
                        pass
        self.proc = None


# ---------------------------------------------------------------------- shrinking


def shrink(source: str, signature: str, check: Callable, budget: int = 300) -> str:
    """Remove chunks of lines, then single lines, then tokens, while `check(text)` still gives a
    defect of this signature; at most `budget` calls of `check`."""

    def same(parts):
        nonlocal budget
        budget -= 1
        out = check("".join(parts))
        return out.defect and out.signature == signature

    def reduce(parts, chunk):
        while chunk >= 1 and budget > 0:
            i = 0
            while i < len(parts) and budget > 0:
                trial = parts[:i] + parts[i + chunk :]
                if trial and same(trial):
                    parts = trial
                else:
                    i += chunk
            chunk //= 2
        return parts

    lines = source.splitlines(keepends=True)
    lines = reduce(lines, max(1, len(lines) // 4))
    toks = tokens("".join(lines))
    toks = reduce(toks, max(1, len(toks) // 16))
    return "".join(toks)
