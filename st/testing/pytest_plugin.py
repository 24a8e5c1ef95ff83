"""The pytest plugin (entry point `pytest11`): ST test files next to Python tests.

- `test_*.st` / `*_test.st` files are collected; every TEST block is one item, so `-k`, `-x`,
  `--lf` and pytest-xdist work as for Python tests. A file is compiled with its source by
  convention (`test_X.st` + `X.st`) and with the ini option `st_sources` (globs).
- A failure shows the TEST's ST lines up to the failing statement, then actual and expected.
- The `plc` fixture is a factory of `TestPLC`s (virtual time, helpers to drive inputs).
- `--st-cov` measures ST line and branch coverage (also of PLCs made by the fixture),
  `--st-cov-html DIR` writes it as HTML; with xdist the workers' data is merged.
- TcUnit: a TwinCAT project (`.plcproj`) whose code has a TcUnit test suite is collected when
  asked for (`--st-tcunit`, ini `st_tcunit = true`, or the .plcproj named on the command line):
  every literal `TEST('name')` of a suite instance is an item `Project.plcproj::PRG.suite::name`;
  the project runs once (st.testing.tcunit) the first time one of its items runs, with the
  libraries of `--st-lib`, ini `st_libs` and ST_LIBPATH.
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from ..diagnostics import CompileError
from .runner import TestSuite, is_test_file, resolve_sources

_BUILDS_KEY = pytest.StashKey[list]()  # every CompiledProgram with coverage probes, this process
_SUITES_KEY = pytest.StashKey[dict]()  # resolved file list → TestSuite (or the compile error)
_TCUNIT_KEY = pytest.StashKey[dict]()  # .plcproj path → TcUnitProject (or why it cannot run)


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
    group.addoption(
        "--st-tcunit",
        action="store_true",
        default=None,
        help="collect TwinCAT projects (.plcproj) with TcUnit test suites: each TEST('name') an item",
    )
    group.addoption(
        "--st-lib",
        action="append",
        default=[],
        metavar="PATH",
        help="a library project (.plcproj) or a folder of them, for TcUnit projects (repeatable)",
    )
    group.addoption(
        "--st-tcunit-max-cycles",
        type=int,
        default=None,
        metavar="N",
        help="scans a TcUnit project may take before its unfinished tests fail (default 10000)",
    )
    parser.addini("st_tcunit", type="bool", default=False, help="collect TwinCAT projects with TcUnit suites")
    parser.addini(
        "st_libs",
        type="linelist",
        default=[],
        help="library projects (.plcproj, folders; globs relative to the ini file) for TcUnit projects",
    )
    parser.addini("st_tcunit_max_cycles", default="10000", help="scans a TcUnit project may take (default 10000)")


def pytest_configure(config):
    config.stash[_BUILDS_KEY] = []
    config.stash[_SUITES_KEY] = {}
    config.stash[_TCUNIT_KEY] = {}


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
    if file_path.suffix.lower() == ".plcproj" and _collect_tcunit(parent.config, file_path):
        from .tcunit import uses_tcunit

        if uses_tcunit(file_path):
            return TcUnitProjectFile.from_parent(parent, path=file_path)
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
    # no fixtures; an empty `funcargs` as a test function's, for plugins that read it from every
    # item (pytest-lsp's runtest wrapper returns without yielding from an item lacking it)
    funcargs: dict = {}

    def __init__(self, *, case, suite, **kw):
        super().__init__(**kw)
        self.case = case
        self.suite = suite
        self.funcargs = {}

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


# ---------------------------------------------------------------------- TcUnit projects


def _collect_tcunit(config, path: Path) -> bool:
    """Opted in (--st-tcunit, ini st_tcunit), or this .plcproj named on the command line."""
    opt = config.getoption("st_tcunit")
    if opt or (opt is None and config.getini("st_tcunit")):
        return True
    here = path.resolve()
    for arg in config.args:
        try:
            if Path(str(arg).split("::")[0]).resolve() == here:
                return True
        except OSError:
            continue
    return False


def _libs(config) -> list:
    """The library search path: --st-lib, then ini st_libs (globs relative to the ini file); the
    compiler reads ST_LIBPATH after them."""
    base = Path(config.inipath).parent if config.inipath else Path(config.rootpath)
    out = [str(p) for p in config.getoption("st_lib")]
    for pattern in config.getini("st_libs"):
        matches = sorted(base.glob(pattern)) if not Path(pattern).is_absolute() else [Path(pattern)]
        if not matches and not any(c in pattern for c in "*?["):
            raise pytest.UsageError(f"st_libs: {pattern} does not exist (relative to {base})")
        out.extend(str(m) for m in matches)
    return out


def _max_cycles(config) -> int:
    opt = config.getoption("st_tcunit_max_cycles")
    return int(opt) if opt is not None else int(config.getini("st_tcunit_max_cycles"))


class TcUnitProjectFile(pytest.File):
    """A .plcproj with TcUnit suites: one collector per suite instance, one item per TEST name."""

    def project(self):
        cache = self.config.stash[_TCUNIT_KEY]
        key = str(self.path)
        if key not in cache:
            from .tcunit import NotATcUnitProject, TcUnitProject

            try:
                cache[key] = TcUnitProject.load([_rel(self.config, self.path)], _libs(self.config))
            except CompileError as e:
                cache[key] = self.CollectError(e.render())
            except NotATcUnitProject as e:
                cache[key] = self.CollectError(
                    f"{_rel(self.config, self.path)}: {e} (is its TcUnit library given? --st-lib, ini st_libs, ST_LIBPATH)"
                )
        got = cache[key]
        if isinstance(got, Exception):
            raise got
        return got

    def collect(self):
        for suite in self.project().suites:
            yield TcUnitSuiteNode.from_parent(self, name=suite.path, suite=suite)

    def tcunit_run(self):
        """The project's run, once: only the suites of the items this session runs."""
        prj = self.project()
        if prj._ran is None:
            mine = {
                it.parent.name
                for it in self.session.items
                if isinstance(it, TcUnitItem) and it.parent is not None and it.parent.parent is self
            }
            run = prj.run(max_cycles=_max_cycles(self.config), suites=mine or None)
            self.config.stash.setdefault(_TCUNIT_RUNS_KEY, []).append((_rel(self.config, self.path), run))
            extra = [t for t in run.tests if not t.file and t.status == "failed"]
            if extra:
                import warnings

                warnings.warn(
                    f"{_rel(self.config, self.path)}: failed TcUnit tests whose names are not literal TEST('…') "
                    f"names (not items): {', '.join(t.nodeid for t in extra)}",
                    stacklevel=1,
                )
        return prj._ran


