"""The OpenPLC Editor's blocks beyond the IEC standard ones (st/stdlib/openplc_fbs.st): INTEGRAL,
DERIVATIVE, PID, RAMP, HYSTERESIS, RTC, SEMA, with MatIEC's interfaces and behaviour.

Expected values are worked out from the blocks' definitions (MatIEC's lib/, the IEC 61131-3 2nd
edition's examples): by hand where the numbers are exact in binary, otherwise by the small model
below, which applies each block's formula in double precision and rounds every REAL store to
single precision (docs/semantics.md: REAL arithmetic)."""

from __future__ import annotations

import math
import struct
from datetime import UTC, datetime

import pytest

from st.testing.harness import TestPLC

from helpers import assert_diagnostics, run

NS = 1_000_000_000


def f32(x: float) -> float:
    """x rounded to IEEE single precision (a REAL store)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def dt_ns(*args: int) -> int:
    """DT#y-m-d-h:m:s as ns since 1970 (UTC, as st holds dates)."""
    return int(datetime(*args, tzinfo=UTC).timestamp()) * NS


@pytest.fixture(scope="module")
def plc() -> TestPLC:
    return TestPLC.from_source("PROGRAM main VAR x : INT; END_VAR x := 1; END_PROGRAM", use_cache=False)


# ------------------------------------------------------------------ interfaces


INTERFACES = {
    "INTEGRAL": [
        ("RUN", "BOOL", "VAR_INPUT"),
        ("R1", "BOOL", "VAR_INPUT"),
        ("XIN", "REAL", "VAR_INPUT"),
        ("X0", "REAL", "VAR_INPUT"),
        ("CYCLE", "TIME", "VAR_INPUT"),
        ("Q", "BOOL", "VAR_OUTPUT"),
        ("XOUT", "REAL", "VAR_OUTPUT"),
    ],
    "DERIVATIVE": [
        ("RUN", "BOOL", "VAR_INPUT"),
        ("XIN", "REAL", "VAR_INPUT"),
        ("CYCLE", "TIME", "VAR_INPUT"),
        ("XOUT", "REAL", "VAR_OUTPUT"),
    ],
    "PID": [
        ("AUTO", "BOOL", "VAR_INPUT"),
        ("PV", "REAL", "VAR_INPUT"),
        ("SP", "REAL", "VAR_INPUT"),
        ("X0", "REAL", "VAR_INPUT"),
        ("KP", "REAL", "VAR_INPUT"),
        ("TR", "REAL", "VAR_INPUT"),
        ("TD", "REAL", "VAR_INPUT"),
        ("CYCLE", "TIME", "VAR_INPUT"),
        ("XOUT", "REAL", "VAR_OUTPUT"),
    ],
    "RAMP": [
        ("RUN", "BOOL", "VAR_INPUT"),
        ("X0", "REAL", "VAR_INPUT"),
        ("X1", "REAL", "VAR_INPUT"),
        ("TR", "TIME", "VAR_INPUT"),
        ("CYCLE", "TIME", "VAR_INPUT"),
        ("BUSY", "BOOL", "VAR_OUTPUT"),
        ("XOUT", "REAL", "VAR_OUTPUT"),
    ],
    "HYSTERESIS": [
        ("XIN1", "REAL", "VAR_INPUT"),
        ("XIN2", "REAL", "VAR_INPUT"),
        ("EPS", "REAL", "VAR_INPUT"),
        ("Q", "BOOL", "VAR_OUTPUT"),
    ],
    "RTC": [
        ("IN", "BOOL", "VAR_INPUT"),
        ("PDT", "DATE_AND_TIME", "VAR_INPUT"),
        ("Q", "BOOL", "VAR_OUTPUT"),
        ("CDT", "DATE_AND_TIME", "VAR_OUTPUT"),
    ],
    "SEMA": [
        ("CLAIM", "BOOL", "VAR_INPUT"),
        ("RELEASE", "BOOL", "VAR_INPUT"),
        ("BUSY", "BOOL", "VAR_OUTPUT"),
    ],
}


