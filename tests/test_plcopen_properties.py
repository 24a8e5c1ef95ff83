"""PLCopen motion: property tests over random command sequences (hypothesis).

One program with one axis and an instance of each commanding block; a sequence of actions (toggle
an Execute or MC_Power's Enable, set an input to a valid or invalid value, run k scans) is played
against it, and after every scan the PLCopen output rules are checked for every Execute-type
instance, plus MC_ReadStatus against the axis state and the set position against a bound.

A failing example is reported as the list of actions up to the failing scan; paste it into
`play(ACTIONS)` to replay it outside hypothesis.

Execution model (st/stdlib/plcopen/axis.py): the program runs first (FB calls submit commands,
the axis state changes at once), then the kernel advances the axis one cycle, which may change
its state again (a move finishes → Standstill). MC_ReadStatus is called last in the program, so
its flags are compared with the state the axis had right before the kernel phase of that scan.
"""

import math

import hypothesis.strategies as hs
import pytest
from hypothesis import HealthCheck, given, settings

from st import PLC
from st.api import compile_text
from st.stdlib.plcopen import axis_of, configure_axes

PROGRAM = """
PROGRAM main
  VAR
    ax : AXIS_REF := (AxisNo := 1);
    pw : MC_Power;
    abs1 : MC_MoveAbsolute; abs2 : MC_MoveAbsolute; rel : MC_MoveRelative; vel : MC_MoveVelocity;
    halt : MC_Halt; stop : MC_Stop; reset : MC_Reset;
    status : MC_ReadStatus;
  END_VAR
  pw(Axis := ax);
  abs1(Axis := ax);
  abs2(Axis := ax);
  rel(Axis := ax);
  vel(Axis := ax);
  halt(Axis := ax);
  stop(Axis := ax);
  reset(Axis := ax);
  status(Axis := ax, Enable := TRUE);
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#10ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""

# Software limits so that ErrorStop (and with it MC_Reset) is reachable; the ErrorStop ramp
# brakes at 1000 units/s².
SW_LIMIT = 500.0
STOP_DEC = 1000.0
AXIS_CFG = dict(sw_limit_min=-SW_LIMIT, sw_limit_max=SW_LIMIT, stop_deceleration=STOP_DEC)

EXECUTE_FBS = ("abs1", "abs2", "rel", "vel", "halt", "stop", "reset")
STATES = ("ErrorStop", "Disabled", "Stopping", "Homing", "Standstill", "DiscreteMotion", "ContinuousMotion")

NAN, INF = float("nan"), float("inf")
VMAX = 1000.0  # the largest valid Velocity generated
JMIN = 1e4  # the smallest positive Jerk generated
AMAX = 1e4  # the largest valid Acceleration / Deceleration generated

# Valid starting inputs of each example (the blocks' own defaults are 0: invalid for a move).
MOVE = dict(Velocity=100.0, Acceleration=1000.0, Deceleration=1000.0, Jerk=0.0)
DEFAULTS = {
    "pw": dict(Enable=True),
    "abs1": dict(Position=100.0, **MOVE),
    "abs2": dict(Position=-50.0, **MOVE),
    "rel": dict(Distance=25.0, **MOVE),
    "vel": dict(**MOVE),
    "halt": dict(Deceleration=1000.0, Jerk=0.0),
    "stop": dict(Deceleration=1000.0, Jerk=0.0),
}

_COMPILED = None


def _compiled():
    global _COMPILED
    if _COMPILED is None:
        _COMPILED = compile_text(PROGRAM, "motion_properties.st")
    return _COMPILED


# ---------------------------------------------------------------------------- actions


def _values(valid, invalid):
    return hs.one_of(hs.sampled_from(valid + invalid), hs.sampled_from(valid))


SPEED = _values([1.0, 10.0, 100.0, 500.0, VMAX], [0.0, -10.0, NAN, INF])
RATE = _values([10.0, 100.0, 1000.0, AMAX], [0.0, -100.0, NAN, INF])
JERK = _values([0.0, 0.0, JMIN, 1e5], [-1.0, NAN])
POSITION = hs.one_of(
    hs.sampled_from([0.0, 100.0, -50.0, 480.0, -499.0, 650.0, NAN, INF]),
    hs.floats(-600.0, 600.0).map(lambda x: round(x, 3)),
)
DISTANCE = hs.one_of(
    hs.sampled_from([0.0, 25.0, -40.0, 300.0, NAN]), hs.floats(-400.0, 400.0).map(lambda x: round(x, 3))
)
BUFFER_MODE = hs.integers(0, 5)
DIRECTION = hs.integers(0, 3)

PARAMS = {
    "abs1": {
        "Position": POSITION,
        "Velocity": SPEED,
        "Acceleration": RATE,
        "Deceleration": RATE,
        "Jerk": JERK,
        "BufferMode": BUFFER_MODE,
        "Direction": DIRECTION,
    },
    "rel": {
        "Distance": DISTANCE,
        "Velocity": SPEED,
        "Acceleration": RATE,
        "Deceleration": RATE,
        "Jerk": JERK,
        "BufferMode": BUFFER_MODE,
    },
    "vel": {
        "Velocity": SPEED,
        "Acceleration": RATE,
        "Deceleration": RATE,
        "Jerk": JERK,
        "BufferMode": BUFFER_MODE,
        "Direction": DIRECTION,
    },
    "halt": {"Deceleration": RATE, "Jerk": JERK, "BufferMode": BUFFER_MODE},
    "stop": {"Deceleration": RATE, "Jerk": JERK},
}
PARAMS["abs2"] = PARAMS["abs1"]

# the moves more often than MC_Stop (held, it keeps the axis in Stopping) and MC_Power (off: Disabled)
toggle = hs.tuples(
    hs.just("toggle"), hs.sampled_from(("abs1", "abs2", "rel", "vel") * 3 + ("halt", "halt", "stop", "reset", "pw"))
)
continuous = hs.tuples(hs.just("continuous"), hs.sampled_from(("abs1", "abs2", "rel", "vel")))
set_param = hs.sampled_from(sorted((fb, p) for fb, ps in PARAMS.items() for p in ps)).flatmap(
    lambda fp: hs.tuples(hs.just("set"), hs.just(fp[0]), hs.just(fp[1]), PARAMS[fp[0]][fp[1]])
)
run = hs.tuples(hs.just("scan"), hs.one_of(hs.integers(1, 5), hs.integers(1, 300)))
action = hs.one_of(toggle, toggle, set_param, run, run, continuous)
actions = hs.lists(action, min_size=20, max_size=60)


def _fmt_value(v):
    if isinstance(v, float) and not math.isfinite(v):
        return f'float("{v}")'
    return repr(v)


def format_actions(acts) -> str:
    return "[\n" + "".join("    (" + ", ".join(_fmt_value(x) for x in a) + "),\n" for a in acts) + "]"


# ---------------------------------------------------------------------------- the harness


class Violation(AssertionError):
    pass


class Run:
    """One PLC playing one action sequence, checking after every scan."""

    def __init__(self, check_outputs=True, check_position=True):
        self.plc = plc = PLC(_compiled())
        configure_axes(plc, {1: AXIS_CFG})
        for fb, inputs in DEFAULTS.items():
            for k, v in inputs.items():
                plc[f"main.{fb}.{k}"] = v
        self.fb = {name: self._obj(f"main.{name}") for name in EXECUTE_FBS + ("pw", "status")}
        self.ax = ax = axis_of(plc, "main.ax")
        self.pre_kernel_state = None
        step = ax.step

        def kernel_step():  # the state the program phase left, for ReadStatus
            self.pre_kernel_state = ax.state
            step()

        ax.step = kernel_step
        self.prev_exec = {name: False for name in EXECUTE_FBS}
        self.started = {name: False for name in EXECUTE_FBS}  # a rising edge since the last terminal report
        self.check_outputs, self.check_position = check_outputs, check_position
        self.scans = self.scan_in_action = 0
        self.last_pos = None
        self.done_actions = []

    def _obj(self, path):
        return self.plc.ref(path).get()

    def play(self, acts) -> None:
        for a in acts:
            self.done_actions.append(a)
            kind = a[0]
            if kind == "toggle":
                name = a[1]
                var = "Enable" if name == "pw" else "Execute"
                self.plc[f"main.{name}.{var}"] = not getattr(self.fb[name], var)
            elif kind == "continuous":
                self.plc[f"main.{a[1]}.ContinuousUpdate"] = not self.fb[a[1]].ContinuousUpdate
            elif kind == "set":
                self.plc[f"main.{a[1]}.{a[2]}"] = a[3]
            else:
                for i in range(a[1]):
                    self.plc.scan()
                    self.scans += 1
                    self.scan_in_action = i + 1
                    self.check()

    def fail(self, what: str) -> None:
        last = self.done_actions[-1]
        where = f"after scan {self.scans}"
        if last[0] == "scan":
            where += f" (scan {self.scan_in_action} of the last action {last!r})"
        raise Violation(
            f"{what}\n  {where}; axis state {self.ax.state}, set_pos {self.ax.set_pos!r}, "
            f"set_vel {self.ax.set_vel!r}\n  actions (replay with play(ACTIONS)):\n"
            f"ACTIONS = {format_actions(self.done_actions)}"
        )

    def check(self) -> None:
        if self.check_outputs:
            self._check_outputs()
        if self.check_position:
            self._check_position()

    def _check_outputs(self) -> None:
        for name in EXECUTE_FBS:
            fb = self.fb[name]
            ex = bool(fb.Execute)
            busy, error = fb.Busy, fb.Error
            done = fb.Done if name != "vel" else False  # MC_MoveVelocity: InVelocity, no Done
            aborted = fb.CommandAborted if name != "reset" else False
            active = fb.Active if name != "reset" else False
            flags = dict(Busy=busy, Done=done, Error=error, CommandAborted=aborted)
            on = [n for n, v in flags.items() if v]
            # (a) at most one of Busy, Done, Error, CommandAborted
            if len(on) > 1:
                self.fail(f"(a) {name}: more than one of Busy/Done/Error/CommandAborted: {on}")
            # (b) exactly one of them while Execute is TRUE
            if ex and len(on) != 1:
                self.fail(f"(b) {name}: Execute is TRUE but Busy/Done/Error/CommandAborted = {on}")
            # (c) at most one of Active, Done, Error, CommandAborted (MC_Stop: Active and Done may both be on)
            on_c = [n for n, v in dict(Active=active, Done=done, Error=error, CommandAborted=aborted).items() if v]
            if name == "stop" and set(on_c) == {"Active", "Done"}:
                on_c = ["Active+Done"]
            if len(on_c) > 1:
                self.fail(f"(c) {name}: more than one of Active/Done/Error/CommandAborted: {on_c}")
            # (d) MC_MoveVelocity: InVelocity implies Busy and Active
            if name == "vel" and fb.InVelocity and not (busy and active):
                self.fail(f"(d) vel: InVelocity without Busy and Active (Busy={busy}, Active={active})")
            # (f) no command without a rising edge: Busy only after an edge not yet followed by a terminal output
            if ex and not self.prev_exec[name]:
                self.started[name] = True
            self.prev_exec[name] = ex
            if busy and not self.started[name]:
                self.fail(f"(f) {name}: Busy without a rising edge of Execute since its last terminal output")
            if done or error or aborted:
                self.started[name] = False
            # ErrorID only with Error
            if bool(fb.ErrorID) != error:
                self.fail(f"{name}: ErrorID {fb.ErrorID:#x} with Error {error}")
        # (e) MC_ReadStatus: exactly one state flag, the axis's state (before the kernel phase of this scan)
        st = self.fb["status"]
        on = [s for s in STATES if getattr(st, s)]
        if len(on) != 1:
            self.fail(f"(e) status: {len(on)} state flags on: {on}")
        if on[0] != self.pre_kernel_state:
            self.fail(f"(e) status shows {on[0]} but the axis was {self.pre_kernel_state}")
        # (g) the outputs agree with the state: nothing runs in Disabled, ErrorStop or Standstill
        # (MC_Power is called first and MC_ReadStatus last, so every block saw the state ReadStatus shows)
        if on[0] in ("Disabled", "ErrorStop", "Standstill"):
            for name in EXECUTE_FBS:
                fb = self.fb[name]
                if name != "reset" and (fb.Busy or fb.Active):
                    self.fail(f"(g) {name}: Busy {fb.Busy} / Active {fb.Active} while the axis is {on[0]}")
        pw = self.fb["pw"]
        if (pw.Status or pw.Valid) and not pw.Enable:
            self.fail(f"pw: Status {pw.Status} / Valid {pw.Valid} with Enable FALSE")

    def _check_position(self) -> None:
        ax = self.ax
        p, v = ax.set_pos, ax.set_vel
        if math.isnan(p) or math.isnan(v) or math.isnan(ax.act_pos):
            self.fail(f"set position / velocity is NaN: set_pos {p!r}, set_vel {v!r}, act_pos {ax.act_pos!r}")
        if abs(p) > POSITION_BOUND or not math.isfinite(v):
            self.fail(f"set position {p!r} outside ±{POSITION_BOUND} (or velocity {v!r} not finite)")
        if abs(v) > SPEED_BOUND:
            self.fail(f"set velocity {v!r} beyond ±{SPEED_BOUND}")
        # continuity: no jump larger than the fastest speed allows in one cycle
        if self.last_pos is not None and abs(p - self.last_pos) > SPEED_BOUND * ax.cycle + 1e-9:
            self.fail(
                f"the set position jumped by {p - self.last_pos!r} in one cycle of {ax.cycle} s "
                f"({self.last_pos!r} → {p!r}; at most {SPEED_BOUND * ax.cycle!r})"
            )
        self.last_pos = p


# Targets outside ±SW_LIMIT are rejected and a move running outward past a limit is an ErrorStop
# braking at STOP_DEC, so the set position stays within the limits plus the braking distance from
# the fastest speed (plus a jerk-limited velocity overshoot ≤ AMAX²/(2·JMIN)), and one cycle.
SPEED_BOUND = VMAX + AMAX**2 / (2 * JMIN)
POSITION_BOUND = SW_LIMIT + SPEED_BOUND**2 / (2 * STOP_DEC) + SPEED_BOUND * 0.01


def play(acts, check_outputs=True, check_position=True) -> Run:
    """Replay an action list (as printed by a failure)."""
    r = Run(check_outputs, check_position)
    r.play(acts)
    return r


# ---------------------------------------------------------------------------- properties

SETTINGS = dict(
    deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large]
)


@pytest.mark.slow
@settings(max_examples=60, **SETTINGS)
@given(acts=actions)
def test_output_rules_hold_after_every_scan(acts):
    play(acts, check_outputs=True, check_position=False)


@pytest.mark.slow
@settings(max_examples=30, **SETTINGS)
@given(acts=actions)
def test_set_position_stays_finite_and_bounded(acts):
    play(acts, check_outputs=False, check_position=True)


def test_replay_of_a_hand_written_sequence():
    """The harness itself: a plain move, then a stop held and released, then an ErrorStop and reset."""
    r = play(
        [
            ("toggle", "pw"),
            ("scan", 2),
            ("toggle", "abs1"),
            ("scan", 120),
            ("toggle", "abs1"),
            ("toggle", "vel"),
            ("scan", 50),
            ("toggle", "stop"),
            ("scan", 30),
            ("toggle", "stop"),
            ("scan", 2),
            ("set", "vel", "Velocity", 500.0),
            ("toggle", "vel"),
            ("scan", 1),
            ("toggle", "vel"),
            ("scan", 200),
            ("toggle", "reset"),
            ("scan", 2),
        ]
    )
    assert r.ax.set_pos <= POSITION_BOUND and r.scans == 407
