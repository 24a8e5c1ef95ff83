"""TcUnit suites as tests (st/testing/tcunit.py, the pytest plugin's TcUnit items, `st test` of a
project): the real TcUnit library from the corpora folder (skipped with a reason when absent),
small suites written here (a passing test, a failing one with TcUnit's exact message, one that
never finishes, a disabled one, a PLC fault), and TcUnit's own verifier project."""

from __future__ import annotations

import os
import textwrap
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from st.cli import main
from st.testing import tcunit

pytest_plugins = ["pytester"]

CORPORA = Path(os.environ.get("ST_CORPORA", "/work/scratch/corpora"))
TCUNIT = CORPORA / "tcunit-TcUnit"
TCUNIT_PROJECT = TCUNIT / "TcUnit/TcUnit/TcUnit.plcproj"
VERIFIER = (
    TCUNIT / "TcUnit-Verifier/TcUnit-Verifier_TwinCAT/TcUnit-Verifier_TwinCAT/TcUnitVerifier/TcUnitVerifier.plcproj"
)

pytestmark = pytest.mark.skipif(
    not TCUNIT_PROJECT.exists(),
    reason=f"TcUnit is not checked out at {TCUNIT} (set ST_CORPORA to the corpora folder)",
)

# ---------------------------------------------------------------------- a small TcUnit project

CALC_TEST = [  # (method, declaration, body): FB_Calc_Test's methods
    (
        "Passing",
        "METHOD Passing\nVAR\n    a : INT := 2;\nEND_VAR",
        "TEST('AddsUp');\nAssertEquals_INT(Expected := 4, Actual := a + a, Message := 'two and two');\nTEST_FINISHED();",
    ),
    (
        "Failing",
        "METHOD Failing\nVAR\n    a : INT := 2;\nEND_VAR",
        "TEST('FailsOnPurpose');\n"
        "AssertEquals_INT(Expected := 4, Actual := a + a, Message := 'same message');\n"
        "AssertEquals_INT(Expected := 5,\n"
        "                 Actual := a + a,\n"
        "                 Message := 'two and two is not five');\n"
        "TEST_FINISHED();",
    ),
    (
        "TakesFiveCycles",
        "METHOD TakesFiveCycles",
        "TEST('TakesFiveCycles');\ncycles := cycles + 1;\nIF cycles >= 5 THEN\n"
        "    AssertTrue(Condition := cycles = 5, Message := 'five');\n    TEST_FINISHED();\nEND_IF",
    ),
    (
        "Disabled",
        "METHOD Disabled",
        "TEST('disabled_NotYet');\nAssertTrue(Condition := FALSE, Message := 'never');\nTEST_FINISHED();",
    ),
]

STUCK_TEST = "TEST('NeverFinishes');\nAssertFalse(Condition := FALSE, Message := 'fine so far');"

FAULT_TEST = "TEST('DividesByZero');\nq := 10 / zero;\nTEST_FINISHED();\nTEST('AfterTheFault');\nTEST_FINISHED();"


def _pou(name: str, decl: str, body: str, methods=()) -> str:
    ms = "".join(
        f'    <Method Name="{m}" Id="{{00000000-0000-0000-0000-00000000{i:04d}}}">\n'
        f"      <Declaration><![CDATA[{d}]]></Declaration>\n"
        f"      <Implementation>\n        <ST><![CDATA[{b}]]></ST>\n      </Implementation>\n"
        "    </Method>\n"
        for i, (m, d, b) in enumerate(methods)
    )
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n<TcPlcObject Version="1.1.0.1">\n'
        f'  <POU Name="{name}" Id="{{00000000-0000-0000-0000-000000000001}}" SpecialFunc="None">\n'
        f"    <Declaration><![CDATA[{decl}]]></Declaration>\n"
        f"    <Implementation>\n      <ST><![CDATA[{body}]]></ST>\n    </Implementation>\n"
        f"{ms}  </POU>\n</TcPlcObject>\n"
    )


