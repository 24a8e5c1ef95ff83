"""TcUnit test suites as tests: a TwinCAT/CODESYS project that uses TcUnit (https://tcunit.org),
run on virtual time until TcUnit reports every suite finished, each `TEST('name')` a result.

TcUnit's model: a test suite is a function block extending `TcUnit.FB_TestSuite` (its FB_init
registers it in `GVL_TcUnit.TestSuiteAddresses`); each test is a `TEST('name')` … `TEST_FINISHED()`
section of the suite's body or of a method it calls, run again every cycle until finished; the
program calls `TcUnit.RUN()` every cycle, which calls every unfinished suite and sets
`GVL_TcUnit.TcUnitRunner.AllTestSuitesFinished` once all are. Each suite keeps its tests in
`Tests[1..NumberOfTests]` (FB_Test: TestName, TestIsFinished, TestIsSkipped, TestIsFailed, the
first failed assertion's message and type, NumberOfAssertions). A failed assertion is written to
TcUnit's message queue as `FAILED TEST '<suite>@<test>', EXP: …, ACT: …, MSG: …`; the queue hands
one message every other cycle to ADSLOGSTR (st: PLC.log, `plc.log`).

`run_tcunit` compiles the project once with its libraries, builds a PLC on virtual time and scans
until AllTestSuitesFinished, at most `max_cycles` scans. It reads the results from those structures
(`plc` paths and the instances themselves), the messages from PLC.log plus the ones still queued
(decoded from the queue's ring buffer, so no waiting for the queue to drain), and maps each failed
assertion to the ST line of its Assert call (the call in the test's section whose Message is the
message). A suite that never finishes is a located failure of each test it left unfinished; a PLC
fault in a suite fails the test that ran (with the fault and its ST line) and ends that suite (its
other unfinished tests fail as not finished), the other suites run on.

What st adds to the program for TcUnit, as TwinCAT's runtime would: each suite's `InstancePath`
(`{attribute 'instance-path'}`, which st does not fill) is set to `<project>.<instance path>`, and
`TwinCAT_SystemInfoVarList._AppInfo.ProjectName` to the .plcproj's name, so TcUnit's messages name
suites as TwinCAT's do (`PRG_TEST.Suite@Test`).
"""

from __future__ import annotations

import fnmatch
import os
import re
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..model import types as T
from ..runtime import byteimage, paths
from ..runtime.faults import FaultInfo, PLCFaultError
from ..runtime.messages import LogMessage
from ..runtime.values import from_python, to_python

DEFAULT_MAX_CYCLES = 10_000
DEFAULT_WATCHDOG = "60s"  # per scan: TcUnit's first scans register hundreds of tests and are slow today
SUITE_BASE = "fb_testsuite"

PASSED, FAILED, SKIPPED = "passed", "failed", "skipped"


# ---------------------------------------------------------------------- results


@dataclass
class Failure:
    """One failed assertion (or why a test did not pass): TcUnit's message and where in the ST."""

    text: str  # TcUnit's line: "FAILED TEST 'PRG_TEST.S@T', EXP: 1, ACT: 2, MSG: m", or st's reason
    expected: str = ""
    actual: str = ""
    message: str = ""  # the assertion's Message argument
    file: str = ""  # the Assert call (or the TEST, or the fault) in the ST sources
    line: int = 0
    kind: str = "assert"  # assert | fault | unfinished | not run
    candidates: list[int] = field(default_factory=list)  # lines of the Assert calls it may be
    end_line: int = 0  # the last line of the Assert call

    def where(self) -> str:
        if self.line:
            return f"{self.file}:{self.line}"
        if self.candidates:
            return f"{self.file}:{self.candidates[0]} (or {', '.join(map(str, self.candidates[1:]))})"
        return self.file


@dataclass
class TestResult:
    __test__ = False

    suite: str  # the suite's instance path, "PRG_TEST.PrimitiveTypes"
    name: str  # the test's name as TcUnit keeps it (trimmed, without "disabled_")
    status: str  # passed | failed | skipped
    failures: list[Failure] = field(default_factory=list)
    file: str = ""  # where its TEST('name') is
    line: int = 0
    asserts: int = 0  # TcUnit's NumberOfAssertions
    registered: bool = True  # TcUnit saw its TEST() call

    @property
    def nodeid(self) -> str:
        return f"{self.suite}::{self.name}"


@dataclass
class Suite:
    """One registered test suite instance: its path, block type and the tests its ST names."""

    path: str
    type_name: str
    index: int  # TcUnit's registry position, 1-based (its ID is index - 1)
    tests: dict[str, tuple[str, int, bool]]  # name → (file, line, disabled) of each literal TEST('…')
    obj: Any = field(default=None, repr=False)
    pou: Any = field(default=None, repr=False)


@dataclass
class Run:
    """What one run of a project's TcUnit suites gave."""

    tests: list[TestResult]
    suites: list[Suite]
    cycles: int  # scans run
    plc_time: int  # ns of PLC time at the end
    finished: bool  # TcUnit reported every suite finished
    wall: float  # seconds
    scan_times: list[float]  # seconds of wall time per scan
    messages: list[str]  # PLC.log, then what TcUnit still had queued
    faults: list[FaultInfo] = field(default_factory=list)
    limit_note: str = ""  # why the run stopped early
    message_kinds: list[str] = field(default_factory=list)  # each message's: error, warning, hint or log

    def counts(self) -> dict[str, int]:
        out = {PASSED: 0, FAILED: 0, SKIPPED: 0}
        for t in self.tests:
            out[t.status] += 1
        return out

    def select(self, keyword: str = "") -> list[TestResult]:
        if not keyword:
            return list(self.tests)
        pat = keyword if any(c in keyword for c in "*?[") else f"*{keyword}*"
        return [t for t in self.tests if fnmatch.fnmatch(t.nodeid.lower(), pat.lower())]

    def result(self, suite: str, name: str) -> TestResult | None:
        for t in self.tests:
            if t.suite.lower() == suite.lower() and t.name == name:
                return t
        return None


