"""MC_SetPosition during a motion, cycle-exact on a virtual axis (10 ms task; issue 31).

PLCopen Part 1: SetPosition may be used during motion "without changing the commanded position,
which is now positioned in the shifted coordinate system"; ExecutionMode mcImmediately (at once),
mcDelayed (when the ongoing motion ends: Done, aborted) and mcQueued (as a Buffered command).
The reference move: 0 → 100 at 50 u/s, 100 u/s² both ways: 2.5 s, at 50 (mid-cruise) after 1.25 s."""

from __future__ import annotations

import pytest

from st import PLC
from st.api import compile_text
from st.stdlib.plcopen import E, axis_of, configure_axes

PROGRAM = """
PROGRAM main
  VAR
    a1 : AXIS_REF := (AxisNo := 1);
    pw : MC_Power; sp : MC_SetPosition; mv : MC_MoveAbsolute; mr : MC_MoveRelative; nxt : MC_MoveAbsolute;
    other : MC_MoveAbsolute; vel : MC_MoveVelocity;
    en : BOOL := TRUE; set, go, gorel, gonext, goother, spin, rel : BOOL; pos : LREAL;
    mode : MC_EXECUTION_MODE;
  END_VAR
  pw(Axis := a1, Enable := en);
  sp(Axis := a1, Execute := set, Position := pos, Relative := rel, ExecutionMode := mode);
  mv(Axis := a1, Execute := go, Position := 100.0, Velocity := 50.0, Acceleration := 100.0, Deceleration := 100.0);
  mr(Axis := a1, Execute := gorel, Distance := 100.0, Velocity := 50.0, Acceleration := 100.0,
     Deceleration := 100.0);
  nxt(Axis := a1, Execute := gonext, Position := 10.0, Velocity := 50.0, Acceleration := 100.0,
      Deceleration := 100.0, BufferMode := mcBuffered);
  other(Axis := a1, Execute := goother, Position := 20.0, Velocity := 50.0, Acceleration := 100.0,
        Deceleration := 100.0);
  vel(Axis := a1, Execute := spin, Velocity := 50.0, Acceleration := 100.0, Deceleration := 100.0);
END_PROGRAM
"""
_COMPILED = None


def make(**cfg):
    global _COMPILED
    if _COMPILED is None:
        _COMPILED = compile_text(PROGRAM, "set_position.st")
    plc = PLC(_COMPILED, cycle="10ms")
    configure_axes(plc, {1: cfg})
    plc.scan()  # power on
    return plc


def sp_out(plc):
    return tuple(plc[f"main.sp.{n}"] for n in ("Busy", "Done", "CommandAborted", "Error"))


BUSY, DONE, ABORTED, IDLE = (
    (True, False, False, False),
    (False, True, False, False),
    (False, False, True, False),
    (
        False,
        False,
        False,
        False,
    ),
)


def scans_until(plc, cond, limit=10_000):
    for n in range(1, limit + 1):
        plc.scan()
        if cond():
            return n
    raise AssertionError("condition never became true")


def at_mid_cruise(plc, start="go"):
    """Start the move (cycle 1) and run until the kernel has put the axis at 50 (cycle 125)."""
    plc[f"main.{start}"] = True
    ax = axis_of(plc, "main.a1")
    n = scans_until(plc, lambda: ax.set_pos == 50.0)
    assert n == 125 and ax.set_vel == 50.0
    return ax


def positions(plc, ax, n):
    out = []
    for _ in range(n):
        plc.scan()
        out.append(ax.set_pos)
    return out


@pytest.mark.parametrize("relative", [True, False])
def test_immediately_keeps_the_commanded_position_of_an_absolute_move_in_the_new_coordinates(relative):
    plc = make()
    ax = at_mid_cruise(plc)
    plc["main.rel"], plc["main.pos"], plc["main.set"] = relative, (-50.0 if relative else 0.0), True
    plc.scan()  # cycle 126: the coordinate moves by -50 in the call, the move goes on from 0 to 100
    assert sp_out(plc) == DONE and plc["main.mv.Busy"] and ax.set_pos == 0.5
    # 100 more at 50 u/s: 87.5 cruising (1.75 s), 12.5 braking (0.5 s): Done in cycle 126 + 225
    n = scans_until(plc, lambda: plc["main.mv.Done"])
    assert 126 + n == 351 and ax.set_pos == 100.0 and ax.state == "Standstill"


def test_immediately_never_makes_the_set_position_jump_but_by_the_shift():
    plc = make()
    ax = at_mid_cruise(plc)
    before = ax.set_pos
    plc["main.rel"], plc["main.pos"], plc["main.set"] = True, -50.0, True
    path = [before] + positions(plc, ax, 300)
    steps = [b - a for a, b in zip(path, path[1:])]
    assert steps[0] == pytest.approx(-50.0 + 0.5)  # the shift, and one cycle at 50 u/s
    assert max(abs(s) for s in steps[1:]) <= 0.5 + 1e-9  # then never faster than 50 u/s


def test_keep_trajectory_moves_the_target_with_the_coordinate_as_codesys_does():
    plc = make(set_position_in_motion="keep_trajectory")
    ax = at_mid_cruise(plc)
    plc["main.rel"], plc["main.pos"], plc["main.set"] = True, -50.0, True
    n = scans_until(plc, lambda: plc["main.mv.Done"])
    # the same 2.5 s trajectory, shifted: Done in cycle 251, at 100 - 50
    assert 125 + n == 251 and ax.set_pos == 50.0


