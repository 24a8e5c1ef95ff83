"""ST unit tests (TEST blocks): assertions, SETUP/TEARDOWN, time, mocks, faults, the runner and `st test`."""

import subprocess
import sys
import textwrap

import pytest

from st import CompileError
from st.api import compile_text
from st.testing import TestSuite

LIB = """
FUNCTION_BLOCK Counter
  VAR_INPUT enable : BOOL; END_VAR
  VAR_OUTPUT count : INT; END_VAR
  IF enable THEN count := count + 1; END_IF;
END_FUNCTION_BLOCK

FUNCTION Twice : INT
  VAR_INPUT x : INT; END_VAR
  Twice := x * 2;
END_FUNCTION

PROGRAM Main
  VAR_EXTERNAL total : DINT; END_VAR
  VAR c : Counter; t : TON; out : INT; done : BOOL; END_VAR
  c(enable := TRUE);
  out := Twice(c.count);
  t(IN := TRUE, PT := T#100ms);
  done := t.Q;
  total := total + 1;
END_PROGRAM

CONFIGURATION cfg
  VAR_GLOBAL total : DINT := 100; END_VAR
  RESOURCE r ON PLC
    TASK tk(INTERVAL := T#10ms);
    PROGRAM main0 WITH tk : Main;
  END_RESOURCE
END_CONFIGURATION
"""


def run(tests: str, lib: str = LIB, timeout="10s"):
    compiled = compile_text(lib + textwrap.dedent(tests), "t.st")
    suite = TestSuite(compiled, timeout)
    return {r.case.name: r for r in suite.run_all()}


def only(tests: str, **kw):
    results = run(tests, **kw)
    assert len(results) == 1
    return next(iter(results.values()))


@pytest.mark.parametrize(
    "stmt, actual, expected",
    [
        ("ASSERT_EQ(c.count, 2);", "1", "2"),
        ("ASSERT_NEQ(c.count, 1);", "1", "not 1"),
        ("ASSERT_GT(c.count, 1);", "1", "> 1"),
        ("ASSERT_LT(c.count, 1);", "1", "< 1"),
        ("ASSERT_GE(c.count, 2);", "1", ">= 2"),
        ("ASSERT_LE(c.count, 0);", "1", "<= 0"),
        ("ASSERT_TRUE(c.count = 2);", "FALSE", "TRUE"),
        ("ASSERT_FALSE(c.enable);", "TRUE", "FALSE"),
        ("ASSERT_NEAR(r, 1.0, 0.1);", "1.25", "1.0 ± 0.1 (difference 0.25)"),
        ("ASSERT_EQ(s, 'abd');", "'abc'", "'abd'"),
        ("ASSERT_EQ(tm, T#1s);", "T#1s500ms", "T#1s"),
        ("ASSERT_EQ(r, 0.1);", "1.25", "0.1"),
    ],
)
def test_each_assertion_reports_actual_and_expected(stmt, actual, expected):
    r = only(f"""
    TEST 'one'
      VAR c : Counter; r : REAL := 1.25; s : STRING := 'abc'; tm : TIME := T#1.5s; END_VAR
      c(enable := TRUE);
      {stmt}
    END_TEST
    """)
    assert not r.passed
    rep = r.report
    assert (rep.kind, rep.file, rep.line, rep.col) == ("assert", "t.st", LIB.count("\n") + 5, 3)
    assert rep.message == stmt[:-1] + " failed"
    assert (rep.actual, rep.expected, rep.note) == (actual, expected, "")


def test_passing_assertions_and_message():
    res = run("""
    TEST 'passes'
      VAR c : Counter; END_VAR
      c(enable := TRUE); c(enable := TRUE);
      ASSERT_EQ(c.count, 2); ASSERT_NEQ(c.count, 3); ASSERT_GT(c.count, 1); ASSERT_LT(c.count, 3);
      ASSERT_GE(c.count, 2); ASSERT_LE(c.count, 2); ASSERT_TRUE(c.enable); ASSERT_FALSE(NOT c.enable);
      ASSERT_NEAR(0.1 + 0.2, 0.3, 1.0E-9, 'float sum');
    END_TEST
    TEST "fails with a message"
      ASSERT_EQ(1 + 1, 3, CONCAT('math ', 'is broken'));
      ASSERT_EQ(1, 1);
    END_TEST
    """)
    assert res["passes"].passed and res["passes"].report is None
    bad = res["fails with a message"]
    assert (bad.passed, bad.report.actual, bad.report.expected, bad.report.note) == (False, "2", "3", "math is broken")
    line = LIB.count("\n") + 10
    assert str(bad.report) == (
        f"t.st:{line}:3: ASSERT_EQ(1 + 1, 3, CONCAT('math ', 'is broken')) failed\n"
        "  actual:   2\n  expected: 3\n  message:  math is broken"
    )