def _plcproj(name: str, files: list[str]) -> str:
    compiles = "".join(f'    <Compile Include="{f}">\n      <SubType>Code</SubType>\n    </Compile>\n' for f in files)
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n'
        '<Project DefaultTargets="Build" xmlns="http://schemas.microsoft.com/developer/msbuild/2003">\n'
        f"  <PropertyGroup>\n    <Name>{name}</Name>\n  </PropertyGroup>\n"
        f"  <ItemGroup>\n{compiles}  </ItemGroup>\n"
        "  <ItemGroup>\n"
        '    <PlaceholderReference Include="TcUnit">\n'
        "      <DefaultResolution>TcUnit, * (www.tcunit.org)</DefaultResolution>\n"
        "      <Namespace>TcUnit</Namespace>\n"
        "    </PlaceholderReference>\n"
        "  </ItemGroup>\n</Project>\n"
    )


def make_project(root: Path, *, fault: bool = False) -> Path:
    """CalcTests.plcproj: PRG_TEST runs TcUnit with FB_Calc_Test (passing, failing, multi-cycle,
    disabled tests) and FB_Stuck_Test (a test that never finishes); with fault, FB_Fault_Test."""
    pous = root / "POUs"
    pous.mkdir(parents=True, exist_ok=True)
    (pous / "FB_Calc_Test.TcPOU").write_text(
        _pou(
            "FB_Calc_Test",
            "FUNCTION_BLOCK FB_Calc_Test EXTENDS TcUnit.FB_TestSuite\nVAR\n    cycles : INT;\nEND_VAR",
            "Passing();\nFailing();\nTakesFiveCycles();\nDisabled();",
            CALC_TEST,
        )
    )
    (pous / "FB_Stuck_Test.TcPOU").write_text(
        _pou("FB_Stuck_Test", "FUNCTION_BLOCK FB_Stuck_Test EXTENDS TcUnit.FB_TestSuite", STUCK_TEST)
    )
    decls = "    Calc : FB_Calc_Test;\n    Stuck : FB_Stuck_Test;\n"
    files = ["POUs\\FB_Calc_Test.TcPOU", "POUs\\FB_Stuck_Test.TcPOU", "POUs\\PRG_TEST.TcPOU"]
    if fault:
        (pous / "FB_Fault_Test.TcPOU").write_text(
            _pou(
                "FB_Fault_Test",
                "FUNCTION_BLOCK FB_Fault_Test EXTENDS TcUnit.FB_TestSuite\nVAR\n    q : INT;\n    zero : INT;\nEND_VAR",
                FAULT_TEST,
            )
        )
        decls += "    Faulty : FB_Fault_Test;\n"
        files.insert(2, "POUs\\FB_Fault_Test.TcPOU")
    (pous / "PRG_TEST.TcPOU").write_text(_pou("PRG_TEST", f"PROGRAM PRG_TEST\nVAR\n{decls}END_VAR", "TcUnit.RUN();"))
    project = root / "CalcTests.plcproj"
    project.write_text(_plcproj("CalcTests", files))
    return project


@pytest.fixture(scope="module")
def calc_run(tmp_path_factory):
    project = make_project(tmp_path_factory.mktemp("calc"), fault=True)
    return project, tcunit.run_tcunit(project, [TCUNIT / "TcUnit"], max_cycles=40)


# ---------------------------------------------------------------------- the API


def test_each_test_passes_fails_or_is_skipped_with_tcunit_s_message_and_the_assert_line(calc_run):
    project, run = calc_run
    got = {(t.suite, t.name): t for t in run.tests}
    assert [s.path for s in run.suites] == ["PRG_TEST.Calc", "PRG_TEST.Stuck", "PRG_TEST.Faulty"]
    assert got[("PRG_TEST.Calc", "AddsUp")].status == "passed"
    assert got[("PRG_TEST.Calc", "AddsUp")].asserts == 1
    assert got[("PRG_TEST.Calc", "TakesFiveCycles")].status == "passed"
    skipped = got[("PRG_TEST.Calc", "NotYet")]
    assert skipped.status == "skipped" and skipped.failures == []
    failed = got[("PRG_TEST.Calc", "FailsOnPurpose")]
    assert failed.status == "failed"
    [f] = failed.failures
    assert f.text == "FAILED TEST 'PRG_TEST.Calc@FailsOnPurpose', EXP: 5, ACT: 4, MSG: two and two is not five"
    assert (f.expected, f.actual, f.message) == ("5", "4", "two and two is not five")
    pou = project.parent / "POUs/FB_Calc_Test.TcPOU"
    text = pou.read_text().splitlines()
    assert f.file == str(pou) and text[f.line - 1].strip().startswith("AssertEquals_INT(Expected := 5,")
    assert failed.file == str(pou) and "TEST('FailsOnPurpose')" in text[failed.line - 1]
    assert run.counts() == {"passed": 2, "failed": 4, "skipped": 1}


