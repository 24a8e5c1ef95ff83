"""The PLC API: virtual time, tasks, variable paths, located variables, faults, standard FBs, SFC."""

from __future__ import annotations

import pytest

from st import PLC, PLCFaultError

TIMERS = """
PROGRAM main
VAR in_ : BOOL; ton1 : TON; tof1 : TOF; tp1 : TP; END_VAR
ton1(IN := in_, PT := T#30ms);
tof1(IN := in_, PT := T#30ms);
tp1(IN := in_, PT := T#30ms);
END_PROGRAM
"""


def trace(plc, paths, scans):
    out = []
    for _ in range(scans):
        plc.scan()
        out.append(tuple(plc[p] for p in paths))
    return out


def test_ton_tof_tp_exact_timing():
    plc = PLC.from_source(TIMERS, cycle="10ms", use_cache=False)
    plc["main.in_"] = True
    on = trace(plc, ["main.ton1.Q", "main.ton1.ET", "main.tof1.Q", "main.tp1.Q", "main.tp1.ET"], 5)
    ms = 1_000_000
    assert on == [
        (False, 0, True, True, 0),
        (False, 10 * ms, True, True, 10 * ms),
        (False, 20 * ms, True, True, 20 * ms),
        (True, 30 * ms, True, False, 30 * ms),
        (True, 30 * ms, True, False, 30 * ms),
    ]
    plc["main.in_"] = False
    off = trace(plc, ["main.ton1.Q", "main.ton1.ET", "main.tof1.Q", "main.tof1.ET", "main.tp1.ET"], 5)
    assert off == [
        (False, 0, True, 0, 0),
        (False, 0, True, 10 * ms, 0),
        (False, 0, True, 20 * ms, 0),
        (False, 0, False, 30 * ms, 0),
        (False, 0, False, 30 * ms, 0),
    ]


COUNTERS = """
PROGRAM main
VAR cu : BOOL; cd : BOOL; r : BOOL; ld : BOOL; up : CTU; dn : CTD_DINT; ud : CTUD_ULINT;
    rt : R_TRIG; ft : F_TRIG; rises : INT; falls : INT; sr1 : SR; rs1 : RS; END_VAR
up(CU := cu, R := r, PV := 3);
dn(CD := cd, LD := ld, PV := 2);
ud(CU := cu, CD := cd, R := r, LD := ld, PV := 10);
rt(CLK := cu); IF rt.Q THEN rises := rises + 1; END_IF;
ft(CLK := cu); IF ft.Q THEN falls := falls + 1; END_IF;
sr1(S1 := cu, R := r); rs1(S := cu, R1 := r);
END_PROGRAM
"""


def test_counters_triggers_and_bistables():
    plc = PLC.from_source(COUNTERS, use_cache=False)
    plc["main.ld"] = True
    plc.scan()
    plc["main.ld"] = False
    assert (plc["main.dn.CV"], plc["main.ud.CV"], plc["main.falls"]) == (2, 10, 0)
    for _ in range(5):
        plc["main.cu"] = True
        plc.scan()
        plc["main.cu"] = False
        plc.scan()
    assert (plc["main.up.CV"], plc["main.up.Q"], plc["main.rises"], plc["main.falls"]) == (3, True, 5, 5)
    assert plc["main.ud.CV"] == 10 and plc["main.ud.QU"] is True
    plc["main.cd"] = True
    plc.scan()
    assert (plc["main.dn.CV"], plc["main.ud.CV"]) == (1, 9)
    plc["main.cu"] = True
    plc["main.r"] = True
    plc.scan()
    assert (plc["main.up.CV"], plc["main.sr1.Q1"], plc["main.rs1.Q1"]) == (0, True, False)


def test_f_trig_first_scan_dialect_switch():
    src = "PROGRAM main\nVAR ft : F_TRIG; q : BOOL; END_VAR\nft(CLK := FALSE); q := ft.Q;\nEND_PROGRAM\n"
    a = PLC.from_source(src, use_cache=False)
    a.scan()
    b = PLC.from_source(src, use_cache=False, f_trig_first_scan=True)
    b.scan()
    assert (a["main.q"], b["main.q"]) == (False, True)