class NotATcUnitProject(ValueError):
    """The compiled program has no TcUnit (no FB_TestSuite) or no suite instance."""


# ---------------------------------------------------------------------- libraries and dialect


def library_files(project: Iterable[str], libs: Iterable[str]) -> tuple[list[str], list[str]]:
    """(files to compile beside the project, the library search path). A .plcproj finds the
    libraries it references itself (compiler/libpath.py: `libs`, then ST_LIBPATH); ST files
    reference none, so each library project of `libs` is compiled with them (a folder: every
    .plcproj below it)."""
    from ..compiler import libpath

    libs = [str(x) for x in libs]
    if any(str(p).lower().endswith(".plcproj") for p in project):
        return [], libs
    out: list[str] = []
    for entry in libs:
        for f in libpath.projects_in(entry) if os.path.isdir(entry) else [entry]:
            if f not in out:
                out.append(f)
    return out, []


def choose_dialect(paths: list[str], dialect: str | None) -> str | None:
    """The dialect: as given, else the one a `{dialect '…'}` pragma of the sources names (None:
    the compiler reads it), else twincat (TcUnit is TwinCAT's; a CODESYS project says so with the
    pragma or --dialect codesys)."""
    if dialect is not None:
        return dialect
    for f in _project_sources(paths):
        try:
            if _DIALECT_PRAGMA.search(Path(f).read_text(encoding="utf-8-sig", errors="replace")):
                return None
        except OSError:
            continue
    return "twincat"


_DIALECT_PRAGMA = re.compile(r"\{\s*dialect\s+'", re.I)


def _project_sources(paths: Iterable) -> list[str]:
    """The files of these paths: a .plcproj's <Compile> files (found as TwinCAT finds them), others as they are."""
    from ..compiler import twincat

    out = []
    for p in paths:
        p = str(p)
        if p.lower().endswith(".plcproj"):
            try:
                xml = Path(p).read_text(encoding="utf-8-sig", errors="replace")
            except OSError:
                continue
            out += twincat.project_files(p, xml)
        else:
            out.append(p)
    return out


def compile_project(project: Iterable, libs: Iterable = (), dialect: str | None = None, **compile_kw):
    """The project's files (a .plcproj, or ST/TwinCAT files) and its libraries, compiled once
    (CompileError when they do not compile)."""
    from ..api import compile_paths

    files = [str(p) for p in project]
    extra, search = library_files(files, libs)
    every = files + extra
    return compile_paths(every, dialect=choose_dialect(every, dialect), lib_path=search, **compile_kw)


def uses_tcunit(path: str | Path) -> bool:
    """Cheap test (no compile) whether a .plcproj (or an ST/TwinCAT file) holds a TcUnit test
    suite: a function block EXTENDS FB_TestSuite in one of its files."""
    for f in _project_sources([path]):
        try:
            if _EXTENDS_SUITE.search(Path(f).read_text(encoding="utf-8-sig", errors="replace")):
                return True
        except OSError:
            continue
    return False


_EXTENDS_SUITE = re.compile(r"\bEXTENDS\s+(?:[A-Za-z_]\w*\s*\.\s*)?FB_TestSuite\b", re.I)


# ---------------------------------------------------------------------- the program's TcUnit state


class _Inst:
    """A block instance or structure with its type: fields read and written by ST name."""

    __slots__ = ("obj", "t")

    def __init__(self, obj: Any, t: Any):
        self.obj, self.t = obj, T.unalias(t)

    def _sym(self, name: str) -> Any:
        t = self.t
        sym: T.VarSym | T.Member | None
        if isinstance(t, T.POUType):
            sym = t.vars.get(name.lower())
        elif isinstance(t, T.StructType):
            sym = t.members.get(name.lower())
        else:
            raise KeyError(f"{t.name} has no variables")
        if sym is None:
            raise KeyError(f"{t.name} has no variable {name}")
        return sym

    def has(self, name: str) -> bool:
        t = self.t
        if isinstance(t, T.POUType):
            return name.lower() in t.vars
        return isinstance(t, T.StructType) and name.lower() in t.members

    def raw(self, name: str) -> Any:
        return getattr(self.obj, self._sym(name).pyname)

    def get(self, name: str) -> Any:
        s = self._sym(name)
        return to_python(getattr(self.obj, s.pyname), s.type)

    def set(self, name: str, value: Any) -> None:
        s = self._sym(name)
        setattr(self.obj, s.pyname, from_python(value, s.type, name))

    def child(self, name: str) -> _Inst:
        s = self._sym(name)
        return _Inst(getattr(self.obj, s.pyname), s.type)

    def items(self, name: str) -> tuple[list, Any]:
        """An array variable: (its elements, the element type)."""
        s = self._sym(name)
        at = T.unalias(s.type)
        if not isinstance(at, T.ArrayType):
            raise KeyError(f"{name} is not an array")
        return getattr(self.obj, s.pyname), at.element


def _global(plc, name: str, type_name: str | None = None) -> _Inst | None:
    """A global variable by name (and its type's name when several globals share the name)."""
    syms = plc.project.global_names.get(name.lower()) or []
    for s in syms:
        if type_name is None or getattr(T.unalias(s.type), "name", "").lower() == type_name.lower():
            return _Inst(plc.ns.get(s.pyname), s.type)
    return None