def test_a_suite_that_never_finishes_is_a_located_failure_not_a_hang(calc_run):
    project, run = calc_run
    assert not run.finished and run.cycles == 40
    assert run.limit_note == "TcUnit did not report every suite finished within 40 cycles (0.4 s of PLC time)"
    [stuck] = [t for t in run.tests if t.suite == "PRG_TEST.Stuck"]
    assert stuck.name == "NeverFinishes" and stuck.status == "failed"
    [f] = stuck.failures
    assert f.kind == "unfinished"
    assert f.text == (
        "PRG_TEST.Stuck@NeverFinishes did not finish within 40 cycles (0.4 s of PLC time): "
        "TEST_FINISHED() was never called"
    )
    assert (f.file, f.line) == (str(project.parent / "POUs/FB_Stuck_Test.TcPOU"), 6)


def test_a_plc_fault_fails_the_test_that_ran_and_ends_its_suite(calc_run):
    project, run = calc_run
    got = {t.name: t for t in run.tests if t.suite == "PRG_TEST.Faulty"}
    div = got["DividesByZero"]
    assert div.status == "failed" and div.failures[-1].kind == "fault"
    assert div.failures[-1].text.startswith("PLC fault [DIV0]")
    assert (div.failures[-1].file, div.failures[-1].line) == (str(project.parent / "POUs/FB_Fault_Test.TcPOU"), 11)
    after = got["AfterTheFault"]  # its TEST() never ran: known from the source only
    assert after.status == "failed" and not after.registered
    assert after.failures[0].text == (
        "PRG_TEST.Faulty@AfterTheFault was not run: the suite ended at a PLC fault in test 'DividesByZero'"
    )
    assert len(run.faults) == 1  # the suite was not called again
    # the other suites ran on
    assert {t.name for t in run.tests if t.status == "passed"} == {"AddsUp", "TakesFiveCycles"}


def test_only_the_suites_asked_for_run_and_tcunit_reports_them_finished(tmp_path):
    project = make_project(tmp_path)
    run = tcunit.run_tcunit(project, [TCUNIT_PROJECT], suites=["PRG_TEST.Calc"], max_cycles=100)
    assert run.finished and [s.path for s in run.suites] == ["PRG_TEST.Calc"]
    assert {t.name: t.status for t in run.tests} == {
        "AddsUp": "passed",
        "FailsOnPurpose": "failed",
        "TakesFiveCycles": "passed",
        "NotYet": "skipped",
    }
    assert 5 <= run.cycles < 100  # TakesFiveCycles needs five scans; then TcUnit stores its results
    # TcUnit's own log lines, in PLC.log or still in its queue: the failed assertion first
    assert run.messages[0] == "FAILED TEST 'PRG_TEST.Calc@FailsOnPurpose', EXP: 5, ACT: 4, MSG: two and two is not five"


def test_drain_log_runs_until_tcunit_has_written_every_message_to_plc_log(tmp_path):
    project = tcunit.TcUnitProject.load([make_project(tmp_path)], [TCUNIT_PROJECT])
    run = project.run(suites=["PRG_TEST.Calc"], drain_log=True, max_cycles=500)
    assert run.finished
    log = project.plc.log.texts()
    assert log == run.messages  # nothing left in TcUnit's queue
    assert log[0] == "FAILED TEST 'PRG_TEST.Calc@FailsOnPurpose', EXP: 5, ACT: 4, MSG: two and two is not five"
    assert log[-7:] == [
        "| ==========TESTS FINISHED RUNNING==========",
        "| Test suites: 1",
        "| Tests: 4",
        "| Successful tests: 3",
        "| Failed tests: 1",
        log[-2],
        "| ======================================",
    ]
    assert log[-2].startswith("| Duration: ")


