"""The pytest plugin (entry point `pytest11`): ST test files next to Python tests.

- `test_*.st` / `*_test.st` files are collected; every TEST block is one item, so `-k`, `-x`,
  `--lf` and pytest-xdist work as for Python tests. A file is compiled with its source by
  convention (`test_X.st` + `X.st`) and with the ini option `st_sources` (globs).
- A failure shows the TEST's ST lines up to the failing statement, then actual and expected.
- The `plc` fixture is a factory of `TestPLC`s (virtual time, helpers to drive inputs).
- `--st-cov` measures ST line and branch coverage (also of PLCs made by the fixture),
  `--st-cov-html DIR` writes it as HTML; with xdist the workers' data is merged.
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from ..diagnostics import CompileError
from .runner import TestSuite, is_test_file, resolve_sources

_BUILDS_KEY = pytest.StashKey[list]()  # every CompiledProgram with coverage probes, this process
_SUITES_KEY = pytest.StashKey[dict]()  # resolved file list → TestSuite (or the compile error)


def pytest_addoption(parser):
    group = parser.getgroup("st", "IEC 61131-3 Structured Text")
    group.addoption(
        "--st-cov",
        action="store_true",
        default=False,
        help="measure which ST lines and branches the tests ran; print a table",
    )
    group.addoption("--st-cov-html", default=None, metavar="DIR", help="also write ST coverage as HTML into DIR")
    group.addoption("--st-timeout", default="10s", metavar="DURATION", help="watchdog per ST TEST block (default 10s)")
    parser.addini(
        "st_sources",
        type="linelist",
        default=[],
        help="ST source files (globs, relative to the ini file) compiled with every ST test file",
    )


def pytest_configure(config):
    config.stash[_BUILDS_KEY] = []
    config.stash[_SUITES_KEY] = {}


def _measuring(config) -> bool:
    return bool(config.getoption("st_cov") or config.getoption("st_cov_html"))


def _ini_sources(config) -> list:
    base = Path(config.inipath).parent if config.inipath else Path(config.rootpath)
    out: list[str] = []
    for pattern in config.getini("st_sources"):
        matches = sorted(base.glob(pattern))
        if not matches and not any(c in pattern for c in "*?["):
            raise pytest.UsageError(f"st_sources: {pattern} does not exist (relative to {base})")
        out.extend(str(m) for m in matches)
    return out


def pytest_collect_file(file_path: Path, parent):
    if is_test_file(file_path):
        return StFile.from_parent(parent, path=file_path)
    return None


def _rel(config, path) -> str:
    """Paths as the user typed them: relative to where pytest was started, when below it."""
    base = config.invocation_params.dir
    try:
        return str(Path(path).resolve().relative_to(Path(base).resolve()))
    except ValueError:
        return str(path)


class StFile(pytest.File):
    def collect(self):
        suite = self._suite()
        here = _rel(self.config, self.path)
        for case in suite.cases:
            if case.file == here:
                yield StItem.from_parent(self, name=case.name, case=case, suite=suite)

    def _suite(self) -> TestSuite:
        config = self.config
        files = tuple(resolve_sources([_rel(config, self.path)], [_rel(config, p) for p in _ini_sources(config)]))
        cache = config.stash[_SUITES_KEY]
        if files not in cache:
            from ..api import compile_paths

            try:
                compiled = compile_paths(list(files), coverage=_measuring(config))
            except CompileError as e:
                cache[files] = e
            else:
                if compiled.coverage_hits is not None:
                    config.stash[_BUILDS_KEY].append(compiled)
                cache[files] = TestSuite(compiled, config.getoption("st_timeout"))
        got = cache[files]
        if isinstance(got, CompileError):
            raise self.CollectError(got.render())
        return got


class StTestFailure(Exception):
    def __init__(self, result):
        super().__init__(str(result.report))
        self.result = result


class StItem(pytest.Item):
    def __init__(self, *, case, suite, **kw):
        super().__init__(**kw)
        self.case = case
        self.suite = suite

    def runtest(self):
        result = self.suite.run(self.case)
        if not result.passed:
            raise StTestFailure(result)

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, StTestFailure):
            return format_failure(excinfo.value.result, self.suite.compiled.sources)
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self):
        return self.path, self.case.line - 1, f"TEST '{self.case.name}'"


def format_failure(result, sources: dict, context: int = 12) -> str:
    """Where and what first (pytest's summary shows that line), then the TEST's ST lines up to
    the failing one (marked '>'), then 'E' lines with actual and expected values."""
    r, case = result.report, result.case
    where = f"{r.file}:{r.line}" + (f":{r.col}" if r.col else "")
    out = [f"{where}: {r.message}", ""]
    src = sources.get(r.file)
    if src is not None and r.line:
        first = max(r.line - context, case.line if r.file == case.file and case.line <= r.line else 1)
        width = len(str(r.line))
        for n in range(first, r.line + 1):
            out.append(f"{'>' if n == r.line else ' '} {n:>{width}} | {src.line_text(n)}")
        if r.col:
            out.append(" " * (width + 5 + r.col - 1) + "^")
    out.append(f"E   {r.message}")
    out += [f"E     {d}" for d in r.details()]
    return "\n".join(out)


# ---------------------------------------------------------------------- the plc fixture


@pytest.fixture(scope="session")
def plc(request):
    """A factory of PLCs on virtual time: plc("programs/x.st"), plc(source="PROGRAM ..."), cycle="10ms"."""
    from ..api import compile_paths, compile_text
    from .harness import TestPLC

    config = request.config

    def make(*paths, source: str | None = None, cycle=None, **compile_kw):
        if (source is None) == (not paths):
            raise TypeError("plc(): give file paths or source=..., not both")
        measure = _measuring(config)
        if source is not None:
            compiled = compile_text(source, coverage=measure, **compile_kw)
        else:
            compiled = compile_paths([str(p) for p in paths], coverage=measure, **compile_kw)
        if compiled.coverage_hits is not None:
            config.stash[_BUILDS_KEY].append(compiled)
        return TestPLC(compiled, cycle)

    return make


# ---------------------------------------------------------------------- coverage


def _collect_coverage(config):
    from .measure import coverage_data

    data = coverage_data(config.stash[_BUILDS_KEY])
    for extra in config.stash.get(_WORKER_DATA_KEY, []):
        data.merge(extra)
    return data


_WORKER_DATA_KEY = pytest.StashKey[list]()


def pytest_sessionfinish(session):
    config = session.config
    if _measuring(config) and hasattr(config, "workeroutput"):  # an xdist worker: hand the data over
        config.workeroutput["st_cov"] = _collect_coverage(config).to_json()


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    """xdist controller: merge a worker's coverage data."""
    payload = getattr(node, "workeroutput", {}).get("st_cov")
    if payload is not None:
        from .covreport import CoverageData

        config = node.config
        config.stash.setdefault(_WORKER_DATA_KEY, []).append(CoverageData.from_json(payload))


def pytest_terminal_summary(terminalreporter, config):
    if not _measuring(config) or hasattr(config, "workeroutput"):
        return
    from .covreport import html_report, terminal_report

    data = _collect_coverage(config)
    terminalreporter.section("ST coverage")
    buf = io.StringIO()
    terminal_report(data, buf)
    terminalreporter.write(buf.getvalue())
    html = config.getoption("st_cov_html")
    if html:
        terminalreporter.write_line(f"HTML report: {html_report(data, html)}")