def test_setup_variables_are_fresh_for_every_test_and_teardown_runs():
    res = run("""
    SETUP
      VAR shared : INT := 5; log : INT; END_VAR
      shared := shared + 1;
    END_SETUP
    TEARDOWN
      ASSERT_EQ(log, 0, 'teardown ran');
    END_TEARDOWN
    TEST 'first'
      ASSERT_EQ(shared, 6);
      shared := 100;
    END_TEST
    TEST 'second sees a fresh SETUP'
      ASSERT_EQ(shared, 6);
      log := 1;
    END_TEST
    """)
    assert res["first"].passed
    second = res["second sees a fresh SETUP"]
    assert not second.passed and second.report.note == "teardown ran" and second.report.actual == "1"


def test_globals_and_program_instances_are_fresh_per_test():
    res = run("""
    TEST 'a'
      VAR p : Main; END_VAR
      p(); p();
      ASSERT_EQ(total, 102);
      ASSERT_EQ(p.out, 4);
    END_TEST
    TEST 'b'
      VAR p : Main; END_VAR
      p();
      ASSERT_EQ(total, 101);
      ASSERT_EQ(p.c.count, 1);
    END_TEST
    """)
    assert [r.passed for r in res.values()] == [True, True], [str(r.report) for r in res.values()]


def test_advance_time_drives_timers_with_time_and_nanoseconds():
    r = only("""
    TEST 'ton'
      VAR t : TON; END_VAR
      t(IN := TRUE, PT := T#100ms);
      ADVANCE_TIME(T#99ms);
      t(IN := TRUE, PT := T#100ms);
      ASSERT_FALSE(t.Q);
      ASSERT_EQ(t.ET, T#99ms);
      ADVANCE_TIME(1000000);
      t(IN := TRUE, PT := T#100ms);
      ASSERT_TRUE(t.Q);
      ASSERT_EQ(t.ET, T#100ms);
    END_TEST
    """)
    assert r.passed, str(r.report)


def test_mock_skips_the_body_keeps_outputs_and_counts_calls():
    r = only("""
    TEST 'mocks'
      VAR p : Main; END_VAR
      MOCK p.c;
      MOCK_FUNCTION Twice RETURNS 42;
      p.c.count := 7;
      p(); p();
      ASSERT_EQ(p.c.count, 7);
      ASSERT_EQ(p.out, 42);
      MOCK_VERIFY_CALLED(p.c);
      MOCK_VERIFY_CALL_COUNT(p.c, 2);
      MOCK_VERIFY_CALL_COUNT(Twice, 2);
      MOCK_VERIFY_CALL_COUNT(p.c, 3);
    END_TEST
    """)
    assert not r.passed
    assert (r.report.message, r.report.actual, r.report.expected) == (
        "MOCK_VERIFY_CALL_COUNT(p.c, 3) failed",
        "called 2 times",
        "called 3 times",
    )


def test_mocks_do_not_leak_into_the_next_test():
    res = run("""
    TEST 'mocked'
      VAR p : Main; END_VAR
      MOCK_FUNCTION Twice RETURNS 42;
      MOCK p.c;
      p();
      ASSERT_EQ(p.out, 42);
    END_TEST
    TEST 'real again'
      VAR p : Main; END_VAR
      p();
      ASSERT_EQ(p.out, 2);
      MOCK_VERIFY_CALLED(p.c);
    END_TEST
    TEST 'never called'
      VAR c : Counter; END_VAR
      MOCK c;
      MOCK_VERIFY_CALLED(c);
    END_TEST
    """)
    assert res["mocked"].passed
    real = res["real again"].report
    assert real.message == "MOCK_VERIFY_CALLED(p.c) failed: it is not mocked (use MOCK first)"
    never = res["never called"].report
    assert (never.actual, never.expected) == ("never called", "called at least once")


def test_runtime_faults_and_endless_loops_fail_the_test_at_their_line():
    base = LIB.count("\n")
    res = run(
        """
    TEST 'div'
      VAR a, b : INT; END_VAR
      a := 1 / b;
    END_TEST
    TEST 'loop'
      VAR a : INT; END_VAR
      WHILE TRUE DO a := a + 1; END_WHILE;
    END_TEST
    TEST 'after'
      ASSERT_TRUE(TRUE);
    END_TEST
    """,
        timeout="200ms",
    )
    div, loop = res["div"].report, res["loop"].report
    assert (div.kind, div.line, div.message) == ("fault", base + 4, "PLC fault [DIV0]: division by zero")
    assert (loop.kind, loop.line) == ("fault", base + 8)
    assert loop.message == "PLC fault [WATCHDOG]: the test did not finish within 0.2 s (endless loop?)"
    assert res["after"].passed