@pytest.mark.parametrize("name", sorted(INTERFACES))
def test_interface_as_matiec_declares_it(plc, name):
    """Names, types and order of the inputs and outputs (the OpenPLC Editor draws them in this order)."""
    pou = plc.project.pous[name.lower()]
    assert pou.pou_kind == "FUNCTION_BLOCK"
    assert [(p.name, str(p.type), p.section) for p in pou.params()] == INTERFACES[name]


def test_initial_state(plc):
    """Every output starts at its type's default (MatIEC: XOUT := 0.0, Q := FALSE, CDT = DT#1970-01-01)."""
    assert (plc.fb("INTEGRAL").XOUT, plc.fb("INTEGRAL").Q) == (0.0, False)
    assert plc.fb("DERIVATIVE").XOUT == 0.0
    assert plc.fb("PID").XOUT == 0.0
    assert (plc.fb("RAMP").XOUT, plc.fb("RAMP").BUSY, plc.fb("RAMP").T) == (0.0, False, 0)
    assert plc.fb("HYSTERESIS").Q is False
    assert (plc.fb("RTC").Q, plc.fb("RTC").CDT, plc.fb("RTC").PDT) == (False, 0, 0)
    assert plc.fb("SEMA").BUSY is False


def test_blocks_in_every_preset_without_diagnostics():
    """Available in every program like TON, in each preset, with no warning of their own."""
    src = """
PROGRAM main
  VAR
    i : INTEGRAL; d : DERIVATIVE; p : PID; r : RAMP; h : HYSTERESIS; c : RTC; s : SEMA;
    y : REAL; b : BOOL; t : DT;
  END_VAR
  i(RUN := TRUE, R1 := FALSE, XIN := 1.0, X0 := 0.0, CYCLE := T#20ms);
  d(RUN := TRUE, XIN := i.XOUT, CYCLE := T#20ms);
  p(AUTO := TRUE, PV := d.XOUT, SP := 1.0, X0 := 0.0, KP := 1.0, TR := 1.0, TD := 0.0, CYCLE := T#20ms);
  r(RUN := TRUE, X0 := 0.0, X1 := 1.0, TR := T#1s, CYCLE := T#20ms);
  h(XIN1 := r.XOUT, XIN2 := 0.5, EPS := 0.1);
  c(IN := FALSE, PDT := DT#2024-01-01-00:00:00);
  s(CLAIM := h.Q, RELEASE := NOT h.Q);
  y := p.XOUT;
  b := s.BUSY AND c.Q AND r.BUSY AND i.Q;
  t := c.CDT;
END_PROGRAM
"""
    for dialect in (None, "openplc", "iec", "codesys", "twincat"):
        assert_diagnostics(src, [], dialect=dialect)


# ------------------------------------------------------------------ INTEGRAL


def test_integral_of_a_constant(plc):
    """XOUT := XOUT + XIN·CYCLE per call (one rectangle, CYCLE in seconds): 2.0 over 0.5 s adds 1.0."""
    i = plc.fb("INTEGRAL")
    out = [i(RUN=True, XIN=2.0, CYCLE="500ms").XOUT for _ in range(5)]
    assert out == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert i.Q is True


def test_integral_reset_overrides_run_then_integrates_from_x0(plc):
    i = plc.fb("INTEGRAL")
    i(RUN=True, XIN=2.0, CYCLE="1s")
    assert i.XOUT == 2.0
    i(R1=True, X0=10.0, XIN=-4.0, CYCLE="250ms")  # RUN still TRUE: R1 wins
    assert (i.XOUT, i.Q) == (10.0, False)
    i(R1=True)  # held at X0 while R1
    assert (i.XOUT, i.Q) == (10.0, False)
    out = [i(R1=False).XOUT for _ in range(3)]
    assert out == [9.0, 8.0, 7.0]
    assert i.Q is True


