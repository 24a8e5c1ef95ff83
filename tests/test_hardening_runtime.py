"""Hardening of the runtime: no scan can hang the PLC, no edit can kill it.

Every loop of generated code is watched (FOR in all its forms too), signals stop a runaway job,
start-up and online change build the whole new program (FB_init included) before anything is
swapped, and any failure leaves the running program and its state untouched."""

import ast
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from st import PLC, OnlineChangeRefused, PLCFaultError, PLCStartError
from st.api import compile_paths, compile_text

from helpers import StRun

ROOT = Path(__file__).resolve().parents[1]


def _fault(src: str, name="loop.st", watchdog="100ms"):
    plc = PLC.from_source(src, name=name, use_cache=False, watchdog=watchdog)
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    f = info.value.fault
    assert plc.state == "FAULT"
    return f.kind, f.line, f.pou


@pytest.mark.parametrize(
    "body, line",
    [
        ("FOR i := 0 TO 2000000000 DO\n  x := x + 1;\nEND_FOR;", 3),  # bounded, but for ever
        ("FOR i := 0 TO 10 DO\n  i := 0; x := x + 1;\nEND_FOR;", 3),  # assigns its own counter
        ("FOR i := 0 TO 10 BY n DO\n  x := x + 1;\nEND_FOR;", None),  # a step of 0 (LOOP fault)
        ("WHILE TRUE DO\n  x := x + 1;\n  CONTINUE;\nEND_WHILE;", 3),  # CONTINUE skips the end
        ("REPEAT\n  x := x + 1;\n  CONTINUE;\nUNTIL FALSE END_REPEAT;", 3),
        ("REPEAT\n  x := x + 1;\nUNTIL x < 0 END_REPEAT;", 3),
        ("FOR i := 0 TO 1000 DO\n  FOR j := 0 TO 1000000 DO\n    x := x + 1;\n  END_FOR;\nEND_FOR;", 4),
    ],
)
def test_every_loop_form_is_ended_by_the_watchdog(body, line):
    src = f"PROGRAM main\nVAR x : DINT; i, j : DINT; n : DINT := 0; END_VAR\n{body}\nEND_PROGRAM\n"
    kind, at, pou = _fault(src)
    if line is None:
        assert (kind, at, pou) == ("LOOP", 3, "main")
    else:
        assert (kind, at, pou) == ("WATCHDOG", line, "main")


def test_a_loop_in_a_function_and_in_a_method_is_watched():
    src = """
FUNCTION Spin : DINT
VAR_INPUT n : DINT; END_VAR
VAR k : DINT; END_VAR
FOR k := 1 TO n DO
  Spin := Spin + k MOD 3;
END_FOR;
END_FUNCTION
FUNCTION_BLOCK Fb
VAR c : DINT; END_VAR
METHOD Run : DINT
WHILE c >= 0 DO c := (c + 1) MOD 100; END_WHILE;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR r : DINT; f : Fb; sel : BOOL; END_VAR
IF sel THEN r := f.Run(); ELSE r := Spin(2147483647); END_IF;
END_PROGRAM
"""
    assert _fault(src) == ("WATCHDOG", 5, "Spin")
    plc = PLC.from_source(src, name="loop.st", use_cache=False, watchdog="100ms")
    plc["main.sel"] = True
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    assert (info.value.fault.kind, info.value.fault.line, info.value.fault.pou) == ("WATCHDOG", 12, "Fb")


