"""Every command-line value is checked before anything starts: a bad one is one `error: …` line on
stderr and exit status 2, never a traceback (st/app/params.py, cli.py). In process with click's
CliRunner: none of these compiles or starts anything, except the --dump-json runs on virtual time."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from st import PLC
from st.api import compile_text
from st.cli import main

ROOT = Path(__file__).resolve().parents[1]

COUNTER = """PROGRAM main
VAR n : INT; END_VAR
VAR RETAIN kept : INT; END_VAR
n := n + 1; kept := kept + 1;
END_PROGRAM
"""


def st(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture
def prog(tmp_path):
    p = tmp_path / "p.st"
    p.write_text(COUNTER)
    return p


def refused(r, line: str) -> None:
    assert (r.exit_code, r.stderr, r.stdout) == (2, line + "\n", ""), r.output
    assert r.exception is None or isinstance(r.exception, SystemExit)


@pytest.mark.parametrize(
    "args, line",
    [
        (["--duration", "10"], "error: --duration 10: a duration needs a unit, e.g. 10s or 10ms"),
        (["--duration", "2.5"], "error: --duration 2.5: a duration needs a unit, e.g. 2.5s or 2.5ms"),
        (["--duration", "-5s"], "error: --duration -5s: must be greater than 0"),
        (["--duration", "0s"], "error: --duration 0s: must be greater than 0"),
        (["--duration", "soon"], "error: --duration soon: not a duration (e.g. 10s, 250ms, 1m30s, T#2s)"),
        (["--scans", "-1"], "error: --scans -1: must be a whole number greater than 0"),
        (["--scans", "0"], "error: --scans 0: must be a whole number greater than 0"),
        (["--scans", "1.5"], "error: --scans 1.5: must be a whole number greater than 0"),
        (["--cycle", "0ms"], "error: --cycle 0ms: must be greater than 0"),
        (["--cycle", "20"], "error: --cycle 20: a duration needs a unit, e.g. 20s or 20ms"),
        (["--watchdog", "0s"], "error: --watchdog 0s: must be greater than 0"),
        (["--retain-interval", "-1s"], "error: --retain-interval -1s: must be greater than 0"),
        (["--rt-priority", "0"], "error: --rt-priority 0: must be a whole number from 1 to 99"),
        (["--rt-priority", "100"], "error: --rt-priority 100: must be a whole number from 1 to 99"),
        (["--sim-cost", "fast"], "error: --sim-cost fast: expected TASK=DURATION, e.g. fast=4ms"),
        (["--sim-cost", "fast=4"], "error: --sim-cost fast=4: 4: a duration needs a unit, e.g. 4s or 4ms"),
        (["--safe-output", "%QX0.1"], "error: --safe-output %QX0.1: expected ADDRESS=VALUE, e.g. %QX0.1=TRUE"),
        (["--safe-output", "%IX0.0=TRUE"], "error: --safe-output %IX0.0=TRUE: only outputs (%Q…) have safe values"),
        (["--safe-output", "%QX0.9=TRUE"], "error: --safe-output %QX0.9=TRUE: %QX0.9: bit 9 is not 0..7"),
        (["--safe-output", "%QX0.1=5"], "error: --safe-output %QX0.1=5: a bit's value is TRUE, FALSE, 0 or 1"),
        (["--safe-output", "%QW1=on"], "error: --safe-output %QW1=on: the value must be TRUE, FALSE or an integer"),
        (["--modbus", "5020x"], "error: --modbus 5020x: expected [HOST:]PORT, e.g. 127.0.0.1:5020"),
        (["--modbus", "0.0.0.0:70000"], "error: --modbus 0.0.0.0:70000: port 70000 is not 0..65535"),
        (["--web", "host:-1"], "error: --web host:-1: expected [HOST:]PORT, e.g. 127.0.0.1:5020"),
        (
            ["--modbus", "5020", "--modbus-max-connections", "0"],
            "error: --modbus-max-connections 0: must be a whole number greater than 0",
        ),
        (
            ["--modbus", "5020", "--modbus-idle-timeout", "0"],
            "error: --modbus-idle-timeout 0: must be a number greater than 0",
        ),
        (["--modbus", "5020", "--modbus-rate", "-1"], "error: --modbus-rate -1: must be a number, at least 0"),
        (
            ["--modbus", "5020", "--modbus-unit-ids", "1,256"],
            "error: --modbus-unit-ids 1,256: expected unit ids 0..255 separated by commas, e.g. 1,255",
        ),
        (
            ["--modbus", "5020", "--modbus-writable", "holding:9-1"],
            "error: --modbus-writable holding:9-1: writable range 'holding:9-1': expected TABLE:FIRST-LAST, "
            "e.g. holding:0-99",
        ),
        (["--policy", "fifo"], "error: --policy: 'fifo' is not one of 'openplc', 'priority', 'edf', 'frame'"),
        (["--zzz"], "error: no such option '--zzz'"),
        (["--scans"], "error: option '--scans' requires an argument"),
    ],
)
def test_a_bad_value_of_st_run_is_one_error_line_and_exit_2(prog, args, line):
    refused(st("run", prog, *args), line)


@pytest.mark.parametrize(
    "args, line",
    [
        (["--virtual"], "error: --virtual needs --duration or --scans (virtual time runs as fast as the CPU allows)"),
        (["--virtual", "--scans", "3", "--web"], "error: --web needs a run in real time (not --virtual)"),
        (["--virtual", "--scans", "3", "--watch"], "error: --watch needs a run in real time (not --virtual)"),
        (["--retain", "x.db", "--no-retain"], "error: --retain and --no-retain exclude each other"),
        (["--all"], "error: --all needs --dump-json"),
        (["--modbus-read-only"], "error: --modbus-read-only needs --modbus"),
        (["--modbus-rate", "10"], "error: --modbus-rate needs --modbus"),
        (["--web-read-only"], "error: --web-read-only needs --web"),
        (["--trace-plot", "t.png"], "error: --trace-plot needs --trace"),
        (["--ethercat-backend", "soem"], "error: --ethercat-backend needs --ethercat"),
    ],
)
def test_options_that_need_or_exclude_each_other(prog, args, line):
    refused(st("run", prog, *args), line)


def test_virtual_without_an_end_is_refused_before_the_plc_is_built_or_retained_data_restored(tmp_path, prog):
    db = tmp_path / "kept.db"
    refused(
        st("run", prog, "--virtual", "--retain", db),
        "error: --virtual needs --duration or --scans (virtual time runs as fast as the CPU allows)",
    )
    assert not db.exists()  # nothing opened, nothing restored
    assert sorted(os.listdir(tmp_path)) == ["p.st"]


def test_files_that_cannot_be_read_or_written(tmp_path, prog):
    a_file = tmp_path / "plain.txt"
    a_file.write_text("")
    missing = tmp_path / "nope.st"
    refused(st("run", missing), f"error: {missing}: no such file")
    refused(st("check", missing), f"error: {missing}: no such file")
    refused(st("compile", tmp_path), f"error: {tmp_path}: is a directory, not a file")
    refused(st("test", missing), f"error: {missing}: no such file or directory")
    refused(
        st("run", prog, "--retain", "/no/such/dir/x.db"),
        "error: --retain /no/such/dir/x.db: no such folder: /no/such/dir",
    )
    refused(st("run", prog, "--retain", a_file / "x.db"), f"error: --retain {a_file / 'x.db'}: not a folder: {a_file}")
    refused(st("run", prog, "--stats-json", tmp_path), f"error: --stats-json {tmp_path}: is a directory")
    refused(
        st("run", prog, "--stats-plot", tmp_path / "no" / "s.png"),
        f"error: --stats-plot {tmp_path / 'no' / 's.png'}: no such folder: {tmp_path / 'no'}",
    )
    refused(
        st("run", prog, "--trace", "main.ax", "--trace-plot", tmp_path / "no" / "t.png"),
        f"error: --trace-plot {tmp_path / 'no' / 't.png'}: no such folder: {tmp_path / 'no'}",
    )
    refused(
        st("run", prog, "--modbus", "5020", "--modbus-map", missing), f"error: --modbus-map {missing}: no such file"
    )
    refused(st("run", prog, "--axes", missing), f"error: --axes {missing}: no such file")
    refused(st("run", prog, "--ethercat", missing), f"error: --ethercat {missing}: no such file")
    refused(st("modbus", "map", prog, "--modbus-map", missing), f"error: --modbus-map {missing}: no such file")
    refused(st("test", prog, "--cov-html", a_file), f"error: --cov-html {a_file}: is a file, not a folder")
    refused(st("experiment", "latency", "--out", a_file), f"error: --out {a_file}: is a file, not a folder")
    assert sorted(os.listdir(tmp_path)) == ["p.st", "plain.txt"]  # the checks left nothing behind


def test_a_read_only_folder(tmp_path, prog):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        try:
            (ro / "probe").write_text("")
            pytest.skip("this user writes into read-only folders (root)")
        except PermissionError:
            pass
        refused(
            st("run", prog, "--retain", ro / "x.db"),
            f"error: --retain {ro / 'x.db'}: cannot write in {ro} (permission denied)",
        )
        refused(
            st("run", prog, "--stats-json", ro / "s.json"),
            f"error: --stats-json {ro / 's.json'}: cannot write in {ro} (permission denied)",
        )
    finally:
        ro.chmod(0o755)


@pytest.mark.skipif(not os.path.isdir("/sys/kernel"), reason="no /sys")
def test_a_folder_nobody_may_write_in_root_included(prog):
    try:
        open("/sys/kernel/st-probe", "w").close()
        pytest.skip("/sys/kernel is writable here")
    except OSError:
        pass
    refused(
        st("run", prog, "--retain", "/sys/kernel/x.db"),
        "error: --retain /sys/kernel/x.db: cannot write in /sys/kernel (permission denied)",
    )


def test_a_retain_file_that_is_not_a_database_is_a_start_error(tmp_path, prog):
    db = tmp_path / "kept.db"
    db.write_text("not SQLite at all " * 100)
    r = st("run", prog, "--virtual", "--scans", "1", "--retain", db)
    assert (r.exit_code, r.stderr) == (2, f"error: cannot open the retained data file {db}: file is not a database\n")


def test_durations_of_the_other_commands(tmp_path, prog):
    refused(st("test", prog, "--timeout", "5"), "error: --timeout 5: a duration needs a unit, e.g. 5s or 5ms")
    refused(st("test", prog, "--timeout", "0s"), "error: --timeout 0s: must be greater than 0")
    seg = ROOT / "programs" / "gantry.segment.toml"
    refused(st("ethercat", "plan", seg, "--cycle", "1"), "error: --cycle 1: a duration needs a unit, e.g. 1s or 1ms")
    refused(
        st("ethercat", "serve", "--iface", "lo", "--config", seg, "--duration", "3"),
        "error: --duration 3: a duration needs a unit, e.g. 3s or 3ms",
    )
    refused(st("experiment", "latency", "--seed", "x"), "error: --seed x: must be a whole number")
    refused(
        st("experiment", "nope"),
        "error: unknown experiment 'nope' (known: single-axis, multi-axis, scheduling, latency)",
    )
    refused(st("ethercat", "scan"), "error: the sim backend needs --config segment.toml")
    refused(st("ethercat", "scan", "--backend", "soem"), "error: the soem backend needs --iface")
    r = st("ethercat", "plan", seg, "--cycle", "250us")
    assert r.exit_code == 0 and "of 250.000 µs" in r.stdout


def test_a_good_command_line_still_runs(prog):
    r = st("run", prog, "--virtual", "--scans", "3", "--no-retain", "--cycle", "T#20ms", "--dump-json", "-q")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout) == {"main.n": 3, "main.kept": 3}


TIMED = """PROGRAM main
VAR
  go : BOOL := TRUE;
  t : TON;
  edge : R_TRIG;
  n : INT;