def _global_value(plc, name: str) -> Any:
    syms = plc.project.global_names.get(name.lower()) or []
    if not syms:
        return None
    s = syms[0]
    return plc.ns.get(s.pyname), s.type


def _extends_suite(pou: Any) -> bool:
    b = pou
    while isinstance(b, T.POUType):
        if b.name.lower() == SUITE_BASE:
            return True
        b = b.base
    return False


def _instance_paths(plc) -> dict[int, tuple[str, Any]]:
    """id(block instance) → (its path, its POUType), for the instances of the programs and the
    globals, arrays of blocks included (not the elements of structures: suites are not there)."""
    out: dict[int, tuple[str, Any]] = {}

    def walk(v: Any, t: Any, path: str, depth: int) -> None:
        u = T.unalias(t)
        if v is None or depth > 12:
            return
        if isinstance(u, T.POUType) and u.pou_kind in ("FUNCTION_BLOCK", "PROGRAM"):
            if id(v) in out:
                return
            out[id(v)] = (path, u)
            for s in u.vars.values():
                if s.section in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP") or s.is_global:
                    continue
                st = T.unalias(s.type)
                if isinstance(st, T.POUType) or (
                    isinstance(st, T.ArrayType) and isinstance(T.unalias(st.element), T.POUType)
                ):
                    walk(getattr(v, s.pyname, None), s.type, f"{path}.{s.name}", depth + 1)
        elif isinstance(u, T.ArrayType) and isinstance(T.unalias(u.element), T.POUType):
            for flat, x in enumerate(v):
                walk(x, u.element, path + _subscript(u, flat), depth + 1)

    for name, obj, pou in plc.instances.values():
        walk(obj, pou, name, 0)
    for g in plc.project.globals.values():
        walk(plc.ns.get(g.pyname), g.type, g.name, 0)
    return out


def _subscript(at: Any, flat: int) -> str:
    idx = []
    for lo, hi in reversed(at.dims):
        n = hi - lo + 1
        idx.append(lo + flat % n)
        flat //= n
    return "[" + ", ".join(str(i) for i in reversed(idx)) + "]"


def _deref(p: Any) -> Any:
    """The instance a POINTER TO / REFERENCE TO value designates (None for a null one)."""
    if p is None:
        return None
    get = getattr(p, "get", None)
    return get() if get is not None else p


# ---------------------------------------------------------------------- static view of the tests


_TEST_CALL = re.compile(
    r"\bTEST(?:_ORDERED)?\s*\(\s*(?:TestName\s*:=\s*)?'((?:[^'$]|\$.)*)'\s*\)",
    re.I,
)
_SECTION_END = re.compile(r"\bTEST(?:_ORDERED)?\s*\(|\bEND_METHOD\b|\bEND_FUNCTION_BLOCK\b|\bEND_ACTION\b", re.I)
_ASSERT_CALL = re.compile(r"\b(Assert\w*)\s*\(", re.I)
_STRING = re.compile(r"'((?:[^'$]|\$.)*)'")


def _st_string(s: str) -> str:
    """The value of an ST string literal's inside ($' $$ $N $T $R $L $P and $hh)."""
    out, i = "", 0
    esc = {"n": "\n", "l": "\n", "r": "\r", "t": "\t", "p": "\f", "'": "'", "$": "$", '"': '"'}
    while i < len(s):
        c = s[i]
        if c == "$" and i + 1 < len(s):
            k = s[i + 1]
            if k.lower() in esc:
                out += esc[k.lower()]
                i += 2
                continue
            if i + 2 < len(s) and re.fullmatch(r"[0-9A-Fa-f]{2}", s[i + 1 : i + 3]):
                out += chr(int(s[i + 1 : i + 3], 16))
                i += 3
                continue
        out += c
        i += 1
    return out


def _test_name(raw: str) -> tuple[str, bool]:
    """(TcUnit's name for TEST(raw): trimmed, without a leading 'disabled_'; whether disabled)."""
    name = raw.strip()
    if name.lower().startswith("disabled_"):
        return name[len("disabled_") :], True
    return name, False


@dataclass
class _Region:
    file: str
    start: int  # offsets into the comment-free text
    end: int
    text: str  # the comment-free text of the whole file
    source: Any


