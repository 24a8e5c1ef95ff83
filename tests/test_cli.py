"""The `st` command line, run as a user would (a subprocess)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def st(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "st", *args], capture_output=True, text=True, cwd=cwd or ROOT, timeout=120
    )


@pytest.mark.slow
def test_run_openplc_export_and_dump_json():
    r = st("run", "programs/blink.st", "--scans", "3", "--dump-json")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert all(k.startswith("instance0.") for k in data)
    assert isinstance(data["instance0.on_time"], str) and data["instance0.on_time"].startswith("T#")


@pytest.mark.slow
def test_run_lone_program_with_cycle(tmp_path):
    f = tmp_path / "p.st"
    f.write_text("PROGRAM p\nVAR n : INT; t : TIME; END_VAR\nn := n + 1;\nEND_PROGRAM\n")
    r = st("run", str(f), "--scans", "5", "--cycle", "20ms", "--dump-json")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == {"p.n": 5, "p.t": "T#0s"}


@pytest.mark.slow
def test_check_reports_errors_with_location_and_exit_code(tmp_path):
    f = tmp_path / "bad.st"
    f.write_text("PROGRAM p\nVAR a : INT; END_VAR\na := b;\nEND_PROGRAM\n")
    r = st("check", str(f))
    assert r.returncode == 1
    assert f"{f}:3:6: error[E010]: undeclared identifier 'b'" in r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.slow
def test_check_ok(tmp_path):
    r = st("check", "programs/traffic_light.st")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("ok: 1 file(s)")


@pytest.mark.slow
def test_missing_file_is_a_clean_error(tmp_path):
    r = st("check", str(tmp_path / "nope.st"))
    assert r.returncode == 2  # a bad argument, refused before compiling (exit 1: compile errors)
    assert r.stderr == f"error: {tmp_path / 'nope.st'}: no such file\n"


@pytest.mark.slow
def test_emit_python_is_readable(tmp_path):
    f = tmp_path / "e.st"
    f.write_text(
        "FUNCTION Twice : INT\nVAR_INPUT x : INT; END_VAR\nTwice := x * 2;\nEND_FUNCTION\n"
        "PROGRAM p\nVAR y : INT; END_VAR\ny := Twice(y + 1);\nEND_PROGRAM\n"
    )
    r = st("compile", str(f), "--emit", "python")
    assert r.returncode == 0, r.stderr
    assert "def _fn_Twice(x):" in r.stdout
    assert "self.y = _fn_Twice((self.y + 1 + 32768 & 65535) - 32768)" in r.stdout  # used twice: on the instance


@pytest.mark.slow
def test_runtime_fault_exit_code_and_message(tmp_path):
    f = tmp_path / "f.st"
    f.write_text("PROGRAM p\nVAR a : INT; b : INT; END_VAR\na := 10 / b;\nEND_PROGRAM\n")
    r = st("run", str(f), "--scans", "1")
    assert r.returncode == 3
    assert f"{f}:3: PLC fault [DIV0]: division by zero (in p, task main)" in r.stderr


@pytest.mark.slow
def test_explain():
    r = st("explain", "E027")
    assert r.returncode == 0
    assert r.stdout.startswith("E027: An implicit narrowing conversion")


def test_diagnostics_doc_is_current():
    from st.errors_doc import markdown

    assert (ROOT / "docs" / "diagnostics.md").read_text() == markdown()