END_VAR
t(IN := go, PT := T#50ms);
edge(CLK := t.Q);
IF edge.Q THEN n := n + 1; END_IF;
END_PROGRAM
"""


def test_dump_json_shows_a_block_instance_by_its_interface_and_all_of_it_with_all(tmp_path):
    p = tmp_path / "timed.st"
    p.write_text(TIMED)
    r = st("run", p, "--virtual", "--duration", "100ms", "--cycle", "10ms", "--dump-json", "-q")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout) == {
        "main.go": True,
        "main.t": {"IN": True, "PT": "T#50ms", "Q": True, "ET": "T#50ms"},
        "main.edge": {"CLK": True, "Q": False},
        "main.n": 1,
    }
    r = st("run", p, "--virtual", "--duration", "100ms", "--cycle", "10ms", "--dump-json", "--all", "-q")
    assert r.exit_code == 0, r.output
    dump = json.loads(r.stdout)
    assert list(dump["main.t"]) == ["IN", "PT", "Q", "ET", "STATE", "PREV_IN", "START_TIME", "NOW"]
    assert list(dump["main.edge"]) == ["CLK", "Q", "M"]


INOUT = """FUNCTION_BLOCK Acc
VAR_INPUT inc : INT; END_VAR
VAR_IN_OUT total : INT; END_VAR
VAR_OUTPUT calls : INT; END_VAR
VAR hidden : INT; t : TON; END_VAR
total := total + inc; calls := calls + 1; hidden := 7;
END_FUNCTION_BLOCK
PROGRAM main
VAR a : Acc; n : INT; many : ARRAY[1..2] OF Acc; END_VAR
a(inc := 2, total := n);
many[2](inc := 1, total := n);
END_PROGRAM
"""


def test_variables_api_public_by_default_everything_with_all():
    plc = PLC(compile_text(INOUT, "inout.st", use_cache=False))
    plc.scan(2)
    assert plc.variables() == {
        "main.a": {"inc": 2, "total": 5, "calls": 2},
        "main.n": 6,
        "main.many": [{"inc": 0, "total": 0, "calls": 0}, {"inc": 1, "total": 6, "calls": 2}],
    }
    everything = plc.variables(all=True)
    assert everything["main.a"]["hidden"] == 7 and everything["main.a"]["t"]["STATE"] == 0
    assert plc.variables(all=True)["main.many"][1]["hidden"] == 7


def test_explain_an_unknown_code():
    r = st("explain", "E999")
    assert r.exit_code == 2 and r.stderr.startswith("error: unknown code E999; codes: E000, ")


@pytest.mark.slow
def test_dump_json_to_a_full_disk_is_an_error_not_a_traceback(prog):
    with open("/dev/full", "w") as full:
        r = subprocess.run(
            [
                sys.executable,
                "-m",
                "st",
                "run",
                str(prog),
                "--virtual",
                "--scans",
                "2",
                "--no-retain",
                "--dump-json",
                "-q",
            ],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
        )
    assert (r.returncode, r.stderr) == (
        2,
        "error: --dump-json: cannot write to the standard output (no space left on device)\n",
    )


@pytest.mark.slow
def test_st_run_duration_without_unit_in_a_subprocess(prog):
    r = subprocess.run(
        [sys.executable, "-m", "st", "run", str(prog), "--duration", "10"], capture_output=True, text=True, timeout=120
    )
    assert (r.returncode, r.stdout, r.stderr) == (
        2,
        "",
        "error: --duration 10: a duration needs a unit, e.g. 10s or 10ms\n",
    )