class _Sources:
    """The ST of the suites' blocks, comments blanked, and what is found in it."""

    def __init__(self, compiled):
        self.compiled = compiled
        self.sources = compiled.sources
        self._clean: dict[str, str] = {}
        self._regions: dict[str, list[_Region]] = {}
        self._calls: dict[tuple[int, int, int], list[_Call]] = {}  # (region, start, end) → its Assert calls

    def text(self, file: str) -> str:
        if file not in self._clean:
            src = self.sources.get(file)
            self._clean[file] = _blank_comments(src.text) if src is not None else ""
        return self._clean[file]

    def regions(self, pou: Any) -> list[_Region]:
        """The text of a block and of its ancestors below FB_TestSuite: from its declaration to the
        next POU declared in the same file (a TwinCAT file holds one POU and its methods)."""
        key = pou.name.lower()
        if key in self._regions:
            return self._regions[key]
        out = []
        b = pou
        while isinstance(b, T.POUType) and b.name.lower() != SUITE_BASE:
            decl = getattr(b, "decl", None)
            span = getattr(decl, "span", None)
            if span is not None and span.file in self.sources:
                src = self.sources[span.file]
                text = self.text(span.file)
                start = src.offset(span.line, 1)
                later = [
                    p.decl.span.line
                    for p in self.compiled.project.pous.values()
                    if getattr(getattr(p, "decl", None), "span", None) is not None
                    and p.decl.span.file == span.file
                    and p.decl.span.line > span.line
                ]
                end = src.offset(min(later), 1) if later else len(text)
                out.append(_Region(span.file, start, end, text, src))
            b = b.base
        self._regions[key] = out
        return out

    def tests(self, pou: Any) -> dict[str, tuple[str, int, bool]]:
        out: dict[str, tuple[str, int, bool]] = {}
        for r in self.regions(pou):
            for m in _TEST_CALL.finditer(r.text, r.start, r.end):
                name, disabled = _test_name(_st_string(m.group(1)))
                if name and name not in out:
                    out[name] = (r.file, r.source.position(m.start())[0], disabled)
        return out

    def assert_line(self, pou: Any, test: str, failure: Failure, first_type: str = "") -> None:
        """Set `failure`'s place: the Assert call of `test` whose Message is the failure's message
        (and, when several are, whose literal Expected is TcUnit's EXP, and whose method can raise
        the test's first failure's type), among the calls of the test's section (from its TEST to
        the next TEST or the end of the method), else of the whole suite. Several calls left: the
        place stays unset and `candidates` lists their lines."""
        sections, whole = [], []
        for r in self.regions(pou):
            for m in _TEST_CALL.finditer(r.text, r.start, r.end):
                if _test_name(_st_string(m.group(1)))[0] != test:
                    continue
                nxt = _SECTION_END.search(r.text, m.end(), r.end)
                sections += self._asserts(r, m.end(), nxt.start() if nxt else r.end)
            whole += self._asserts(r, r.start, r.end)
        for calls in (sections, whole):
            hits = [c for c in calls if _message_matches(c.message, failure.message)]
            if len(hits) > 1:
                same = [c for c in hits if _literal_is(c.expected, failure.expected)]
                hits = same or hits
            if len(hits) > 1 and first_type:
                hits = [c for c in hits if _type_matches(c.method, first_type)] or hits
            if len(hits) == 1:
                failure.file, failure.line, failure.end_line = hits[0].file, hits[0].line, hits[0].end_line
                return
            if hits:
                failure.candidates = sorted({c.line for c in hits})
                failure.file = hits[0].file
                return

    def _asserts(self, r: _Region, start: int, end: int) -> list[_Call]:
        """Each Assert call in range: its place, method, Message literal and Expected text (read
        once per range: a suite's failures all look among the same calls)."""
        key = (id(r), start, end)
        if key not in self._calls:
            self._calls[key] = self._read_asserts(r, start, end)
        return self._calls[key]

    def _read_asserts(self, r: _Region, start: int, end: int) -> list[_Call]:
        out = []
        text = r.text
        for m in _ASSERT_CALL.finditer(text, start, end):
            args = _call_args(text, m.end())
            line, end = r.source.position(m.start())[0], r.source.position(m.end() + len(args))[0]
            out.append(_Call(r.file, line, m.group(1), _message_arg(args), _expected_arg(args), end))
        return out


@dataclass
class _Call:
    file: str
    line: int
    method: str
    message: str | None
    expected: str
    end_line: int


_COMMENT_TOKEN = re.compile(r"\(\*|\*\)|/\*|\*/|//|\{|\}|'|\"|\n")


def _blank_comments(text: str) -> str:
    """The text with comments ((* *) nested, /* */, //) and pragmas ({ }) blanked, strings kept:
    every offset, line and column unchanged."""
    out = list(text)
    depth, mode, start, pos = 0, "", 0, 0  # mode: "" code, "(" / "/" / "{" comment, "'" / '"' string
    for m in _COMMENT_TOKEN.finditer(text):
        tok, at = m.group(), m.start()
        if at < pos:
            continue
        pos = m.end()
        if mode in ("'", '"'):
            if tok == mode and text[at - 1 : at] != "$":
                mode = ""
            continue
        if mode == "":
            if tok in ("'", '"'):
                mode = tok
            elif tok in ("(*", "/*", "{"):
                mode, depth, start = tok[0], 1, at
            elif tok == "//":
                end = text.find("\n", at)
                end = len(text) if end < 0 else end
                out[at:end] = " " * (end - at)
                pos = end
            continue
        opener, closer = {"(": ("(*", "*)"), "/": ("/*", "*/"), "{": ("{", "}")}[mode]
        if tok == opener and mode == "(":
            depth += 1
        elif tok == closer:
            depth -= 1
            if depth == 0:
                out[start : m.end()] = [c if c == "\n" else " " for c in text[start : m.end()]]
                mode = ""
    if mode in ("(", "/", "{"):
        out[start:] = [c if c == "\n" else " " for c in text[start:]]
    return "".join(out)


def _call_args(text: str, pos: int) -> str:
    """The text between the '(' that ends before `pos` and its ')' (strings skipped)."""
    depth, i, n = 1, pos, len(text)
    while i < n and depth:
        c = text[i]
        if c == "'":
            j = text.find("'", i + 1)
            while j > 0 and text[j - 1] == "$" and text[j - 2 : j] != "$$":
                j = text.find("'", j + 1)
            i = n if j < 0 else j + 1
            continue
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
        i += 1
    return text[pos : i - 1]


def _message_arg(args: str) -> str | None:
    m = re.search(r"\bMessage\s*:=\s*'((?:[^'$]|\$.)*)'", args, re.I)
    if m:
        return _st_string(m.group(1))
    if ":=" not in args:
        lits = _STRING.findall(args)
        if lits:
            return _st_string(lits[-1])
    return None


def _expected_arg(args: str) -> str:
    """The text of the Expected argument (named, else the first positional one)."""
    m = re.search(r"\bExpecteds?\s*:=\s*([^,]*)", args, re.I)
    if m:
        return m.group(1).strip()
    return args.split(",")[0].strip() if ":=" not in args else ""