def test_time_unit_dialect_switch():
    src = "PROGRAM main\nVAR d : DINT; t : TIME; END_VAR\nd := TIME_TO_DINT(T#2s500ms); t := DINT_TO_TIME(3);\nEND_PROGRAM\n"
    a = PLC.from_source(src, use_cache=False)
    a.scan()
    b = PLC.from_source(src, use_cache=False, time_unit="s")
    b.scan()
    assert (a["main.d"], a["main.t"], b["main.d"], b["main.t"]) == (2500, 3_000_000, 2, 3_000_000_000)


def test_advance_and_time():
    plc = PLC.from_source(
        "PROGRAM main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n", cycle="20ms", use_cache=False
    )
    assert plc.time == 0
    plc.advance("1s")
    assert (plc["main.n"], plc.time) == (50, 1_000_000_000)
    plc.advance("T#30ms")
    assert (plc["main.n"], plc.time) == (52, 1_040_000_000)


MULTI = """
PROGRAM fast
VAR_EXTERNAL shared : INT; END_VAR
VAR n : INT; END_VAR
n := n + 1; shared := shared + 1;
END_PROGRAM
PROGRAM slow
VAR_EXTERNAL shared : INT; END_VAR
VAR n : INT; seen : INT; END_VAR
n := n + 1; seen := shared;
END_PROGRAM
CONFIGURATION c
  VAR_GLOBAL shared : INT; trigger : BOOL; END_VAR
  RESOURCE r ON PLC
    TASK tf(INTERVAL := T#10ms, PRIORITY := 1);
    TASK ts(INTERVAL := T#30ms, PRIORITY := 2);
    TASK te(SINGLE := trigger, PRIORITY := 3);
    PROGRAM f WITH tf : fast;
    PROGRAM s WITH ts : slow;
    PROGRAM e WITH te : slow;
  END_RESOURCE
END_CONFIGURATION
"""


def test_tasks_run_at_their_intervals_and_event_tasks_on_edges():
    plc = PLC.from_source(MULTI, use_cache=False)
    assert plc.tick == 10_000_000
    plc.scan(7)
    assert (plc["f.n"], plc["s.n"], plc["s.seen"], plc["shared"], plc["e.n"]) == (7, 3, 7, 7, 0)
    plc["trigger"] = True
    plc.scan(3)
    assert plc["e.n"] == 1
    plc["trigger"] = False
    plc.scan()
    plc["trigger"] = True
    plc.scan()
    assert plc["e.n"] == 2


def test_paths_into_arrays_structs_and_bits():
    src = """
TYPE P : STRUCT x : INT; tags : ARRAY[1..2] OF STRING[4]; END_STRUCT; END_TYPE
PROGRAM main
VAR a : ARRAY[1..2, 0..1] OF P; w : WORD; out AT %QX0.3 : BOOL; inp AT %IW2 : INT; c : INT; END_VAR
a[2, 1].x := a[2, 1].x + 1; out := w.2; c := inp;
END_PROGRAM
"""
    plc = PLC.from_source(src, use_cache=False)
    plc["main.a[1,0].tags[2]"] = "abcdef"
    plc["main.w.2"] = True
    plc["%IW2"] = -5
    plc.scan()
    assert plc["main.a[2,1].x"] == 1
    assert plc["main.a[1,0].tags"] == ["", "abcd"]
    assert plc["main.w"] == 4
    assert plc["%QX0.3"] is True
    assert plc["main.c"] == -5
    with pytest.raises(KeyError, match="outside 1..2"):
        plc["main.a[3,0].x"]
    with pytest.raises(ValueError, match="does not fit in INT"):
        plc["main.c"] = 40000


def test_fault_state_names_file_line_and_pou():
    src = "PROGRAM main\nVAR i : INT := 1; a : ARRAY[1..3] OF INT; END_VAR\ni := i + 1;\na[i] := 1;\nEND_PROGRAM\n"
    plc = PLC.from_source(src, name="idx.st", use_cache=False)
    plc.scan(2)
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    f = info.value.fault
    assert (f.kind, f.file, f.line, f.pou, plc.state) == ("INDEX", "idx.st", 4, "main", "FAULT")
    assert plc["main.a"] == [0, 1, 1]
    with pytest.raises(PLCFaultError):
        plc.scan()


