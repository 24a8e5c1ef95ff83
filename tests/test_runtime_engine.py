"""The runtime engine: policies, overload, process image, faults and safe outputs, retain, online change,
statistics and `st run`."""

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from st import PLC, PLCFaultError
from st.api import compile_text
from st.runtime.stats import TaskStats

from helpers import StRun

ORDER = """
VAR_GLOBAL log : ARRAY[0..39] OF INT; n : INT; go : BOOL; END_VAR
PROGRAM Rec
  VAR_INPUT id : INT; END_VAR
  VAR_EXTERNAL log : ARRAY[0..39] OF INT; n : INT; END_VAR
  IF n < 40 THEN log[n] := id; n := n + 1; END_IF;
END_PROGRAM
CONFIGURATION c
  VAR_GLOBAL log : ARRAY[0..39] OF INT; n : INT; go : BOOL; END_VAR
  RESOURCE r ON PLC
    TASK slow (INTERVAL := T#40ms, PRIORITY := 1);
    TASK fast (INTERVAL := T#10ms, PRIORITY := 3);
    TASK mid (INTERVAL := T#20ms, PRIORITY := 2);
    TASK ev (SINGLE := go, PRIORITY := 0);
    PROGRAM p_slow WITH slow : Rec (id := 40);
    PROGRAM p_fast WITH fast : Rec (id := 10);
    PROGRAM p_mid WITH mid : Rec (id := 20);
    PROGRAM p_ev WITH ev : Rec (id := 99);
  END_RESOURCE
END_CONFIGURATION
""".replace("VAR_GLOBAL log : ARRAY[0..39] OF INT; n : INT; go : BOOL; END_VAR\nPROGRAM", "PROGRAM", 1)


@pytest.mark.parametrize(
    "policy, first_tick",
    [
        ("openplc", [40, 10, 20]),  # declaration order
        ("priority", [40, 20, 10]),  # PRIORITY 1, 2, 3
        ("edf", [10, 20, 40]),  # deadlines 10, 20, 40 ms
        ("frame", [10, 20, 40]),  # same release: shorter period first
    ],
)
def test_every_task_runs_at_its_interval_under_every_policy(policy, first_tick):
    plc = PLC.from_source(ORDER, policy=policy)
    plc.advance("1s")
    runs = {t.name: t.runs for t in plc.tasks}
    assert runs == {"slow": 25, "fast": 100, "mid": 50, "ev": 0}
    assert plc["log"][:3] == first_tick
    assert plc.tick == 10_000_000 and plc.time == 1_000_000_000


def test_several_program_instances_share_a_task_and_run_in_declaration_order():
    src = ORDER.replace(
        "PROGRAM p_mid WITH mid : Rec (id := 20);",
        "PROGRAM p_mid WITH mid : Rec (id := 20);\n    PROGRAM p_fast2 WITH fast : Rec (id := 11);",
    )
    plc = PLC.from_source(src, policy="edf")
    plc.scan(2)  # ticks 0 and 10 ms: fast's job runs p_fast then p_fast2 each time
    assert plc["log"][:6] == [10, 11, 20, 40, 10, 11]
    assert [t.runs for t in plc.tasks] == [1, 2, 1, 0]
    assert plc["p_fast2.id"] == 11 and plc.tasks[1].stats.jobs == 2


def test_event_task_runs_once_per_rising_edge():
    for policy in ("openplc", "priority"):
        plc = PLC.from_source(ORDER, policy=policy)
        plc.scan(3)
        plc["go"] = True
        plc.scan(3)
        plc["go"] = False
        plc.scan(1)
        plc["go"] = True
        plc.scan(1)
        assert plc.tasks[3].runs == 2, policy
        assert plc["log"].count(99) == 2


ONE = """
PROGRAM P VAR x : INT; END_VAR x := x + 1; END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK a (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p1 WITH a : P;
END_RESOURCE END_CONFIGURATION
"""


@pytest.mark.parametrize("policy, skipped", [("openplc", 0), ("priority", 4), ("edf", 4), ("frame", 4)])
def test_an_overrunning_task_is_late_or_skips_but_never_runs_twice(policy, skipped):
    # a 10 ms task whose job takes 25 ms, for 100 ms: openplc runs the ticks at 0, 10, 20, 30 late
    # (at 0, 25, 50, 75); the other policies start the newest release when the CPU frees (0, 20, 50, 70)
    plc = PLC.from_source(ONE, policy=policy)
    plc.set_cost("a", "25ms")
    plc.advance("100ms")
    s = plc.tasks[0].stats
    assert (s.jobs, s.skipped, s.overruns, plc["p1.x"]) == (4, skipped, 4, 4)
    lat = [round(v / 1e6) for v in s.latencies]
    assert lat == ([0, 15, 30, 45] if policy == "openplc" else [0, 5, 0, 5])
    assert s.utility == 0.0


