"""PLCopen motion: each FB, the axis state machine, output rules, buffer modes and the documented
choices, cycle-exact on virtual time (1 ms task). Cycle n is the scan whose FB call first sees Execute."""

import math

import pytest

from st import PLC
from st.api import compile_text
from st.stdlib.plcopen import E, axis_of, configure_axes, registry

PROGRAM = """
PROGRAM main
  VAR
    ax : AXIS_REF := (AxisNo := 1);
    power : MC_Power; power2 : MC_Power;
    abs1 : MC_MoveAbsolute; abs2 : MC_MoveAbsolute; rel : MC_MoveRelative; vel : MC_MoveVelocity;
    halt : MC_Halt; stop : MC_Stop; stop2 : MC_Stop; reset : MC_Reset; setpos : MC_SetPosition; home : MC_Home;
    status : MC_ReadStatus; apos : MC_ReadActualPosition; avel : MC_ReadActualVelocity; aerr : MC_ReadAxisError;
    en : BOOL := TRUE;
    seen_state_after_abs1 : BOOL;
    ref_switch : BOOL;
  END_VAR
  power(Axis := ax, Enable := en);
  power2(Axis := ax);
  abs1(Axis := ax);
  status(Axis := ax, Enable := TRUE);
  seen_state_after_abs1 := status.DiscreteMotion;
  abs2(Axis := ax);
  rel(Axis := ax);
  vel(Axis := ax);
  halt(Axis := ax);
  stop(Axis := ax);
  stop2(Axis := ax);
  reset(Axis := ax);
  setpos(Axis := ax);
  home(Axis := ax);
  status(Axis := ax, Enable := TRUE);
  apos(Axis := ax, Enable := TRUE);
  avel(Axis := ax, Enable := TRUE);
  aerr(Axis := ax, Enable := TRUE);
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#1ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""
_COMPILED = None
MOVE = dict(Velocity=50.0, Acceleration=100.0, Deceleration=100.0)


def make(**axis_cfg) -> PLC:
    global _COMPILED
    if _COMPILED is None:
        _COMPILED = compile_text(PROGRAM, "motion.st")
    plc = PLC(_COMPILED)
    if axis_cfg:
        configure_axes(plc, {1: axis_cfg})
    plc.scan()  # power on
    return plc


def put(plc, fb, **inputs):
    for k, v in inputs.items():
        plc[f"main.{fb}.{k}"] = v


def out(plc, fb, names=("Busy", "Active", "Done", "CommandAborted", "Error")):
    return tuple(plc[f"main.{fb}.{n}"] for n in names)


def state(plc):
    return axis_of(plc, "main.ax").state


def scans_until(plc, cond, limit=100_000):
    for n in range(1, limit + 1):
        plc.scan()
        if cond():
            return n
    raise AssertionError("condition never became true")


BUSY = (True, True, False, False, False)
DONE = (False, False, True, False, False)
ABORTED = (False, False, False, True, False)
ERROR = (False, False, False, False, True)
IDLE = (False, False, False, False, False)


# ---------------------------------------------------------------------------- timing and output rules


def test_move_absolute_is_busy_in_cycle_n_and_done_in_cycle_n_plus_2500():
    plc = make()
    assert (state(plc), plc["main.power.Status"], plc["main.status.Standstill"]) == ("Standstill", True, True)
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan()  # cycle n
    assert out(plc, "abs1") == BUSY
    assert plc["main.seen_state_after_abs1"] is True  # the state changed inside the scan
    for _ in range(2499):
        plc.scan()
    # the FB calls of cycle n + 2499 still see the move (the kernel then finishes it)
    assert out(plc, "abs1") == BUSY and plc["main.status.DiscreteMotion"]
    plc.scan()  # cycle n + 2500
    assert out(plc, "abs1") == DONE and state(plc) == "Standstill"
    assert (plc["main.apos.Position"], plc["main.avel.Velocity"]) == (100.0, 0.0)
    plc.scan(5)
    assert out(plc, "abs1") == DONE  # stays while Execute is TRUE
    put(plc, "abs1", Execute=False)
    plc.scan()
    assert out(plc, "abs1") == IDLE


def test_profile_samples_are_the_exact_trapezoid():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan(500)  # end of the acceleration phase
    ax = axis_of(plc, "main.ax")
    assert (ax.set_pos, ax.set_vel) == pytest.approx((12.5, 50.0), abs=1e-9)
    plc.scan(500)  # t = 1 s
    assert ax.set_pos == pytest.approx(37.5, abs=1e-9)
    assert plc["main.avel.Velocity"] == pytest.approx(50.0)


def test_done_shows_for_exactly_one_call_when_execute_fell_before_the_end():
    plc = make()
    put(plc, "rel", Distance=10.0, Execute=True, **MOVE)
    plc.scan()
    put(plc, "rel", Execute=False)
    n = scans_until(plc, lambda: plc["main.rel.Done"])
    assert n == 633  # 10 units, a triangle: 2·√(10/100) s
    assert out(plc, "rel") == DONE
    plc.scan()
    assert out(plc, "rel") == IDLE


def test_retrigger_of_the_same_instance_starts_the_new_command_without_reporting_the_old():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan(1000)
    put(plc, "abs1", Execute=False)
    plc.scan()
    put(plc, "abs1", Position=20.0, Execute=True)
    plc.scan()
    assert out(plc, "abs1") == BUSY  # no CommandAborted, no Done for the old one
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    assert n == 1601 and axis_of(plc, "main.ax").set_pos == 20.0  # from 37.55: brake 0.5 s to 50.05, back 1.101 s


def test_move_velocity_stays_busy_and_active_after_in_velocity():
    plc = make()
    put(plc, "vel", Velocity=50.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    plc.scan()
    assert out(plc, "vel", ("Busy", "Active", "InVelocity")) == (True, True, False)
    assert state(plc) == "ContinuousMotion"
    n = scans_until(plc, lambda: plc["main.vel.InVelocity"])
    assert n == 500
    put(plc, "vel", Execute=False)
    plc.scan(10)
    assert out(plc, "vel", ("Busy", "Active", "InVelocity", "CommandAborted")) == (True, True, True, False)
    put(plc, "halt", Deceleration=100.0, Execute=True)
    plc.scan()  # halt is called after vel: vel sees it next scan
    assert state(plc) == "DiscreteMotion" and out(plc, "halt") == BUSY
    plc.scan()
    assert out(plc, "vel", ("Busy", "Active", "InVelocity", "CommandAborted")) == (False, False, False, True)
    n = scans_until(plc, lambda: plc["main.halt.Done"])
    assert n == 499 and state(plc) == "Standstill"


def test_move_velocity_zero_ramps_to_rest_and_stays_in_continuous_motion():
    plc = make()
    put(plc, "vel", Velocity=20.0, Acceleration=100.0, Deceleration=50.0, Execute=True)
    plc.scan(300)
    put(plc, "vel", Execute=False)
    plc.scan()
    put(plc, "vel", Velocity=0.0, Execute=True)
    plc.scan()
    n = scans_until(plc, lambda: plc["main.vel.InVelocity"])
    assert n == 400  # 20 / 50 = 0.4 s
    assert (state(plc), axis_of(plc, "main.ax").set_vel) == ("ContinuousMotion", 0.0)


def test_move_velocity_negative_direction_and_reversal_uses_dec_then_acc():
    plc = make()
    put(plc, "vel", Velocity=50.0, Acceleration=100.0, Deceleration=20.0, Execute=True)
    scans_until(plc, lambda: plc["main.vel.InVelocity"])
    put(plc, "vel", Execute=False)
    plc.scan()
    put(plc, "vel", Direction=2, Execute=True)  # mcNegativeDirection: -50
    plc.scan()
    n = scans_until(plc, lambda: plc["main.vel.InVelocity"])
    assert n == 3000  # 50/20 + 50/100 = 3.0 s
    assert axis_of(plc, "main.ax").set_vel == -50.0


# ---------------------------------------------------------------------------- state machine and rejections


def test_motion_commands_are_rejected_in_disabled_and_the_axis_stays():
    plc = make()
    plc["main.en"] = False
    plc.scan()
    assert (state(plc), plc["main.power.Status"], plc["main.status.Disabled"]) == ("Disabled", False, True)
    put(plc, "abs1", Position=10.0, Execute=True, **MOVE)
    plc.scan()
    assert out(plc, "abs1") == ERROR and plc["main.abs1.ErrorID"] == E.AXIS_DISABLED
    assert state(plc) == "Disabled"


def test_enable_false_goes_to_disabled_and_aborts_the_move():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan(100)
    plc["main.en"] = False
    plc.scan()
    assert state(plc) == "Disabled"
    plc.scan()
    assert out(plc, "abs1") == ABORTED


def test_stop_holds_stopping_while_execute_and_releases_when_done_and_low():
    plc = make()
    put(plc, "vel", Velocity=50.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    plc.scan(600)
    put(plc, "stop", Deceleration=100.0, Execute=True)
    plc.scan()
    assert state(plc) == "Stopping" and out(plc, "stop") == BUSY
    plc.scan()
    assert out(plc, "vel", ("Busy", "Active", "InVelocity", "CommandAborted")) == (False, False, False, True)
    put(plc, "abs1", Position=0.0, Execute=True, **MOVE)  # rejected while Stopping
    plc.scan()
    assert out(plc, "abs1") == ERROR and plc["main.abs1.ErrorID"] == E.AXIS_STOPPING
    put(plc, "stop2", Deceleration=100.0, Execute=True)  # a second MC_Stop: error
    plc.scan()
    assert out(plc, "stop2") == ERROR and plc["main.stop2.ErrorID"] == E.STOP_ALREADY_ACTIVE
    n = scans_until(plc, lambda: plc["main.stop.Done"])
    assert n == 497  # 0.5 s from 50: Done at n + 500
    plc.scan(20)
    assert state(plc) == "Stopping"  # Execute still TRUE
    put(plc, "stop", Execute=False)
    plc.scan()
    assert state(plc) == "Standstill" and plc["main.status.Standstill"]


def test_stop_whose_execute_fell_early_releases_to_standstill_when_done():
    plc = make()
    put(plc, "vel", Velocity=10.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    plc.scan(200)
    put(plc, "stop", Deceleration=100.0, Execute=True)
    plc.scan()
    put(plc, "stop", Execute=False)
    n = scans_until(plc, lambda: state(plc) == "Standstill")
    assert n == 99  # 0.1 s: the kernel of n + 99 releases it


def test_halt_can_be_aborted_by_move_velocity():
    plc = make()
    put(plc, "vel", Velocity=50.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    plc.scan(600)
    put(plc, "vel", Execute=False)
    put(plc, "halt", Deceleration=10.0, Execute=True)
    plc.scan(100)
    assert state(plc) == "DiscreteMotion" and out(plc, "halt") == BUSY
    put(plc, "vel", Execute=True)
    plc.scan()
    assert state(plc) == "ContinuousMotion"
    plc.scan()
    assert out(plc, "halt") == ABORTED


def test_error_stop_reports_error_on_active_and_buffered_fbs_and_reset_recovers():
    plc = make(sw_limit_min=-1000.0, sw_limit_max=30.0, max_deceleration=1000.0)
    put(plc, "abs1", Position=25.0, Execute=True, **MOVE)
    put(plc, "abs2", Position=28.0, BufferMode=1, Execute=True, **MOVE)
    plc.scan()
    assert out(plc, "abs2") == (True, False, False, False, False)  # buffered: Busy, not Active
    put(plc, "abs1", Position=60.0)  # beyond the limit: rejected up front
    put(plc, "rel", Distance=100.0, Execute=True, **MOVE)
    plc.scan()
    assert out(plc, "rel") == ERROR and plc["main.rel.ErrorID"] == E.SW_LIMIT_TARGET
    put(plc, "vel", Velocity=40.0, Acceleration=100.0, Deceleration=100.0, BufferMode=1, Execute=True)
    plc.scan()
    # the velocity move queued after abs2 runs into the software limit at 30: ErrorStop
    scans_until(plc, lambda: state(plc) == "ErrorStop")
    plc.scan()
    assert out(plc, "vel", ("Busy", "Active", "CommandAborted", "Error")) == (False, False, False, True)
    assert plc["main.vel.ErrorID"] == E.AXIS_ERRORSTOP
    assert plc["main.aerr.AxisErrorID"] == E.SW_LIMIT_REACHED and plc["main.status.ErrorStop"]
    put(plc, "abs2", Execute=False)
    put(plc, "abs1", Position=0.0, Execute=False)
    plc.scan()
    put(plc, "abs1", Execute=True)
    plc.scan()
    assert out(plc, "abs1") == ERROR and plc["main.abs1.ErrorID"] == E.AXIS_ERRORSTOP
    put(plc, "reset", Execute=True)
    plc.scan()
    assert plc["main.reset.Done"] and state(plc) == "Standstill"  # power on: Standstill
    assert plc["main.aerr.AxisErrorID"] == 0


def test_reset_outside_error_stop_is_an_error_and_reset_with_power_off_goes_to_disabled():
    plc = make(sw_limit_max=5.0, max_deceleration=1e6)
    put(plc, "reset", Execute=True)
    plc.scan()
    assert out(plc, "reset", ("Busy", "Done", "Error")) == (False, False, True)
    assert plc["main.reset.ErrorID"] == E.NO_ERROR_TO_RESET
    put(plc, "vel", Velocity=10.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    scans_until(plc, lambda: state(plc) == "ErrorStop")
    plc["main.en"] = False
    plc.scan()
    assert state(plc) == "ErrorStop"  # Enable FALSE does not leave ErrorStop
    put(plc, "reset", Execute=False)
    plc.scan()
    put(plc, "reset", Execute=True)
    plc.scan()
    assert plc["main.reset.Done"] and state(plc) == "Disabled"


def test_a_second_mc_power_is_an_error():
    plc = make()
    put(plc, "power2", Enable=True)
    plc.scan()
    assert (plc["main.power2.Error"], plc["main.power2.ErrorID"], plc["main.power.Status"]) == (
        True,
        E.POWER_ALREADY_ACTIVE,
        True,
    )


def test_enable_timeout_leaves_the_axis_disabled():
    plc = make(enable_delay=math.inf, enable_timeout=2.0)
    assert state(plc) == "Disabled"
    n = scans_until(plc, lambda: plc["main.power.Error"])
    assert n == 2000 and plc["main.power.ErrorID"] == E.ENABLE_TIMEOUT and state(plc) == "Disabled"


# ---------------------------------------------------------------------------- parameters (documented choices)


@pytest.mark.parametrize(
    "inputs, code",
    [
        (dict(Acceleration=0.0), E.INVALID_ACCELERATION),
        (dict(Acceleration=-1.0), E.INVALID_ACCELERATION),
        (dict(Deceleration=float("nan")), E.INVALID_DECELERATION),
        (dict(Jerk=-1.0), E.INVALID_JERK),
        (dict(Velocity=0.0), E.INVALID_VELOCITY),
        (dict(Velocity=-5.0), E.INVALID_VELOCITY),
        (dict(Position=float("inf")), E.INVALID_POSITION),
    ],
)
def test_invalid_parameters_are_errors_and_leave_the_running_move_alone(inputs, code):
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan(1000)
    put(plc, "abs2", **{**MOVE, "Position": 0.0, **inputs})
    put(plc, "abs2", Execute=True)  # Aborting, but invalid
    plc.scan()
    assert out(plc, "abs2") == ERROR and plc["main.abs2.ErrorID"] == code
    assert out(plc, "abs1") == BUSY  # the running move goes on
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    assert n == 1500


def test_jerk_zero_is_a_trapezoid_and_jerk_positive_an_s_curve():
    plc = make()
    put(plc, "abs1", Position=100.0, Jerk=1000.0, Execute=True, **MOVE)
    plc.scan()
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    assert n == 2600 and axis_of(plc, "main.ax").set_pos == 100.0  # ruckig: 2.6 s


def test_buffer_full_is_an_error():
    plc = make(buffer_size=1)
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    put(plc, "abs2", Position=150.0, BufferMode=1, Execute=True, **MOVE)
    put(plc, "rel", Distance=10.0, BufferMode=1, Execute=True, **MOVE)
    plc.scan()
    assert out(plc, "rel") == ERROR and plc["main.rel.ErrorID"] == E.BUFFER_FULL


# ---------------------------------------------------------------------------- buffer modes


def test_buffered_successor_starts_when_the_predecessor_is_done():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    put(plc, "abs2", Position=130.0, BufferMode=1, Execute=True, **MOVE)
    plc.scan()
    assert out(plc, "abs2") == (True, False, False, False, False)
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    assert n == 2500 and out(plc, "abs2") == BUSY  # Active in the hand-over cycle
    n = scans_until(plc, lambda: plc["main.abs2.Done"])
    assert n == 1100 and axis_of(plc, "main.ax").set_pos == 130.0  # 100 → 130 from rest: 1.1 s


def test_a_command_buffered_after_move_velocity_starts_at_in_velocity_and_aborts_it():
    plc = make()
    put(plc, "vel", Velocity=50.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    put(plc, "halt", Deceleration=100.0, BufferMode=1, Execute=True)
    plc.scan()
    assert out(plc, "halt") == (True, False, False, False, False)  # queued: Busy, not Active
    n = scans_until(plc, lambda: plc["main.halt.Active"])
    assert n == 500  # 0.5 s: Active in cycle n + 500
    assert out(plc, "vel", ("Busy", "Active", "InVelocity", "CommandAborted")) == (False, False, False, True)
    assert state(plc) == "DiscreteMotion"
    n = scans_until(plc, lambda: plc["main.halt.Done"])
    assert n == 500 and state(plc) == "Standstill"


def test_enable_false_while_stopping_aborts_the_stop_and_disables():
    plc = make()
    put(plc, "vel", Velocity=50.0, Acceleration=100.0, Deceleration=100.0, Execute=True)
    plc.scan(600)
    put(plc, "stop", Deceleration=100.0, Execute=True)
    plc.scan(10)
    assert state(plc) == "Stopping" and out(plc, "stop") == BUSY
    plc["main.en"] = False
    plc.scan()
    assert state(plc) == "Disabled"
    plc.scan()
    assert out(plc, "stop") == ABORTED
    put(plc, "stop", Execute=False)
    plc.scan()
    assert out(plc, "stop") == (False, False, False, False, False)


@pytest.mark.parametrize("mode, first, second", [(2, 2313, 4125), (3, 2250, 4000), (4, 2313, 4125), (5, 2250, 4000)])
def test_blending_hands_over_at_the_standard_velocity(mode, first, second):
    # abs1: 0 → 100 at 50; abs2: 100 → 200 at 25. Low/Next hand over at 25, Previous/High at 50.
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    put(plc, "abs2", Position=200.0, BufferMode=mode, Execute=True, **{**MOVE, "Velocity": 25.0})
    plc.scan()
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    assert n == first
    ax = axis_of(plc, "main.ax")
    assert ax.set_pos == pytest.approx(100.0 + ax.set_vel * 0.001, abs=0.06)
    n = scans_until(plc, lambda: plc["main.abs2.Done"])
    assert n == second and ax.set_pos == 200.0


def test_blending_between_opposite_directions_degrades_to_buffered():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    put(plc, "abs2", Position=70.0, BufferMode=5, Execute=True, **MOVE)
    plc.scan()
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    ax = axis_of(plc, "main.ax")  # abs1 ended at rest; abs2 took one step back
    assert n == 2500 and ax.set_vel == pytest.approx(-0.1) and ax.set_pos == pytest.approx(100 - 0.00005)


# ---------------------------------------------------------------------------- positions


def test_move_relative_measures_from_the_set_position_at_its_start():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan(1000)  # at 37.5, moving at 50
    put(plc, "rel", Distance=40.0, Execute=True, **MOVE)  # aborting: ends at 77.5
    plc.scan()
    scans_until(plc, lambda: plc["main.rel.Done"])
    assert axis_of(plc, "main.ax").set_pos == 77.5


def test_set_position_and_home_shift_the_coordinates():
    plc = make()
    put(plc, "setpos", Position=500.0, Execute=True)
    plc.scan()
    assert out(plc, "setpos", ("Busy", "Done", "Error")) == (False, True, False)
    assert plc["main.apos.Position"] == 500.0
    put(plc, "home", Position=0.0, Execute=True)
    plc.scan()
    assert plc["main.status.Homing"] and out(plc, "home") == BUSY  # referencing at the current position
    plc.scan()
    assert plc["main.home.Done"] and state(plc) == "Standstill" and plc["main.apos.Position"] == 0.0


HOMING = dict(
    homing="switch", home_switch_position=-20.005, home_direction=-1, home_velocity=10.0, home_acceleration=100.0
)


def test_home_by_a_move_latches_the_switch_edge_and_shifts_the_coordinates():
    plc = make(**HOMING)
    put(plc, "home", Position=100.0, Execute=True)
    plc.scan()
    assert state(plc) == "Homing" and out(plc, "home") == BUSY
    ax = axis_of(plc, "main.ax")
    n = scans_until(plc, lambda: plc["main.home.Done"])
    assert n == 2151  # 0.1 s ramp, 19.505 units at 10/s seen in the next cycle, 0.1 s brake
    assert state(plc) == "Standstill"
    assert ax.act_pos == pytest.approx(99.495, abs=1e-9)  # the edge at -20.005 is now 100; 0.505 past it
    assert plc["main.apos.Position"] == ax.act_pos


def test_home_starting_on_the_switch_leaves_it_the_other_way():
    plc = make(**HOMING)
    put(plc, "setpos", Position=-30.0, Execute=True)
    plc.scan()
    put(plc, "home", Position=0.0, Execute=True)
    plc.scan()
    ax = axis_of(plc, "main.ax")
    scans_until(plc, lambda: plc["main.home.Done"])
    # searched upwards until the cam (active at ≤ -20.005) went inactive, seen at -20.0, then braked
    # 0.5 further: 0.505 past the edge, which is now 0
    assert ax.act_pos == pytest.approx(0.505, abs=1e-9)


def test_home_on_a_bool_variable_latches_the_actual_position_of_that_cycle():
    plc = make(**{**HOMING, "home_switch_position": math.nan, "home_switch": "main.ref_switch"})
    ax = axis_of(plc, "main.ax")
    put(plc, "home", Position=0.0, Execute=True)
    plc.scan(300)  # searching downwards at 10 units/s
    assert state(plc) == "Homing" and ax.act_pos == pytest.approx(-2.5, abs=1e-9)
    plc["main.ref_switch"] = True  # the switch closes
    n = scans_until(plc, lambda: plc["main.home.Done"])
    assert n == 102  # latched by the next kernel phase, 100 cycles braking, Done
    assert ax.act_pos == pytest.approx(-0.5, abs=1e-9)  # the latched position is 0; braked 0.5 past it


def test_home_errors_not_configured_search_distance_and_stop():
    plc = make(homing="switch")
    put(plc, "home", Position=0.0, Execute=True)
    plc.scan()
    assert out(plc, "home") == ERROR and plc["main.home.ErrorID"] == E.HOMING_NOT_CONFIGURED
    assert state(plc) == "Standstill"

    plc = make(**HOMING, home_search_distance=5.005)
    put(plc, "home", Position=0.0, Execute=True)
    plc.scan()
    n = scans_until(plc, lambda: state(plc) == "ErrorStop")
    assert n == 550  # 0.5 units of ramp + 4.505 at 10/s
    plc.scan()
    assert out(plc, "home") == ERROR and plc["main.home.ErrorID"] == E.AXIS_ERRORSTOP
    assert plc["main.aerr.AxisErrorID"] == E.HOMING_FAILED

    plc = make(**HOMING)
    put(plc, "home", Position=0.0, Execute=True)
    plc.scan(100)
    put(plc, "abs1", Position=0.0, Execute=True, **MOVE)  # rejected while Homing
    put(plc, "stop", Deceleration=100.0, Execute=True)  # MC_Stop is allowed
    plc.scan()
    assert out(plc, "abs1") == ERROR and plc["main.abs1.ErrorID"] == E.AXIS_HOMING
    assert state(plc) == "Stopping"
    plc.scan()
    assert out(plc, "home") == ABORTED


@pytest.mark.parametrize(
    "start, target, direction, end_unwrapped",
    [
        (350.0, 10.0, 0, 370.0),  # positive
        (10.0, 350.0, 2, -10.0),  # negative
        (10.0, 350.0, 1, -10.0),  # shortest: backwards
        (0.0, 180.0, 1, 180.0),  # exactly half a period: positive
        (90.0, 90.0, 0, 90.0),  # the same position with Positive: no move
    ],
)
def test_modulo_axis_directions(start, target, direction, end_unwrapped):
    plc = make(modulo=360.0)
    put(plc, "setpos", Position=start, Execute=True)
    plc.scan()
    put(plc, "abs1", Position=target, Direction=direction, Execute=True, **{**MOVE, "Velocity": 100.0})
    plc.scan()
    scans_until(plc, lambda: plc["main.abs1.Done"])
    ax = axis_of(plc, "main.ax")
    assert ax.set_pos - start == pytest.approx(end_unwrapped - start)
    assert plc["main.apos.Position"] == pytest.approx(target % 360.0)


def test_continuous_update_retargets_a_relative_move_from_its_original_start():
    # the standard's example: MoveRelative by 100 from 0; at 50 the distance becomes 130 → ends at 130
    plc = make()
    put(plc, "rel", Distance=100.0, ContinuousUpdate=True, Execute=True, **MOVE)
    plc.scan()
    scans_until(plc, lambda: axis_of(plc, "main.ax").set_pos >= 50.0)
    put(plc, "rel", Distance=130.0)
    scans_until(plc, lambda: plc["main.rel.Done"])
    assert axis_of(plc, "main.ax").set_pos == 130.0


def test_halt_in_standstill_is_done_at_once():
    plc = make()
    put(plc, "halt", Deceleration=10.0, Execute=True)
    plc.scan()
    plc.scan()
    assert out(plc, "halt") == DONE and state(plc) == "Standstill"
    put(plc, "setpos", Position=12.5, Relative=True, Execute=True)
    plc.scan()
    assert plc["main.apos.Position"] == 12.5 and state(plc) == "Standstill"


def test_online_change_keeps_the_axes_and_the_running_move():
    plc = make()
    put(plc, "abs1", Position=100.0, Execute=True, **MOVE)
    plc.scan(1000)
    changed = PROGRAM.replace("seen_state_after_abs1 : BOOL;", "seen_state_after_abs1 : BOOL; extra : INT;")
    assert plc.online_change(compile_text(changed, "motion.st")) == "online change: 1 instance(s) carried over"
    assert axis_of(plc, "main.ax").set_pos == pytest.approx(37.5)
    n = scans_until(plc, lambda: plc["main.abs1.Done"])
    assert n == 1501 and axis_of(plc, "main.ax").set_pos == 100.0  # Done in cycle n + 2500


HANDLES = """
PROGRAM main
  VAR
    bad : AXIS_REF := (Handle := -1);
    bad1 : AXIS_REF := (AxisNo := 1, Handle := 12345);
    v : AXIS_REF; v_copy : AXIS_REF; a1 : AXIS_REF := (AxisNo := 1);
    pw_bad : MC_Power; rs_bad : MC_ReadStatus; mv_bad : MC_MoveAbsolute; pw_bad1 : MC_Power;
    pw_v : MC_Power; rs_copy : MC_ReadStatus; pw_a1 : MC_Power; scribble : BOOL;
  END_VAR
  IF scribble THEN a1.Handle := 77; END_IF
  pw_bad(Axis := bad, Enable := TRUE);
  rs_bad(Axis := bad, Enable := TRUE);
  mv_bad(Axis := bad, Execute := TRUE, Position := 1.0, Velocity := 1.0, Acceleration := 1.0, Deceleration := 1.0);
  pw_bad1(Axis := bad1, Enable := TRUE);
  pw_v(Axis := v, Enable := TRUE);
  v_copy := v;
  rs_copy(Axis := v_copy, Enable := TRUE);
  pw_a1(Axis := a1, Enable := TRUE);
END_PROGRAM
"""


def test_an_axis_ref_whose_handle_the_library_never_issued_is_invalid():
    plc = PLC(compile_text(HANDLES, "handles.st", use_cache=False))
    plc.scan(2)
    for fb, on in (("pw_bad", "Status"), ("rs_bad", "Valid"), ("mv_bad", "Busy"), ("pw_bad1", "Status")):
        assert (plc[f"main.{fb}.Error"], plc[f"main.{fb}.ErrorID"], plc[f"main.{fb}.{on}"]) == (
            True,
            E.INVALID_AXIS_REF,
            False,
        )
    assert plc["main.rs_copy.Standstill"]  # a copy of an issued handle is the same (virtual) axis
    assert (plc["main.a1.Handle"], plc["main.pw_a1.Status"]) == (1, True)  # AxisNo n's handle is n
    plc["main.scribble"] = True  # the program overwrites the handle with one never issued
    plc.scan()
    assert (plc["main.pw_a1.Error"], plc["main.pw_a1.ErrorID"]) == (True, E.INVALID_AXIS_REF)
    assert len(registry(plc).axes) == 2  # axis 1 and the virtual one: nothing made up
