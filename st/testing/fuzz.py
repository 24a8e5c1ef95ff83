"""A fuzzer over mutated example programs: no input may crash the compiler or the runtime.

`mutant(seed, index)` is a pure function: a program of programs/ (its test file joined to the
program it tests) with one to four token-level mutations: tokens deleted, duplicated or swapped,
names, operators and type names replaced, literals replaced by extreme ones, statements inserted
that fault or never end, pragmas inserted, brackets nested deeply, the text cut short.

`classify(source)` compiles and runs a mutant and says what happened. Acceptable outcomes:
`ok`, `diagnostics` (located compile errors), `fault:KIND` (a located PLC fault of a named kind,
at start-up or in a scan). Defects: `internal` (E099 or an exception out of the compiler),
`start-error` (the PLC refused to start without a located ST fault), `raw-fault` (a fault of
the generic kind or with Python's text in it), `crash` (an exception out of the runtime),
`timeout` (see `Worker`). Defects carry a signature for grouping.
"""
from __future__ import annotations

import multiprocessing as mp
import random
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

ROOT = Path(__file__).resolve().parents[2]
ACCEPTABLE = ("ok", "diagnostics", "fault:")
DEFECTS = ("internal", "start-error", "raw-fault", "crash", "timeout")
NAMED_KINDS = {"DIV0", "INDEX", "RANGE", "NULL", "LOOP", "WATCHDOG", "CONVERSION", "OVERFLOW", "RECURSION"}
_PYTHON_TEXT = re.compile(r"\b[A-Z][a-z]+Error\b|Traceback|math domain|invalid literal|Exceeds the limit|"
                          r"too large to convert|unsupported operand|NoneType|object has no attribute")

_TOKEN = re.compile(r"\(\*.*?\*\)|//[^\n]*|'(?:[^'$\n]|\$.)*'|\"(?:[^\"$\n]|\$.)*\"|"
                    r"[A-Za-z_][A-Za-z0-9_]*#[A-Za-z0-9_.:+\-#]*|[A-Za-z_][A-Za-z0-9_]*|"
                    r"\d[\d_]*(?:\.\d+)?(?:[eE][+-]?\d+)?|%[IQM][XBWDL]?[\d.*]*|:=|=>|<>|<=|>=|\*\*|\s+|\S", re.S)
EXTREMES = ["0", "-1", "2147483647", "-2147483648", "4294967295", "18446744073709551615",
            "18446744073709551616", "1.0E308", "-1.0E308", "1.0E-320", "16#FFFFFFFFFFFFFFFF", "2#1010_1010",
            "8#777", "T#-1s", "T#106751d", "T#0s", "LT#1ns", "DT#1970-01-01-00:00:00", "DT#9999-12-31-23:59:59",
            "D#2024-02-30", "TOD#24:00:00", "TOD#23:59:59.999", "'x'", "''", "'$N$T$$'", '"w"', "TRUE", "FALSE",
            "16#" + "F" * 40, "9" * 30, "0.0", "-0.0", "REAL#1.5", "INT#-5", "BYTE#300"]
OPERATORS = ["+", "-", "*", "/", "MOD", "AND", "OR", "XOR", "NOT", "<", ">", "=", "<>", "<=", ">=", "**", "&",
             ":=", "=>", ".", "^", "#", ",", ";", "(", ")", "[", "]"]
TYPES = ["INT", "UINT", "SINT", "DINT", "UDINT", "LINT", "ULINT", "BYTE", "WORD", "DWORD", "LWORD", "BOOL", "REAL",
         "LREAL", "STRING", "WSTRING", "TIME", "LTIME", "DATE", "TOD", "DT", "CHAR", "ARRAY[0..3] OF INT",
         "ARRAY[1..0] OF INT", "STRING[1]", "REF_TO INT", "POINTER TO INT", "TON", "CTU", "R_TRIG"]
STATEMENTS = ["x_f := x_f / 0;", "WHILE TRUE DO END_WHILE;", "FOR i_f := 0 TO 2000000000 DO END_FOR;",
              "REPEAT UNTIL FALSE END_REPEAT;", "a_f[i_f + 100] := 1;", "x_f := SHL(x_f, -1);",
              "r_f := SIN(1.0E308 * 10.0);", "x_f := LREAL_TO_DINT(1.0E30);", "x_f := MUX(i_f + 99, 1, 2);",
              "x_f := x_f MOD 0;", "s_f := MID(s_f, 2, -5);", "x_f := STRING_TO_DINT(s_f);", "RETURN;", "EXIT;",
              "CONTINUE;", "x_f := x_f * x_f * x_f * x_f;", "FOR i_f := 10 TO 0 BY 0 DO END_FOR;"]
DECLS = "VAR x_f : DINT := 7; i_f : DINT; r_f : LREAL; s_f : STRING := 'abc'; a_f : ARRAY[0..3] OF INT; END_VAR\n"
PRAGMAS = ["{attribute 'hide'}", "{dialect 'codesys'}", "{dialect 'iec'}", "{dialect 'openplc'}",
           "{dialect 'bogus'}", "{{ raw c }}", "(* unterminated", "{", "(* (* nested *) *)"]