def _literal_is(text: str, shown: str) -> bool:
    """Whether an Expected argument is a literal TcUnit shows as `shown` (numbers compared as
    numbers, 16#AB as 0xAB, strings by their value)."""
    if not text or not shown:
        return False
    t = text.strip()
    if t.startswith("'") and t.endswith("'"):
        return _st_string(t[1:-1]) == shown
    t = re.sub(r"^(?:[A-Za-z_]+#)(?=[-+0-9])", "", t).replace("_", "")
    if re.fullmatch(r"16#[0-9A-Fa-f]+", t):
        return shown.lower().startswith("0x") and int(t[3:], 16) == int(shown, 16)
    try:
        a, b = float(t), float(shown)
    except ValueError:
        return t.upper() == shown.upper()
    return a == b or abs(a - b) <= 1e-9 * max(abs(a), abs(b))


def _message_matches(literal: str | None, message: str) -> bool:
    if literal is None:
        return False
    if literal == message:
        return True
    # TcUnit appends to an array assertion's message, and shortens long ones to fit 253 characters
    return bool(literal) and (
        message.startswith(literal + ", size of") or (len(message) > 40 and literal.startswith(message))
    )


_TYPE_OF_ASSERT = {"asserttrue": "bool", "assertfalse": "bool", "assertequals": "any"}


def _type_matches(method: str, assertion_type: str) -> bool:
    """Whether an Assert method (AssertEquals_INT, AssertArrayEquals_REAL, AssertTrue) can have
    raised TcUnit's E_AssertionType (Type_INT, Type_Array_REAL, Type_BOOL)."""
    t = assertion_type.lower().removeprefix("type_")
    m = method.lower()
    if m in _TYPE_OF_ASSERT:
        return _TYPE_OF_ASSERT[m] == t
    if t.startswith("array2d_") or t.startswith("array3d_"):
        return m == f"assertarray{t[5:7]}equals_{t[8:]}"
    if t.startswith("array_"):
        return m == f"assertarrayequals_{t[6:]}"
    return m == f"assertequals_{t}"


# ---------------------------------------------------------------------- TcUnit's messages


_FAILED = re.compile(
    r"^FAILED TEST '(?P<where>.*?)', EXP: (?P<exp>.*?), ACT: (?P<act>.*?)(?:, MSG: (?P<msg>.*))?$", re.S
)


def _adslog_text(fmt: str, arg: str) -> str:
    """ADSLOGSTR's text: the format with %s (and %d, %f) replaced by the argument."""
    out, i = "", 0
    while i < len(fmt):
        c = fmt[i]
        if c == "%" and i + 1 < len(fmt):
            k = fmt[i + 1]
            out += "%" if k == "%" else str(arg) if k in "sdf" else fmt[i : i + 2]
            i += 2
            continue
        out += c
        i += 1
    return out[:253]


def _queued_messages(plc) -> list[tuple[int, str]]:
    """The messages still in TcUnit's queue (FB_AdsLogStringMessageFifoQueue: records of
    ST_AdsLogStringMessage in a FB_MemRingBuffer over a byte array), oldest first, with their
    ADSLOG_MSGTYPE mask."""
    q = _global(plc, "AdsMessageQueue")
    rec_t = plc.project.types.get("st_adslogstringmessage")
    if q is None or rec_t is None or not (q.has("ArrayBuffer") and q.has("MemRingBuffer")):
        return []
    spec = T.byte_layout(rec_t)
    if spec is None or spec[0] != "r":
        return []
    ring = q.child("MemRingBuffer")
    if not (ring.has("head") and ring.has("nCount")):
        return []  # another FB_MemRingBuffer than st's
    buf = q.raw("ArrayBuffer")
    cb = len(buf)
    head, count = int(ring.raw("head")), int(ring.raw("nCount"))
    members = {name.lower(): (off, ms) for name, off, ms in spec[2]}
    out = []
    for _ in range(count):
        n = int.from_bytes(bytes(buf[(head + k) % cb] for k in range(4)), "little")
        data = bytes(buf[(head + 4 + k) % cb] for k in range(n))
        head = (head + 4 + n) % cb
        try:
            mask, fmt, arg = (_member(data, *members[name]) for name in ("msgctrlmask", "msgfmtstr", "strarg"))
        except (KeyError, IndexError, ValueError):
            break
        out.append((int(mask), _adslog_text(str(fmt), str(arg))))
    return out


def _member(data: bytes, offset: int, spec: Any) -> Any:
    return byteimage.unpack(spec, data[offset : offset + byteimage.size(spec)])


def _clean_path(path: str, project_name: str) -> str:
    """F_RemoveInstancePathAndProjectNameFromTestInstancePath: the path without everything up to
    and including the first '<project>.' (twice: the project may also be the namespace)."""
    key = project_name + "."
    for _ in range(2):
        i = path.find(key)
        if i >= 0:
            path = path[i + len(key) :]
    return path


# ---------------------------------------------------------------------- the run


