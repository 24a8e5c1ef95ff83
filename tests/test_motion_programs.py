"""The motion example programs, on virtual time, and `st run --trace`."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from st import PLC
from st.stdlib.plcopen import axis_of, configure_axes

ROOT = Path(__file__).resolve().parent.parent


def run_program(name: str, seconds: str) -> PLC:
    plc = PLC.from_files(str(ROOT / "programs" / f"{name}.st"))
    configure_axes(plc, ROOT / "programs" / f"{name}.axes.toml")
    plc.advance(seconds)
    return plc


def test_pick_and_place_places_three_parts_in_ten_seconds():
    plc = run_program("pick_and_place", "10s")
    assert (plc["cell.parts"], plc["cell.step"], plc["cell.fault"]) == (3, 40, False)
    x, z = axis_of(plc, "cell.x"), axis_of(plc, "cell.z")
    assert (x.cfg.name, z.cfg.name, x.state, x.set_pos) == ("x", "z", "Standstill", 0.0)
    assert z.state == "DiscreteMotion" and 0.0 < z.set_pos < 80.0  # lifting the fourth part


def test_conveyor_sync_processes_parts_while_moving_with_the_conveyor():
    plc = run_program("conveyor_sync", "12s")
    assert (plc["line.parts"], plc["line.synchronised_ms"]) == (2, 1506)
    conveyor = axis_of(plc, "line.conveyor")
    assert conveyor.cfg.modulo == 1000.0 and conveyor.set_vel == 200.0
    # the program read the position before the last cycle's kernel step (0.4 mm earlier), wrapped
    assert conveyor.set_pos == 2350.0 and plc["line.conveyor_pos.Position"] == pytest.approx(349.6)


@pytest.mark.slow
def test_st_run_trace_writes_csv_and_plot(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "st.cli",
            "run",
            str(ROOT / "programs" / "pick_and_place.st"),
            "--axes",
            str(ROOT / "programs" / "pick_and_place.axes.toml"),
            "--virtual",
            "--duration",
            "2s",
            "--trace",
            "cell.x",
            "--trace",
            "cell.z",
            "--trace-plot",
            str(tmp_path / "m.png"),
            "--dump-json",
        ],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    assert "trace: 2000 samples of cell.x, cell.z" in out.stderr
    rows = list(csv.reader((tmp_path / "m.csv").open()))
    assert rows[0] == [
        "time_s",
        "axis",
        "set_position",
        "set_velocity",
        "set_acceleration",
        "actual_position",
        "actual_velocity",
        "state",
    ]
    assert len(rows) == 2001 and rows[1][:2] == ["0.000000", "cell.x"]
    assert (tmp_path / "m.png").read_bytes()[:4] == b"\x89PNG"
    assert json.loads(out.stdout.splitlines()[-1])["cell.step"] == 70


@pytest.mark.slow
def test_st_run_trace_of_something_else_is_a_clear_error(tmp_path):
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "st.cli",
            "run",
            str(ROOT / "programs" / "pick_and_place.st"),
            "--virtual",
            "--scans",
            "1",
            "--trace",
            "cell.parts",
        ],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 2 and "error: --trace cell.parts: not an AXIS_REF (it is DINT)" in out.stderr