def corpus() -> list:
    """(name, text) of every example program; a test file is joined to the program it tests."""
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
    return _TOKEN.findall(text)


def _significant(toks):
    return [i for i, t in enumerate(toks) if not t.isspace() and not t.startswith(("(*", "//"))]


_LITERAL = re.compile(r"\d[\d_.eE+-]*|[A-Za-z_]+#\S+|'.*'|\".*\"|TRUE|FALSE", re.I)
_OPERATOR = {"+", "-", "*", "/", "MOD", "AND", "OR", "XOR", "<", ">", "=", "<>", "<=", ">=", "**", "&"}
_TYPE_NAMES = {t.upper() for t in TYPES if t.isalpha()}


def _mutate_once(toks: list, rng: random.Random) -> list:
    sig = _significant(toks)
    if not sig:
        return toks
    i = rng.choice(sig)
    # weights: most mutations keep the program compilable, so that the runtime is exercised too
    kind = rng.choices(range(12), weights=[2, 1, 1, 3, 14, 5, 5, 14, 0, 2, 2, 1])[0]
    names = [t for t in toks if re.fullmatch(r"[A-Za-z_]\w*", t) and t.upper() not in _TYPE_NAMES]
    pool = {3: [k for k in sig if toks[k] in names], 4: [k for k in sig if _LITERAL.fullmatch(toks[k])],
            5: [k for k in sig if toks[k].upper() in _OPERATOR], 6: [k for k in sig if toks[k].upper() in _TYPE_NAMES]}
    if kind in pool and pool[kind]:
        i = rng.choice(pool[kind])
    if kind == 0:                                       # delete a token
        return toks[:i] + toks[i + 1:]
    if kind == 1:                                       # duplicate a token
        return toks[:i + 1] + [" ", toks[i]] + toks[i + 1:]
    if kind == 2:                                       # swap two tokens
        j = rng.choice(sig)
        toks = list(toks)
        toks[i], toks[j] = toks[j], toks[i]
        return toks
    if kind == 3 and names:                             # another name of the program
        return toks[:i] + [rng.choice(names)] + toks[i + 1:]
    if kind == 4:                                       # an extreme literal
        return toks[:i] + [rng.choice(EXTREMES)] + toks[i + 1:]
    if kind == 5:                                       # an operator
        return toks[:i] + [" ", rng.choice(OPERATORS), " "] + toks[i + 1:]
    if kind == 6:                                       # a type name
        return toks[:i] + [rng.choice(TYPES)] + toks[i + 1:]
    if kind == 7:                                       # a statement that faults or never ends, in a body
        bodies = [k for k in sig if toks[k] == ";" and _in_body(toks, k)] or [i]
        k = rng.choice(bodies)
        toks = toks[:k + 1] + ["\n", rng.choice(STATEMENTS), "\n"] + toks[k + 1:]
        heads = [m for m in sig if m < k and toks[m].upper() in ("PROGRAM", "FUNCTION_BLOCK", "FUNCTION",
                                                                  "METHOD")]
        if heads:                                       # and the variables it uses, in that POU
            end = next((m for m in range(heads[-1], len(toks)) if "\n" in toks[m]), len(toks) - 1)
            toks = toks[:end + 1] + [DECLS] + toks[end + 1:]
        return toks
    if kind == 9:                                       # a pragma
        return toks[:i] + [rng.choice(PRAGMAS), " "] + toks[i:]
    if kind == 10:                                      # brackets nested deeply
        n = rng.choice([5, 50, 500, 3000])
        opener, closer = rng.choice([("(", ")"), ("[", "]"), ("-", "")])
        return toks[:i] + [opener * n, toks[i], closer * n] + toks[i + 1:]
    return toks[:max(i, 1)]                             # cut short


def _in_body(toks: list, k: int) -> bool:
    """Is token k after the last END_VAR of its POU (a statement, not a declaration)?"""
    for m in range(k, -1, -1):
        up = toks[m].upper()
        if up == "END_VAR":
            return True
        if up.startswith("VAR") or up in ("TYPE", "STRUCT", "END_STRUCT", "END_TYPE"):
            return False
    return False


def mutate(text: str, rng: random.Random) -> str:
    toks = tokens(text)
    for _ in range(rng.randint(1, 4)):
        toks = _mutate_once(toks, rng)
    return "".join(toks)


def mutant(seed: int, index: int, programs: Optional[list] = None) -> tuple:
    """(base program name, mutated text): a pure function of (seed, index)."""
    programs = programs if programs is not None else corpus()
    rng = random.Random(f"st-fuzz:{seed}:{index}")
    name, text = programs[rng.randrange(len(programs))]
    return name, mutate(text, rng)


# ---------------------------------------------------------------------- classification