def test_st_files_with_the_library_project_given_explicitly(tmp_path):
    src = tmp_path / "suites.st"
    src.write_text(
        textwrap.dedent("""\
        FUNCTION_BLOCK FB_Text_Test EXTENDS TcUnit.FB_TestSuite
          TEST('Concat');
          AssertEquals_STRING(Expected := 'ab', Actual := CONCAT('a', 'c'), Message := 'concat');
          TEST_FINISHED();
        END_FUNCTION_BLOCK

        PROGRAM MAIN
          VAR suite : FB_Text_Test; END_VAR
          TcUnit.RUN();
        END_PROGRAM
        """)
    )
    run = tcunit.run_tcunit(src, [TCUNIT_PROJECT], max_cycles=100)
    [t] = run.tests
    assert (t.suite, t.name, t.status) == ("MAIN.suite", "Concat", "failed")
    assert t.failures[0].text == "FAILED TEST 'MAIN.suite@Concat', EXP: ab, ACT: ac, MSG: concat"
    assert (t.failures[0].file, t.failures[0].line) == (str(src), 3)


def test_a_program_without_tcunit_is_refused(tmp_path):
    src = tmp_path / "plain.st"
    src.write_text("PROGRAM MAIN\n  VAR x : INT; END_VAR\n  x := x + 1;\nEND_PROGRAM\n")
    with pytest.raises(tcunit.NotATcUnitProject):
        tcunit.run_tcunit(src)


# ---------------------------------------------------------------------- st test


def test_st_test_runs_a_project_s_suites_with_tcunit_s_summary(tmp_path):
    project = make_project(tmp_path)
    r = CliRunner().invoke(
        main, ["test", str(project), "--lib", str(TCUNIT / "TcUnit"), "--max-cycles", "30", "-k", "Calc"]
    )
    assert r.exit_code == 1, r.output
    out = r.output.splitlines()
    pou = project.parent / "POUs/FB_Calc_Test.TcPOU"
    line = pou.read_text().splitlines().index("        <ST><![CDATA[TEST('AddsUp');") + 1
    assert f"PASS  PRG_TEST.Calc@AddsUp  ({pou}:{line})" in out
    assert any(line.startswith("FAIL  PRG_TEST.Calc@FailsOnPurpose") for line in out)
    assert any(
        line.endswith("FAILED TEST 'PRG_TEST.Calc@FailsOnPurpose', EXP: 5, ACT: 4, MSG: two and two is not five")
        for line in out
    )
    assert any(line.startswith("SKIP  PRG_TEST.Calc@NotYet") for line in out)
    assert "| Tests: 4" in out and "| Failed tests: 1" in out
    assert out[-1] == "2 passed, 1 failed, 1 skipped"
    assert "Stuck" not in r.output  # -k Calc: only that suite ran


# ---------------------------------------------------------------------- pytest


def _ini(pytester, extra: str = "") -> None:
    pytester.makeini(f"[pytest]\nst_libs =\n    {TCUNIT / 'TcUnit'}\nst_tcunit_max_cycles = 30\n{extra}")


def test_pytest_collects_a_named_project_s_tests_as_items(pytester):
    make_project(pytester.path)
    _ini(pytester)
    result = pytester.runpytest("-p", "no:cacheprovider", "CalcTests.plcproj", "--collect-only", "-q")
    result.stdout.fnmatch_lines(
        [
            "CalcTests.plcproj::PRG_TEST.Calc::AddsUp",
            "CalcTests.plcproj::PRG_TEST.Calc::FailsOnPurpose",
            "CalcTests.plcproj::PRG_TEST.Calc::TakesFiveCycles",
            "CalcTests.plcproj::PRG_TEST.Calc::NotYet",
            "CalcTests.plcproj::PRG_TEST.Stuck::NeverFinishes",
            "5 tests collected*",
        ]
    )