def test_every_generated_loop_starts_with_the_watchdog_check():
    """One mechanism: a pass over the generated modules guards every loop, whatever its ST form."""
    every_form = """
FUNCTION Fn : DINT
VAR_INPUT n : DINT; END_VAR
VAR k, m : DINT; END_VAR
FOR k := 1 TO n DO Fn := Fn + k; END_FOR;
m := n;
WHILE m > 0 DO m := m - 1; IF m = 5 THEN CONTINUE; END_IF; END_WHILE;
END_FUNCTION
FUNCTION_BLOCK Fb
VAR c, k, s : DINT; END_VAR
METHOD M : DINT
REPEAT c := c + 1; UNTIL c > 10 END_REPEAT;
END_METHOD
FOR k := 10 TO 1 BY s DO c := c + 1; END_FOR;
FOR k := 1 TO 10 DO k := k + 1; END_FOR;
ACTION A: REPEAT c := c - 1; IF c < 0 THEN CONTINUE; END_IF; UNTIL c < 5 END_REPEAT; END_ACTION
END_FUNCTION_BLOCK
PROGRAM main
VAR f : Fb; r : DINT; END_VAR
r := Fn(3); f(); f.A(); r := f.M();
END_PROGRAM
"""
    forms = compile_text(every_form, "forms.st", emit_python=True, use_cache=False).python_source["forms.st"]
    assert _guarded_loops(forms, "forms.st") == 6
    total = 0
    for prog in sorted((ROOT / "programs").rglob("*.st")):
        if not prog.name.startswith("test_"):
            for path, text in compile_paths([str(prog)], emit_python=True, use_cache=False).python_source.items():
                total += _guarded_loops(text, path)
    assert total >= 6  # the example programs and the standard library's ST have loops too


def _guarded_loops(text: str, path: str) -> int:
    loops = 0
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.For, ast.While)):
            loops += 1
            first = node.body[0]
            assert isinstance(first, ast.If) and ast.unparse(first) == "if _wd_armed:\n    _wd_check()", (
                f"{path}: an unguarded loop at line {node.lineno}"
            )
    return loops


def test_a_normal_loop_is_not_disturbed_and_the_plc_runs_on_after_a_watchdog_fault():
    src = (
        "PROGRAM main\nVAR x : DINT; i : DINT; spin : BOOL; END_VAR\n"
        "FOR i := 1 TO 1000 DO x := x + i; END_FOR;\n"
        "WHILE spin DO x := x + 1; END_WHILE;\nEND_PROGRAM\n"
    )
    plc = PLC.from_source(src, name="loop.st", use_cache=False, watchdog="100ms")
    plc.scan(3)
    assert (plc["main.x"], plc["main.i"]) == (1501500, 1001)
    plc["main.spin"] = True
    with pytest.raises(PLCFaultError):
        plc.scan()
    plc["main.spin"] = False
    plc.reset_fault()
    x = plc["main.x"]
    plc.scan()
    assert plc["main.x"] == x + 500500 and plc.state == "RUN"


# ---------------------------------------------------------------------- stop requests and signals


def test_a_stop_request_ends_the_engine_at_the_next_scan_boundary():
    src = "PROGRAM main\nVAR n : DINT; END_VAR\nn := n + 1;\nEND_PROGRAM\n"
    plc = PLC.from_source(src, cycle="10ms")
    plc.scan(5)
    plc.request_stop("test")
    plc.scan(100)  # returns at once: the request is taken at the first boundary
    assert plc["main.n"] == 5
    plc.scan(2)  # a request is used up by the stop it caused
    assert plc["main.n"] == 7


def test_a_second_stop_request_ends_a_running_job_at_once():
    src = "PROGRAM main\nVAR x : DINT; END_VAR\nWHILE TRUE DO x := x + 1; END_WHILE;\nEND_PROGRAM\n"
    plc = PLC.from_source(src, name="spin.st", use_cache=False, watchdog="60s")
    import threading

    def twice():
        time.sleep(0.3)
        plc.request_stop("first")
        time.sleep(0.2)
        plc.request_stop("SIGINT")

    threading.Thread(target=twice).start()
    t0 = time.monotonic()
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    assert time.monotonic() - t0 < 30  # not the 60 s budget
    f = info.value.fault
    assert (f.kind, f.line, f.message) == ("WATCHDOG", 3, "the job was ended by a second stop request (SIGINT)")


RUNAWAY = """
PROGRAM main
VAR RETAIN kept : DINT; END_VAR
VAR x : DINT; i : DINT; lamp AT %QX0.0 : BOOL; END_VAR
kept := kept + 1;
lamp := TRUE;
IF kept > 5 THEN
  FOR i := 0 TO 2000000000 DO x := x + 1; END_FOR;
END_IF;
END_PROGRAM
"""


def _retained(db: Path) -> dict:
    from st.runtime.retain import RetainStore

    store = RetainStore(str(db))
    try:
        return {k: v[1] for k, v in store.load().items()}
    finally:
        store.close()


