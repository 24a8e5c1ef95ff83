"""The native tier by default (st/app/native_upgrade.py): `st run` starts on the Python tier, builds
the program compiled to C beside the scan and swaps it in at a scan boundary with its state;
`--python` stays on Python; `--native` with `--python` is refused."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from st import PLC
from st.api import compile_paths
from st.app.native_upgrade import NativeUpgrade, start_native_upgrade
from st.app.options import RunOptions
from st.cli import main
from st.compiler.native import toolchain

ROOT = Path(__file__).resolve().parents[1]
COUNTER = "PROGRAM main\nVAR n : DINT; s : LREAL; i : INT; END_VAR\nn := n + 1;\nFOR i := 1 TO 10 DO s := s + 0.5; END_FOR;\nEND_PROGRAM\n"
needs_toolchain = pytest.mark.skipif(toolchain.missing() is not None, reason=f"native tier: {toolchain.missing()}")


@needs_toolchain
def test_the_native_build_is_swapped_in_at_a_scan_boundary_with_the_state(tmp_path, capsys):
    src = tmp_path / "counter.st"
    src.write_text(COUNTER)
    plc = PLC(compile_paths([str(src)]))
    plc.scan(7)
    assert not plc.compiled.native
    up = NativeUpgrade(plc, RunOptions(files=[str(src)]))
    end = time.monotonic() + 120
    while up.prepared is None and not up.note and time.monotonic() < end:
        plc.scan(1)  # the PLC goes on meanwhile
        time.sleep(0.05)
    n_before = plc["main.n"]
    up.poll()
    assert plc.compiled.native and up.done
    assert plc["main.n"] == n_before  # carried over
    plc.scan(3)
    assert plc["main.n"] == n_before + 3 and plc["main.s"] == 5.0 * (n_before + 3)
    assert "block bodies now run compiled to C (swapped in at a scan boundary, the state carried over)" in (
        capsys.readouterr().err
    )


def test_no_background_build_when_native_already_opted_out_virtual_or_with_web():
    from contextlib import ExitStack

    plc = object()
    for o in (
        RunOptions(files=["x.st"], native=True),
        RunOptions(files=["x.st"], python=True),
        RunOptions(files=["x.st"], virtual=True),
        RunOptions(files=["x.st"], web="127.0.0.1:0"),
    ):
        assert start_native_upgrade(ExitStack(), plc, o) is None


def test_native_and_python_exclude_each_other():
    r = CliRunner().invoke(
        main, ["run", str(ROOT / "programs" / "blink.st"), "--native", "--python", "--duration", "1s"]
    )
    assert r.exit_code == 2 and "--native and --python exclude each other" in r.output


@pytest.mark.slow  # (a real-time run)
@needs_toolchain
def test_st_run_says_when_the_program_runs_compiled_to_c(tmp_path):
    src = tmp_path / "counter.st"
    src.write_text(COUNTER)
    env = {"ST_CACHE_DIR": str(tmp_path / "cache"), "PATH": "/usr/bin:/bin"}
    subprocess.run(
        [sys.executable, "-m", "st", "compile", "--native", str(src)], env=env, check=True, capture_output=True
    )
    run = [sys.executable, "-m", "st", "run", str(src), "--duration", "2s", "--no-rt"]
    out = subprocess.run(run, env=env, capture_output=True, text=True, timeout=120)
    assert "native: built in" in out.stderr and "now run compiled to C" in out.stderr, out.stderr
    out = subprocess.run([*run, "--python"], env=env, capture_output=True, text=True, timeout=120)
    assert "native:" not in out.stderr, out.stderr


@needs_toolchain
def test_an_edit_swapped_in_on_python_is_built_natively_in_its_turn_and_a_stale_build_is_not_used(tmp_path):
    from st.api import compile_text

    src = tmp_path / "counter.st"
    src.write_text(COUNTER)
    plc = PLC(compile_paths([str(src)]))
    plc.scan(2)
    up = NativeUpgrade(plc, RunOptions(files=[str(src)]))
    # an edit swapped in (as --watch does) while the first build runs: that build is for a program
    # that no longer runs, so it is not used, and the edit is built instead
    edited = COUNTER.replace("n := n + 1;", "n := n + 1; k := k + 2;").replace(
        "VAR n : DINT;", "VAR n : DINT; k : DINT;"
    )
    plc.online_change(compile_text(edited, str(src)))
    end = time.monotonic() + 180
    while not (up.done and plc.compiled.native) and time.monotonic() < end:
        plc.scan(1)
        up.poll()
        time.sleep(0.05)
    assert plc.compiled.native and plc["main.k"] > 0  # the edit, compiled to C
    k = plc["main.k"]
    plc.scan(2)
    assert plc["main.k"] == k + 4