def test_pytest_collects_projects_in_a_folder_only_when_asked(pytester):
    make_project(pytester.path / "plc")
    _ini(pytester)
    pytester.runpytest("-p", "no:cacheprovider", "--collect-only", "-q").assert_outcomes()
    result = pytester.runpytest("-p", "no:cacheprovider", "--st-tcunit", "--collect-only", "-q")
    result.stdout.fnmatch_lines(["5 tests collected*"])
    _ini(pytester, "st_tcunit = true")
    pytester.runpytest("-p", "no:cacheprovider", "--collect-only", "-q").stdout.fnmatch_lines(["5 tests collected*"])


def test_pytest_runs_the_project_once_and_reports_tcunit_s_messages(pytester):
    make_project(pytester.path)
    _ini(pytester)
    result = pytester.runpytest("-p", "no:cacheprovider", "CalcTests.plcproj", "-rA")
    result.assert_outcomes(passed=2, failed=2, skipped=1)
    result.stdout.fnmatch_lines(
        [
            "*_ PRG_TEST.Calc::FailsOnPurpose _*",
            "POUs/FB_Calc_Test.TcPOU:*: FAILED TEST 'PRG_TEST.Calc@FailsOnPurpose', EXP: 5, ACT: 4, MSG: two and two is not five",
            "> * | AssertEquals_INT(Expected := 5,",
            "  * |                  Actual := a + a,",
            "*_ PRG_TEST.Stuck::NeverFinishes _*",
            "POUs/FB_Stuck_Test.TcPOU:6: PRG_TEST.Stuck@NeverFinishes did not finish within 30 cycles*",
            "*= TcUnit =*",
            "CalcTests.plcproj: 2 suites, 5 tests (2 passed, 2 failed, 1 skipped) in 30 scans*",
            "FAILED CalcTests.plcproj::PRG_TEST.Calc::FailsOnPurpose - POUs/FB_Calc*",
        ]
    )


def test_pytest_k_runs_only_the_selected_suites(pytester):
    make_project(pytester.path)
    _ini(pytester)
    result = pytester.runpytest(
        "-p", "no:cacheprovider", "CalcTests.plcproj", "-k", "AddsUp or TakesFiveCycles or NotYet"
    )
    result.assert_outcomes(passed=2, skipped=1, deselected=2)
    result.stdout.fnmatch_lines(["CalcTests.plcproj: 1 suites, 4 tests (*"])  # Stuck not run: no timeout


def test_pytest_finds_the_library_through_st_libpath(pytester, monkeypatch):
    make_project(pytester.path)
    monkeypatch.setenv("ST_LIBPATH", str(TCUNIT / "TcUnit"))
    result = pytester.runpytest("-p", "no:cacheprovider", "CalcTests.plcproj", "-k", "AddsUp")
    result.assert_outcomes(passed=1, deselected=4)


def test_pytest_without_the_library_is_a_collection_error(pytester, monkeypatch):
    make_project(pytester.path)
    monkeypatch.delenv("ST_LIBPATH", raising=False)
    result = pytester.runpytest("-p", "no:cacheprovider", "CalcTests.plcproj")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["*TcUnit*"])


# ---------------------------------------------------------------------- TcUnit's verifier

# TcUnit-Verifier_DotNet/Program.cs: `expectedNumberOfFailedTests = 121`; the verifier's FBs fail on
# purpose (FB_PrimitiveTypes' *_Differ, ...). st differs in one test: FB_StreamBuffer's Append writes
# the string's terminating NUL one byte past the end of a full buffer (FB_StreamBuffer.TcPOU:34,
# `ByteBuffer^ := 0` when _Length = _BufferSize); TwinCAT writes past the end unchecked, st stops the
# write with an INDEX fault, so Test_BufferOverflow fails here (as a located PLC fault).
VERIFIER_TESTS = 267
VERIFIER_FAILED_ON_TWINCAT = 121
ST_DEVIATIONS = {("PRG_TEST.TestStreamBuffer", "Test_BufferOverflow"): "PLC fault [INDEX]"}