def test_three_task_overload_counts_per_policy():
    # equal PRIORITY everywhere, so `priority` falls back to rate monotonic (shorter interval first)
    src = re.sub(
        r"PRIORITY := \d",
        "PRIORITY := 1",
        ORDER.replace("(SINGLE := go, PRIORITY := 0)", "(INTERVAL := T#1000ms, PRIORITY := 9)"),
    )
    counts = {}
    for policy in ("frame", "openplc", "priority"):
        plc = PLC(compile_text(src, "o.st"), policy=policy)
        for task, cost in (("fast", "4ms"), ("mid", "6ms"), ("slow", "14ms"), ("ev", "0ms")):
            plc.set_cost(task, cost)
        plc.advance("6s")
        counts[policy] = [t.runs for t in plc.tasks[:3]] + [sum(t.stats.skipped for t in plc.tasks)]
    # (slow, fast, mid runs; skipped releases): the thesis's Table 6.5 with exact costs
    assert counts["frame"] == [150, 450, 300, 150]  # all slow runs kept, fast loses one in four
    assert counts["openplc"] == [143, 571, 286, 0]  # FCFS never skips: everything runs late
    assert counts["priority"] == [150, 525, 300, 80]  # non-preemptive RMS: slow blocks fast at times


def test_process_image_latches_inputs_and_publishes_outputs():
    src = textwrap.dedent("""
        PROGRAM main
          VAR
            b AT %IX0.3 : BOOL; w AT %IW2 : INT; q AT %QX1.0 : BOOL; m AT %MD4 : REAL; copy : INT; seen : BOOL;
          END_VAR
          seen := b; copy := w; q := b; m := m + 0.5;
        END_PROGRAM
    """)
    plc = PLC.from_source(src)
    plc["%IX0.3"] = True
    plc["%IW2"] = -7
    assert plc["main.seen"] is False and plc["%QX1.0"] is False  # latched only at the next scan
    plc.scan()
    assert (plc["main.seen"], plc["main.copy"], plc["%QX1.0"], plc["%MD4"]) == (True, -7, True, 0.5)
    assert plc.image.tables[("I", "W")][2] == 65529  # raw 16-bit pattern of -7
    assert plc.image.tables[("M", "D")][4] == 0x3F000000  # IEEE-754 of 0.5
    plc["%MD4"] = 2.0  # an HMI write to %M, seen next scan
    plc.scan()
    assert plc["main.m"] == 2.5
    plc["main.b"] = False  # a write by path keeps the image in step
    plc.scan()
    assert plc["%QX1.0"] is False and plc["%IX0.3"] is False
    plc["%QW100"] = 42  # unbound cells are scratch memory
    assert plc["%QW100"] == 42
    with pytest.raises(KeyError, match="outside the process image"):
        plc["%IX1024.0"]
    assert plc["%QX3"] is False and plc["%QX3.0"] is False  # a bit address without its bit: bit 0 (issue 34)


FAULTY = """
PROGRAM main
  VAR d : INT; x : INT; lamp AT %QX0.0 : BOOL; valve AT %QX0.1 : BOOL; END_VAR
  VAR RETAIN total : DINT; END_VAR
  lamp := TRUE; valve := TRUE;
  total := total + 1;
  x := 100 / d;
END_PROGRAM
"""


