"""ST coverage: probes in generated code, the data model, the terminal/HTML reports, --st-cov."""

import io
import textwrap

import pytest

from st import PLC
from st.api import compile_text
from st.testing.covreport import CoverageData, Point, html_report, terminal_report
from st.testing.measure import coverage_data

pytest_plugins = ["pytester"]

SRC = textwrap.dedent("""\
    TYPE Mode : (IDLE, RUN); END_TYPE
    PROGRAM main
      VAR x : INT; m : Mode; s : STRING := '<ok>'; END_VAR
      x := x + 1;
      IF x > 100 THEN
        x := 0;
      ELSIF x > 2 THEN
        s := 'big';
      END_IF;
      CASE x OF
        1: m := RUN;
        2, 3: m := IDLE;
      END_CASE;
      CASE m OF
        IDLE: x := x;
        RUN: ;
      END_CASE;
    END_PROGRAM
    """)


def _measured(scans: int, path: str) -> CoverageData:
    compiled = compile_text(SRC, path, coverage=True)
    plc = PLC(compiled)
    plc.scan(scans)
    return coverage_data([compiled])


def test_lines_and_arms_that_ran(tmp_path):
    path = str(tmp_path / "prog.st")
    (f,) = _measured(2, path).files()
    assert f.statements == [4, 5, 6, 8, 10, 11, 12, 14, 15]
    assert f.missed == [6, 8]
    # IF: THEN, ELSIF, implicit ELSE; CASE x: 1, "2, 3", implicit ELSE; CASE m names every value: no ELSE arm
    labels = [(p.line, p.label, p.target, h) for p, h in f.arms]
    assert labels == [
        (5, "THEN", 6, False),
        (5, "ELSIF (line 7)", 8, False),
        (5, "implicit ELSE", 0, True),
        (10, "CASE 1", 11, True),
        (10, "CASE 2, 3", 12, True),
        (10, "implicit ELSE", 0, False),
        (14, "CASE IDLE", 15, True),
        (14, "CASE RUN", 0, True),
    ]
    assert (f.branches, f.branches_taken, f.partial) == (8, 5, [5, 10])
    assert f.missing_ranges() == "6-8, 5->THEN, 5->ELSIF (line 7), 10->implicit ELSE"
    assert round(f.percent, 4) == round(100 * (7 + 5) / (9 + 8), 4)


def test_terminal_report_and_totals(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    data = _measured(3, "prog.st")
    data.merge(CoverageData([Point("other.st", 1, "line"), Point("other.st", 2, "line")], bytearray([1, 1])))
    buf = io.StringIO()
    total = terminal_report(data, buf)
    assert buf.getvalue().splitlines() == [
        "Name      Stmts   Miss  Branch  BrPart  Cover   Missing",
        "-------------------------------------------------------",
        "other.st      2      0       0       0   100%",
        "prog.st       9      1       8       2    82%   6, 5->THEN, 10->implicit ELSE",
        "-------------------------------------------------------",
        "TOTAL        11      1       8       2    84%",
    ]
    assert round(total, 3) == round(100 * (10 + 6) / 19, 3)  # 84.2 rounds down to 84


def test_merge_and_json_round_trip():
    a = CoverageData([Point("f.st", 1, "line"), Point("f.st", 2, "branch", "THEN", 3)], bytearray([1, 0]))
    b = CoverageData(list(a.points), bytearray([0, 1]))
    a.merge(b)
    assert list(a.hits) == [1, 1]
    c = CoverageData([Point("g.st", 9, "line")], bytearray([1]))
    a.merge(c)
    assert [(p.file, p.line) for p in a.points] == [("f.st", 1), ("f.st", 2), ("g.st", 9)]
    again = CoverageData.from_json(a.to_json())
    assert again.points == a.points and again.hits == a.hits


def test_html_report(tmp_path):
    path = str(tmp_path / "prog.st")
    (tmp_path / "prog.st").write_text(SRC)
    index = html_report(_measured(2, path), tmp_path / "html")
    text = open(index).read()
    assert "<a href='file_0.html'>" in text and "<td>9</td><td>2</td><td>8</td><td>2</td>" in text
    page = (tmp_path / "html" / "file_0.html").read_text()
    assert "<tr class='miss'><td class='n'>6</td><td>    x := 0;</td></tr>" in page
    assert (
        "<tr class='part'><td class='n'>5</td><td>  IF x &gt; 100 THEN <span class='note'>"
        "(THEN never taken; ELSIF (line 7) never taken)</span></td></tr>" in page
    )
    assert "&#x27;&lt;ok&gt;&#x27;" in page


@pytest.mark.slow
def test_pytest_st_cov_serial_and_xdist_agree(pytester):
    pytester.makefile(".st", prog=SRC)
    pytester.makefile(
        ".st",
        test_prog=textwrap.dedent("""\
        TEST 'one scan'
          VAR p : main; END_VAR
          p();
          ASSERT_EQ(p.x, 1);
        END_TEST
        TEST 'three scans'
          VAR p : main; END_VAR
          p(); p(); p();
          ASSERT_EQ(p.s, 'big');
        END_TEST
        """),
    )
    expected = "prog.st      9      1       8       2    82%   6, 5->THEN, 10->implicit ELSE"
    serial = pytester.runpytest("--st-cov", "--st-cov-html", "cov")
    serial.assert_outcomes(passed=2)
    serial.stdout.fnmatch_lines(["*ST coverage*", "Name *Stmts*", expected, "HTML report: cov*index.html"])
    parallel = pytester.runpytest_subprocess("--st-cov", "-n", "2")
    parallel.assert_outcomes(passed=2)
    parallel.stdout.fnmatch_lines([expected])


@pytest.mark.slow
def test_st_test_cov_command(tmp_path):
    import subprocess
    import sys

    (tmp_path / "prog.st").write_text(SRC)
    (tmp_path / "test_prog.st").write_text(
        "TEST 'one'\n  VAR p : main; END_VAR\n  p();\n  ASSERT_EQ(p.x, 1);\nEND_TEST\n"
    )
    out = subprocess.run(
        [sys.executable, "-m", "st.cli", "test", "--cov", "test_prog.st"], cwd=tmp_path, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert (
        "prog.st      9      4       8       3    47%   6-8, 12, 15, 5->THEN, 5->ELSIF (line 7), "
        "10->CASE 2, 3, 10->implicit ELSE, 14->CASE IDLE" in lines
    )  # (5 + 3) / (9 + 8)
    assert lines[-1] == "1 passed, 0 failed"