@pytest.mark.slow
@pytest.mark.parametrize("sig, twice", [(signal.SIGTERM, False), (signal.SIGINT, False), (signal.SIGINT, True)])
def test_signals_stop_a_runaway_job_outputs_safe_retain_flushed(tmp_path, sig, twice):
    prog = tmp_path / "runaway.st"
    prog.write_text(RUNAWAY)
    db = tmp_path / "r.db"
    watchdog = "2s" if not twice else "120s"
    child = StRun(
        str(prog), "--no-rt", "--cycle", "10ms", "--watchdog", watchdog, "--retain", str(db), "--duration", "600s"
    )
    child.wait_for("running in real time")
    time.sleep(0.5)  # five scans, then the sixth runs away
    child.send_signal(sig)
    if twice:
        time.sleep(0.3)
        child.send_signal(sig)
    out, err = child.communicate(timeout=60)
    assert child.returncode == 3, err  # the job ended in a fault: state FAULT
    if twice:
        assert (
            f"runaway.st:8: PLC fault [WATCHDOG]: the job was ended by a second stop request "
            f"({sig.name}) (in main, task main)" in err
        )
    else:
        assert (
            "runaway.st:8: PLC fault [WATCHDOG]: the job did not finish within 2 s (endless loop?) "
            "(in main, task main)" in err
        )
    assert "state FAULT" in err
    assert _retained(db) == {"main.kept": 6}  # as the faulting job left it


def test_api_stop_from_another_thread_makes_outputs_safe():
    src = "PROGRAM main\nVAR lamp AT %QX0.0 : BOOL; n : DINT; END_VAR\nlamp := TRUE; n := n + 1;\nEND_PROGRAM\n"
    plc = PLC.from_source(src, cycle="10ms")
    import threading

    threading.Timer(0.3, plc.request_stop).start()
    t0 = time.monotonic()
    plc.run_realtime(duration="60s", gc_control=False)
    assert time.monotonic() - t0 < 30
    assert plc["%QX0.0"] is True and plc.state == "RUN"
    plc.stop()
    assert plc["%QX0.0"] is False and plc.state == "STOP"


# ---------------------------------------------------------------------- start-up

FBINIT = """
FUNCTION_BLOCK Div
VAR_INPUT d : INT; END_VAR
VAR q : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
q := 100 / d;
END_METHOD
END_FUNCTION_BLOCK
"""


@pytest.mark.slow
def test_a_fault_in_fb_init_at_start_up_is_a_start_error_with_its_st_line(tmp_path):
    src = FBINIT + "PROGRAM main\nVAR f : Div; END_VAR\nf();\nEND_PROGRAM\n"
    with pytest.raises(PLCStartError) as info:
        PLC.from_source(src, name="init.st", use_cache=False)
    f = info.value.fault
    assert (f.kind, f.file, f.line, f.pou) == ("DIV0", "init.st", 7, "Div")
    assert str(info.value) == "init.st:7: PLC fault [DIV0]: division by zero (in Div)"
    prog = tmp_path / "init.st"
    prog.write_text(src)
    out = subprocess.run(
        [sys.executable, "-m", "st.cli", "run", str(prog), "--virtual", "--scans", "2"], capture_output=True, text=True
    )
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        f"error: cannot start the PLC: {prog}:7: PLC fault [DIV0]: division by zero (in Div)"
    ]


def test_an_endless_loop_in_fb_init_or_an_initial_value_is_ended_at_start_up():
    src = (
        FBINIT.replace("q := 100 / d;", "WHILE TRUE DO q := q + 1; END_WHILE;")
        + "PROGRAM main\nVAR f : Div; END_VAR\nf();\nEND_PROGRAM\n"
    )
    with pytest.raises(PLCStartError) as info:
        PLC.from_source(src, name="init.st", use_cache=False, watchdog="50ms")
    f = info.value.fault
    assert (f.kind, f.line, f.message) == (
        "WATCHDOG",
        7,
        "the start-up (initial values, FB_init) did not finish within 1 s (endless loop?)",
    )


def test_a_located_address_outside_the_image_is_a_start_error_not_a_traceback(monkeypatch):
    # st check refuses it (tests/test_hardening_compiler.py); the runtime asks the same rule again
    # when it binds, here with an image made smaller after the program was compiled
    src = "PROGRAM main\nVAR y AT %QW20 : INT; END_VAR\ny := 1;\nEND_PROGRAM\n"
    compiled = compile_text(src, "addr.st", use_cache=False)
    import st.model.addresses as addresses

    monkeypatch.setattr(addresses, "TABLE_LEN", 8)
    with pytest.raises(PLCStartError) as info:
        PLC(compiled)
    assert str(info.value) == "addr.st:2:5: %QW20 is outside the process image (8 entries per table)"