def test_integral_holds_when_not_running(plc):
    i = plc.fb("INTEGRAL")
    i(RUN=True, XIN=3.0, CYCLE="500ms")
    i(RUN=True)
    assert i.XOUT == 3.0
    assert [i(RUN=False, XIN=100.0).XOUT for _ in range(3)] == [3.0, 3.0, 3.0]
    assert i.Q is True  # Q is NOT R1, whatever RUN
    assert i(RUN=True, XIN=-2.0).XOUT == 2.0


def test_integral_zero_cycle_adds_nothing(plc):
    i = plc.fb("INTEGRAL")
    i(R1=True, X0=1.5)
    assert [i(R1=False, RUN=True, XIN=1000.0, CYCLE="0s").XOUT for _ in range(3)] == [1.5, 1.5, 1.5]


def test_integral_of_a_tenth_of_a_second_rounds_as_real(plc):
    """CYCLE = T#100ms is 0.1 s as a REAL (TIME_TO_REAL); the sum is rounded to REAL at each store."""
    i = plc.fb("INTEGRAL")
    model = 0.0
    for _ in range(10):
        model = f32(model + f32(1.0) * f32(0.1))
        assert i(RUN=True, XIN=1.0, CYCLE="100ms").XOUT == model
    assert model != 1.0 and abs(model - 1.0) < 1e-6


def test_integral_counts_seconds_whatever_the_time_unit():
    """MatIEC's TIME_TO_REAL gives seconds: so does the integral under `openplc` (TIME_TO_DINT in
    seconds), the default (milliseconds) and --time-unit s alike."""
    src = """
PROGRAM main
  VAR i : INTEGRAL; n : DINT; END_VAR
  i(RUN := TRUE, XIN := 4.0, CYCLE := T#250ms);
  n := TIME_TO_DINT(T#2s);
END_PROGRAM
"""
    for dialect, time_unit, n in ((None, "ms", 2000), ("openplc", "ms", 2), (None, "s", 2)):
        plc = run(src, 3, dialect=dialect, time_unit=time_unit)
        assert (plc["main.i.XOUT"], plc["main.n"]) == (3.0, n)


def test_integral_en_false_skips_the_call():
    plc = run(
        """
PROGRAM main
  VAR i : INTEGRAL; go : BOOL; ok : BOOL := TRUE; END_VAR
  i(EN := go, RUN := TRUE, XIN := 1.0, CYCLE := T#1s, ENO => ok);
END_PROGRAM
""",
        2,
    )
    assert (plc["main.i.XOUT"], plc["main.i.Q"], plc["main.ok"]) == (0.0, False, False)
    plc["main.go"] = True
    plc.scan(2)
    assert (plc["main.i.XOUT"], plc["main.i.Q"], plc["main.ok"]) == (2.0, True, True)


# ------------------------------------------------------------------ DERIVATIVE


def derivative_model(xs, cycle_s, history=0.0):
    """XOUT = (3·(x[n] - x[n-3]) + x[n-1] - x[n-2]) / (10·CYCLE), the history starting at `history`."""
    x1 = x2 = x3 = history
    out = []
    for x in xs:
        out.append(f32((3.0 * (x - x3) + x1 - x2) / (10.0 * f32(cycle_s))))
        x3, x2, x1 = x2, x1, x
    return out


def test_derivative_of_a_ramp(plc):
    """XIN rising by 2.0 every 0.5 s: the output settles at 4.0 per second from the fourth call."""
    d = plc.fb("DERIVATIVE")
    d(RUN=False, XIN=0.0)
    assert d.XOUT == 0.0
    xs = [2.0, 4.0, 6.0, 8.0, 10.0]
    out = [d(RUN=True, XIN=x, CYCLE="500ms").XOUT for x in xs]
    # (3·2 + 0 - 0)/5, (3·4 + 2 - 0)/5, (3·6 + 4 - 2)/5, (3·6 + 6 - 4)/5, ...
    assert out == [f32(1.2), f32(2.8), 4.0, 4.0, 4.0]
    assert out == derivative_model(xs, 0.5)


