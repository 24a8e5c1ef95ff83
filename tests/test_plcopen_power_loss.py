"""PLCopen on a CiA 402 drive when the power stage or the link is lost, cycle by cycle on the
emulated drive (issue 31): the controller never switches a drive on again by itself (only MC_Reset
leaves ErrorStop, EN 60204-1 "unexpected start-up"), the axis's state and errors stay readable
through a communication outage, and MC_Reset ends in the scan whose inputs show the drive out of
Fault. Scan k sees the inputs of the exchange at the end of scan k - 1."""

from __future__ import annotations

from st import PLC
from st.api import compile_text
from st.io.ethercat import EtherCATDriver
from st.io.ethercat.config import from_dict
from st.io.ethercat.devices import State
from st.stdlib.plcopen import E, axis_of, configure_axes

PROGRAM = """
PROGRAM main
  VAR
    a1 : AXIS_REF := (AxisNo := 1);
    pw : MC_Power; rst : MC_Reset; rs : MC_ReadStatus; re : MC_ReadAxisError;
    rp : MC_ReadActualPosition; rv : MC_ReadActualVelocity;
    en : BOOL := TRUE; reset : BOOL;
  END_VAR
  pw(Axis := a1, Enable := en);
  rst(Axis := a1, Execute := reset);
  rs(Axis := a1, Enable := TRUE);
  re(Axis := a1, Enable := TRUE);
  rp(Axis := a1, Enable := TRUE);
  rv(Axis := a1, Enable := TRUE);
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#1ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""
SEGMENT = {
    "segment": {"cycle": "1ms", "dc": True, "lost_frame_limit": 3},
    "slave": [{"name": "d1", "type": "cia402", "axis": 1}],
}
ENABLE_BITS = 0x0F  # what a controlword needs to switch a drive on (Switch On 0x07, Enable Operation 0x0F)
_COMPILED = None


def make():
    global _COMPILED
    if _COMPILED is None:
        _COMPILED = compile_text(PROGRAM, "power_loss.st")
    plc = PLC(_COMPILED)
    configure_axes(plc, {1: {"following_error_window": 5.0}})
    drv = EtherCATDriver(plc, from_dict(SEGMENT), backend="sim")
    return plc, drv, drv.segment.slaves[0].device


def until(plc, cond, limit=20000):
    for n in range(1, limit + 1):
        plc.scan()
        if cond():
            return n
    raise AssertionError("condition never became true")


def enabled():
    plc, drv, d1 = make()
    until(plc, lambda: plc["main.pw.Status"])
    plc.scan(20)
    assert plc["main.rs.Standstill"]
    return plc, drv, d1


def controlword(drv) -> int:
    link = drv.links[0]
    return link.out_values[link.i_cw]


def scan_recording(plc, drv, n):
    """n scans: per scan (controlword sent, drive state read, MC_Power.Status, axis state)."""
    rows = []
    for _ in range(n):
        plc.scan()
        rows.append((controlword(drv), drv.links[0].state, plc["main.pw.Status"], plc.axis("main.a1").state))
    return rows


def never_switched_on(rows) -> bool:
    return all(cw & ENABLE_BITS in (0x00,) and st != "OPERATION_ENABLED" and not status for cw, st, status, _ in rows)


def test_after_safe_torque_off_the_drive_stays_off_until_reset_even_once_sto_is_released():
    plc, drv, d1 = enabled()
    d1.safe_torque_off()
    plc.scan()  # the exchange at its end reads Switch On Disabled
    rows = scan_recording(plc, drv, 100)
    assert never_switched_on(rows) and {r[3] for r in rows} == {"ErrorStop"}
    assert (plc["main.re.AxisErrorID"], plc["main.re.StAxisErrorID"]) == (E.POWER_STAGE_LOST, E.POWER_STAGE_LOST)
    d1.safe_torque_off(False)  # the safety circuit closes again: still nothing switches on
    rows = scan_recording(plc, drv, 300)
    assert never_switched_on(rows) and {r[3] for r in rows} == {"ErrorStop"}
    assert d1.state == State.SWITCH_ON_DISABLED
    plc["main.reset"] = True
    plc.scan()
    # MC_Reset leaves ErrorStop at once (the drive is not in Fault): Disabled, AxisErrorID 0
    assert (plc["main.rst.Done"], plc["main.rs.Disabled"], plc["main.re.AxisErrorID"]) == (True, True, 0)
    assert controlword(drv) == 0x00  # MC_Power (called before MC_Reset) saw ErrorStop in this scan
    plc.scan()
    assert controlword(drv) == 0x06  # Enable still TRUE: the enable sequence starts in the next scan
    n = until(plc, lambda: drv.links[0].state == "OPERATION_ENABLED", 50)
    assert not plc["main.pw.Status"] and plc["main.rs.Disabled"]  # read in this scan's exchange
    plc.scan()
    assert plc["main.pw.Status"] and plc["main.rs.Standstill"] and n > 3


def test_a_drive_that_drops_out_of_operation_enabled_is_not_switched_on_again():
    """No safety circuit holds it off: the old code's enable sequence brought it back within a few
    cycles while the axis sat in ErrorStop with MC_Power.Status TRUE."""
    plc, drv, d1 = enabled()
    d1._set_state(State.SWITCH_ON_DISABLED)  # the drive switches itself off
    d1._publish()
    plc.scan()
    rows = scan_recording(plc, drv, 500)
    assert never_switched_on(rows) and {r[3] for r in rows} == {"ErrorStop"}
    assert plc.axis("main.a1").axis_error == E.POWER_STAGE_LOST
    # an Enable edge is not a reset either
    plc["main.en"] = False
    rows = scan_recording(plc, drv, 5)
    plc["main.en"] = True
    rows += scan_recording(plc, drv, 100)
    assert never_switched_on(rows) and {r[3] for r in rows} == {"ErrorStop"}
    plc["main.reset"] = True
    n = until(plc, lambda: plc["main.rs.Standstill"], 50)
    assert plc["main.pw.Status"] and drv.links[0].state == "OPERATION_ENABLED" and n > 3


def test_reset_with_enable_false_leaves_the_drive_off_until_enable_comes_back():
    plc, drv, d1 = enabled()
    d1.safe_torque_off()
    plc.scan(3)
    d1.safe_torque_off(False)
    plc["main.en"] = False
    plc["main.reset"] = True
    rows = scan_recording(plc, drv, 200)
    assert never_switched_on(rows) and rows[-1][3] == "Disabled" and plc["main.rst.Done"]
    plc["main.en"] = True
    until(plc, lambda: plc["main.rs.Standstill"], 50)
    assert plc["main.pw.Status"]


def test_reset_after_a_drive_fault_is_done_in_the_scan_whose_inputs_show_the_drive_out_of_fault():
    plc, drv, d1 = enabled()
    d1.inject_fault(0x7500)
    plc.scan(5)
    assert (plc["main.rs.ErrorStop"], plc["main.re.AxisErrorID"]) == (True, 0x7500)
    plc["main.reset"] = True
    read_sod = None
    for k in range(1, 20):
        plc.scan()
        if read_sod is None:
            # until the drive is read out of Fault: Busy, ErrorStop, the drive's code
            assert (plc["main.rst.Busy"], plc["main.rs.ErrorStop"], plc["main.re.AxisErrorID"]) == (True, True, 0x7500)
            assert controlword(drv) == 0x80  # the fault reset bit, held
            if drv.links[0].state == "SWITCH_ON_DISABLED":
                read_sod = k
        elif k == read_sod + 1:
            # the first scan whose inputs show Switch On Disabled: Done, Disabled, no error
            assert (plc["main.rst.Done"], plc["main.rst.Busy"]) == (True, False)
            assert (plc["main.rs.Disabled"], plc["main.rs.ErrorStop"]) == (True, False)
            assert (plc["main.re.AxisErrorID"], plc["main.re.StAxisErrorID"]) == (0, 0)
            break
    assert read_sod == 3  # the emulated drive leaves Fault in the third exchange after the edge
    plc.scan()
    assert controlword(drv) == 0x06  # then MC_Power, with Enable TRUE, switches it on again


def test_an_outage_keeps_the_axis_state_and_error_readable_and_the_drive_values_invalid():
    plc, drv, d1 = enabled()
    drv.segment.drop_frames(150)  # 150 ms: longer than the drive's SyncManager watchdog
    for _ in range(3):  # up to lost_frame_limit lost frames: the last values, Valid
        plc.scan()
        assert (plc["main.rs.Standstill"], plc["main.rp.Valid"], plc["main.rv.Valid"]) == (True, True, True)
    assert drv.outage  # the third lost frame in a row, in the exchange of the third scan
    for _ in range(100):
        plc.scan()
        # the controller's own knowledge: valid, ErrorStop, COMMUNICATION_LOST
        assert (plc["main.rs.Valid"], plc["main.rs.Error"], plc["main.rs.ErrorStop"]) == (True, False, True)
        assert (plc["main.re.Valid"], plc["main.re.AxisErrorID"], plc["main.re.StAxisErrorID"]) == (
            True,
            E.COMMUNICATION_LOST,
            E.COMMUNICATION_LOST,
        )
        # what only the drive knows: not valid
        for fb in ("rp", "rv"):
            assert (plc[f"main.{fb}.Valid"], plc[f"main.{fb}.Error"], plc[f"main.{fb}.ErrorID"]) == (
                False,
                True,
                E.COMMUNICATION_LOST,
            )
        assert not plc["main.pw.Status"] and controlword(drv) == 0x00
    n = until(plc, lambda: not drv.outage, 100)
    assert drv.stats()["recoveries"] == 1 and 40 <= n <= 60  # 150 ms lost, then back to OP
    plc.scan()
    # the drive values come back in the next scan, without an Enable edge; the axis stays in
    # ErrorStop, and a drive that kept its power stage on through the outage is switched off
    assert (plc["main.rp.Valid"], plc["main.rv.Valid"], plc["main.rs.ErrorStop"]) == (True, True, True)
    rows = scan_recording(plc, drv, 5)
    assert {r[0] for r in rows} == {0x00} and rows[-1][1] == "SWITCH_ON_DISABLED"
    rows = scan_recording(plc, drv, 300)
    assert never_switched_on(rows) and {r[3] for r in rows} == {"ErrorStop"}
    plc["main.reset"] = True
    until(plc, lambda: plc["main.rs.Standstill"], 50)
    assert plc["main.pw.Status"] and plc["main.re.AxisErrorID"] == 0


def test_a_drive_fault_during_an_outage_shows_st_s_code_until_the_drive_can_be_read_again():
    plc, drv, d1 = enabled()
    d1.inject_fault(0x7500, persistent=True)
    plc.scan(3)
    assert (plc["main.re.AxisErrorID"], plc["main.re.StAxisErrorID"]) == (0x7500, E.DRIVE_FAULT)
    drv.segment.drop_frames(20)
    plc.scan(4)
    # the drive's 0x603F is not known now; the axis error (DRIVE_FAULT, the first cause) is
    assert (plc["main.re.Valid"], plc["main.re.AxisErrorID"], plc["main.re.StAxisErrorID"]) == (
        True,
        E.DRIVE_FAULT,
        E.DRIVE_FAULT,
    )
    until(plc, lambda: not drv.outage, 100)
    plc.scan()
    assert (plc["main.re.AxisErrorID"], plc["main.re.StAxisErrorID"]) == (0x7500, E.DRIVE_FAULT)
    assert axis_of(plc, "main.a1").state == "ErrorStop"