# ---------------------------------------------------------------------- online change: all or nothing

BASE = """
FUNCTION_BLOCK Counter
VAR_INPUT step : INT; END_VAR
VAR n : INT; END_VAR
n := n + step;
END_FUNCTION_BLOCK
PROGRAM main
VAR c : Counter; total : INT; out AT %QW0 : INT; END_VAR
c(step := 1);
total := c.n;
out := total;
END_PROGRAM
"""


def _running():
    plc = PLC.from_source(BASE, name="v1.st", use_cache=False)
    plc.scan(10)
    return plc


def _assert_untouched(plc, old_obj, old_code):
    assert plc.instances["main"][1] is old_obj  # the same instance, not a fresh one
    assert plc.compiled is old_code
    plc.scan(2)
    assert (plc["main.total"], plc["%QW0"], plc.state) == (12, 12, "RUN")


def test_a_change_whose_fb_init_faults_leaves_the_old_program_and_its_state_untouched():
    plc = _running()
    old_obj, old_code = plc.instances["main"][1], plc.compiled
    with pytest.raises(OnlineChangeRefused) as info:
        plc.online_change(
            compile_text(FBINIT + BASE.replace("total : INT;", "total : INT; d : Div;"), "v2.st", use_cache=False)
        )
    assert str(info.value).splitlines() == [
        "online change refused, the old program keeps running:",
        "  the new program cannot start: v2.st:7: PLC fault [DIV0]: division by zero (in Div)",
    ]
    _assert_untouched(plc, old_obj, old_code)


def test_a_change_with_an_address_the_image_cannot_hold_is_refused_whole(monkeypatch):
    """`st check` refuses such an address; the runtime checks again (a smaller image, here) and
    must not half-apply the change: no new code with fresh state, no 'carried over'."""
    plc = _running()
    old_obj, old_code = plc.instances["main"][1], plc.compiled
    change = BASE.replace("out AT %QW0 : INT;", "out AT %QW0 : INT; far AT %QW9 : INT;").replace(
        "n := n + step", "n := n + 100 * step"
    )
    compiled = compile_text(change, "v2.st", use_cache=False)
    import st.model.addresses as addresses

    monkeypatch.setattr(addresses, "TABLE_LEN", 8)
    with pytest.raises(OnlineChangeRefused) as info:
        plc.online_change(compiled)
    assert (
        str(info.value).splitlines()[1]
        == "  the new program cannot start: v2.st:8:50: %QW9 is outside the process image (8 entries per table)"
    )
    _assert_untouched(plc, old_obj, old_code)


def test_an_endless_fb_init_in_a_change_is_refused_and_the_old_program_runs_on():
    plc = _running()
    old_obj, old_code = plc.instances["main"][1], plc.compiled
    change = FBINIT.replace("q := 100 / d;", "WHILE TRUE DO q := q + 1; END_WHILE;") + BASE.replace(
        "total : INT;", "total : INT; d : Div;"
    )
    with pytest.raises(OnlineChangeRefused) as info:
        plc.online_change(compile_text(change, "v2.st", use_cache=False))
    assert "PLC fault [WATCHDOG]: the online change (initial values, FB_init) did not finish within 1 s" in str(
        info.value
    )
    _assert_untouched(plc, old_obj, old_code)


def test_a_change_that_fails_while_carrying_state_over_is_refused(monkeypatch):
    plc = _running()
    old_obj, old_code = plc.instances["main"][1], plc.compiled
    import st.runtime.online_change as online_change

    def broken(*a, **k):
        raise ValueError("array size changed")

    monkeypatch.setattr(online_change, "relink", broken)
    with pytest.raises(OnlineChangeRefused) as info:
        plc.online_change(compile_text(BASE.replace("n := n + step", "n := n + 2 * step"), "v2.st", use_cache=False))
    assert str(info.value).splitlines()[1] == "  the state cannot be carried over: array size changed"
    _assert_untouched(plc, old_obj, old_code)