def test_fault_sets_safe_outputs_and_restart_restores_retained(tmp_path):
    db = str(tmp_path / "r.db")
    plc = PLC.from_source(
        FAULTY.replace("100 / d", "100 / (d + 1)"),
        name="f.st",
        retain=db,
        retain_interval="20ms",
        safe_outputs={"%QX0.1": True},
    )
    plc.advance("100ms")
    assert (plc["%QX0.0"], plc["%QX0.1"], plc["main.total"]) == (True, True, 10)
    plc["main.d"] = -1
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    f = info.value.fault
    assert (f.kind, f.file, f.line, f.pou, f.task, plc.state) == ("DIV0", "f.st", 7, "main", "main", "FAULT")
    assert (plc["%QX0.0"], plc["%QX0.1"]) == (False, True)  # safe values: FALSE, or as configured
    assert plc["main.lamp"] is True  # the variable keeps what the scan wrote
    with pytest.raises(PLCFaultError):
        plc.scan()
    plc.restart()  # warm: fresh instances, retained restored
    # total was 10 after ten scans; the faulting scan incremented it before dividing, and the fault
    # committed it as it stood (a PLC's retain memory keeps what the scan wrote)
    assert (plc.state, plc["main.total"], plc["main.d"]) == ("RUN", 11, 0)
    plc.scan()
    assert plc["main.total"] == 12 and plc["%QX0.0"] is True
    plc.close()
    again = PLC.from_source(FAULTY, name="f.st", retain=db)
    assert again.retain_restored == 1 and again["main.total"] == 12
    cold = PLC.from_source(FAULTY, name="f.st", retain=db, cold=True)
    assert cold["main.total"] == 0


KINDS = """
FUNCTION_BLOCK Worker
  VAR_INPUT kind : INT; END_VAR
  VAR a : ARRAY[1..3] OF INT; r : REF_TO INT; d : INT; i : INT := 4; x : INT; END_VAR
  CASE kind OF
    1: x := 10 / d;
    2: a[i] := 1;
    3: x := r^;
    4: WHILE TRUE DO x := x + 1; END_WHILE;
  END_CASE;
END_FUNCTION_BLOCK
PROGRAM Cell
  VAR_INPUT kind : INT; END_VAR
  VAR w : Worker; lamp AT %QX2.3 : BOOL; speed AT %QW4 : INT; END_VAR
  lamp := TRUE; speed := 1500;
  w(kind := kind);
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK cyc (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM cell WITH cyc : Cell;
END_RESOURCE END_CONFIGURATION
"""


@pytest.mark.parametrize(
    "kind, code, line, policy",
    [(1, "DIV0", 6, "openplc"), (2, "INDEX", 7, "priority"), (3, "NULL", 8, "edf"), (4, "WATCHDOG", 9, "frame")],
)
def test_every_fault_kind_stops_the_task_with_a_located_diagnostic(kind, code, line, policy):
    plc = PLC.from_source(KINDS, name="k.st", policy=policy, watchdog="50ms")
    plc.scan(3)
    assert (plc["%QX2.3"], plc["%QW4"]) == (True, 1500)
    plc["cell.kind"] = kind
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    f = info.value.fault
    assert (f.kind, f.file, f.line, f.pou, f.task, plc.state) == (code, "k.st", line, "Worker", "cyc", "FAULT")
    assert (plc["%QX2.3"], plc["%QW4"]) == (False, 0)  # outputs safe
    assert plc.time == 40_000_000  # the faulting job consumed its tick
    plc["cell.kind"] = 0
    plc.reset_fault()
    plc.scan()
    assert (plc.state, plc["%QX2.3"], plc.tasks[0].runs) == ("RUN", True, 4)


def test_stop_and_start():
    plc = PLC.from_source(FAULTY.replace("100 / d", "d"))
    plc.scan(2)
    plc.stop()
    assert (plc.state, plc["%QX0.0"]) == ("STOP", False)
    plc.scan(5)
    assert plc["main.total"] == 2
    plc.start()
    plc.scan()
    assert (plc.state, plc["main.total"], plc["%QX0.0"]) == ("RUN", 3, True)


CHILD = """
import sys, time
from st import PLC
src = '''PROGRAM main VAR RETAIN a : DINT; b : DINT; s : ARRAY[1..3] OF DINT; END_VAR
a := a + 1; b := 2 * a; s[1] := a; s[2] := b; s[3] := a + b; END_PROGRAM'''
plc = PLC.from_source(src, cycle="1ms", retain=sys.argv[1], retain_interval="2ms")
print("ready", flush=True)
plc.run_realtime(duration="60s", gc_control=False)
"""