def test_watchdog_ends_an_endless_loop():
    src = "PROGRAM main\nVAR x : DINT; END_VAR\nWHILE TRUE DO x := x + 1; END_WHILE;\nEND_PROGRAM\n"
    plc = PLC.from_source(src, name="loop.st", use_cache=False, watchdog="100ms")
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    assert (info.value.fault.kind, info.value.fault.line) == ("WATCHDOG", 3)


SFC = """
PROGRAM main
VAR start : BOOL; cnt : INT; lamp : BOOL; done : BOOL; END_VAR
INITIAL_STEP Idle:
END_STEP
TRANSITION FROM Idle TO Work := start; END_TRANSITION
STEP Work:
  lamp(N);
  count(P);
  latch(S);
END_STEP
TRANSITION FROM Work TO Idle := Work.T >= T#30ms; END_TRANSITION
ACTION count: cnt := cnt + 1; END_ACTION
ACTION latch: done := TRUE; END_ACTION
END_PROGRAM
"""


def test_sfc_steps_transitions_and_qualifiers():
    plc = PLC.from_source(SFC, cycle="10ms", use_cache=False)
    plc.scan()
    assert (plc["main.lamp"], plc["main.cnt"]) == (False, 0)
    plc["main.start"] = True
    got = trace(plc, ["main.lamp", "main.cnt", "main.done"], 5)
    # Work is active from t=10ms; at t=40ms its .T reaches 30ms and Idle takes over for one scan
    assert got == [(True, 1, True), (True, 1, True), (True, 1, True), (False, 1, True), (True, 2, True)]


CONNECTED = """
PROGRAM P
VAR_INPUT go : BOOL; lim : INT; END_VAR
VAR_OUTPUT lamp : BOOL; level : INT; END_VAR
VAR speed : INT; alarm AT %Q* : BOOL; END_VAR
lamp := go; level := lim * 2 + speed;
END_PROGRAM
CONFIGURATION C
  VAR_GLOBAL g_level : INT; g_lim : INT := 21; END_VAR
  RESOURCE R ON PLC
    TASK t(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst WITH t : P (go := %IX0.1, lim := g_lim, lamp => %QX0.2, level => g_level);
  END_RESOURCE
  VAR_CONFIG
    inst.speed : INT := 100;
    inst.alarm AT %QX1.7 : BOOL;
  END_VAR
END_CONFIGURATION
"""


def test_program_connections_and_var_config():
    plc = PLC.from_source(CONNECTED, use_cache=False)
    plc["%IX0.1"] = True
    plc.scan()
    assert (plc["%QX0.2"], plc["g_level"], plc["inst.level"], plc["inst.speed"]) == (True, 142, 142, 100)
    plc["inst.alarm"] = True
    assert plc["%QX1.7"] is True


def test_globals_of_struct_and_fb_types():
    src = """
TYPE S : STRUCT a : INT := 7; END_STRUCT; END_TYPE
FUNCTION_BLOCK Cnt
VAR_OUTPUT n : INT; END_VAR
n := n + 1;
END_FUNCTION_BLOCK
VAR_GLOBAL gs : S; gc : Cnt; END_VAR
PROGRAM main
VAR_EXTERNAL gs : S; gc : Cnt; END_VAR
VAR total : INT; END_VAR
gc();
total := gs.a + gc.n;
END_PROGRAM
"""
    plc = PLC.from_source(src, use_cache=False)
    plc.scan(3)
    assert (plc["main.total"], plc["gs.a"], plc["gc.n"]) == (10, 7, 3)


def test_conversions_iec_does_not_define_are_unknown_functions():
    from st.api import compile_text
    from st.diagnostics import CompileError

    with pytest.raises(CompileError) as info:
        compile_text("PROGRAM p\nVAR r : REAL; t : TOD; END_VAR\nt := REAL_TO_TOD(r);\nEND_PROGRAM\n", use_cache=False)
    assert [(d.code, d.span.line) for d in info.value.errors] == [("E010", 3)]