def test_derivative_of_a_falling_ramp_at_100ms(plc):
    d = plc.fb("DERIVATIVE")
    d(RUN=False, XIN=1.0)
    xs = [1.0 - 0.25 * k for k in range(1, 7)]
    out = [d(RUN=True, XIN=x, CYCLE="100ms").XOUT for x in xs]
    assert out == derivative_model(xs, 0.1, history=1.0)
    assert out[3:] == [f32(-0.25 / f32(0.1))] * 3  # -2.5 per second, as REAL


def test_derivative_not_running_is_zero_and_tracks_the_input(plc):
    """RUN = FALSE: XOUT 0 and the history set to XIN, so that a constant input resumes at 0."""
    d = plc.fb("DERIVATIVE")
    d(RUN=True, XIN=7.0, CYCLE="1s")
    assert d.XOUT == f32(21.0 / 10.0)
    assert d(RUN=False, XIN=5.0).XOUT == 0.0
    assert (d.X1, d.X2, d.X3) == (5.0, 5.0, 5.0)
    assert [d(RUN=True, XIN=5.0).XOUT for _ in range(4)] == [0.0] * 4


def test_derivative_zero_cycle_divides_by_zero_as_ieee(plc):
    """CYCLE = 0: the division by zero gives +INF, -INF, or NaN for 0/0 (REAL division, as MatIEC's C)."""
    d = plc.fb("DERIVATIVE")
    d(RUN=False, XIN=0.0)
    assert d(RUN=True, XIN=1.0, CYCLE="0s").XOUT == math.inf
    d(RUN=False, XIN=0.0)
    assert d(RUN=True, XIN=-1.0).XOUT == -math.inf
    d(RUN=False, XIN=3.0)
    assert math.isnan(d(RUN=True, XIN=3.0).XOUT)


# ------------------------------------------------------------------ PID


def pid_model(steps, kp, tr, td, cycle_s, x0=0.0):
    """PID from its definition: ERROR := PV - SP; ITERM, an INTEGRAL of ERROR preset to TR·(X0 - ERROR)
    in manual; DTERM, the DERIVATIVE of ERROR; XOUT := KP·(ERROR + ITERM/TR + DTERM·TD).
    `steps`: (AUTO, PV, SP) per call."""
    iterm = dterm = x1 = x2 = x3 = 0.0
    cyc = f32(cycle_s)
    out = []
    for auto, pv, sp in steps:
        err = f32(pv - sp)
        if not auto:
            iterm = f32(tr * (x0 - err))
            dterm = 0.0
            x1 = x2 = x3 = err
        else:
            iterm = f32(iterm + err * cyc)
            dterm = f32((3.0 * (err - x3) + x1 - x2) / (10.0 * cyc))
            x3, x2, x1 = x2, x1, err
        out.append(f32(kp * (err + iterm / tr + dterm * td)))
    return out


def test_pid_manual_output_and_bumpless_start(plc):
    """Manual (AUTO = FALSE): XOUT = KP·X0 whatever the error; AUTO then starts from that value and the
    integral term moves it by KP·ERROR·CYCLE/TR per call."""
    p = plc.fb("PID")
    p(AUTO=False, PV=0.0, SP=1.0, X0=3.0, KP=2.0, TR=1.0, TD=0.5, CYCLE="500ms")
    assert p.XOUT == 6.0  # 2·(-1 + 1·(3 - -1)/1 + 0)
    out = [p(AUTO=True).XOUT for _ in range(3)]
    # ERROR = -1: ITERM 4 - 0.5 = 3.5, 3.0, 2.5; DTERM 0 (constant error)
    assert out == [5.0, 4.0, 3.0]