@pytest.mark.slow
def test_retained_snapshot_survives_kill_9(tmp_path):
    db = str(tmp_path / "kill.db")
    child = subprocess.Popen([sys.executable, "-c", CHILD, db], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "ready"
    time.sleep(0.6)
    os.kill(child.pid, signal.SIGKILL)
    child.wait()
    plc = PLC.from_source(
        "PROGRAM main VAR RETAIN a : DINT; b : DINT; s : ARRAY[1..3] OF DINT; END_VAR a := a + 1; END_PROGRAM",
        retain=db,
    )
    a, b, s = plc["main.a"], plc["main.b"], plc["main.s"]
    assert a > 50 and b == 2 * a and s == [a, 2 * a, 3 * a]  # one whole snapshot, not a torn one
    assert plc.retain_restored == 3


V1 = """
TYPE Rec : STRUCT v : INT; END_STRUCT; END_TYPE
PROGRAM main
  VAR n : INT; t : TON; r : Rec; hist : ARRAY[1..2] OF INT; END_VAR
  n := n + 1; r.v := n; hist[1] := n; t(IN := TRUE, PT := T#1s);
END_PROGRAM
"""


def test_online_change_carries_values_over_and_refuses_type_changes():
    plc = PLC.from_source(V1)
    plc.advance("500ms")
    assert plc["main.n"] == 50
    msg = plc.online_change(
        compile_text(
            V1.replace("n := n + 1", "n := n + 10") + "FUNCTION Unused : INT Unused := 1; END_FUNCTION", "v2.st"
        )
    )
    assert msg == "online change: 1 instance(s) carried over"
    plc.scan()
    assert (plc["main.n"], plc["main.r.v"], plc["main.hist"]) == (60, 60, [60, 0])
    assert plc["main.t.ET"] == 500_000_000  # the timer kept running across the swap
    bad = V1.replace("n : INT;", "n : REAL;").replace("v : INT;", "v : DINT;")
    with pytest.raises(ValueError) as info:
        plc.online_change(
            compile_text(
                bad.replace("n := n + 1", "n := n + 1.0")
                .replace("hist[1] := n", "hist[1] := 0")
                .replace("r.v := n", "r.v := 0"),
                "v3.st",
            )
        )
    assert str(info.value).splitlines() == [
        "online change refused, the old program keeps running:",
        "  main.n changed its type from INT to REAL",
        "  main.r.v changed its type from INT to DINT",
    ]
    plc.scan()
    assert plc["main.n"] == 70  # still the v2 code


def test_mk_window_counts_the_job_that_fills_it_and_skips():
    s = TaskStats("t", 10_000_000, k=4, m=3)
    for i, end in enumerate([15, 15, 5, 5, 5, 5]):  # two misses, then on time
        s.record(i * 10_000_000, i * 10_000_000, i * 10_000_000 + end * 1_000_000)
    # [0,0,1,1] (filled by an on-time job) is below 3 of 4; [0,1,1,1] and [1,1,1,1] are not
    assert (s.mk_violations, s.utility, s.utility_window) == (1, 1.0, [1, 1, 1, 1])
    s.record_skip(2)  # [1,1,1,0] then [1,1,0,0]
    assert (s.skipped, s.mk_violations, s.utility, s.utility_window) == (2, 2, 0.5, [1, 1, 0, 0])
    assert TaskStats("e", 1_000_000).utility == 1.0  # no job yet


def test_mk_firm_utility_and_summary():
    s = TaskStats("t", 10_000_000, k=4, m=3)
    for i, end in enumerate([5, 5, 12, 5, 15, 5]):  # R of 12 and 15 ms miss the 10 ms deadline
        s.record(i * 10_000_000, i * 10_000_000, i * 10_000_000 + end * 1_000_000)
    assert (s.jobs, s.overruns, s.utility) == (6, 2, 0.5)
    assert s.mk_violations == 2  # windows [1,0,1,0] and [0,1,0,1] are below 3 of 4
    d = s.summary()
    assert d["exec_us"] == {"min": 5000.0, "avg": 7833.333, "max": 15000.0}
    assert d["latency_us"]["max"] == 0.0 and d["utility"] == {"k": 4, "m": 3, "U": 0.5, "windows_below_m_over_k": 2}


def _st(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "st.cli", *args], capture_output=True, text=True, cwd=cwd)


@pytest.mark.slow
def test_st_run_virtual_stats_json_and_fault_exit(tmp_path):
    prog = tmp_path / "one.st"
    prog.write_text(ONE)
    out = _st(
        "run",
        str(prog),
        "--virtual",
        "--duration",
        "1s",
        "--policy",
        "edf",
        "--sim-cost",
        "a=4ms",
        "--stats-json",
        str(tmp_path / "s.json"),
    )
    assert out.returncode == 0, out.stderr
    d = json.loads((tmp_path / "s.json").read_text())
    assert (d["policy"], d["clock"], d["plc_time_s"], d["state"]) == ("edf", "virtual", 1.0, "STOP")
    assert d["tasks"][0]["jobs"] == 100 and d["tasks"][0]["exec_us"]["max"] == 4000.0
    bad = tmp_path / "bad.st"
    bad.write_text(FAULTY)
    out = _st("run", str(bad), "--virtual", "--scans", "3", "--no-retain")
    assert out.returncode == 3 and "PLC fault [DIV0]: division by zero (in main, task main)" in out.stderr
    out = _st(
        "run",
        str(bad),
        "--virtual",
        "--scans",
        "3",
        "--on-fault",
        "restart",
        "--retain",
        str(tmp_path / "b.db"),
        "--dump-json",
    )
    assert out.returncode == 0 and out.stderr.count("restarted (warm)") == 3
    assert json.loads(out.stdout.splitlines()[-1])["main.total"] == 3


