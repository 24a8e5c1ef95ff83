"""PLCopen on a drive-bound axis (issue 19): what the program sees is what the emulated CiA 402
drive does, cycle by cycle."""

from __future__ import annotations

import pytest

from st import PLC
from st.api import compile_text
from st.io.ethercat import EtherCATDriver
from st.io.ethercat.config import from_dict
from st.stdlib.plcopen import E, axis_of, configure_axes

PROGRAM = """
PROGRAM main
  VAR
    a1 : AXIS_REF := (AxisNo := 1);
    pw : MC_Power;
    sp : MC_SetPosition;
    hm : MC_Home;
    mv : MC_MoveAbsolute;
    mr : MC_MoveRelative;
    en : BOOL := TRUE;
    cu, next : BOOL;
    acc : LREAL := 3600.0;
    vel : LREAL := 360.0;
    set, home, go : BOOL;
    pos : LREAL := 1000.0;
    rel : BOOL;
    mode : MC_EXECUTION_MODE := mcImmediately;
    target : LREAL := 1090.0;
  END_VAR
  pw(Axis := a1, Enable := en);
  sp(Axis := a1, Execute := set, Position := pos, Relative := rel, ExecutionMode := mode);
  hm(Axis := a1, Execute := home, Position := pos);
  mv(Axis := a1, Execute := go, ContinuousUpdate := cu, Position := target, Velocity := vel, Acceleration := acc,
     Deceleration := 3600.0);
  mr(Axis := a1, Execute := next, Distance := 10.0, Velocity := 100.0, Acceleration := 1000.0, Deceleration := 1000.0,
     BufferMode := mcBuffered);
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#1ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""
SEGMENT = {"segment": {"cycle": "1ms", "dc": True}, "slave": [{"name": "d1", "type": "cia402", "axis": 1}]}
CPR = 1 << 23  # the emulated drive's increments per revolution (360 units)
_COMPILED = None


def make(**axis_cfg):
    global _COMPILED
    if _COMPILED is None:
        _COMPILED = compile_text(PROGRAM, "drive.st")
    plc = PLC(_COMPILED)
    configure_axes(plc, {1: {"following_error_window": 5.0, **axis_cfg}})
    drv = EtherCATDriver(plc, from_dict(SEGMENT), backend="sim")
    return plc, drv, drv.segment.slaves[0].device


def until(plc, cond, limit=20000):
    for n in range(1, limit + 1):
        plc.scan()
        if cond():
            return n
    raise AssertionError("condition never became true")


def enabled(plc):
    until(plc, lambda: plc["main.pw.Status"])
    plc.scan(20)  # settled


@pytest.mark.parametrize(("relative", "pos", "expected"), [(False, 1000.0, 1000.0), (True, 1000.0, 1000.0)])
def test_set_position_moves_the_coordinate_not_the_motor(relative, pos, expected):
    plc, drv, d1 = make()
    enabled(plc)
    before_target, before_pos = d1.od[0x607A], d1.position
    plc["main.rel"], plc["main.pos"] = relative, pos
    plc["main.set"] = True
    targets = []
    for _ in range(50):
        plc.scan()
        targets.append(d1.od[0x607A])
    ax = axis_of(plc, "main.a1")
    assert plc["main.sp.Done"] and not plc["main.sp.Error"]
    assert set(targets) == {before_target} and d1.position == before_pos  # no jump, no motion
    assert abs(ax.act_pos - expected) < 1e-6 and abs(ax.set_pos - expected) < 1e-6
    # a move to 1090 in the new coordinates turns the motor by 90°
    plc["main.go"] = True
    until(plc, lambda: plc["main.mv.Done"])
    plc.scan(100)
    assert abs(d1.position - (before_pos + CPR // 4)) <= 64
    assert abs(ax.act_pos - 1090.0) < 0.003


def test_home_at_the_current_position_does_not_move_the_motor():
    plc, drv, d1 = make()
    enabled(plc)
    before_target = d1.od[0x607A]
    plc["main.pos"] = -250.0
    plc["main.home"] = True
    targets = []
    for _ in range(30):
        plc.scan()
        targets.append(d1.od[0x607A])
    assert plc["main.hm.Done"]
    assert set(targets) == {before_target}
    assert abs(axis_of(plc, "main.a1").act_pos - -250.0) < 1e-6


def test_set_position_queued_waits_for_the_move_and_immediate_is_refused_in_motion():
    plc, drv, d1 = make()
    enabled(plc)
    start = d1.position
    plc["main.target"] = 90.0
    plc["main.go"] = True
    plc.scan(100)  # moving
    plc["main.mode"] = "mcQueued"
    plc["main.set"] = True
    plc.scan()
    assert (plc["main.sp.Busy"], plc["main.sp.Done"], plc["main.mv.Busy"]) == (True, False, True)
    n = until(plc, lambda: plc["main.sp.Done"])
    ax = axis_of(plc, "main.a1")
    assert plc["main.mv.Done"] and ax.state == "Standstill" and n > 200  # after the move (0.35 s)
    plc.scan(100)
    assert abs(ax.act_pos - 1000.0) < 0.003 and abs(d1.position - (start + CPR // 4)) <= 64


def test_set_position_immediate_during_a_move_keeps_the_trajectory_when_configured_so():
    """CODESYS SM3's choice (set_position_in_motion = "keep_trajectory"): the drive gets what it
    would have got without the shift."""
    plc, drv, d1 = make(set_position_in_motion="keep_trajectory")
    enabled(plc)
    start = d1.position
    plc["main.target"], plc["main.go"] = 90.0, True
    plc.scan(150)  # moving
    targets = [d1.od[0x607A]]
    plc["main.rel"], plc["main.pos"], plc["main.set"] = True, 1000.0, True
    for _ in range(400):
        plc.scan()
        targets.append(d1.od[0x607A])
    ax = axis_of(plc, "main.a1")
    assert plc["main.sp.Done"] and plc["main.mv.Done"] and not plc["main.mv.Error"]
    step = 360.0 / 360.0 * CPR / 1000  # at most 360°/s: increments per cycle
    assert max(abs(b - a) for a, b in zip(targets, targets[1:])) <= step * 1.01  # no jump
    plc.scan(100)
    # the move ends where it would have: 90° of motor turn, 1090 in the shifted coordinates
    assert abs(d1.position - (start + CPR // 4)) <= 64 and abs(ax.act_pos - 1090.0) < 0.003


def test_set_position_immediate_during_a_move_keeps_its_commanded_position_in_the_new_coordinates():
    """PLCopen (the default): the absolute move still goes to 90, now in the shifted coordinates;
    the drive's target does not jump, the rest of the move is planned from where the axis is."""
    plc, drv, d1 = make()
    enabled(plc)
    start = d1.position
    plc["main.target"], plc["main.go"] = 90.0, True
    plc.scan(150)  # moving
    targets = [d1.od[0x607A]]
    plc["main.rel"], plc["main.pos"], plc["main.set"] = True, 30.0, True
    for _ in range(400):
        plc.scan()
        targets.append(d1.od[0x607A])
    ax = axis_of(plc, "main.a1")
    assert plc["main.sp.Done"] and plc["main.mv.Done"] and not plc["main.mv.Error"]
    step = 360.0 / 360.0 * CPR / 1000
    assert max(abs(b - a) for a, b in zip(targets, targets[1:])) <= step * 1.01  # no jump
    plc.scan(100)
    # at 90 in the new coordinates: the motor turned 30° less than 90°
    assert abs(ax.act_pos - 90.0) < 0.003 and abs(d1.position - (start + CPR // 6)) <= 64


def test_set_position_is_refused_in_errorstop():
    plc, drv, d1 = make()
    enabled(plc)
    d1.inject_fault(0x7500)
    plc.scan(3)
    plc["main.set"] = True
    plc.scan()
    assert (plc["main.sp.Error"], plc["main.sp.ErrorID"]) == (True, E.INVALID_STATE)


RESET_PROGRAM = PROGRAM.replace(
    "    mv : MC_MoveAbsolute;", "    mv : MC_MoveAbsolute;\n    rst : MC_Reset; reset : BOOL;"
).replace("  pw(Axis := a1, Enable := en);", "  pw(Axis := a1, Enable := en);\n  rst(Axis := a1, Execute := reset);")
_RESET = None


def make_reset(**axis_cfg):
    global _RESET
    if _RESET is None:
        _RESET = compile_text(RESET_PROGRAM, "reset.st")
    plc = PLC(_RESET)
    configure_axes(plc, {1: {"following_error_window": 5.0, **axis_cfg}})
    drv = EtherCATDriver(plc, from_dict(SEGMENT), backend="sim")
    return plc, drv, drv.segment.slaves[0].device


def test_reset_sends_the_fault_reset_edge_at_once_and_is_busy_until_the_drive_left_fault():
    plc, drv, d1 = make_reset()
    enabled(plc)
    d1.inject_fault(0x7500)
    until(plc, lambda: axis_of(plc, "main.a1").state == "ErrorStop", 5)
    plc.scan(3)
    link = drv.links[0]
    sent = [link.out_values[link.i_cw]]
    plc["main.reset"] = True
    plc.scan()
    sent.append(link.out_values[link.i_cw])
    assert sent == [0x00, 0x80]  # the edge goes out with the frame of the Execute cycle
    assert (plc["main.rst.Busy"], plc["main.rst.Done"]) == (True, False)
    assert axis_of(plc, "main.a1").state == "ErrorStop"  # until the drive has left Fault
    n = until(plc, lambda: plc["main.rst.Done"], 50)
    ax = axis_of(plc, "main.a1")
    assert ax.state in ("Disabled", "Standstill") and not plc["main.rst.Busy"] and n >= 2
    until(plc, lambda: ax.state == "Standstill", 100)  # MC_Power brings the power stage back


def test_reset_of_a_drive_that_stays_in_fault_fails_after_the_reset_timeout():
    plc, drv, d1 = make_reset(reset_timeout=0.05)
    enabled(plc)
    d1.inject_fault(0x7500, persistent=True)
    until(plc, lambda: axis_of(plc, "main.a1").state == "ErrorStop", 5)
    link = drv.links[0]
    plc["main.reset"] = True
    plc.scan(10)
    assert (plc["main.rst.Busy"], link.out_values[link.i_cw]) == (True, 0x80)  # bit 7 held up
    n = 10 + until(plc, lambda: plc["main.rst.Error"], 200)
    # 50 ms run out in the kernel step of cycle 50; the block reports it at its next call
    assert n == 51 and plc["main.rst.ErrorID"] == E.RESET_FAILED
    assert axis_of(plc, "main.a1").state == "ErrorStop" and link.out_values[link.i_cw] == 0x00  # bit 7 down


REFS_PROGRAM = """
PROGRAM main
  VAR
    a1 : AXIS_REF := (AxisNo := 1);
    again : AXIS_REF := (AxisNo := 1);
    typo : AXIS_REF := (AxisNo := 3);
    pw : MC_Power; pw3 : MC_Power; rd3 : MC_ReadActualPosition; mv3 : MC_MoveAbsolute; st_again : MC_ReadStatus;
  END_VAR
  pw(Axis := a1, Enable := TRUE);
  st_again(Axis := again, Enable := TRUE);
  pw3(Axis := typo, Enable := TRUE);
  rd3(Axis := typo, Enable := TRUE);
  mv3(Axis := typo, Execute := TRUE, Position := 1.0, Velocity := 1.0, Acceleration := 1.0, Deceleration := 1.0);
END_PROGRAM
"""


def test_an_axis_ref_naming_no_configured_axis_is_invalid_and_one_axis_no_is_one_axis():
    plc = PLC(compile_text(REFS_PROGRAM, "refs.st", use_cache=False))
    configure_axes(plc, {1: {}})
    plc.scan(3)
    assert (plc["main.pw.Status"], plc["main.st_again.Standstill"]) == (True, True)  # the same axis 1
    assert axis_of(plc, "main.again") is axis_of(plc, "main.a1")
    for fb, on in (("pw3", "Status"), ("rd3", "Valid"), ("mv3", "Busy")):
        assert (plc[f"main.{fb}.Error"], plc[f"main.{fb}.ErrorID"], plc[f"main.{fb}.{on}"]) == (
            True,
            E.INVALID_AXIS_REF,
            False,
        )


def test_a_following_error_reported_by_the_drive_is_a_following_error():
    plc, drv, d1 = make(following_error_window=1e9)  # the axis's own check never fires
    enabled(plc)
    d1.od[0x6065] = 100  # the drive's following error window: 100 increments
    d1.motor.max_speed = 1.0  # the motor cannot follow
    plc["main.target"], plc["main.go"] = 10000.0, True
    until(plc, lambda: axis_of(plc, "main.a1").state == "ErrorStop", 2000)
    ax = axis_of(plc, "main.a1")
    assert ax.axis_error == E.FOLLOWING_ERROR and drv.links[0].error_code == 0x8611
    plc.scan()
    assert (plc["main.mv.Error"], plc["main.mv.ErrorID"]) == (True, E.AXIS_ERRORSTOP)


STOP_PROGRAM = RESET_PROGRAM.replace(
    "    rst : MC_Reset; reset : BOOL;", "    rst : MC_Reset; reset : BOOL; stp : MC_Stop; stop : BOOL;"
).replace(
    "  rst(Axis := a1, Execute := reset);",
    "  rst(Axis := a1, Execute := reset);\n  stp(Axis := a1, Execute := stop, Deceleration := 3600.0);",
)
_STOP = None


def make_stop():
    global _STOP
    if _STOP is None:
        _STOP = compile_text(STOP_PROGRAM, "stop.st")
    plc = PLC(_STOP)
    configure_axes(plc, {1: {"following_error_window": 5.0}})
    drv = EtherCATDriver(plc, from_dict(SEGMENT), backend="sim")
    return plc, drv, drv.segment.slaves[0].device


def held_stop(plc):
    enabled(plc)
    plc["main.stop"] = True
    until(plc, lambda: plc["main.stp.Done"], 100)
    plc.scan(5)
    assert plc["main.stp.Done"] and axis_of(plc, "main.a1").state == "Stopping"  # held: Execute stays TRUE


def test_a_held_stop_ends_with_command_aborted_when_the_axis_is_powered_off():
    plc, drv, d1 = make_stop()
    held_stop(plc)
    plc["main.en"] = False
    plc.scan()
    assert (plc["main.stp.Done"], plc["main.stp.CommandAborted"], plc["main.stp.Error"]) == (False, True, False)


def test_a_held_stop_ends_with_error_when_the_axis_goes_to_errorstop():
    plc, drv, d1 = make_stop()
    held_stop(plc)
    d1.inject_fault(0x7500)
    plc.scan(3)
    assert (plc["main.stp.Done"], plc["main.stp.Error"], plc["main.stp.ErrorID"]) == (False, True, E.AXIS_ERRORSTOP)


def test_power_status_follows_the_drives_statusword_not_the_enable_request():
    plc, drv, d1 = make_stop()
    statuses, enabled_in_drive = [], []
    for _ in range(40):
        plc.scan()
        statuses.append(plc["main.pw.Status"])
        enabled_in_drive.append(drv.links[0].enabled)
    # the block sees the statusword of the exchange at the end of the scan before
    assert statuses[1:] == enabled_in_drive[:-1] and statuses[-1] and not statuses[0]
    plc["main.en"] = False
    statuses, enabled_in_drive = [], []
    for _ in range(10):
        plc.scan()
        statuses.append(plc["main.pw.Status"])
        enabled_in_drive.append(drv.links[0].enabled)
    # TRUE until the drive reports it left Operation Enabled, a few cycles after Enable fell
    assert statuses[1:] == enabled_in_drive[:-1] and statuses[:2] == [True, True] and not statuses[-1]


@pytest.mark.parametrize(
    ("name", "value", "code"), [("acc", -1.0, E.INVALID_ACCELERATION), ("vel", 0.0, E.INVALID_VELOCITY)]
)
def test_an_invalid_continuous_update_ends_the_move_with_error_and_the_axis_halts(name, value, code):
    plc, drv, d1 = make()
    enabled(plc)
    plc["main.cu"], plc["main.go"] = True, True
    plc.scan(100)
    plc[f"main.{name}"] = value
    plc.scan()
    ax = axis_of(plc, "main.a1")
    assert (plc["main.mv.Error"], plc["main.mv.ErrorID"], plc["main.mv.Busy"]) == (True, code, False)
    assert ax.state == "DiscreteMotion" and ax.set_vel > 0  # halting with the last valid deceleration
    until(plc, lambda: ax.state == "Standstill", 200)
    assert ax.set_vel == 0.0 and ax.set_pos < 1090.0


def test_an_invalid_continuous_update_hands_over_to_the_buffered_successor():
    plc, drv, d1 = make()
    enabled(plc)
    plc["main.cu"], plc["main.go"] = True, True
    plc.scan(100)
    plc["main.next"] = True
    plc.scan()
    assert plc["main.mr.Busy"] and not plc["main.mr.Active"]  # buffered behind the move
    plc["main.acc"] = 0.0
    plc.scan(2)
    assert (plc["main.mv.ErrorID"], plc["main.mr.Active"]) == (E.INVALID_ACCELERATION, True)  # it starts now
    start = plc["main.mr.Active"] and axis_of(plc, "main.a1").set_pos
    until(plc, lambda: plc["main.mr.Done"], 2000)
    assert abs(axis_of(plc, "main.a1").set_pos - (start + 10.0)) < 1.0


def test_safe_torque_off_is_a_loss_of_the_power_stage_and_blocks_enabling_until_released():
    plc, drv, d1 = make_reset()
    enabled(plc)
    d1.safe_torque_off()
    plc.scan(2)
    view = plc.axis("main.a1")
    assert (view.state, view.axis_error, view.drive_state) == ("ErrorStop", E.POWER_STAGE_LOST, "SWITCH_ON_DISABLED")
    assert view.drive_error == 0  # no drive fault: the safety circuit
    plc["main.reset"] = True
    plc.scan(50)
    assert not plc["main.pw.Status"] and plc.axis(1).state == "Disabled"  # reset, but STO still cuts power
    d1.safe_torque_off(False)
    until(plc, lambda: plc["main.pw.Status"], 100)
    assert plc.axis("axis1").state == "Standstill"  # the configured name


def test_the_axis_view_is_what_the_read_blocks_saw_in_the_same_scan():
    plc = PLC(compile_text(VIEW_PROGRAM, "view.st", use_cache=False))
    configure_axes(plc, {1: {"name": "x"}})
    drv = EtherCATDriver(plc, SEGMENT, backend="sim")  # a segment from a dict
    for n in range(60):
        plc.scan()
        if n == 30:
            plc["main.go"] = True
        v = plc.axis("x")
        assert (v.state == "Standstill", v.state == "DiscreteMotion") == (
            plc["main.rs.Standstill"],
            plc["main.rs.DiscreteMotion"],
        )
        assert v.actual_position == plc["main.rp.Position"] and v.readable == plc["main.rp.Valid"]
    assert plc.axis("x").state == "DiscreteMotion" and drv.links[0].axis is axis_of(plc, "main.a1")


VIEW_PROGRAM = """
PROGRAM main
  VAR
    a1 : AXIS_REF := (AxisNo := 1);
    pw : MC_Power; mv : MC_MoveAbsolute; rs : MC_ReadStatus; rp : MC_ReadActualPosition; go : BOOL;
  END_VAR
  pw(Axis := a1, Enable := TRUE);
  mv(Axis := a1, Execute := go, Position := 90.0, Velocity := 90.0, Acceleration := 900.0, Deceleration := 900.0);
  rs(Axis := a1, Enable := TRUE);
  rp(Axis := a1, Enable := TRUE);
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#1ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""


def test_configure_axes_names_an_unknown_setting_as_the_toml_file_does():
    plc = PLC(compile_text(VIEW_PROGRAM, "view.st", use_cache=False))
    with pytest.raises(ValueError) as info:
        configure_axes(plc, {1: {"max_velocty": 5.0}})
    assert str(info.value).startswith("configure_axes: axis 1: unknown setting 'max_velocty' (known: buffer_size, ")


IDEAL = {
    "segment": {"cycle": "1ms", "dc": False},
    "slave": [{"name": "d1", "type": "cia402", "axis": 1, "ideal": True}],
}


def test_an_ideal_drive_follows_each_controlword_and_the_target_in_the_next_exchange():
    plc = PLC(compile_text(VIEW_PROGRAM, "view.st", use_cache=False))
    configure_axes(plc, {1: {"name": "x"}})
    drv = EtherCATDriver(plc, IDEAL, backend="sim")
    link, seen = drv.links[0], []
    for _ in range(6):
        plc.scan()
        seen.append((link.out_values[link.i_cw], link.state))
    # every controlword is answered by the frame of the next cycle (which the link, deciding
    # before it reads that frame, still sends the same controword in)
    assert seen == [
        (0x06, "SWITCH_ON_DISABLED"),
        (0x06, "READY_TO_SWITCH_ON"),
        (0x07, "READY_TO_SWITCH_ON"),
        (0x07, "SWITCHED_ON"),
        (0x0F, "SWITCHED_ON"),
        (0x0F, "OPERATION_ENABLED"),
    ]
    plc["main.go"] = True
    ax = axis_of(plc, "main.a1")
    sets = []
    for _ in range(1200):
        sets.append(ax.set_pos)
        plc.scan()
        assert ax.act_pos == pytest.approx(sets[-1], abs=360 / CPR)  # the previous set position, to an increment
    assert plc["main.mv.Done"] and ax.act_pos == pytest.approx(90.0, abs=360 / CPR)


BAD_ENUMS = """
PROGRAM main
  VAR
    a1 : AXIS_REF;
    pw : MC_Power; mv : MC_MoveAbsolute; mv2 : MC_MoveAbsolute;
    dir : MC_DIRECTION; mode : MC_BUFFER_MODE;
  END_VAR
  dir := 7;    (* CODESYS: an integer into an enumeration without {attribute 'strict'} *)
  mode := 9;
  pw(Axis := a1, Enable := TRUE);
  mv(Axis := a1, Execute := pw.Status, Position := 1.0, Velocity := 1.0, Acceleration := 1.0, Deceleration := 1.0,
     Direction := dir);
  mv2(Axis := a1, Execute := pw.Status, Position := 1.0, Velocity := 1.0, Acceleration := 1.0, Deceleration := 1.0,
      BufferMode := mode);
END_PROGRAM
"""


def test_an_enumeration_input_out_of_its_values_is_invalid_direction_or_buffer_mode():
    plc = PLC(compile_text(BAD_ENUMS, "bad.st", dialect="codesys", use_cache=False))
    plc.scan(3)
    assert (plc["main.mv.Error"], plc["main.mv.ErrorID"]) == (True, E.INVALID_DIRECTION)
    assert (plc["main.mv2.Error"], plc["main.mv2.ErrorID"]) == (True, E.INVALID_BUFFER_MODE)


def test_homing_on_a_switch_shifts_the_coordinate_at_the_end_without_a_jump_in_the_drive_target():
    plc, drv, d1 = make(homing="switch", home_switch="main.rel", home_direction=1, home_velocity=90.0,
                        home_acceleration=900.0)  # fmt: skip
    enabled(plc)
    plc["main.pos"], plc["main.home"] = 0.0, True
    targets, latched_at = [], None
    for n in range(600):
        plc.scan()
        targets.append(d1.od[0x607A])
        if n == 200:
            plc["main.rel"] = True  # the reference switch (a BOOL of the program) comes on
            latched_at = axis_of(plc, "main.a1").act_pos
        if plc["main.hm.Done"]:
            break
    ax = axis_of(plc, "main.a1")
    assert plc["main.hm.Done"] and ax.state == "Standstill"
    step = 90.0 / 360.0 * CPR / 1000  # increments per cycle at the homing velocity
    assert max(abs(b - a) for a, b in zip(targets, targets[1:])) <= step * 1.01  # no jump at the shift
    # the switch edge is now at Position 0: the axis stands its braking distance past it
    assert 0.0 < ax.act_pos < 5.0 and latched_at > 0.0