def test_pid_step_of_the_process_value(plc):
    """A step of PV from 0 to 1 (SP = 1) in automatic: the derivative kick, then its decay over the
    four-point difference, then the integral alone."""
    steps = [(False, 0.0, 1.0)] + [(True, 0.0, 1.0)] * 3 + [(True, 1.0, 1.0)] * 5
    p = plc.fb("PID")
    out = [p(AUTO=a, PV=pv, SP=sp, X0=3.0, KP=2.0, TR=1.0, TD=0.5, CYCLE="500ms").XOUT for a, pv, sp in steps]
    assert out == pid_model(steps, kp=2.0, tr=1.0, td=0.5, cycle_s=0.5, x0=3.0)
    # by hand: manual 2·3; ERROR -1: ITERM 3.5, 3.0, 2.5; then ERROR 0: ITERM stays 2.5 and DTERM is
    # (3·(0 - -1) + -1 - -1)/5, (3·1 + 0 - -1)/5, (3·1 + 0 - 0)/5, then 0 once the history is all 0
    kick = [f32(2.0 * (2.5 + f32(d) * 0.5)) for d in (0.6, 0.8, 0.6)]
    assert out == [6.0, 5.0, 4.0, 3.0, *kick, 5.0, 5.0]


def test_pid_in_st_at_100ms_follows_the_model():
    """Called from ST as the OpenPLC Editor generates it, each scan, for 20 scans."""
    src = """
PROGRAM main
  VAR PID0 : PID; pv : REAL := 20.0; n : INT; y : REAL; END_VAR
  n := n + 1;
  IF n = 8 THEN pv := 22.5; END_IF;
  PID0(AUTO := n > 1, PV := pv, SP := 25.0, X0 := 10.0, KP := 0.8, TR := 3.0, TD := 0.25, CYCLE := T#100ms);
  y := PID0.XOUT;
END_PROGRAM
"""
    steps = [(n > 1, 22.5 if n >= 8 else 20.0, 25.0) for n in range(1, 21)]
    model = pid_model(steps, kp=f32(0.8), tr=3.0, td=0.25, cycle_s=0.1, x0=10.0)
    plc = run(src, 0)
    for want in model:
        plc.scan()
        assert plc["main.y"] == want
    assert plc["main.PID0.ERROR"] == -2.5


def test_pid_zero_reset_time_is_nan_in_manual_and_inf_in_auto(plc):
    """TR = 0 divides the integral by zero: 0/0 (NaN) in manual, ±INF once it integrates (as MatIEC)."""
    p = plc.fb("PID")
    p(AUTO=False, PV=0.0, SP=1.0, X0=3.0, KP=2.0, TR=0.0, TD=0.0, CYCLE="500ms")
    assert math.isnan(p.XOUT)
    assert p(AUTO=True).XOUT == -math.inf  # ITERM = 0 + (-1)·0.5


# ------------------------------------------------------------------ RAMP


def test_ramp_reaches_its_target(plc):
    """From X0 = 2 to X1 = 10 in TR = 2 s at 0.5 s per call: XI + (X1 - XI)·T/TR with T = 0, 0.5, ...;
    X1 (and BUSY = FALSE) on the call after T reaches TR."""
    r = plc.fb("RAMP")
    r(RUN=False, X0=2.0, X1=10.0, TR="2s", CYCLE="500ms")
    assert (r.XOUT, r.BUSY) == (2.0, False)
    trace = [(r(RUN=True).XOUT, r.BUSY) for _ in range(6)]
    assert trace == [(2.0, True), (4.0, True), (6.0, True), (8.0, True), (10.0, False), (10.0, False)]
    assert r.T == 2 * NS  # T stops at TR
    assert (r(X1=12.0).XOUT, r.BUSY) == (12.0, False)  # after the ramp, XOUT follows X1


