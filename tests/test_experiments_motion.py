"""The thesis's motion experiments (st/experiments): the mechanisms they show, in short runs, and
that `st experiment` writes its files reproducibly."""

import os
import subprocess
import sys

import pytest

from st.experiments import multi_axis, single_axis

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_a_velocity_command_is_held_and_tracked():
    rows, steady, tracking = single_axis.velocity_command(10.0, 0.3)
    assert len(rows) == 1300  # 1 s ramp at 10 rev/s² + 0.3 s, one row per ms
    assert rows[-1][1] == pytest.approx(10.0)  # the set speed
    assert steady < 0.001  # % after the ramp
    assert 0.05 < tracking < 1.0  # % over the whole command (the ramp's corners)


def test_rotate_and_stop_loses_the_lag_once_per_cycle_and_pi_bounds_it():
    plain = single_axis.rotate_and_stop(1, 12, False)
    assert [c for c, _ in plain] == list(range(1, 13))
    per_cycle = plain[-1][1] / 12
    assert per_cycle < -0.01  # degrees lost per cycle
    # linear in the cycles: the second half loses as much as the first
    assert plain[5][1] == pytest.approx(plain[-1][1] / 2, rel=0.05)
    ten = single_axis.rotate_and_stop(10, 6, False)
    assert ten[-1][1] / 6 == pytest.approx(per_cycle, rel=1.0)  # about the same per cycle for 10 rotations
    pi = single_axis.rotate_and_stop(1, 12, True)
    assert abs(pi[-1][1]) < 0.1 * abs(plain[-1][1])  # the calibration removes > 90 %


def test_offset_between_two_axes_is_speed_times_delay_and_compensation_removes_it():
    plain = multi_axis.offset_run(1.0, 10.0, False, 0.6)
    comp = multi_axis.offset_run(1.0, 10.0, True, 0.6)
    assert plain[-1][1] == pytest.approx(0.36, rel=0.01)  # 1 rev/s × 1 ms = 0.36°
    assert abs(comp[-1][1]) < 0.002
    # the PLC's own view compares samples the drives took 1 ms apart: no offset visible there
    assert abs(plain[-1][2]) < 0.01


@pytest.mark.slow
def test_st_experiment_writes_csv_plots_and_a_reproducible_summary(tmp_path):
    outs = []
    for k in range(2):
        out = tmp_path / f"run{k}"
        r = subprocess.run(
            [sys.executable, "-m", "st", "experiment", "multi-axis", "--quick", "--out", str(out)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert r.returncode == 0, r.stderr
        outs.append(out)
    summary = (outs[0] / "summary.md").read_text()
    assert "| delay (ms) | expected speed × delay (°) |" in summary and "| 0.5 | 0.18 |" in summary
    assert summary == (outs[1] / "summary.md").read_text()
    csvs = sorted(p.name for p in outs[0].glob("*.csv"))
    assert "offset_delay_2.csv" in csvs and "offset_delay_2_compensated.csv" in csvs
    for name in csvs:
        assert (outs[0] / name).read_text() == (outs[1] / name).read_text()
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return
    assert (outs[0] / "fig6_8_6_9_offsets.png").stat().st_size > 10_000


@pytest.mark.slow
def test_unknown_experiment_is_a_clear_error():
    r = subprocess.run([sys.executable, "-m", "st", "experiment", "nope"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "unknown experiment 'nope' (known: single-axis, multi-axis" in r.stderr
