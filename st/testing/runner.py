"""Runs ST unit tests (TEST blocks) on virtual time, each in a fresh namespace.

A test is the generated function `_test_<n>()`. Before it runs, the modules are
executed into a new namespace (new globals, new FB classes, the clock at 0), so
no state or mock leaks from one test into the next. The test statements call
the helpers installed here: a failed assertion raises `TestFailed` with a
`Report` that names the file, line, statement, actual and expected values; any
other exception from ST code is a PLC fault at its ST line, and an endless loop
is ended by the watchdog.
"""

from __future__ import annotations

import fnmatch
import time
import types
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from ..model.compiled import CompiledProgram
from ..runtime.faults import PLCFault, fault_from_exception
from ..runtime.namespace import build_namespace
from ..runtime.values import parse_duration_arg, to_st_literal
from ..runtime.watchdog import Watchdog

DEFAULT_TIMEOUT = "10s"


@dataclass
class Report:
    """Why a test did not pass."""

    kind: str  # "assert" (a test statement failed) or "fault" (a PLC fault, the watchdog)
    message: str  # first line, e.g. "ASSERT_EQ(c.CV, 3) failed"
    file: str = ""
    line: int = 0
    col: int = 0
    actual: str = ""
    expected: str = ""
    note: str = ""  # the assertion's optional message

    def details(self) -> list:
        out = []
        if self.actual or self.expected:
            out += [f"actual:   {self.actual}", f"expected: {self.expected}"]
        if self.note:
            out.append(f"message:  {self.note}")
        return out

    def __str__(self) -> str:
        where = (
            f"{self.file}:{self.line}:{self.col}: " if self.col else (f"{self.file}:{self.line}: " if self.file else "")
        )
        return "\n".join([where + self.message] + ["  " + d for d in self.details()])


class TestFailed(Exception):
    __test__ = False  # (the Test* names are not pytest classes)

    def __init__(self, report: Report):
        super().__init__(str(report))
        self.report = report


@dataclass
class TestCase:
    __test__ = False

    name: str
    file: str
    line: int
    pyname: str


@dataclass
class TestResult:
    __test__ = False

    case: TestCase
    passed: bool
    report: Report | None
    duration: float  # seconds of wall time


class TestSuite:
    """The TEST blocks of one compiled program, and how to run them."""

    __test__ = False

    def __init__(self, compiled: CompiledProgram, timeout=DEFAULT_TIMEOUT):
        self.compiled = compiled
        self.asserts = compiled.project.test_asserts
        self.timeout_ns = parse_duration_arg(timeout)
        self.cases = [TestCase(t.name, t.span.file, t.span.line, t.pyname) for t in compiled.project.tests]
        # the test functions' code, defined once; each run binds one of them to its fresh namespace
        self._code: dict = {}
        for _path, code in compiled.test_modules:
            scratch: dict = {}
            exec(code, scratch)
            self._code.update({k: f.__code__ for k, f in scratch.items() if k.startswith("_test_")})

    @classmethod
    def from_paths(cls, paths: Iterable, *, coverage: bool = False, timeout=DEFAULT_TIMEOUT, **compile_kw) -> TestSuite:
        """Compile the files (plus the sources each test file names by convention) into one suite."""
        from ..api import compile_paths

        return cls(compile_paths(resolve_sources(paths), coverage=coverage, **compile_kw), timeout)

    def select(self, keyword: str = "") -> list:
        if not keyword:
            return list(self.cases)
        pat = keyword if any(c in keyword for c in "*?[") else f"*{keyword}*"
        return [c for c in self.cases if fnmatch.fnmatch(c.name.lower(), pat.lower())]

    def run_all(self, cases=None, on_result: Callable | None = None, stop_first: bool = False) -> list:
        results = []
        for case in self.cases if cases is None else cases:
            r = self.run(case)
            results.append(r)
            if on_result is not None:
                on_result(r)
            if stop_first and not r.passed:
                break
        return results

    def run(self, case: TestCase) -> TestResult:
        t0 = time.perf_counter()
        ctx = _TestContext(self)
        report = None
        try:
            ns = build_namespace(self.compiled, ctx.install)
            watchdog = ctx.watchdog
            assert watchdog is not None  # ctx.install made it
            watchdog.start(self.timeout_ns)
            try:
                types.FunctionType(self._code[case.pyname], ns, case.pyname)()
            finally:
                watchdog.stop()
        except TestFailed as f:
            report = f.report
        except Exception as exc:  # noqa: BLE001 - a fault of ST code, reported at its ST line
            info = fault_from_exception(exc)
            if info.kind == "WATCHDOG":
                info.message = f"the test did not finish within {self.timeout_ns / 1e9:g} s (endless loop?)"
            where = f" (in {info.pou})" if info.pou and not info.pou.startswith("_test_") else ""
            report = Report("fault", f"PLC fault [{info.kind}]: {info.message}{where}", info.file, info.line)
        return TestResult(case, report is None, report, time.perf_counter() - t0)