def test_a_relative_move_keeps_its_distance_from_its_start():
    plc = make()
    ax = at_mid_cruise(plc, "gorel")
    plc["main.rel"], plc["main.pos"], plc["main.set"] = True, -50.0, True
    n = scans_until(plc, lambda: plc["main.mr.Done"])
    assert 125 + n == 251 and ax.set_pos == 50.0  # its start moved with the coordinate: 0 → -50


def test_delayed_waits_for_the_end_of_the_ongoing_move():
    plc = make()
    plc["main.go"] = True
    plc.scan(50)
    plc["main.pos"], plc["main.mode"], plc["main.set"] = 0.0, "mcDelayed", True
    ax = axis_of(plc, "main.a1")
    for _ in range(200):  # cycles 51 .. 250: the move runs as commanded
        plc.scan()
        assert sp_out(plc) == BUSY and plc["main.mv.Busy"]
    # the kernel ended the move in cycle 250, at 100, and moved the coordinate then
    assert ax.set_pos == 0.0 and ax.act_pos == 0.0 and ax.state == "Standstill"
    plc.scan()  # cycle 251: both report Done
    assert sp_out(plc) == DONE and plc["main.mv.Done"] and ax.set_pos == 0.0


def test_delayed_is_applied_before_a_buffered_successor_is_planned():
    plc = make()
    plc["main.go"] = True
    plc.scan(50)
    plc["main.pos"], plc["main.mode"], plc["main.set"] = 1000.0, "mcDelayed", True
    plc.scan(10)
    plc["main.gonext"] = True  # buffered: to 10, in the coordinates after the shift
    plc.scan(191)  # cycle 251: the kernel of cycle 250 ended the move, shifted, started the successor
    ax = axis_of(plc, "main.a1")
    assert ax.state == "DiscreteMotion" and plc["main.nxt.Active"] and sp_out(plc) == DONE
    assert 990.0 < ax.set_pos < 1000.0  # on its way back from 1000
    scans_until(plc, lambda: plc["main.nxt.Done"])
    assert ax.set_pos == 10.0  # 1000 → 10: it went back 990


def test_delayed_is_applied_when_another_command_aborts_the_move():
    plc = make()
    ax = at_mid_cruise(plc)
    plc["main.pos"], plc["main.mode"], plc["main.set"] = 0.0, "mcDelayed", True
    plc.scan(10)
    assert sp_out(plc) == BUSY
    plc["main.goother"] = True  # aborting, to 20: the shift first, then the new plan from 0
    plc.scan()
    assert plc["main.other.Busy"] and 0.0 < ax.set_pos < 1.0
    plc.scan()  # the blocks called before `other` see it in the next scan
    assert sp_out(plc) == DONE and plc["main.mv.CommandAborted"]
    scans_until(plc, lambda: plc["main.other.Done"])
    assert ax.set_pos == 20.0


def test_delayed_at_standstill_is_applied_at_once():
    plc = make()
    plc["main.pos"], plc["main.mode"], plc["main.set"] = 7.0, "mcDelayed", True
    plc.scan()
    assert sp_out(plc) == DONE and axis_of(plc, "main.a1").set_pos == 7.0


def test_delayed_ends_with_error_when_the_axis_goes_to_errorstop_and_nothing_moves():
    plc = make(sw_limit_max=60.0)
    plc["main.spin"] = True
    plc.scan(20)
    plc["main.pos"], plc["main.mode"], plc["main.set"] = 500.0, "mcDelayed", True
    plc.scan()
    assert sp_out(plc) == BUSY
    ax = axis_of(plc, "main.a1")
    scans_until(plc, lambda: ax.state == "ErrorStop")  # past the software limit
    plc.scan()
    assert (sp_out(plc), plc["main.sp.ErrorID"]) == ((False, False, False, True), E.AXIS_ERRORSTOP)
    assert ax.set_pos < 100.0  # the coordinate was not shifted


def test_queued_in_the_buffer_reports_command_aborted_when_power_goes_off():
    plc = make()
    plc["main.go"] = True
    plc.scan(10)
    plc["main.pos"], plc["main.mode"], plc["main.set"] = 0.0, "mcQueued", True
    plc.scan()
    assert sp_out(plc) == BUSY
    plc["main.en"] = False
    plc.scan()
    assert sp_out(plc) == ABORTED and plc["main.mv.CommandAborted"]


def test_an_execution_mode_outside_the_enumeration_is_an_error():
    plc = PLC(
        compile_text(PROGRAM.replace("  pw(Axis", "  mode := 5;\n  pw(Axis"), "bad_mode.st", dialect="codesys"),
        cycle="10ms",
    )
    plc["main.set"] = True
    plc.scan(2)
    assert (sp_out(plc), plc["main.sp.ErrorID"]) == ((False, False, False, True), E.INVALID_EXECUTION_MODE)


def test_the_execution_modes_have_codesys_s_names_and_values():
    plc = make()
    for name, value in (("mcImmediately", 0), ("mcDelayed", 1), ("mcQueued", 2), ("mcImmediate", 0)):
        plc["main.mode"] = name
        assert plc.ref("main.mode").get() == value


def test_an_unknown_set_position_in_motion_setting_is_refused():
    plc = PLC(compile_text(PROGRAM, "set_position.st"), cycle="10ms")
    with pytest.raises(ValueError, match="set_position_in_motion must be 'keep_target' or 'keep_trajectory'"):
        configure_axes(plc, {1: {"set_position_in_motion": "shift"}})
