"""Where `st run` keeps retained data: only for a program with RETAIN or PERSISTENT variables, never
for a --virtual run unless --retain PATH says so, by default in a per-user data folder keyed by the
project ($XDG_DATA_HOME/st/retain/<name>-<hash>.db), never beside the sources (st/app/session.py)."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from st.app.session import default_retain_path
from st.cli import main

ROOT = Path(__file__).resolve().parents[1]
# the compile cache stays where it is when a test moves HOME
CACHE = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")

KEPT = """PROGRAM main
VAR n : INT; END_VAR
VAR RETAIN kept : INT; END_VAR
n := n + 1; kept := kept + 1;
END_PROGRAM
"""

PLAIN = """PROGRAM main
VAR n : INT; END_VAR
n := n + 1;
END_PROGRAM
"""


def expected(*files: Path, root: Path) -> Path:
    paths = sorted(str(f.resolve()) for f in files)
    digest = hashlib.sha256("\n".join(paths).encode()).hexdigest()[:12]
    return root / "st" / "retain" / f"{Path(paths[0]).stem}-{digest}.db"


def st_run(*args, env: dict, timeout: float = 120):
    """`st run` in real time, in a subprocess (the real-time loop is the process's own)."""
    return subprocess.run(
        [sys.executable, "-m", "st", "run", *map(str, args)],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=timeout,
    )


@pytest.fixture
def src(tmp_path):
    d = tmp_path / "project"
    d.mkdir()
    return d


@pytest.fixture
def env(tmp_path):
    e = dict(os.environ)
    e["XDG_DATA_HOME"] = str(tmp_path / "data")
    e["HOME"] = str(tmp_path / "home")
    e["XDG_CACHE_HOME"] = CACHE
    return e


def test_the_default_place_is_keyed_by_the_project_in_xdg_data_home(tmp_path, monkeypatch):
    a, b = tmp_path / "line.st", tmp_path / "lib.st"
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    assert default_retain_path([str(b), str(a)]) == expected(a, b, root=tmp_path / "data")
    assert default_retain_path([str(a), str(b)]) == default_retain_path([str(b), str(a)])  # any order
    assert default_retain_path([str(a)]) != default_retain_path([str(a), str(b)])
    assert default_retain_path([str(a)]).name.startswith("line-")
    monkeypatch.delenv("XDG_DATA_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_retain_path([str(a)]) == expected(a, root=tmp_path / "home" / ".local" / "share")
    monkeypatch.setenv("XDG_DATA_HOME", "relative/dir")  # not absolute: ignored, as the XDG spec says
    assert default_retain_path([str(a)]) == expected(a, root=tmp_path / "home" / ".local" / "share")


@pytest.mark.slow
def test_a_real_time_run_keeps_retained_data_in_the_data_folder_not_beside_the_source(src, env, tmp_path):
    prog = src / "plant.st"
    prog.write_text(KEPT)
    db = expected(prog, root=tmp_path / "data")
    r = st_run(prog, "--no-rt", "--cycle", "10ms", "--duration", "100ms", env=env)
    assert r.returncode == 0, r.stderr
    assert f"retained data: {db} (0 value(s) restored)\n" in r.stderr
    assert sorted(os.listdir(src)) == ["plant.st"]
    assert sorted(os.listdir(db.parent)) == [db.name]  # no -wal or -shm after a clean stop
    r = st_run(prog, "--no-rt", "--cycle", "10ms", "--duration", "100ms", env=env)
    assert f"retained data: {db} (1 value(s) restored)\n" in r.stderr
    assert sorted(os.listdir(src)) == ["plant.st"]


@pytest.mark.slow
def test_without_xdg_data_home_the_folder_is_under_home(src, env, tmp_path):
    prog = src / "plant.st"
    prog.write_text(KEPT)
    del env["XDG_DATA_HOME"]
    db = expected(prog, root=tmp_path / "home" / ".local" / "share")
    r = st_run(prog, "--no-rt", "--cycle", "10ms", "--duration", "50ms", env=env)
    assert r.returncode == 0, r.stderr
    assert f"retained data: {db} (0 value(s) restored)\n" in r.stderr
    assert db.exists() and sorted(os.listdir(src)) == ["plant.st"]


@pytest.mark.slow
def test_a_program_without_retain_writes_no_file(src, env, tmp_path):
    prog = src / "plain.st"
    prog.write_text(PLAIN)
    r = st_run(prog, "--no-rt", "--cycle", "10ms", "--duration", "50ms", env=env)
    assert r.returncode == 0, r.stderr
    assert "retained data" not in r.stderr
    assert not (tmp_path / "data").exists() and not (tmp_path / "home").exists()
    assert sorted(os.listdir(src)) == ["plain.st"]


def test_a_virtual_run_keeps_no_retained_data_unless_retain_is_given(src, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setenv("XDG_CACHE_HOME", CACHE)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    prog = src / "plant.st"
    prog.write_text(KEPT)
    r = CliRunner().invoke(main, ["run", str(prog), "--virtual", "--scans", "3"])
    assert r.exit_code == 0, r.output
    assert "retained data" not in r.stderr
    assert not (tmp_path / "data").exists() and not (tmp_path / "home").exists()
    assert sorted(os.listdir(src)) == ["plant.st"]
    chosen = tmp_path / "chosen.retain.db"
    r = CliRunner().invoke(main, ["run", str(prog), "--virtual", "--scans", "3", "--retain", str(chosen)])
    assert r.exit_code == 0, r.output
    assert f"retained data: {chosen} (0 value(s) restored)\n" in r.stderr
    r = CliRunner().invoke(main, ["run", str(prog), "--virtual", "--scans", "3", "--retain", str(chosen)])
    assert f"retained data: {chosen} (1 value(s) restored)\n" in r.stderr
    assert sorted(os.listdir(tmp_path)) == ["chosen.retain.db", "project"]
    assert sorted(os.listdir(src)) == ["plant.st"]


def test_retain_for_a_program_without_retained_variables_writes_nothing(src, tmp_path):
    prog = src / "plain.st"
    prog.write_text(PLAIN)
    chosen = tmp_path / "chosen.db"
    r = CliRunner().invoke(main, ["run", str(prog), "--virtual", "--scans", "3", "--retain", str(chosen)])
    assert r.exit_code == 0, r.output
    assert "retained data: none (the program has no RETAIN or PERSISTENT variable)\n" in r.stderr
    assert not chosen.exists()


def test_no_retain_keeps_nothing(src, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    prog = src / "plant.st"
    prog.write_text(KEPT)
    r = CliRunner().invoke(main, ["run", str(prog), "--virtual", "--scans", "3", "--no-retain"])
    assert r.exit_code == 0 and "retained data" not in r.stderr
    assert not (tmp_path / "data").exists() and sorted(os.listdir(src)) == ["plant.st"]


@pytest.mark.slow
def test_a_killed_run_leaves_its_wal_files_in_the_data_folder_only(src, env, tmp_path):
    prog = src / "plant.st"
    prog.write_text(KEPT)
    db = expected(prog, root=tmp_path / "data")
    child = subprocess.Popen(
        [sys.executable, "-m", "st", "run", str(prog), "--no-rt", "--cycle", "10ms", "--retain-interval", "20ms"],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=ROOT,
    )
    try:
        assert child.stderr is not None
        for line in child.stderr:
            if line.startswith("running in real time"):
                break
        time.sleep(0.3)  # a few commits
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=30)
    assert sorted(os.listdir(src)) == ["plant.st"]
    assert db.exists() and set(os.listdir(db.parent)) <= {db.name, db.name + "-wal", db.name + "-shm"}


def test_gitignore_covers_a_retain_file_chosen_inside_a_project():
    lines = (ROOT / ".gitignore").read_text().splitlines()
    assert {"*.retain.db", "*.retain.db-wal", "*.retain.db-shm"} <= set(lines)