class _TestContext:
    """The helpers one test run calls (`_t_fail`, `_t_advance`, `_t_mock`, ...), bound to its namespace."""

    def __init__(self, suite: TestSuite):
        self.asserts = suite.asserts
        self.ns: dict = {}
        self.function_calls: dict = {}
        self.watchdog: Watchdog | None = None

    def install(self, ns: dict) -> None:
        self.ns = ns
        self.watchdog = Watchdog(ns)
        ns.update(
            _t_fail=self.fail,
            _t_advance=self.advance,
            _t_mock=self.mock,
            _t_mock_function=self.mock_function,
            _t_verify=self.verify,
        )

    # ------------------------------------------------------------------ assertions
    def fail(self, idx: int, msg, *vals) -> None:
        info = self.asserts[idx]
        types = list(info.types) + [None] * 3
        kind = info.kind
        fmt = to_st_literal
        if kind in ("ASSERT_TRUE", "ASSERT_FALSE"):
            actual, expected = fmt(vals[0], types[0]), "TRUE" if vals[1] else "FALSE"
        elif kind == "ASSERT_NEAR":
            a, b, tol = vals
            actual = fmt(a, types[0])
            expected = f"{fmt(b, types[1])} ± {fmt(tol, types[2])} (difference {_num(abs(a - b))})"
        else:
            actual = fmt(vals[0], types[0])
            rel = {
                "ASSERT_EQ": "",
                "ASSERT_NEQ": "not ",
                "ASSERT_GT": "> ",
                "ASSERT_LT": "< ",
                "ASSERT_GE": ">= ",
                "ASSERT_LE": "<= ",
            }[kind]
            expected = rel + fmt(vals[1], types[1])
        raise TestFailed(
            Report(
                "assert",
                f"{info.text or kind} failed",
                info.span.file,
                info.span.line,
                info.span.col,
                actual,
                expected,
                msg or "",
            )
        )

    def advance(self, duration) -> None:
        d = int(duration)
        if d < 0:
            raise PLCFault(f"ADVANCE_TIME cannot go back in time ({d} ns)", "TEST")
        self.ns["_now"] = self.ns["_now"] + d

    # ------------------------------------------------------------------ mocks
    def mock(self, inst) -> None:
        cls = type(inst)
        if getattr(cls, "_st_mock", False):
            return

        def _body(self):
            type(self)._calls += 1

        inst.__class__ = type(
            cls.__name__,
            (cls,),
            {"__slots__": (), "_body": _body, "_calls": 0, "_st_mock": True, "__module__": cls.__module__},
        )

    def mock_function(self, pyname: str, value) -> None:
        calls = self.function_calls
        calls[pyname] = 0

        def fake(*args):
            calls[pyname] += 1
            return value

        self.ns[pyname] = fake

    def verify(self, idx: int, target, expected) -> None:
        info = self.asserts[idx]
        if isinstance(target, str):
            count = self.function_calls.get(target)
            what = f"MOCK_FUNCTION {target[4:]} RETURNS ..."
        else:
            count = type(target)._calls if getattr(type(target), "_st_mock", False) else None
            what = "MOCK"
        if count is None:
            raise TestFailed(
                Report(
                    "assert",
                    f"{info.text} failed: it is not mocked (use {what} first)",
                    info.span.file,
                    info.span.line,
                    info.span.col,
                )
            )
        if expected is None:
            if count > 0:
                return
            actual, want = "never called", "called at least once"
        else:
            if count == expected:
                return
            actual, want = _times(count), _times(expected)
        raise TestFailed(
            Report("assert", f"{info.text} failed", info.span.file, info.span.line, info.span.col, actual, want)
        )


def _times(n: int) -> str:
    return f"called {n} time" + ("" if n == 1 else "s")


def _num(v) -> str:
    return f"{v:.9g}" if isinstance(v, float) else str(v)


# ---------------------------------------------------------------------- sources


def is_test_file(path) -> bool:
    name = Path(path).name.lower()
    return name.endswith(".st") and (name.startswith("test_") or name.endswith("_test.st"))


def sources_by_convention(test_file) -> list:
    """`test_X.st` / `X_test.st` is compiled with `X.st` from its directory, when that exists."""
    p = Path(test_file)
    name = p.name
    low = name.lower()
    stem = name[5:] if low.startswith("test_") else name[:-8] + ".st" if low.endswith("_test.st") else ""
    if not stem:
        return []
    cand = p.with_name(stem)
    return [cand] if cand.is_file() else []


def resolve_sources(paths: Iterable, extra: Iterable = ()) -> list:
    """Files to compile for these paths: directories give their test files; each test file brings
    its source by convention; `extra` (e.g. pytest's `st_sources`) comes first. No file twice."""
    out: list = []
    seen: set = set()

    def add(p):
        key = str(Path(p).resolve())
        if key not in seen:
            seen.add(key)
            out.append(str(p))

    for p in extra:
        add(p)
    for p in paths:
        p = Path(p)
        files = sorted(f for f in p.rglob("*.st") if is_test_file(f)) if p.is_dir() else [p]
        for f in files:
            for src in sources_by_convention(f):
                add(src)
            add(f)
    return out