class TcUnitProject:
    """A compiled project with TcUnit suites, built as a PLC on virtual time (not yet run)."""

    def __init__(self, compiled, *, project_name: str = "", cycle=None, watchdog=DEFAULT_WATCHDOG):
        from .harness import TestPLC

        self.compiled = compiled
        self.plc = TestPLC(compiled, cycle, watchdog=watchdog)
        self._src = _Sources(compiled)
        self.project_name = project_name
        self.runner = _global(self.plc, "TcUnitRunner", "FB_TcUnitRunner")
        registry = _global_value(self.plc, "TestSuiteAddresses")
        count = _global_value(self.plc, "NumberOfInitializedTestSuites")
        if self.runner is None or registry is None or count is None:
            raise NotATcUnitProject("the program does not use TcUnit (no GVL_TcUnit.TcUnitRunner)")
        where = _instance_paths(self.plc)
        self.suites: list[Suite] = []
        for i in range(int(count[0])):
            obj = _deref(registry[0][i])
            path, pou = where.get(id(obj), (f"TestSuite{i + 1}", None))
            if pou is None:
                pou = next((p for p in compiled.project.pous.values() if p.pyname == type(obj).__name__), None)
            tests = self._src.tests(pou) if pou is not None else {}
            self.suites.append(Suite(path, pou.name if pou is not None else "?", i + 1, tests, obj, pou))
        self._ran: Run | None = None
        self._app_name = ""  # TwinCAT_SystemInfoVarList._AppInfo.ProjectName while running
        self._limit = ""  # "N cycles (… s of PLC time)"

    @classmethod
    def load(
        cls,
        project: Iterable,
        libs: Iterable = (),
        *,
        dialect: str | None = None,
        cycle=None,
        watchdog=DEFAULT_WATCHDOG,
        **compile_kw,
    ) -> TcUnitProject:
        files = [str(p) for p in project]
        compiled = compile_project(files, libs, dialect, **compile_kw)
        name = _plcproj_name(files)
        return cls(compiled, project_name=name, cycle=cycle, watchdog=watchdog)

    # ------------------------------------------------------------------ preparing
    def _prepare(self, only: set[str] | None) -> list[Suite]:
        plc = self.plc
        app = _global(plc, "_AppInfo")
        if self.project_name and app is not None and app.has("ProjectName"):
            app.set("ProjectName", self.project_name[:63])
        project_name = app.get("ProjectName") if app is not None and app.has("ProjectName") else ""
        self._app_name = project_name
        for s in self.suites:
            inst = _Inst(s.obj, s.pou) if s.pou is not None else None
            if inst is not None and inst.has("InstancePath") and not inst.get("InstancePath"):
                inst.set("InstancePath", (f"{project_name}.{s.path}" if project_name else s.path)[:255])
        running = self.suites
        if only is not None:  # TcUnit runs the suites its registry lists: list only those
            running = [s for s in self.suites if s.path.lower() in only]
            reg, _t = _global_value(plc, "TestSuiteAddresses")
            keep = [reg[s.index - 1] for s in running]
            for i, v in enumerate(keep):
                reg[i] = v
            cont, key, _t = paths.resolve(plc, "NumberOfInitializedTestSuites")
            paths.write(cont, key, len(keep))
        return running

    # ------------------------------------------------------------------ running
    def run(
        self,
        *,
        max_cycles: int = DEFAULT_MAX_CYCLES,
        suites: Iterable[str] | None = None,
        drain_log: bool = False,
        on_scan: Callable[[int, float], None] | None = None,
    ) -> Run:
        """Scan until TcUnit reports every suite finished (and its results stored), at most
        `max_cycles` scans; `suites`: run only these suite instances (paths); `drain_log`: go on
        until TcUnit's message queue is empty (every message in PLC.log: 2 scans a message)."""
        if self._ran is not None:
            return self._ran
        only = {s.lower() for s in suites} if suites is not None else None
        running = self._prepare(only)
        plc = self.plc
        runner = self.runner
        assert runner is not None
        results = runner.child("TestResults") if runner.has("TestResults") else None
        queue = _global(plc, "AdsMessageQueue")
        ring = queue.child("MemRingBuffer") if queue is not None and queue.has("MemRingBuffer") else None
        t0 = time.perf_counter()
        scan_times: list[float] = []
        faults: list[FaultInfo] = []
        aborted: dict[str, tuple[str, FaultInfo]] = {}  # suite path → (test, fault)
        cycles, finished, note = 0, False, ""
        self._limit = f"{max_cycles} cycles ({max_cycles * plc.tick / 1e9:g} s of PLC time)"

        def done() -> bool:
            if not runner.get("AllTestSuitesFinished"):
                return False
            if results is not None and results.has("StoredGeneralTestResults"):
                if not (results.get("StoredTestSuiteResults") and results.get("StoredGeneralTestResults")):
                    return False
            if drain_log and ring is not None and ring.has("nCount") and ring.get("nCount"):
                return False
            return True

        while True:
            if done():
                finished = True
                break
            if cycles >= max_cycles:
                note = f"TcUnit did not report every suite finished within {self._limit}"
                break
            ts = time.perf_counter()
            try:
                plc.scan()
            except PLCFaultError as e:
                faults.append(e.fault)
                if not self._abort_suite(e.fault, aborted):
                    note = f"a PLC fault outside the test suites ended the run: {e.fault}"
                    cycles += 1
                    scan_times.append(time.perf_counter() - ts)
                    break
                plc.reset_fault()
            cycles += 1
            scan_times.append(time.perf_counter() - ts)
            if on_scan is not None:
                on_scan(cycles, scan_times[-1])
        logged = [(m.mask, m.text) for m in plc.log.entries] + _queued_messages(plc)
        messages = [text for _mask, text in logged]
        kinds = [LogMessage(0, mask, "").kind for mask, _text in logged]
        tests = self._results(running, messages, aborted, finished, note)
        self._ran = Run(
            tests,
            running,
            cycles,
            plc.time,
            finished,
            time.perf_counter() - t0,
            scan_times,
            messages,
            faults,
            note,
            kinds,
        )
        return self._ran

    def _suite_of(self, obj: Any) -> Suite | None:
        return next((s for s in self.suites if s.obj is obj), None)

    def _abort_suite(self, fault: FaultInfo, aborted: dict) -> bool:
        """A fault while a suite ran: its current test failed, the suite ended (every test it
        registered marked finished, so TcUnit calls it no more). False: no suite to blame."""
        if fault.pou.split(".")[0].lower() in _RUNNER_BLOCKS:
            return False  # TcUnit's own bookkeeping after the suites, not a test
        cur = _global_value(self.plc, "CurrentTestSuiteBeingCalled")
        suite = self._suite_of(_deref(cur[0])) if cur is not None else None
        if suite is None or suite.path in aborted or suite.pou is None:
            return False
        inst = _Inst(suite.obj, suite.pou)
        name_v = _global_value(self.plc, "CurrentTestNameBeingCalled")
        test = str(to_python(*name_v)) if name_v is not None else ""
        aborted[suite.path] = (test, fault)
        tests, et = inst.items("Tests")
        for i in range(min(int(inst.get("NumberOfTests")), len(tests))):
            t = _Inst(tests[i], et)
            if not t.get("TestIsFinished") and not t.get("TestIsSkipped"):
                t.set("TestIsFinished", True)
                t.set("TestIsFailed", True)
                if not t.get("AssertionMessage"):
                    why = (
                        f"PLC fault [{fault.kind}]: {fault.message}"
                        if t.get("TestName") == test
                        else (f"not finished: the suite ended at a PLC fault in test '{test}'")
                    )
                    t.set("AssertionMessage", why[:255])
        return True

    # ------------------------------------------------------------------ reading the results
    def _results(self, running: list[Suite], messages: list[str], aborted: dict, finished: bool, note: str):
        failures: dict[tuple[str, str], list[Failure]] = {}
        app = self._app_name
        by_clean = {}  # the suite as TcUnit's messages name it → the suite
        for s in running:
            inst = _Inst(s.obj, s.pou) if s.pou is not None else None
            own = str(inst.get("InstancePath")) if inst is not None and inst.has("InstancePath") else ""
            own = own or (f"{app}.{s.path}" if app else s.path)
            by_clean[(_clean_path(own, app) if app else own).lower()] = s
        for text in messages:
            m = _FAILED.match(text)
            if not m:
                continue
            where = m.group("where")
            at = where.rfind("@")
            suite = by_clean.get(where[:at].lower()) if at >= 0 else None
            if suite is None:
                continue
            f = Failure(text, m.group("exp"), m.group("act"), m.group("msg") or "")
            failures.setdefault((suite.path, where[at + 1 :]), []).append(f)
        out: list[TestResult] = []
        for s in running:
            if s.pou is None:
                continue
            inst = _Inst(s.obj, s.pou)
            arr, et = inst.items("Tests")
            seen = set()
            for i in range(min(int(inst.get("NumberOfTests")), len(arr))):
                t = _Inst(arr[i], et)
                name = str(t.get("TestName"))
                if name in seen:
                    continue
                seen.add(name)
                file, line, _disabled = s.tests.get(name, ("", 0, False))
                r = TestResult(s.path, name, PASSED, [], file, line, int(t.get("NumberOfAssertions")))
                fs = failures.get((s.path, name), [])
                first_type = str(t.get("AssertionType"))
                for k, f in enumerate(fs):
                    self._src.assert_line(s.pou, name, f, first_type if k == 0 else "")
                _spread(fs)
                fault_test, fault = aborted.get(s.path, ("", None))
                if t.get("TestIsSkipped"):
                    r.status = SKIPPED
                elif fault is not None and name == fault_test:
                    r.status = FAILED
                    r.failures = fs + [
                        Failure(
                            f"PLC fault [{fault.kind}]: {fault.message}" + (f" (in {fault.pou})" if fault.pou else ""),
                            file=fault.file,
                            line=fault.line,
                            kind="fault",
                        )
                    ]
                elif t.get("TestIsFailed") and (fs or fault is None):
                    r.status = FAILED
                    r.failures = fs or [Failure(str(t.get("AssertionMessage")), message=str(t.get("AssertionMessage")))]
                    for f in r.failures:
                        if not f.file:
                            f.file, f.line = file, line
                elif not t.get("TestIsFinished") or (fault is not None and t.get("TestIsFailed")):
                    r.status = FAILED
                    why = (
                        f"did not finish: the suite ended at a PLC fault in test '{fault_test}'"
                        if fault is not None
                        else f"did not finish within {self._limit}: TEST_FINISHED() was never called"
                        if not note or note.startswith("TcUnit did not")
                        else f"did not finish: {note}"
                    )
                    r.failures = fs + [Failure(f"{s.path}@{name} {why}", file=file, line=line, kind="unfinished")]
                out.append(r)
            for name, (file, line, disabled) in s.tests.items():
                if name in seen:
                    continue
                r = TestResult(s.path, name, SKIPPED, [], file, line, 0, registered=False)
                if disabled:
                    pass
                elif not finished or s.path in aborted:
                    r.status = FAILED
                    why = (
                        f"the suite ended at a PLC fault in test '{aborted[s.path][0]}'"
                        if s.path in aborted
                        else note or "the run stopped"
                    )
                    r.failures = [Failure(f"{s.path}@{name} was not run: {why}", file=file, line=line, kind="not run")]
                else:
                    r.failures = [
                        Failure(
                            f"{s.path}@{name}: TcUnit never registered this test (its TEST call did not run)",
                            file=file,
                            line=line,
                            kind="not run",
                        )
                    ]
                out.append(r)
        return out