@dataclass
class Outcome:
    cls: str                    # ok, diagnostics, fault:KIND, or one of DEFECTS
    signature: str = ""         # for defects: what groups them
    detail: str = ""

    @property
    def defect(self) -> bool:
        return not self.cls.startswith(ACCEPTABLE)


def _norm(text: str) -> str:
    return re.sub(r"\d+", "N", re.sub(r"'[^']*'", "'…'", text))[:100]


def _frame(exc: BaseException) -> str:
    import traceback
    st_frames = [f for f in traceback.extract_tb(exc.__traceback__) if "/st/" in f.filename]
    f = st_frames[-1] if st_frames else None
    return f"{type(exc).__name__} at {Path(f.filename).name}:{f.name}" if f else type(exc).__name__


def classify(source: str, name: str = "fuzz.st", scans: int = 5, watchdog: str = "100ms") -> Outcome:
    from ..api import compile_text
    from ..runtime.plc import PLC, PLCFaultError, PLCStartError
    try:
        compiled = compile_text(source, name, raise_on_error=False, use_cache=False)
    except Exception as e:
        return Outcome("internal", f"compile: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
    errors = [d for d in compiled.diagnostics if d.is_error and d.span.file == name]
    internal = [d for d in compiled.diagnostics if d.code == "E099"]
    if internal:
        return Outcome("internal", f"E099 {_norm(internal[0].message)}", internal[0].message[:300])
    if errors:
        return Outcome("diagnostics")
    if any(d.is_error for d in compiled.diagnostics):
        return Outcome("internal", "error in a library file", str(compiled.diagnostics[0])[:300])
    try:
        plc = PLC(compiled, watchdog=watchdog)
    except PLCStartError as e:
        f = getattr(e, "fault", None)
        if f is not None and f.kind in NAMED_KINDS and f.file and not _PYTHON_TEXT.search(f.message):
            return Outcome(f"fault:{f.kind}")
        return Outcome("start-error", f"start: {_norm(str(e))}", str(e)[:300])
    except Exception as e:
        return Outcome("crash", f"start: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
    try:
        for _ in range(scans):
            plc.scan()
    except PLCFaultError as e:
        f = e.fault
        if f.kind not in NAMED_KINDS or _PYTHON_TEXT.search(f.message) or not f.file:
            return Outcome("raw-fault", f"[{f.kind}] {_norm(f.message)}", str(f)[:300])
        return Outcome(f"fault:{f.kind}")
    except Exception as e:
        return Outcome("crash", f"scan: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
    finally:
        try:
            plc.close()
        except Exception:
            pass
    return Outcome("ok")


# ---------------------------------------------------------------------- isolation

def _serve(conn) -> None:
    import sys
    sys.setrecursionlimit(10_000)
    while True:
        job = conn.recv()
        if job is None:
            return
        source, name, watchdog = job
        try:
            out = classify(source, name, watchdog=watchdog)
        except BaseException as e:       # what escapes classify is itself a defect
            out = Outcome("crash", f"classify: {_frame(e)}", f"{type(e).__name__}: {e}"[:300])
        conn.send(out)


class Worker:
    """One long-lived subprocess classifying mutants; a mutant that takes longer than `timeout`
    seconds (or kills the process) is a defect, and the worker is replaced."""

    def __init__(self, timeout: float = 10.0, watchdog: str = "100ms"):
        self.timeout = timeout
        self.watchdog = watchdog
        self.proc = None
        self.conn = None

    def _start(self) -> None:
        ctx = mp.get_context("spawn")
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_serve, args=(child,), daemon=True)
        self.proc.start()

    def classify(self, source: str, name: str = "fuzz.st") -> Outcome:
        if self.proc is None or not self.proc.is_alive():
            self._start()
        self.conn.send((source, name, self.watchdog))
        if self.conn.poll(self.timeout):
            try:
                return self.conn.recv()
            except EOFError:
                pass
            self.close()
            return Outcome("crash", "the worker process died", "")
        self.close()
        return Outcome("timeout", "timeout", f"more than {self.timeout} s")

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.is_alive():
                self.proc.kill()
            self.proc.join(5)
        self.proc = self.conn = None


def shrink(source: str, signature: str, check, budget: int = 300) -> str:
    """Remove lines, then tokens, while `check(text)` still gives an outcome of this signature."""
    def same(text):
        nonlocal budget
        budget -= 1
        out = check(text)
        return out.defect and out.signature == signature
    lines = source.splitlines(keepends=True)
    i = 0
    while i < len(lines) and budget > 0:
        trial = lines[:i] + lines[i + 1:]
        if same("".join(trial)):
            lines = trial
        else:
            i += 1
    toks = tokens("".join(lines))
    chunk = max(1, len(toks) // 8)
    while chunk >= 1 and budget > 0:
        i = 0
        while i < len(toks) and budget > 0:
            trial = toks[:i] + toks[i + chunk:]
            if same("".join(trial)):
                toks = trial
            else:
                i += chunk
        chunk //= 2
    return "".join(toks)