def test_ramp_down_and_back_to_tracking_x0(plc):
    r = plc.fb("RAMP")
    r(RUN=False, X0=10.0, X1=0.0, TR="1s", CYCLE="250ms")
    assert [r(RUN=True).XOUT for _ in range(5)] == [10.0, 7.5, 5.0, 2.5, 0.0]
    assert (r(RUN=False, X0=4.0).XOUT, r.BUSY, r.T, r.XI) == (4.0, False, 0, 4.0)
    assert [r(RUN=True, X1=5.0).XOUT for _ in range(5)] == [4.0, 4.25, 4.5, 4.75, 5.0]


def test_ramp_started_on_the_first_call_ramps_from_zero(plc):
    """XI is set only while RUN is FALSE: a ramp running from the first call starts at XI = 0, not X0."""
    r = plc.fb("RAMP")
    trace = [(r(RUN=True, X0=5.0, X1=10.0, TR="1s", CYCLE="500ms").XOUT, r.BUSY) for _ in range(3)]
    assert trace == [(0.0, True), (5.0, True), (10.0, False)]


def test_ramp_zero_duration_jumps_and_zero_cycle_never_moves(plc):
    r = plc.fb("RAMP")
    r(RUN=False, X0=1.0, X1=9.0, TR="0s", CYCLE="100ms")
    assert (r(RUN=True).XOUT, r.BUSY) == (9.0, False)
    r = plc.fb("RAMP")
    r(RUN=False, X0=1.0, X1=9.0, TR="1s", CYCLE="0s")
    assert [(r(RUN=True).XOUT, r.BUSY) for _ in range(3)] == [(1.0, True)] * 3


def test_ramp_thirds_round_as_real(plc):
    """TR = 300 ms at 100 ms per call: 0 + 3·T/TR, each time read as REAL seconds."""
    r = plc.fb("RAMP")
    r(RUN=False, X0=0.0, X1=3.0, TR="300ms", CYCLE="100ms")
    out = [r(RUN=True).XOUT for _ in range(4)]
    assert out == [0.0] + [f32(3.0 * f32(k / 10) / f32(0.3)) for k in (1, 2)] + [3.0]


# ------------------------------------------------------------------ HYSTERESIS


def test_hysteresis_switching_points(plc):
    """On when XIN1 > XIN2 + EPS, off when XIN1 < XIN2 - EPS, both strict; in between Q holds."""
    h = plc.fb("HYSTERESIS")
    xs = [5.5, 6.0, 6.5, 5.0, 4.0, 3.9, 5.0, 6.0, 6.01]
    qs = [h(XIN1=x, XIN2=5.0, EPS=1.0).Q for x in xs]
    assert qs == [False, False, True, True, True, False, False, False, True]


def test_hysteresis_without_band_and_with_a_negative_one(plc):
    h = plc.fb("HYSTERESIS")
    assert [h(XIN1=x, XIN2=0.0, EPS=0.0).Q for x in (0.0, 0.5, 0.0, -0.5, 0.0)] == [False, True, True, False, False]
    # EPS < 0: on above XIN2 - 1, off below XIN2 + 1: in between Q toggles every call
    h = plc.fb("HYSTERESIS")
    assert [h(XIN1=5.0, XIN2=5.0, EPS=-1.0).Q for _ in range(4)] == [True, False, True, False]


# ------------------------------------------------------------------ RTC


def test_rtc_without_preset_is_the_plc_clock(plc):
    """IN = FALSE: CDT = DT#1970-01-01-00:00:00 + the PLC clock (OpenPLC's __CURRENT_TIME counts from 0)."""
    c = plc.fb("RTC")
    start = plc.time
    c(IN=False, PDT="DT#2024-05-01-12:00:00")
    assert (c.Q, c.CDT) == (False, start)
    plc.advance("90s")
    assert c().CDT == start + 90 * NS


