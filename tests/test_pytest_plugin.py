"""The pytest plugin: ST test files collected next to Python tests, reports, options, fixture, xdist."""

import textwrap

import pytest

pytest_plugins = ["pytester"]


@pytest.fixture(autouse=True, scope="module")
def _compiler_loaded():
    """The in-process runs below drop the modules each imported (pytester restores sys.modules),
    and the compiler imports its stages on first use: were a stage first imported inside a run, the
    next run would import it again beside a parser cache holding the first one's syntax classes.
    So every stage is loaded here, once, before any run."""
    import st.testing.runner  # noqa: F401 - loaded for the same reason
    from st.api import compile_text

    compile_text("FUNCTION_BLOCK F VAR_INPUT a : INT; END_VAR a := a + 1; END_FUNCTION_BLOCK\n", use_cache=False)


COUNTER = """
FUNCTION_BLOCK Counter
  VAR_INPUT enable : BOOL; END_VAR
  VAR_OUTPUT count : INT; END_VAR
  IF enable THEN count := count + 1; END_IF;
END_FUNCTION_BLOCK

FUNCTION Twice : INT
  VAR_INPUT x : INT; END_VAR
  Twice := x * 2;
END_FUNCTION
"""

TESTS = """\
TEST 'counts'
  VAR c : Counter; END_VAR
  c(enable := TRUE);
  ASSERT_EQ(c.count, 1);
END_TEST

TEST 'twice is wrong'
  VAR x : INT := 2; END_VAR
  x := x + 0;
  ASSERT_EQ(Twice(x), 5, 'on purpose');
END_TEST
"""


def _project(pytester, tests=TESTS):
    pytester.makefile(".st", counter=COUNTER)
    pytester.makefile(".st", test_counter=tests)


def test_st_items_pass_and_fail_with_st_lines(pytester):
    _project(pytester)
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(
        [
            "*_ TEST 'twice is wrong' _*",
            "test_counter.st:10:3: ASSERT_EQ(Twice(x), 5, 'on purpose') failed",
            "   7 | TEST 'twice is wrong'",
            "   8 |   VAR x : INT := 2; END_VAR",
            "   9 |   x := x + 0;",
            "> 10 |   ASSERT_EQ(Twice(x), 5, 'on purpose');",
            "         ^",
            "E   ASSERT_EQ(Twice(x), 5, 'on purpose') failed",
            "E     actual:   4",
            "E     expected: 5",
            "E     message:  on purpose",
            "FAILED test_counter.st::twice is wrong - test_counter.st:10:3: ASSERT_EQ*",
        ]
    )


def test_keyword_exitfirst_and_last_failed(pytester):
    _project(pytester)
    pytester.runpytest("-k", "counts").assert_outcomes(passed=1, deselected=1)
    pytester.runpytest("-x").assert_outcomes(passed=1, failed=1)
    result = pytester.runpytest("--lf")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["collected 1 item", "run-last-failure: rerun previous 1 failure"])


def test_python_and_st_tests_side_by_side_with_the_plc_fixture(pytester):
    _project(pytester)
    pytester.makepyfile(
        test_side=textwrap.dedent("""
        def test_fb_from_python(plc):
            p = plc("counter.st")
            c = p.fb("Counter")
            c(enable=True); c(enable=True)
            assert c.count == 2
            assert p.function("Twice")(21) == 42

        def test_timer_on_virtual_time(plc):
            p = plc(source="PROGRAM P VAR t : TON; q : BOOL; END_VAR t(IN := TRUE, PT := T#50ms); q := t.Q; END_PROGRAM",
                    cycle="10ms")
            assert p.run_until("p.q", timeout="1s") == 60_000_000
    """)
    )
    pytester.runpytest().assert_outcomes(passed=3, failed=1)


def test_compile_errors_are_collection_errors_with_diagnostics(pytester):
    pytester.makefile(".st", test_bad="TEST 'x'\n  ASSERT_EQ(missing, 1);\nEND_TEST\n")
    result = pytester.runpytest()
    assert result.ret == 2
    assert "test_bad.st:2:13: error[E010]: undeclared identifier 'missing'" in result.stdout.lines


def test_st_sources_ini_option(pytester):
    pytester.mkdir("src")
    (pytester.path / "src" / "lib.st").write_text(COUNTER)
    pytester.mkdir("checks")
    (pytester.path / "checks" / "test_lib.st").write_text(TESTS)
    pytester.makeini("[pytest]\nst_sources = src/*.st\n")
    pytester.runpytest().assert_outcomes(passed=1, failed=1)


@pytest.mark.slow
def test_xdist_runs_st_items(pytester):
    _project(pytester)
    pytester.runpytest_subprocess("-n", "2").assert_outcomes(passed=1, failed=1)