_TCUNIT_RUNS_KEY = pytest.StashKey[list]()  # (project, Run) of this process, for the summary


class TcUnitSuiteNode(pytest.Collector):
    def __init__(self, *, suite, **kw):
        super().__init__(**kw)
        self.suite = suite

    def collect(self):
        for name, (_file, _line, _disabled) in self.suite.tests.items():
            yield TcUnitItem.from_parent(self, name=name)


class TcUnitTestFailure(Exception):
    def __init__(self, result, text):
        super().__init__(text)
        self.result = result
        self.text = text


class TcUnitItem(pytest.Item):
    funcargs: dict = {}  # (see StItem)

    def runtest(self):
        from .tcunit import SKIPPED, format_failure

        project = self.parent.parent
        run = project.tcunit_run()
        suite = self.parent.suite.path
        r = run.result(suite, self.name)
        if r is None:
            pytest.fail(f"{suite}@{self.name}: TcUnit did not run this suite", pytrace=False)
        if r.status == SKIPPED:
            why = "disabled in TcUnit (its TEST name starts with disabled_)" if r.registered else "not run"
            raise pytest.skip.Exception(r.failures[0].text if r.failures else why, _use_item_location=True)
        if r.status != "passed":
            for f in r.failures:
                f.file = _rel(self.config, f.file) if f.file else f.file
            sources = {_rel(self.config, k): v for k, v in project.project().compiled.sources.items()}
            raise TcUnitTestFailure(r, format_failure(r, sources))

    def repr_failure(self, excinfo, style=None):
        if isinstance(excinfo.value, TcUnitTestFailure):
            return excinfo.value.text
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self):
        file, line, _d = self.parent.suite.tests.get(self.name, ("", 0, False))
        return (Path(file) if file else self.path), max(line - 1, 0), f"{self.parent.name}::{self.name}"


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
    runs = config.stash.get(_TCUNIT_RUNS_KEY, [])
    if runs:
        terminalreporter.section("TcUnit")
        for name, run in runs:
            c = run.counts()
            per = run.wall / run.cycles if run.cycles else 0.0
            terminalreporter.write_line(
                f"{name}: {len(run.suites)} suites, {len(run.tests)} tests ({c['passed']} passed, {c['failed']} failed, "
                f"{c['skipped']} skipped) in {run.cycles} scans, {run.plc_time / 1e9:g} s of PLC time, "
                f"{run.wall:.1f} s ({per * 1000:.1f} ms a scan)" + ("" if run.finished else f"; {run.limit_note}")
            )
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