@pytest.mark.parametrize(
    "src, code, fragment",
    [
        ("PROGRAM P VAR x : INT; END_VAR ASSERT_EQ(x, 1); END_PROGRAM", "E033", "ASSERT_EQ is only allowed"),
        ("PROGRAM P VAR c : Counter; END_VAR MOCK c; END_PROGRAM", "E033", "MOCK is only allowed"),
        ("TEST 'x' MOCK_FUNCTION ABS RETURNS 1; END_TEST", "E020", "'ABS' is a standard function"),
        ("TEST 'x' VAR i : INT; END_VAR MOCK i; END_TEST", "E013", "MOCK needs a function block or program instance"),
        ("TEST 'x' ASSERT_EQ(1); END_TEST", "E017", "ASSERT_EQ takes 2 or 3 arguments, not 1"),
        ("TEST 'x' ASSERT_TRUE(2); END_TEST", "E013", "ASSERT_TRUE needs a BOOL"),
        ("TEST 'x' ASSERT_EQ(1, 'a'); END_TEST", "E014", ""),
        ("TEST 'x' ASSERT_EQ(1, 1, 5); END_TEST", "E013", "the message of ASSERT_EQ must be a STRING"),
        ("TEST 'x' ADVANCE_TIME('soon'); END_TEST", "E013", "ADVANCE_TIME needs a TIME"),
        ("TEST 'x' ASSERT_TRUE(TRUE); END_TEST TEST 'x' ASSERT_TRUE(TRUE); END_TEST", "E011", "named 'x' already"),
        ("SETUP END_SETUP SETUP END_SETUP", "E011", "one SETUP block"),
        ("TEST 'x' VAR c : Counter; END_VAR MOCK_VERIFY_CALLED(nothing); END_TEST", "E010", "neither an instance"),
    ],
)
def test_misused_test_statements_are_diagnostics(src, code, fragment):
    with pytest.raises(CompileError) as e:
        compile_text(LIB + src, "t.st")
    msgs = [(d.code, d.message) for d in e.value.diagnostics if d.is_error]
    assert any(c == code and fragment in m for c, m in msgs), msgs


def test_tests_split_over_files_and_source_by_convention(tmp_path):
    (tmp_path / "counter.st").write_text(LIB)
    (tmp_path / "test_counter.st").write_text(
        "TEST 'counts'\n  VAR c : Counter; END_VAR\n  c(enable := TRUE);\n  ASSERT_EQ(c.count, 1);\nEND_TEST\n"
    )
    suite = TestSuite.from_paths([tmp_path / "test_counter.st"])
    assert [(c.name, c.line) for c in suite.cases] == [("counts", 1)]
    assert [r.passed for r in suite.run_all()] == [True]


def _st(*args, cwd):
    return subprocess.run([sys.executable, "-m", "st.cli", *args], cwd=cwd, capture_output=True, text=True)


@pytest.mark.slow
def test_st_test_command_output_and_exit_codes(tmp_path):
    (tmp_path / "counter.st").write_text(LIB)
    (tmp_path / "test_counter.st").write_text(
        textwrap.dedent("""\
        TEST 'good'
          ASSERT_EQ(Twice(2), 4);
        END_TEST
        TEST 'bad'
          ASSERT_EQ(Twice(2), 5);
        END_TEST
        """)
    )
    p = _st("test", "test_counter.st", cwd=tmp_path)
    assert p.returncode == 1
    assert p.stdout.splitlines() == [
        "PASS  good  (test_counter.st:1)",
        "FAIL  bad  (test_counter.st:4)",
        "      test_counter.st:5:3: ASSERT_EQ(Twice(2), 5) failed",
        "        actual:   4",
        "        expected: 5",
        "1 passed, 1 failed",
    ]
    assert _st("test", "-k", "good", "test_counter.st", cwd=tmp_path).returncode == 0
    assert _st("test", "-k", "nothing", "test_counter.st", cwd=tmp_path).returncode == 5
    (tmp_path / "test_broken.st").write_text("TEST 'x'\n  ASSERT_EQ(nope, 1);\nEND_TEST\n")
    broken = _st("test", "test_broken.st", cwd=tmp_path)
    assert broken.returncode == 2 and "test_broken.st:2:13: error[E010]" in broken.stderr