def _spread(failures: list[Failure]) -> None:
    """Failures that may each be any of the same n Assert calls, n of them: TcUnit logs failures
    in the order the calls ran, so the k-th is the k-th call."""
    groups: dict[tuple, list[Failure]] = {}
    for f in failures:
        if not f.line and f.candidates:
            groups.setdefault((f.file, tuple(f.candidates)), []).append(f)
    for (_file, lines), fs in groups.items():
        if len(fs) == len(lines):
            for f, line in zip(fs, lines):
                f.line, f.candidates = line, []


# TcUnit's blocks that run after the suites in a cycle (a fault there is no test's)
_RUNNER_BLOCKS = frozenset(
    n.lower()
    for n in (
        "FB_TcUnitRunner",
        "FB_TestResults",
        "FB_AdsTestResultLogger",
        "FB_xUnitXmlPublisher",
        "FB_AdsLogStringMessageFifoQueue",
        "RUN",
        "RUN_IN_SEQUENCE",
    )
)


def _plcproj_name(files: list[str]) -> str:
    """The <Name> of the first .plcproj among the files (TwinCAT's project name), else ''."""
    for f in files:
        if f.lower().endswith(".plcproj"):
            try:
                xml = Path(f).read_text(encoding="utf-8-sig", errors="replace")
            except OSError:
                continue
            m = re.search(r"<Name>\s*([^<]+?)\s*</Name>", xml)
            return m.group(1) if m else Path(f).stem
    return ""