@pytest.mark.slow
@pytest.mark.skipif(not VERIFIER.exists(), reason=f"TcUnit's verifier is not checked out at {VERIFIER}")
def test_tcunit_s_verifier_passes_and_fails_as_tcunit_documents():
    t0 = time.perf_counter()
    project = tcunit.TcUnitProject.load([VERIFIER], [TCUNIT / "TcUnit"])
    load = time.perf_counter() - t0
    run = project.run()
    c = run.counts()
    per_scan = run.wall / run.cycles
    print(
        f"\nTcUnit verifier: {len(run.suites)} suites, {len(run.tests)} tests: {c['passed']} passed, "
        f"{c['failed']} failed, {c['skipped']} skipped; {run.cycles} scans ({run.plc_time / 1e9:g} s of PLC time) "
        f"in {run.wall:.1f} s: {per_scan * 1000:.1f} ms a scan (first {run.scan_times[0]:.2f} s, "
        f"slowest {max(run.scan_times):.2f} s); compile and build {load:.1f} s"
    )
    assert run.finished
    assert len(run.suites) == 26 and len(run.tests) == VERIFIER_TESTS
    failed = {(t.suite, t.name) for t in run.tests if t.status == "failed"}
    for key, why in ST_DEVIATIONS.items():
        assert key in failed
        assert run.result(*key).failures[-1].text.startswith(why)
    assert len(failed) == VERIFIER_FAILED_ON_TWINCAT + len(ST_DEVIATIONS)
    assert [(t.suite, t.name) for t in run.tests if t.status == "skipped"] == [
        ("PRG_TEST.CreateDisabledTest", "ThisShouldNotExecute")
    ]
    # TcUnit's own count agrees (its FB_TestResults, stored when the suites finished)
    results = project.runner.child("TestResults").child("TestSuiteResults")
    assert results.get("NumberOfTestCases") == VERIFIER_TESTS
    assert results.get("NumberOfFailedTestCases") == len(failed)
    # every failed assertion TcUnit logged is a failure of its test, and most are placed at their Assert
    failures = [f for t in run.tests for f in t.failures if f.kind == "assert"]
    assert sum(1 for m in run.messages if m.startswith("FAILED TEST")) == len(failures)
    placed = sum(1 for f in failures if f.line)
    print(f"failed assertions: {len(failures)}, placed at their Assert call: {placed}")


TCLOG = CORPORA / "bengeisler-TcLog/src/TcLogProj"


@pytest.mark.slow
@pytest.mark.skipif(not TCLOG.exists(), reason=f"TcLog is not checked out at {TCLOG}")
def test_tclog_s_own_suites_pass_writing_their_log_file(tmp_path, monkeypatch):
    """TcLog's TcUnit suites (TcLogTEST with the TcLog library project and TcUnit): its logger on
    the vendor library's file blocks, FB_StringRingBuffer and Tc3_DynamicMemory; the test's
    `c:\\UnitTest\\` is a folder under the file root, as it must exist on the target."""
    from st.stdlib.vendor import sysfile

    (tmp_path / "C" / "UnitTest").mkdir(parents=True)
    monkeypatch.setattr(sysfile, "FILE_ROOT", tmp_path)
    project = tcunit.TcUnitProject.load([TCLOG / "TcLogTEST/TcLogTEST.plcproj"], [TCUNIT / "TcUnit", TCLOG / "TcLog"])
    run = project.run()
    assert run.finished
    c = run.counts()
    assert (c["passed"], c["failed"], c["skipped"]) == (21, 0, 1)
    # the one skipped is written but never called by its suite's body
    assert [t.name for t in run.tests if t.status == "skipped"] == ["ConvertAnyDWordToString"]
    (log,) = (tmp_path / "C" / "UnitTest").iterdir()
    lines = log.read_text().splitlines()
    assert len(lines) == 50 * 51  # 50 cycles of 51 messages
    assert lines[0].endswith("|3|Cycle: 0, Message: 0") and lines[-1].endswith("|3|Cycle: 49, Message: 50")