def test_rtc_preset_and_running(plc):
    """The rising edge of IN loads PDT; while IN stays TRUE, CDT = PDT + the time since; PDT changes
    then do nothing; IN FALSE returns to the PLC clock; the next rising edge loads PDT again."""
    c = plc.fb("RTC")
    pdt = dt_ns(2024, 5, 1, 12, 0, 0)
    assert (c(IN=True, PDT="DT#2024-05-01-12:00:00").CDT, c.Q) == (pdt, True)
    plc.advance("1500ms")
    assert c(PDT="DT#2030-01-01-00:00:00").CDT == pdt + 1_500_000_000
    plc.advance("1h")
    assert c().CDT == dt_ns(2024, 5, 1, 13, 0, 1) + 500_000_000
    assert (c(IN=False).CDT, c.Q) == (plc.time, False)
    assert c(IN=True).CDT == dt_ns(2030, 1, 1, 0, 0, 0)


def test_rtc_in_st_reads_the_clock_latched_per_scan():
    """Scan k runs at (k-1)·10 ms: after 100 scans the preset clock shows PDT + 990 ms."""
    src = """
PROGRAM main
  VAR clock : RTC; now : DT; d : DATE; tod : TOD; END_VAR
  clock(IN := TRUE, PDT := DT#2023-12-31-23:59:59.5);
  now := clock.CDT;
  d := DT_TO_DATE(now);
  tod := DT_TO_TOD(now);
END_PROGRAM
"""
    plc = run(src, 100)
    assert plc["main.now"] == dt_ns(2024, 1, 1, 0, 0, 0) + 490_000_000
    assert plc["main.d"] == dt_ns(2024, 1, 1, 0, 0, 0)
    assert plc["main.tod"] == 490_000_000


# ------------------------------------------------------------------ SEMA


def test_sema_claim_and_release(plc):
    s = plc.fb("SEMA")
    seq = [
        (False, False, False),
        (True, False, True),  # claimed
        (False, False, True),  # stays claimed
        (False, True, False),  # released
        (False, False, False),
        (True, True, True),  # CLAIM wins over RELEASE
        (False, True, False),
    ]
    for claim, release, busy in seq:
        assert s(CLAIM=claim, RELEASE=release).BUSY is busy


def test_sema_guards_a_resource_between_two_programs():
    """Two programs of one task share a SEMA; the first to find it free claims it, the other waits."""
    src = """
VAR_GLOBAL lock : SEMA; owner : INT; END_VAR
PROGRAM a
  VAR_EXTERNAL lock : SEMA; owner : INT; END_VAR
  VAR n : INT; END_VAR
  n := n + 1;
  IF owner = 0 AND NOT lock.BUSY THEN
    lock(CLAIM := TRUE, RELEASE := FALSE);
    owner := 1;
  ELSIF owner = 1 AND n = 3 THEN
    lock(CLAIM := FALSE, RELEASE := TRUE);
    owner := 0;
  END_IF;
END_PROGRAM
PROGRAM b
  VAR_EXTERNAL lock : SEMA; owner : INT; END_VAR
  VAR got : INT; END_VAR
  IF owner = 0 AND NOT lock.BUSY THEN
    lock(CLAIM := TRUE, RELEASE := FALSE);
    owner := 2;
    got := got + 1;
  END_IF;
END_PROGRAM
"""
    plc = run(src, 2)
    assert (plc["lock.BUSY"], plc["owner"], plc["b.got"]) == (True, 1, 0)
    plc.scan()  # a releases in its third scan, b claims in the same scan
    assert (plc["lock.BUSY"], plc["owner"], plc["b.got"]) == (True, 2, 1)


# ------------------------------------------------------------------ replacing a block


def test_a_user_block_of_the_same_name_replaces_the_librarys():
    src = """
FUNCTION_BLOCK RAMP
  VAR_INPUT target : REAL; END_VAR
  VAR_OUTPUT out : REAL; END_VAR
  out := target * 2.0;
END_FUNCTION_BLOCK
PROGRAM main
  VAR r : RAMP; END_VAR
  r(target := 1.5);
END_PROGRAM
"""
    assert_diagnostics(src, [("W004", 2)])
    assert run(src)["main.r.out"] == 3.0