def run_tcunit(
    project: Iterable | str,
    libs: Iterable = (),
    *,
    dialect: str | None = None,
    max_cycles: int = DEFAULT_MAX_CYCLES,
    cycle=None,
    watchdog=DEFAULT_WATCHDOG,
    suites: Iterable[str] | None = None,
    drain_log: bool = False,
) -> Run:
    """Compile a project (a .plcproj or ST/TwinCAT files) with its libraries (`libs`: library
    .plcproj files or folders of them, see `library_files`), run its TcUnit suites and return the
    results (see the module doc)."""
    files = [project] if isinstance(project, (str, Path)) else list(project)
    prj = TcUnitProject.load(files, libs, dialect=dialect, cycle=cycle, watchdog=watchdog)
    return prj.run(max_cycles=max_cycles, suites=suites, drain_log=drain_log)


# ---------------------------------------------------------------------- reports


def format_failure(r: TestResult, sources: dict | None = None, context: int = 3) -> str:
    """A failed test: each failure's ST place and TcUnit's line, then the ST up to its Assert call
    (or the Assert calls it may be, marked '?')."""
    out = []
    for f in r.failures:
        out.append((f"{f.where()}: " if f.file else "") + f.text)
        src = (sources or {}).get(f.file)
        if src is None:
            continue
        if f.line:
            last = max(f.line, min(f.end_line, f.line + 5))
            width = len(str(last))
            for n in range(max(1, f.line - context), last + 1):
                out.append(f"{'>' if n == f.line else ' '} {n:>{width}} | {src.line_text(n).rstrip()}")
        for n in f.candidates:
            out.append(f"? {n} | {src.line_text(n).rstrip()}")
    return "\n".join(out)


def summary_lines(run: Run) -> list[str]:
    """TcUnit's own summary, from the results st read."""
    c = run.counts()
    return [
        "| ==========TESTS FINISHED RUNNING=========="
        if run.finished
        else "| ==========TESTS DID NOT FINISH==========",
        f"| Test suites: {len(run.suites)}",
        f"| Tests: {len(run.tests)}",
        f"| Successful tests: {c[PASSED]}",
        f"| Failed tests: {c[FAILED]}",
        f"| Skipped tests: {c[SKIPPED]}",
        f"| Cycles: {run.cycles} ({run.plc_time / 1e9:g} s of PLC time, {run.wall:.1f} s wall)",
        "| ======================================",
    ]


def command(
    files, libs, *, keyword: str = "", quiet: bool = False, max_cycles: int = DEFAULT_MAX_CYCLES, dialect=None
) -> int:
    """`st test PROJECT.plcproj --lib …`: run the project's TcUnit suites, print each test (PASS,
    FAIL with TcUnit's messages and the ST of the Assert call, SKIP) and TcUnit's summary; the
    exit code (0 all passed, 1 a test failed, 2 no compile, 5 no test)."""
    import click

    from ..diagnostics import CompileError

    try:
        project = TcUnitProject.load(list(files), list(libs), dialect=dialect)
    except CompileError as e:
        click.echo(e.render(), err=True)
        return 2
    except NotATcUnitProject as e:
        click.echo(f"{', '.join(files)}: {e} (give its TcUnit library with --lib or ST_LIBPATH)", err=True)
        return 5
    chosen = None
    if keyword:  # run only the suites that hold a matching test
        pat = keyword if any(c in keyword for c in "*?[") else f"*{keyword}*"
        chosen = [
            s.path
            for s in project.suites
            if fnmatch.fnmatch(s.path.lower(), pat.lower())
            or any(fnmatch.fnmatch(f"{s.path}::{n}".lower(), pat.lower()) for n in s.tests)
        ]
    run = project.run(max_cycles=max_cycles, suites=chosen)
    results = run.select(keyword)
    if not results:
        click.echo("no tests ran" + (f" (none matches -k {keyword!r})" if keyword else ""))
        return 5
    label = {PASSED: click.style("PASS", fg="green"), FAILED: click.style("FAIL", fg="red"), SKIPPED: "SKIP"}
    for r in results:
        if quiet and r.status != FAILED:
            continue
        where = f"  ({r.file}:{r.line})" if r.file else ""
        click.echo(f"{label[r.status]}  {r.suite}@{r.name}{where}")
        if r.status == FAILED:
            for line in format_failure(r, project.compiled.sources).splitlines():
                click.echo("      " + line)
    for line in summary_lines(run):
        click.echo(line)
    failed = sum(1 for r in results if r.status == FAILED)
    skipped = sum(1 for r in results if r.status == SKIPPED)
    click.echo(
        f"{len(results) - failed - skipped} passed, {failed} failed" + (f", {skipped} skipped" if skipped else "")
    )
    return 1 if failed else 0
