"""The thesis's scheduling (Table 6.5) and latency (Tables 6.2–6.4) experiments: quick runs.

Scheduling runs on virtual time and must be bit-for-bit reproducible; latency runs in real time
(SCHED_FIFO only when root), so only its shape is checked."""

import csv
import importlib.util

import pytest

from st.api import compile_text
from st.experiments import latency, scheduling

pytestmark = pytest.mark.slow  # every test here runs the thesis experiments end to end

HAVE_MPL = importlib.util.find_spec("matplotlib") is not None


@pytest.fixture(scope="module")
def sched_runs(tmp_path_factory):
    a = tmp_path_factory.mktemp("sched_a")
    b = tmp_path_factory.mktemp("sched_b")
    scheduling.run(a, quick=True)
    scheduling.run(b, quick=True)
    return a, b


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_scheduling_is_deterministic(sched_runs):
    a, b = sched_runs
    for name in ("runs.csv", "executions.csv"):
        assert (a / name).read_text() == (b / name).read_text()
    assert (a / "summary.md").read_text() == (b / "summary.md").read_text()


def test_scheduling_summary_has_tables_and_thesis_numbers(sched_runs):
    text = (sched_runs[0] / "summary.md").read_text()
    assert "| policy | thread_1 (10 ms) | thread_2 (20 ms) | thread_3 (40 ms) | thesis (Table 6.5) |" in text
    assert "| policy | task | executions | overruns | skipped |" in text
    for thesis in ("600/300/202", "600/295/158", "554/297/151"):
        assert thesis in text
    assert "openplc (FCFS)" in text and "priority (RMS)" in text and "frame (semaphore-based)" in text
    assert "20 runs" in text


def test_scheduling_pinned_counts(sched_runs):
    rows = _rows(sched_runs[0] / "runs.csv")
    assert len(rows) == 4 * 20 * 3  # policies × runs × tasks
    frame_1x = [int(r["executions"]) for r in rows if r["policy"] == "frame" and r["task"] == "thread_1"]
    assert len(frame_1x) == 20
    assert sum(frame_1x) == 9000  # 450.0 per run on average (seed 1, 20 runs)
    assert frame_1x[0] == 449
    # frame keeps every release of the slower tasks; FCFS drops none but falls behind
    for task, n in (("thread_2", 300), ("thread_3", 150)):
        assert all(int(r["executions"]) == n for r in rows if r["policy"] == "frame" and r["task"] == task)
    assert all(int(r["skipped"]) == 0 for r in rows if r["policy"] == "openplc")
    assert (
        "| frame (semaphore-based) | 450.0 ± 0.9 | 300.0 ± 0.0 | 150.0 ± 0.0 |"
        in (sched_runs[0] / "summary.md").read_text()
    )


@pytest.mark.skipif(not HAVE_MPL, reason="matplotlib is not installed")
def test_scheduling_figures(sched_runs):
    for name in ("executions.png", "utility.png", "timeline.png"):
        p = sched_runs[0] / name
        assert p.exists() and p.stat().st_size > 1000


def test_utility_windows():
    assert scheduling.windows(bytes([1] * 10)) == [1.0]
    assert scheduling.windows(bytes([1, 0] * 6), k=4) == [0.5] * 9
    assert scheduling.windows(b"") == [1.0]


def test_axes_program_compiles():
    for n in (1, 3):
        compiled = compile_text(latency.axes_program(n), f"axes_{n}.st")
        assert compiled is not None
    seg = latency.segment_toml(3)
    assert seg.count("[[slave]]") == 3 and "axis = 3" in seg


def test_latency_quick(tmp_path):
    rep = latency.run(tmp_path, quick=True, axes=(1,), seconds=1)
    summary = tmp_path / "summary.md"
    assert rep.write() == summary and summary.exists()
    text = summary.read_text()
    assert "not reproducible" in text
    assert "1.2802" in text and "533.034" in text and "23.47" in text  # Table 6.2 beside ours
    rows = _rows(tmp_path / "latency.csv")
    st_rows = [r for r in rows if r["tool"] == "st run"]
    assert len(st_rows) == 1
    r = st_rows[0]
    assert int(r["samples"]) > 500
    assert 0 < float(r["min_us"]) <= float(r["avg_us"]) <= float(r["max_us"])
    assert float(r["cpu_percent"]) > 0 and float(r["exec_avg_us"]) > 0
    for c in (x for x in rows if x["tool"] == "cyclictest"):
        assert float(c["max_us"]) >= float(c["min_us"]) >= 0
    if HAVE_MPL:
        assert (tmp_path / "latency.png").exists()
