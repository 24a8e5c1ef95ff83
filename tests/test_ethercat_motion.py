"""EtherCAT bound to the scan: CiA 402 drives moving PLCopen axes through the `sim` backend — the
enable sequence, CSP setpoints, faults and recovery, lost frames, I/O bindings, the gantry
example, delay compensation, and `st run --ethercat`."""

import json
import os
import subprocess
import sys

import pytest

from st import PLC
from st.api import compile_text
from st.io.ethercat import EtherCATDriver, MasterError, load_segment
from st.io.ethercat.config import ConfigError, from_dict
from st.io.ethercat.devices import State
from st.stdlib.plcopen import E, axis_of, configure_axes

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

PROGRAM = """
PROGRAM main
  VAR
    a1 : AXIS_REF := (AxisNo := 1);
    a2 : AXIS_REF := (AxisNo := 2);
    pw1 : MC_Power; pw2 : MC_Power;
    mv1 : MC_MoveAbsolute; mv2 : MC_MoveAbsolute;
    vel1 : MC_MoveVelocity; vel2 : MC_MoveVelocity;
    rst1 : MC_Reset;
    st1 : MC_ReadStatus;
    err1 : MC_ReadAxisError;
    en : BOOL := TRUE;
    go : BOOL; spin : BOOL; reset : BOOL;
    target : LREAL := 90.0;
    speed : LREAL := 360.0;
    button AT %IX0.0 : BOOL;
    lamp AT %QX0.1 : BOOL;
    seen_button : BOOL;
  END_VAR
  pw1(Axis := a1, Enable := en);
  pw2(Axis := a2, Enable := en);
  mv1(Axis := a1, Execute := go, Position := target, Velocity := 360.0, Acceleration := 3600.0, Deceleration := 3600.0);
  mv2(Axis := a2, Execute := go, Position := target, Velocity := 360.0, Acceleration := 3600.0, Deceleration := 3600.0);
  vel1(Axis := a1, Execute := spin, Velocity := speed, Acceleration := 3600.0, Deceleration := 3600.0);
  vel2(Axis := a2, Execute := spin, Velocity := speed, Acceleration := 3600.0, Deceleration := 3600.0);
  rst1(Axis := a1, Execute := reset);
  st1(Axis := a1, Enable := TRUE);
  err1(Axis := a1, Enable := TRUE);
  seen_button := button;
  lamp := mv1.Busy;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#1ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""
_COMPILED = None

SEGMENT = {
    "segment": {"cycle": "1ms", "dc": True, "lost_frame_limit": 3},
    "slave": [
        {"name": "d1", "type": "cia402", "axis": 1},
        {"name": "d2", "type": "cia402", "axis": 2},
        {"name": "io", "type": "dio", "inputs_at": "%IX0.0", "outputs_at": "%QX0.0"},
    ],
}


def make(segment=None, **axis_cfg):
    global _COMPILED
    if _COMPILED is None:
        _COMPILED = compile_text(PROGRAM, "ecat_motion.st")
    plc = PLC(_COMPILED)
    configure_axes(plc, {1: {"following_error_window": 5.0, **axis_cfg}, 2: {"following_error_window": 5.0}})
    drv = EtherCATDriver(plc, from_dict(segment or SEGMENT), backend="sim")
    return plc, drv


def drive(drv, i):
    return drv.segment.slaves[i].device


def until(plc, cond, limit=20000):
    for n in range(1, limit + 1):
        plc.scan()
        if cond():
            return n
    raise AssertionError("condition never became true")


def test_enable_sequence_holds_the_target_at_the_actual_position():
    plc, drv = make()
    d1 = drive(drv, 0)
    seen = []
    orig = d1.on_outputs

    def record():
        seen.append((d1.od[0x6040], d1.od[0x607A], d1.position))
        orig()

    d1.on_outputs = record
    n = until(plc, lambda: plc["main.pw1.Status"])
    cws = [c for c, _, _ in seen]
    # 0x06 → 0x07 → 0x0F, each sent until the statusword shows the state it asks for
    assert [cws[0], cws[cws.index(0x07)], cws[-1]] == [0x06, 0x07, 0x0F] and sorted(set(cws)) == [0x06, 0x07, 0x0F]
    assert all(target == pos for _, target, pos in seen)  # never a jump on enabling
    # the first SYNC0 pulse comes 10 cycles after DC start-up; then each command takes effect at the
    # next pulse and its state is read back in the frame after
    assert n == 19 and axis_of(plc, "main.a1").state == "Standstill"
    assert d1.state == State.OPERATION_ENABLED


def test_two_axes_move_through_the_drives_and_arrive_together():
    plc, drv = make()
    until(plc, lambda: plc["main.pw1.Status"] and plc["main.pw2.Status"])
    plc["main.go"] = True
    n = until(plc, lambda: plc["main.mv1.Done"] and plc["main.mv2.Done"])
    assert n == 351  # 90° at 360°/s with 3600°/s²: 0.35 s, + the exchange
    a1, a2 = axis_of(plc, "main.a1"), axis_of(plc, "main.a2")
    assert a1.set_pos == 90.0 and a2.set_pos == 90.0
    plc.scan(100)  # the drives settle on the last setpoint
    cpr = 1 << 23
    for i in (0, 1):
        assert abs(drive(drv, i).position - cpr // 4) <= 64  # within 0.003°
    assert abs(a1.act_pos - 90.0) < 0.003 and plc["main.lamp"] is False
    s = drv.stats()
    assert s["lost_frames"] == 0 and s["wkc_errors"] == 0 and s["frames"] == plc.scans + 2


def test_digital_terminal_bits_reach_located_variables():
    plc, drv = make()
    io = drive(drv, 2)
    io.set_input(0, True)
    plc.scan(3)
    assert plc["main.seen_button"] is True
    until(plc, lambda: plc["main.pw1.Status"])
    plc["main.go"] = True
    plc.scan(5)
    assert bool(io.outputs[1]) is True  # %QX0.1 = mv1.Busy


def test_a_drive_fault_stops_the_axis_and_reset_recovers_it():
    plc, drv = make()
    until(plc, lambda: plc["main.pw1.Status"])
    plc["main.spin"] = True
    plc.scan(200)
    drive(drv, 0).inject_fault(0x7500)
    n = until(plc, lambda: plc["main.st1.ErrorStop"])
    # AxisErrorID: the drive's own code (0x603F); StAxisErrorID: st's
    assert n <= 3 and (plc["main.err1.AxisErrorID"], plc["main.err1.StAxisErrorID"]) == (0x7500, E.DRIVE_FAULT)
    assert plc["main.vel1.Error"] and plc["main.vel1.ErrorID"] == E.AXIS_ERRORSTOP
    assert axis_of(plc, "main.a2").state == "ContinuousMotion"  # the other axis goes on
    plc["main.spin"] = False
    plc["main.reset"] = True
    n = until(plc, lambda: plc["main.st1.Standstill"])
    assert n < 20 and drive(drv, 0).state == State.OPERATION_ENABLED and plc["main.rst1.Done"]


def test_loss_of_operation_enabled_is_power_stage_lost():
    plc, drv = make()
    until(plc, lambda: plc["main.pw1.Status"])
    d = drive(drv, 0)
    d._set_state(State.SWITCH_ON_DISABLED)  # the drive drops its power stage on its own
    d._publish()
    until(plc, lambda: plc["main.st1.ErrorStop"], 5)
    assert plc["main.err1.AxisErrorID"] == E.POWER_STAGE_LOST


def test_lost_frames_put_the_axes_in_errorstop_and_the_segment_recovers():
    plc, drv = make()
    until(plc, lambda: plc["main.pw1.Status"] and plc["main.pw2.Status"])
    drv.segment.drop_frames(2)  # fewer than lost_frame_limit: tolerated
    plc.scan(5)
    assert axis_of(plc, "main.a1").state == "Standstill"
    assert drv.stats()["lost_frames"] == 2 and drv.stats()["outages"] == 0
    drv.segment.drop_frames(150)  # 150 ms: the drives' SyncManager watchdog fires too
    plc.scan(4)  # the third lost frame; the read blocks see it in the next scan
    assert axis_of(plc, "main.a1").state == "ErrorStop" and axis_of(plc, "main.a2").state == "ErrorStop"
    # the axis's state and error are the controller's: readable through the outage
    assert (plc["main.st1.Valid"], plc["main.st1.Error"], plc["main.st1.ErrorStop"]) == (True, False, True)
    assert (plc["main.err1.Valid"], plc["main.err1.AxisErrorID"]) == (True, E.COMMUNICATION_LOST)
    plc.scan(200)
    # back in OP: the axis error is still the lost communication, until MC_Reset
    assert (plc["main.st1.Valid"], plc["main.st1.ErrorStop"]) == (True, True)
    assert (plc["main.err1.AxisErrorID"], plc["main.err1.StAxisErrorID"]) == (
        E.COMMUNICATION_LOST,
        E.COMMUNICATION_LOST,
    )
    s = drv.stats()
    assert s["lost_frames"] == 152 and s["outages"] == 1 and s["recoveries"] == 1
    assert [x.state_name for x in drv.segment.slaves] == ["OP", "OP", "OP"]
    plc["main.reset"] = True
    until(plc, lambda: plc["main.st1.Standstill"], 50)
    plc["main.reset"] = False
    plc["main.go"] = True
    until(plc, lambda: plc["main.mv1.Done"], 1000)


def test_working_counter_errors_from_a_broken_cable_count_as_lost():
    plc, drv = make()
    until(plc, lambda: plc["main.pw2.Status"])
    drv.segment.break_after(0)
    plc.scan(4)
    s = drv.stats()
    assert s["wkc_errors"] == 4 and axis_of(plc, "main.a2").state == "ErrorStop"
    assert axis_of(plc, "main.a2").axis_error == E.COMMUNICATION_LOST
    drv.segment.break_after(None)
    plc.scan(5)
    assert drv.stats()["recoveries"] == 1


def _offset_after(compensate: bool) -> float:
    seg = {
        "segment": {"cycle": "1ms", "dc": False, "forwarding_delay_us": 200.0, "compensate_delay": compensate},
        "slave": [{"name": "d1", "type": "cia402", "axis": 1}, {"name": "d2", "type": "cia402", "axis": 2}],
    }
    plc, drv = make(seg)
    until(plc, lambda: plc["main.pw1.Status"] and plc["main.pw2.Status"])
    plc["main.spin"] = True
    plc.scan(500)  # both at 360°/s
    t = drv.segment.t + 0.0005
    drv.segment.advance(t)  # both drives at the same instant
    return (drive(drv, 0).position - drive(drv, 1).position) / (1 << 23) * 360.0


def test_delay_compensation_removes_the_offset_between_axes():
    plain, compensated = _offset_after(False), _offset_after(True)
    # drive 2 sees every setpoint 200 µs later: at 360°/s it trails by 0.072°
    assert plain == pytest.approx(0.072, abs=0.002)
    assert abs(compensated) < 0.002


def test_configuration_errors_name_the_file_and_the_slave(tmp_path):
    with pytest.raises(ConfigError, match=r"x.toml: slave 1 \(d\): type must be cia402, dio or esi"):
        from_dict({"slave": [{"name": "d", "type": "servo"}]}, "x.toml")
    with pytest.raises(ConfigError, match="axis 1 is bound to more than one drive"):
        from_dict({"slave": [{"name": "a", "axis": 1}, {"name": "b", "axis": 1}]}, "x.toml")
    with pytest.raises(ConfigError, match="'%QQ1' .* is not a located address"):
        from_dict({"slave": [{"name": "io", "type": "dio", "outputs_at": "%QQ1"}]}, "x.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[segment]\ncycle = \n")
    with pytest.raises(ConfigError, match=r"bad.toml: .*line 2"):
        load_segment(str(bad))
    with pytest.raises(MasterError, match="task 'slow' is not a task of the program"):
        make({"segment": {"task": "slow"}, "slave": [{"name": "a", "axis": 1}]})


@pytest.mark.slow
def test_gantry_program_runs_with_st_run(tmp_path):
    stats = tmp_path / "stats.json"
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "st",
            "run",
            "programs/gantry.st",
            "--ethercat",
            "programs/gantry.segment.toml",
            "--axes",
            "programs/gantry.axes.toml",
            "--virtual",
            "--duration",
            "3s",
            "--dump-json",
            "--stats-json",
            str(stats),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    v = json.loads(out.stdout)
    assert v["gantry.strokes"] == 3 and v["gantry.fault"] is False  # 200 mm strokes of 0.9 s
    assert v["gantry.max_offset"] < 0.01  # mm between the two sides
    io = json.loads(stats.read_text())["io"]["ethercat"]
    assert (
        io["lost_frames"] == 0
        and io["wkc_errors"] == 0
        and io["drives"] == {"axis1": "OPERATION_ENABLED", "axis2": "OPERATION_ENABLED"}
    )
    assert "ethercat: 3 slave(s) in OP (sim backend), 2 drive(s) bound" in out.stderr


def test_pdo_mapping_changed_in_preop_resizes_the_process_data():
    """The master remaps 0x1A00 over SDO in PREOP (adding torque actual 0x6077): the drive accepts
    it, the SyncManager and FMMU follow, and the new entry arrives in every frame."""
    import struct

    from st.io.ethercat.config import build_segment
    from st.io.ethercat.master import FrameMaster
    from st.io.ethercat.od import ABORT_NOT_MAPPABLE

    seg = build_segment(from_dict({"slave": [{"name": "d1", "type": "cia402"}]}))
    clock = [0.0]
    m = FrameMaster(
        lambda f: seg.exchange(f, clock[0]),
        pause=lambda s: clock.__setitem__(0, clock[0] + s),
        now_ns=lambda: int(clock[0] * 1e9),
    )
    m.scan()
    refused = []

    def remap(master):
        master.sdo_write(0, 0x1A00, 0, b"\0")
        master.sdo_write(0, 0x1A00, 5, struct.pack("<I", 0x60770010))
        master.sdo_write(0, 0x1A00, 0, b"\x05")
        with pytest.raises(Exception, match=f"{ABORT_NOT_MAPPABLE:#010x}"):
            master.sdo_write(0, 0x1A00, 6, struct.pack("<I", 0x10180120))  # the identity is not process data
        refused.append(True)

    m.configure(preop_hook=remap)
    assert refused == [True]
    assert (m.slaves[0].out_bytes, m.slaves[0].in_bytes) == (11, 14)
    assert [e.name for e in m.slaves[0].tx_layout.data_entries][-1] == "torque_actual"
    m.set_state("OP")
    assert m.exchange() == 3


def test_a_drive_layout_from_an_esi_file():
    seg_cfg = {
        "slave": [
            {
                "name": "xd",
                "type": "cia402",
                "axis": 1,
                "esi": "tests/data/esi/example_drive.xml",
                "product_code": 0x00D20001,
            }
        ]
    }
    from st.io.ethercat.config import build_devices

    [dev] = build_devices(from_dict(seg_cfg))
    assert (dev.vendor_id, dev.product_code) == (0xABC, 0x00D20001)
    assert (dev.rx_layout.size, dev.tx_layout.size) == (11, 12)
    plc, drv = make(
        {
            "slave": [
                {**seg_cfg["slave"][0], "esi": os.path.join(ROOT, "tests/data/esi/example_drive.xml")},
                {"name": "d2", "type": "cia402", "axis": 2},
            ]
        }
    )
    assert drv.master.slaves[0].vendor_id == 0xABC
    until(plc, lambda: plc["main.pw1.Status"])


def test_a_segment_that_cannot_start_leaves_its_master_and_capture_closed(monkeypatch, tmp_path):
    from st.io.ethercat import segment as segment_module

    closed = []
    real = segment_module.Segment.close
    monkeypatch.setattr(segment_module.Segment, "close", lambda self: (closed.append(self), real(self))[1])
    seg = {
        "segment": {"cycle": "1ms"},
        "slave": [{"name": "d1", "type": "cia402", "axis": 1, "bind": {"no_such_entry": "%IW3"}}],
    }
    plc = PLC(compile_text(PROGRAM, "ecat_motion.st"))
    with pytest.raises(MasterError, match="slave d1: no PDO entry 'no_such_entry' to bind to %IW3"):
        EtherCATDriver(plc, from_dict(seg), backend="sim", capture=str(tmp_path / "c.pcap"))
    assert len(closed) == 1 and (tmp_path / "c.pcap").read_bytes()[:4] == bytes.fromhex("d4c3b2a1")