def test_a_good_change_after_a_refused_one_carries_the_state_over():
    plc = _running()
    with pytest.raises(OnlineChangeRefused):
        plc.online_change(
            compile_text(FBINIT + BASE.replace("total : INT;", "total : INT; d : Div;"), "v2.st", use_cache=False)
        )
    assert (
        plc.online_change(compile_text(BASE.replace("n := n + step", "n := n + 10 * step"), "v3.st", use_cache=False))
        == "online change: 1 instance(s) carried over"
    )
    plc.scan()
    assert (plc["main.total"], plc["%QW0"]) == (20, 20)


WATCHED = BASE


@pytest.mark.slow
def test_st_run_watch_survives_a_faulting_fb_init_and_keeps_the_old_program(tmp_path):
    prog = tmp_path / "w.st"
    prog.write_text(WATCHED)
    stats = tmp_path / "stats.json"
    child = StRun(
        str(prog),
        "--duration",
        "4s",
        "--no-rt",
        "--cycle",
        "10ms",
        "--watch",
        "--dump-json",
        "--all",  # main.c's internal counters
        "--stats-json",
        str(stats),
    )
    child.wait_for("watching 1 file(s)")
    prog.write_text(FBINIT + WATCHED.replace("total : INT;", "total : INT; d : Div;"))
    child.wait_for("online change refused")
    prog.write_text(
        WATCHED.replace("n := n + step;", "n := n + step; m := m + 1;").replace("VAR n : INT;", "VAR n : INT; m : INT;")
    )
    child.wait_for("online change: 1 instance(s) carried over")
    out, err = child.communicate()
    assert child.returncode == 0, err
    assert (
        f"online change refused, the old program keeps running:\n  the new program cannot start: "
        f"{prog}:7: PLC fault [DIV0]: division by zero (in Div)" in err
    )
    c = json.loads(out.splitlines()[-1])["main.c"]
    jobs = json.loads(stats.read_text())["tasks"][0]["jobs"]  # 400 unless a loaded machine skipped some
    assert c["n"] == jobs and 0 < c["m"] < jobs  # every job counted once; m: the last build's


RETAIN_IN_BLOCKS = """
FUNCTION_BLOCK Counter
VAR RETAIN n : DINT; END_VAR
VAR plain : DINT; END_VAR
n := n + 1; plain := plain + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Station
VAR c : Counter; END_VAR
c();
END_FUNCTION_BLOCK
VAR_GLOBAL g : Counter; END_VAR
PROGRAM main
VAR one : Counter; many : ARRAY[1..2, 0..1] OF Counter; deep : Station; END_VAR
one(); many[2, 1](); deep(); g();
END_PROGRAM
"""


def test_retain_variables_inside_block_instances_survive_a_restart(tmp_path):
    db = str(tmp_path / "r.db")
    for expected in (3, 6):
        plc = PLC.from_source(RETAIN_IN_BLOCKS, name="blocks.st", retain=db, use_cache=False)
        for _ in range(3):
            plc.scan()
        assert [
            plc["main.one.n"],
            plc["main.many[2, 1].n"],
            plc["main.many[1, 0].n"],
            plc["main.deep.c.n"],
            plc["g.n"],
        ] == [expected, expected, 0, expected, expected]
        assert plc["main.one.plain"] == 3  # not retained: starts from 0 every time
        plc.close()
    assert set(_retained(db)) == {
        "main.one.n",
        "main.many[1,0].n",
        "main.many[1,1].n",
        "main.many[2,0].n",
        "main.many[2,1].n",
        "main.deep.c.n",
        "g.n",
    }


def test_a_change_planned_against_a_program_that_no_longer_runs_is_refused_as_stale():
    from st.runtime.online_change import STALE

    plc = _running()
    first = plc.prepare_change(
        compile_text(BASE.replace("n := n + step", "n := n + 2 * step"), "v2.st", use_cache=False)
    )
    plc.online_change(compile_text(BASE.replace("n := n + step", "n := n + 3 * step"), "v3.st", use_cache=False))
    n = plc["main.c.n"]
    with pytest.raises(OnlineChangeRefused) as info:
        plc.apply_change(first)  # planned against v1: v3 runs now
    assert info.value.reasons == [STALE]
    plc.scan()
    assert plc["main.c.n"] == n + 3  # v3 goes on