@pytest.mark.slow
def test_st_run_real_time_for_a_short_duration(tmp_path):
    prog = tmp_path / "one.st"
    prog.write_text(ONE)
    out = _st("run", str(prog), "--duration", "300ms", "--no-rt", "--stats-json", str(tmp_path / "s.json"))
    assert out.returncode == 0, out.stderr
    d = json.loads((tmp_path / "s.json").read_text())
    assert d["clock"] == "real" and d["tasks"][0]["jobs"] == 30


WATCHED = """PROGRAM P VAR x : DINT; y : INT; END_VAR
x := x + 1;
IF x = 60 THEN ADSLOGSTR(msgCtrlMask := ADSLOG_MSGTYPE_HINT, msgFmtStr := '%s jobs', strArg := 'sixty'); END_IF;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK a (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM p1 WITH a : P;
END_RESOURCE END_CONFIGURATION
"""
# the second build counts its own jobs in thousands and says when it has run sixty of them
SECOND = WATCHED.replace("x := x + 1;", "x := x + 1000;").replace("IF x = 60", "IF x / 1000 = 60")


@pytest.mark.slow
def test_st_run_watch_swaps_new_code_in_and_refuses_a_type_change(tmp_path):
    """Every wait is for what the PLC says (no fixed sleep: a loaded machine only makes it slower)."""
    prog = tmp_path / "w.st"
    prog.write_text(WATCHED)
    stats = tmp_path / "stats.json"
    run = StRun(
        str(prog),
        "--no-rt",
        "--watch",
        "--dump-json",
        "--stats-json",
        str(stats),
        "--stats-plot",
        str(tmp_path / "lat.png"),
    )
    run.wait_for("watching 1 file(s)")
    run.wait_for("hint: sixty jobs")  # of the first build
    prog.write_text(SECOND)
    run.wait_for("online change: 1 instance(s) carried over")
    deadline = time.monotonic() + 120
    while run.stderr.count("hint: sixty jobs") < 2:  # of the second build
        assert run.returncode is None and time.monotonic() < deadline, run.stderr
        time.sleep(0.02)
    prog.write_text(SECOND.replace("y : INT", "y : REAL").replace("x := x + 1000;", "x := x + 7;"))
    run.wait_for("online change refused")
    run.send_signal(signal.SIGINT)
    out, err = run.communicate()
    assert run.returncode == 0, err
    assert "online change refused, the old program keeps running:\n  p1.y changed its type from INT to REAL" in err
    x = json.loads(out.splitlines()[-1])["p1.x"]
    before, after = x % 1000, x // 1000  # jobs of the first build, then of the second
    jobs = json.loads(stats.read_text())["tasks"][0]["jobs"]
    assert before >= 60 and after >= 60 and before + after == jobs
    assert (tmp_path / "lat.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_motion_kernel_joins_the_drivers_with_its_first_axis():
    from st.stdlib.plcopen import registry

    idle = PLC(compile_text("PROGRAM main VAR x : INT; END_VAR x := x + 1; END_PROGRAM", "idle.st"))
    idle.scan(3)
    assert registry(idle) is not None and idle.io == [] and idle.job_task is None
    src = """PROGRAM main
VAR ax : AXIS_REF; pw : MC_Power; on : BOOL; END_VAR
pw(Axis := ax, Enable := on, EnableNegative := TRUE, EnablePositive := TRUE);
END_PROGRAM"""
    plc = PLC(compile_text(src, "pw.st"))
    assert plc.io == []
    plc.scan()
    reg = registry(plc)
    assert plc.io == [reg] and plc.job_task is None
    ax = next(iter(reg.axes.values()))
    assert ax.task is plc.tasks[0] and ax.cycle == plc.tasks[0].interval / 1e9
    plc["main.on"] = True
    plc.scan(2)
    assert plc["main.pw.Status"] is True  # stepped after its task's jobs
