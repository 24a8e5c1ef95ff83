"""Emulated EtherCAT devices: the CiA 402 drive (state machine, modes, faults, object dictionary,
process data), its motor model (control cascade, current limit, encoder) and digital I/O.
Everything is deterministic, so the values are exact unless a physical tolerance is stated."""

import math
import struct

import pytest

from st.io.ethercat.devices import CiA402Drive, DigitalIO, MotorModel, MotorParams, State
from st.io.ethercat.devices.cia402 import wrap32
from st.io.ethercat.devices.motor import CSP, CST, CSV
from st.io.ethercat.od import ABORT_NOT_MAPPABLE, ABORT_READ_ONLY, ABORT_STATE, ABORT_VALUE_RANGE, SdoAbort
from st.io.ethercat.pdo import CIA402_RX, CIA402_TX, PdoLayout

CPR = 1 << 23
RPM = CPR / 60.0  # increments/s per rev/min

SOD, RTSO, SO = 0x0250, 0x0231, 0x0233
OE_AT_TARGET = 0x1637  # OE + following (bit 12) + target reached (bit 10)
QSA_MOVING, QSA_STOPPED = 0x0217, 0x0617
FRA, FAULT = 0x021F, 0x0218


class Rig:
    """A minimal cyclic master: write outputs into the OD, on_outputs(), step one cycle."""

    def __init__(self, drive=None, cycle=1e-3):
        self.d = drive if drive is not None else CiA402Drive()
        self.t = 0.0
        self.cycle = cycle

    def run(self, n=1, cw=None, follow=False, **objs):
        d = self.d
        for _ in range(n):
            if cw is not None:
                d.od[0x6040] = cw
            for key, v in objs.items():
                d.od[int(key[1:], 16)] = v
            if follow:  # the CSP master convention while not enabled
                d.od[0x607A] = d.od[0x6064]
            d.on_outputs()
            self.t += self.cycle
            d.step(self.t, self.cycle)
        return d.statusword

    def enable(self, mode=CSP):
        """Power-up to Operation enabled in `mode`, one command per cycle."""
        self.d.od[0x6060] = mode
        self.run(1, follow=True)
        assert self.run(1, 0x06, follow=True) == RTSO
        assert self.run(1, 0x07, follow=True) == SO
        self.run(1, 0x0F, follow=True)
        assert self.d.state == State.OPERATION_ENABLED


# ---------------------------------------------------------------------------------- state machine
def test_power_up_not_ready_for_one_step_then_switch_on_disabled():
    d = CiA402Drive()
    assert d.state_name == "NOT_READY_TO_SWITCH_ON" and d.statusword == 0x0210
    d.od[0x6040] = 0x06  # ignored while not ready
    d.step(0.001, 0.001)
    assert d.state_name == "SWITCH_ON_DISABLED" and d.statusword == SOD
    d.step(0.002, 0.001)
    assert d.state_name == "READY_TO_SWITCH_ON" and d.statusword == RTSO


def test_statusword_of_every_enable_step_and_refused_commands():
    r = Rig()
    assert r.run() == SOD
    assert r.run(3, 0x0F) == SOD  # enable operation from Switch on disabled: nothing
    assert r.run(1, 0x07) == SOD  # switch on from Switch on disabled: nothing
    assert r.run(1, 0x86) == SOD  # bit 7 set: a fault reset, no command
    assert r.run(1, 0x06) == RTSO  # 2
    assert r.run(1, 0x06) == RTSO
    assert r.run(1, 0x07) == SO  # 3
    assert r.run(1, 0x0F, follow=True) == OE_AT_TARGET  # 4
    assert r.d.state_name == "OPERATION_ENABLED" and r.d.motor.enabled
    assert r.run(1, 0x07) == SO  # 5 disable operation
    assert not r.d.motor.enabled
    assert r.run(1, 0x0F, follow=True) == OE_AT_TARGET
    assert r.run(1, 0x06) == RTSO  # 8
    assert r.run(1, 0x0F, follow=True) == SO  # 3 first ...
    assert r.run(1, 0x0F, follow=True) == OE_AT_TARGET  # ... then 4, one transition per step
    assert r.run(1, 0x00) == SOD  # 9 disable voltage
    r.run(1, 0x06)
    assert r.run(1, 0x02) == SOD  # 7 quick stop from Ready to switch on
    r.run(1, 0x06)
    r.run(1, 0x07)
    assert r.run(1, 0x0B) == SOD  # 10 quick stop from Switched on
    r.run(1, 0x06)
    r.run(1, 0x07)
    assert r.run(1, 0x06) == RTSO  # 6


def test_enable_delay_holds_switched_on():
    r = Rig(CiA402Drive(enable_delay=0.005))
    r.run(1)
    r.run(1, 0x06)
    r.run(1, 0x07)
    seen = [r.run(1, 0x0F, follow=True) for _ in range(7)]
    assert seen == [SO] * 5 + [OE_AT_TARGET] * 2


def test_mains_off_refuses_switch_on_and_mains_loss_faults():
    r = Rig()
    r.d.mains_on = False
    r.run(1)
    assert r.d.statusword == 0x0240  # no voltage-enabled bit
    assert r.run(1, 0x06) == 0x0221
    assert r.run(3, 0x07) == 0x0221  # switch on refused without DC link
    r.d.mains_on = True
    assert r.run(1, 0x07) == SO
    r.run(1, 0x0F, follow=True)
    r.d.mains_on = False
    r.run(1)
    assert r.d.state == State.FAULT_REACTION_ACTIVE and r.d.od[0x603F] == 0x3220


def test_statuswords_decode_with_the_cia402_masks():
    masks = {
        State.NOT_READY_TO_SWITCH_ON: (0x4F, 0x00),
        State.SWITCH_ON_DISABLED: (0x4F, 0x40),
        State.READY_TO_SWITCH_ON: (0x6F, 0x21),
        State.SWITCHED_ON: (0x6F, 0x23),
        State.OPERATION_ENABLED: (0x6F, 0x27),
        State.QUICK_STOP_ACTIVE: (0x6F, 0x07),
        State.FAULT_REACTION_ACTIVE: (0x4F, 0x0F),
        State.FAULT: (0x4F, 0x08),
    }
    words = {
        State.NOT_READY_TO_SWITCH_ON: 0x0210,
        State.SWITCH_ON_DISABLED: SOD,
        State.READY_TO_SWITCH_ON: RTSO,
        State.SWITCHED_ON: SO,
        State.OPERATION_ENABLED: OE_AT_TARGET,
        State.QUICK_STOP_ACTIVE: QSA_STOPPED,
        State.FAULT_REACTION_ACTIVE: FRA,
        State.FAULT: FAULT,
    }
    for state, (mask, value) in masks.items():
        assert words[state] & mask == value
        assert all(w & mask != value for s, w in words.items() if s != state)
        assert words[state] & 0x0200  # remote


# ---------------------------------------------------------------------------------- faults
def test_injected_fault_emergency_and_reset_on_rising_edge():
    r = Rig()
    r.enable(CSV)
    r.run(50, 0x0F, o60FF=int(300 * RPM))
    assert r.d.motor.rpm == pytest.approx(300, abs=1)
    r.d.inject_fault(0x7500)
    assert r.d.statusword == FRA and r.d.state_name == "FAULT_REACTION_ACTIVE"
    assert r.d.emergencies == [(0x7500, 0x01, b"\0" * 5)]
    assert r.d.od[0x603F] == 0x7500 and r.d.od[0x1001] == 0x01
    assert r.run(1, 0x0F) == FRA  # shown for one step
    assert r.run(1, 0x0F) == FAULT  # 14
    assert r.d.torque == 0 and not r.d.motor.enabled  # coasting (0x605E = 0)
    assert r.run(3, 0x06) == FAULT  # commands are ignored in Fault
    assert r.run(1, 0x80) == SOD  # 15 on the rising edge of bit 7
    assert r.d.od[0x603F] == 0 and r.d.od[0x1001] == 0
    assert r.d.emergencies[-1] == (0x0000, 0x00, b"\0" * 5)  # CiA 301 "error reset"
    assert r.run(1, 0x80) == SOD  # bit 7 held: no command
    assert r.run(1, 0x06) == RTSO


def test_persistent_fault_needs_clear_and_a_new_edge():
    r = Rig()
    r.run(1)
    r.d.inject_fault(0x2310, persistent=True)
    r.run(2)
    assert r.d.statusword == FAULT and r.d.error_code == 0x2310
    assert r.run(1, 0x80) == FAULT  # reset refused while the condition persists
    r.d.clear_fault()
    assert r.run(2, 0x80) == FAULT  # bit 7 still high: no new edge
    assert r.run(1, 0x00) == FAULT
    assert r.run(1, 0x80) == SOD


def test_fault_reaction_with_quick_stop_ramp():
    r = Rig()
    r.d.od[0x605E] = 2  # fault reaction: quick-stop ramp
    r.enable(CSV)
    r.run(30, 0x0F, o60FF=int(1000 * RPM))
    r.d.inject_fault()
    n = 0
    while r.d.state == State.FAULT_REACTION_ACTIVE:
        assert r.d.motor.enabled  # braking under control
        r.run(1, 0x0F)
        n += 1
    assert r.d.statusword == FAULT and r.d.velocity == 0
    assert 16 <= n <= 22  # 1000 rev/min at 60000 rev/min/s: 16.7 ms


# ---------------------------------------------------------------------------------- quick stop
def test_quick_stop_ramp_then_switch_on_disabled():
    r = Rig()
    r.enable(CSV)
    r.run(30, 0x0F, o60FF=int(1000 * RPM))
    assert r.d.statusword == OE_AT_TARGET  # CSV at speed: target reached
    assert r.run(1, 0x02) == QSA_MOVING  # 11
    speeds = [r.d.motor.rpm]
    while r.d.state == State.QUICK_STOP_ACTIVE:
        r.run(1, 0x02)
        speeds.append(r.d.motor.rpm)
    assert r.d.statusword == SOD  # 12 automatic (0x605A = 2)
    ramp = [v for v in speeds if v > 0]
    assert all(b < a for a, b in zip(ramp, ramp[1:])) and min(speeds) > -5  # hardly any overshoot
    # 1000 rev/min at 60000 rev/min per second: 16.7 ms, then one step to leave QSA
    assert 17 <= len(speeds) <= 20
    decel = (speeds[2] - speeds[6]) / 0.004
    assert decel == pytest.approx(60000, rel=0.02)


def test_quick_stop_option_6_stays_and_reenables():
    r = Rig()
    assert r.d.od.entry(0x605A).on_write(None, 6) == 0
    r.d.od[0x605A] = 6
    r.enable(CSV)
    r.run(30, 0x0F, o60FF=int(500 * RPM))
    r.run(40, 0x02)
    assert r.d.statusword == QSA_STOPPED and abs(r.d.motor.rpm) < 0.01  # holding
    assert r.run(1, 0x0F, o60FF=0) == OE_AT_TARGET  # 16
    assert r.run(1, 0x02) == QSA_STOPPED  # already at rest
    assert r.run(1, 0x00) == SOD  # 12 by disable voltage


# ---------------------------------------------------------------------------------- modes
def test_mode_switching_and_display():
    r = Rig()
    r.enable(CSP)
    assert r.d.od[0x6061] == CSP
    r.run(20, 0x0F, o6060=CSV, o60FF=int(200 * RPM))
    assert r.d.od[0x6061] == CSV and r.d.motor.mode == CSV
    assert r.d.motor.rpm == pytest.approx(200, abs=0.5)
    r.run(2, 0x0F, o6060=1)  # profile position: not supported, display unchanged
    assert r.d.od[0x6061] == CSV and r.d.state == State.OPERATION_ENABLED
    r.run(1, 0x0F, o6060=CST, o6071=0)
    assert r.d.od[0x6061] == CST
    r.run(5, 0x0F, o6071=100)  # 10 % of rated torque
    assert r.d.torque == 100
    assert r.d.od[0x6077] == 100
    assert r.d.motor.rpm > 200  # accelerating
    # back to CSP: the master must present the actual position as the target first
    r.run(1, 0x0F, o6071=0)
    r.d.od[0x607A] = r.d.od[0x6064]
    r.run(1, 0x0F, o6060=CSP)
    assert r.d.state == State.OPERATION_ENABLED and r.d.od[0x6061] == CSP
    r.run(30, 0x0F)  # holds: brakes to rest and back to the target
    assert r.d.velocity == 0 or abs(r.d.motor.rpm) < 0.5


def test_switch_to_csp_with_stale_target_faults_instead_of_jumping():
    r = Rig()
    r.enable(CSV)
    r.run(100, 0x0F, o60FF=int(600 * RPM))  # 1 rev in 100 ms: far from target 0x607A
    r.run(1, 0x0F, o6060=CSP)
    assert r.d.error_code == 0x8611 and r.d.state == State.FAULT_REACTION_ACTIVE


# ---------------------------------------------------------------------------------- CSP / CSV / CST
def test_csp_follows_a_trapezoid_with_bounded_following_error():
    r = Rig()
    r.enable(CSP)
    vmax = 3000 * RPM
    acc = vmax / 0.05
    p = float(r.d.position)
    v = 0.0
    worst = 0
    for k in range(200):
        if k < 50:
            v = min(vmax, v + acc * 1e-3)
        elif k >= 100:
            v = max(0.0, v - acc * 1e-3)
        p += v * 1e-3
        r.run(1, 0x0F, o607A=wrap32(int(p)))
        worst = max(worst, abs(r.d.od[0x60F4]), abs(int(p) - r.d.position))
        assert r.d.state == State.OPERATION_ENABLED
    assert r.d.position / CPR == pytest.approx(5.0, rel=1e-3)  # 3000 rev/min × 100 ms
    assert worst < 4500  # 0.19° (125 µs physics steps)
    r.run(20, 0x0F)
    assert abs(int(p) - r.d.position) <= 16
    assert r.d.statusword == OE_AT_TARGET and r.d.od[0x60F4] == r.d.od[0x6062] - r.d.od[0x6064]


def test_interpolation_period_measured_until_0x60c2_is_written():
    r = Rig(cycle=2e-3)
    r.enable(CSP)
    assert r.d.interpolation_period == pytest.approx(2e-3)
    p = r.d.position
    for _ in range(50):  # 300 rev/min with a 2 ms cycle: smooth, small error
        p += int(300 * RPM * 2e-3)
        r.run(1, 0x0F, o607A=wrap32(p))
        assert abs(r.d.od[0x60F4]) < 2000
    r.d.od.state = "PREOP"
    r.d.od.download(0x60C2, 1, bytes([4]))
    assert r.d.interpolation_period == pytest.approx(4e-3)


def test_csp_across_the_32_bit_wrap():
    r = Rig()
    r.d.motor.set_position(2**31 - CPR // 4)
    r.enable(CSP)
    assert r.d.od[0x6064] == 2**31 - CPR // 4
    p = r.d.position
    for _ in range(100):  # 600 rev/min: 0.5 rev forward in 50 ms … 100 ms
        p += int(600 * RPM * 1e-3)
        r.run(1, 0x0F, o607A=wrap32(p))
    r.run(30, 0x0F)  # the last target stops abruptly: let it settle
    assert r.d.state == State.OPERATION_ENABLED
    assert r.d.position == pytest.approx(p, abs=16) and r.d.position > 2**31
    assert r.d.od[0x6064] == wrap32(r.d.position) < 0


def test_csv_reaches_commanded_velocity():
    r = Rig()
    r.enable(CSV)
    r.run(10, 0x0F, o60FF=int(1500 * RPM))
    assert r.d.motor.rpm == pytest.approx(1500, rel=0.005)  # within 0.5 % after 10 ms
    assert r.d.od[0x606C] == r.d.velocity
    assert r.d.statusword & 0x0400
    r.run(10, 0x0F, o60FF=int(-1500 * RPM))
    assert r.d.motor.rpm == pytest.approx(-1500, rel=0.005)


def test_current_limit_bounds_acceleration():
    m = MotorModel()
    p = m.params
    m.enable(CSV)
    m.target_velocity = int(6000 * RPM)
    goal = 0.75 * m.max_speed
    t = 0.0
    limited = False
    while m.omega < goal:
        m.step(1e-5)
        t += 1e-5
        limited = limited or m.limited
        assert abs(m.torque_nm) <= p.max_torque + 1e-12
    # constant torque against Coulomb and viscous friction: ω(t) = (T - Tc)/b · (1 - exp(-b t / J))
    J, b = p.inertia, p.viscous_friction
    t_analytic = -J / b * math.log(1 - goal * b / (p.max_torque - p.coulomb_friction))
    assert t == pytest.approx(t_analytic, rel=0.05)
    assert limited and m.torque == 2969  # at the current limit, per-mille of 0.32 N·m
    # a small step stays inside the limit and settles within a few ms
    m2 = MotorModel()
    m2.enable(CSV)
    m2.target_velocity = int(50 * RPM)
    m2.step(0.005)
    assert not m2.limited and m2.rpm == pytest.approx(50, rel=0.01)


def test_internal_limit_bit_while_saturated():
    r = Rig()
    r.enable(CSV)
    sw = r.run(1, 0x0F, o60FF=int(6000 * RPM))
    assert sw == 0x1A37  # OE + following + internal limit, not yet at target
    r.run(30, 0x0F)
    assert r.d.statusword == OE_AT_TARGET


def test_torque_limit_object_limits_torque():
    r = Rig()
    r.enable(CST)
    r.run(3, 0x0F, o6072=500, o6071=1500)
    assert r.d.torque == 500


def test_an_object_written_between_cycles_is_taken_at_the_next_step():
    r = Rig()
    r.enable(CST)
    r.run(2, 0x0F, o6072=500, o6071=300)
    assert r.d.motor.torque_limit == 500
    r.d.od[0x6072] = 250  # outside the cyclic outputs (as an SDO download writes it)
    r.t += r.cycle
    r.d.step(r.t, r.cycle)
    assert r.d.motor.torque_limit == 250
    r.d.od.state = "OP"
    r.d.od.download(0x6072, 0, struct.pack("<H", 120))  # an SDO download (the drive in OP)
    r.t += r.cycle
    r.d.step(r.t, r.cycle)
    assert r.d.motor.torque_limit == 120


def test_disabled_motor_coasts_down_by_friction():
    m = MotorModel()
    m.enable(CSV)
    m.target_velocity = int(600 * RPM)
    m.step(0.02)
    w0 = m.omega
    m.disable()
    t = 0.0
    while m.omega > 0:
        m.step(1e-3)
        t += 1e-3
        assert m.torque_nm == 0.0
    p = m.params
    t_stop = p.inertia / p.viscous_friction * math.log(1 + p.viscous_friction * w0 / p.coulomb_friction)
    assert t == pytest.approx(t_stop, abs=2e-3)
    pos = m.position
    m.step(0.1)
    assert m.position == pos and m.velocity == 0


def test_motion_is_deterministic():
    def run():
        r = Rig()
        r.enable(CSV)
        r.run(25, 0x0F, o60FF=int(2345 * RPM))
        r.run(25, 0x0F, o6060=CST, o6071=-300)
        return r.d.position, r.d.velocity, r.d.torque, r.d.motor.turns

    assert run() == run()


def test_noise_is_seeded():
    def run(seed):
        m = MotorModel(MotorParams(torque_noise=0.01, seed=seed))
        m.enable(CSV)
        m.target_velocity = int(100 * RPM)
        m.step(0.01)
        return m.turns

    assert run(1) == run(1) != run(2)


# ---------------------------------------------------------------------------------- encoder
def test_encoder_quantisation_23_bits():
    d = CiA402Drive()
    assert d.motor.cpr == 8388608
    assert d.od[(0x608F, 1)] == 8388608 and d.od[(0x608F, 2)] == 1
    m = d.motor
    m.turns = 1.0
    assert m.position == 8388608
    m.turns = 0.5 / CPR
    assert m.position == 0
    m.turns = 1.5 / CPR
    assert m.position == 1
    m.turns = -0.5 / CPR
    assert m.position == -1  # floor: the count below the angle
    m.turns = 0.25
    d.step(0.001, 0.001)
    assert d.od[0x6064] == 2097152
    assert CiA402Drive(encoder_bits=17).motor.cpr == 131072


def test_one_revolution_at_60_rpm_is_8388608_increments():
    r = Rig()
    r.enable(CSV)
    r.run(1000, 0x0F, o60FF=int(60 * RPM))
    start = r.d.position
    r.run(1000, 0x0F)
    assert r.d.position - start == pytest.approx(8388608, abs=200)


# ---------------------------------------------------------------------------------- following error
def test_following_error_fault_after_window_and_timeout():
    r = Rig()
    r.d.od[0x6065] = 20000
    r.d.od[0x6066] = 3  # ms
    r.enable(CSP)
    r.d.motor.load_torque = -2.0  # more than the drive can hold
    states, errors = [], []
    for _ in range(20):
        states.append(r.run(1, 0x0F))
        errors.append(r.d.od[0x60F4])
        if r.d.state != State.OPERATION_ENABLED:
            break
    assert r.d.error_code == 0x8611
    assert r.d.emergencies == [(0x8611, 0x01, b"\0" * 5)]
    assert states[-1] == 0x221F  # fault reaction + following error (bit 13)
    assert r.run(1, 0x0F) == 0x2218  # Fault, following error still shown
    # beyond the window for more than 3 ms: three cycles over it are shown, the fourth faults
    # (and with the power stage off the drive's demand follows the actual position again)
    over = [abs(e) > 20000 for e in errors]
    assert over[-4:] == [True, True, True, False] and not any(over[:-4]) and errors[-1] == 0
    r.d.motor.load_torque = 0.0
    assert r.run(1, 0x80) == SOD


def test_enable_with_far_target_reports_following_error_without_moving():
    r = Rig()
    r.d.motor.set_position(123456)
    r.run(1)
    r.run(1, 0x06)
    r.run(1, 0x07)
    r.d.od[0x607A] = 123456 + CPR  # one revolution away; window is 1/8 rev
    r.run(1, 0x0F)
    assert r.d.state == State.FAULT_REACTION_ACTIVE and r.d.error_code == 0x8611
    assert r.d.statusword == 0x221F
    r.run(2, 0x0F)
    assert r.d.statusword == 0x2218 and r.d.position == 123456


def test_enable_with_close_target_moves_there():
    r = Rig()
    r.run(1)
    r.run(1, 0x06)
    r.run(1, 0x07)
    r.d.od[0x607A] = 5000
    r.run(1, 0x0F)
    r.run(20, 0x0F)
    assert r.d.state == State.OPERATION_ENABLED and abs(r.d.position - 5000) <= 24  # Coulomb friction
    assert r.d.statusword == OE_AT_TARGET


# ---------------------------------------------------------------------------------- object dictionary
def test_sdo_access():
    d = CiA402Drive()
    od = d.od
    od.state = "PREOP"
    assert struct.unpack("<I", od.upload(0x1000, 0))[0] == 0x00020192
    assert struct.unpack("<I", od.upload(0x1018, 1))[0] == 0x66F
    assert struct.unpack("<I", od.upload(0x1018, 2))[0] == 0x60380004
    assert [od[(0x1C00, s)] for s in range(5)] == [4, 1, 2, 3, 4]
    assert od[(0x60C2, 1)] == 1 and od[(0x60C2, 2)] == -3 and d.interpolation_period == pytest.approx(1e-3)
    assert od[0x6502] == 0x380
    with pytest.raises(SdoAbort) as e:
        od.download(0x6060, 0, struct.pack("<b", 1))
    assert e.value.code == ABORT_VALUE_RANGE
    od.download(0x6060, 0, struct.pack("<b", CSV))
    assert od[0x6060] == CSV
    with pytest.raises(SdoAbort) as e:
        od.download(0x6041, 0, b"\0\0")
    assert e.value.code == ABORT_READ_ONLY
    with pytest.raises(SdoAbort) as e:
        od.download(0x605A, 0, struct.pack("<h", 9))
    assert e.value.code == ABORT_VALUE_RANGE
    od.download(0x60C2, 1, bytes([2]))
    assert d.interpolation_period == pytest.approx(2e-3)
    od.state = "OP"
    with pytest.raises(SdoAbort) as e:
        od.download(0x1600, 0, bytes([0]))
    assert e.value.code == ABORT_STATE
    with pytest.raises(SdoAbort) as e:
        od.download(0x1C12, 0, bytes([0]))
    assert e.value.code == ABORT_STATE
    od.download(0x607A, 0, struct.pack("<i", -5))  # process data is writable in OP
    assert od[0x607A] == -5


def test_pdo_remapping_in_preop():
    d = CiA402Drive()
    od = d.od
    od.state = "PREOP"
    assert d.tx_layout.size == 12
    od.download(0x1C13, 0, bytes([0]))
    od.download(0x1A00, 0, bytes([0]))
    od.download(0x1A00, 5, struct.pack("<I", 0x60770010))
    od.download(0x1A00, 6, struct.pack("<I", 0x60610008))
    od.download(0x1A00, 7, struct.pack("<I", 0x00000008))  # padding
    od.download(0x1A00, 0, bytes([7]))
    od.download(0x1C13, 0, bytes([1]))
    assert d.tx_layout.size == 16
    assert [e.name for e in d.tx_layout.data_entries][-2:] == ["Torque actual value", "Modes of operation display"]
    for sub, word in ((8, 0x12340010), (8, 0x60410010), (8, 0x607A0010)):
        target = 0x1600 if word == 0x60410010 else 0x1A00
        with pytest.raises(SdoAbort) as e:  # missing object; ro object in an RxPDO; wrong length
            od.download(target, sub, struct.pack("<I", word))
        assert e.value.code == ABORT_NOT_MAPPABLE
    with pytest.raises(SdoAbort) as e:
        od.download(0x1C12, 1, struct.pack("<H", 0x1A00))
    assert e.value.code == ABORT_VALUE_RANGE
    # a mapping whose entries were written directly is checked when sub 0 enables it
    od[(0x1600, 5)] = 0x60410010
    with pytest.raises(SdoAbort) as e:
        od.download(0x1600, 0, bytes([5]))
    assert e.value.code == ABORT_NOT_MAPPABLE
    od[(0x1600, 5)] = 0x60710010
    od.download(0x1600, 0, bytes([5]))
    assert d.rx_layout.size == 13
    # complete access: sub 0 and the entries in one download
    data = struct.pack("<BxIII", 3, 0x60410010, 0x60640020, 0x606C0020)
    od.download(0x1A00, 0, data, complete=True)
    assert d.tx_layout.size == 10


def test_constructor_overrides_and_bad_mapping():
    d = CiA402Drive(
        "axis1",
        vendor_id=0x29C,
        product_code=0x03B11002,
        rx_mapping=CIA402_RX + [(0x6071, 0, 16, "INT", "target_torque"), (0, 0, 8, "PAD", "")],
        tx_mapping=CIA402_TX + [(0x6077, 0, 16, "INT", "torque_actual")],
        motor=MotorParams(load_inertia=0.2e-4),
    )
    assert d.name == "axis1" and d.od[(0x1018, 1)] == 0x29C and d.od[(0x1018, 2)] == 0x03B11002
    assert d.rx_layout.size == 14 and d.tx_layout.size == 14
    assert d.motor.params.inertia == pytest.approx(0.251e-4)
    with pytest.raises(ValueError):  # a read-only object in an RxPDO
        CiA402Drive(rx_mapping=[(0x6041, 0, 16, "UINT", "statusword")])
    with pytest.raises(ValueError):  # the wrong length for an object
        CiA402Drive(tx_mapping=[(0x6041, 0, 32, "UDINT", "statusword")])
    # objects from an ESI file that the drive does not implement: carried, not acted on
    d = CiA402Drive(
        rx_mapping=CIA402_RX + [(0x60B8, 0, 16, "UINT", "Touch probe function")],
        tx_mapping=CIA402_TX + [(0x60B9, 0, 16, "UINT", "Touch probe status")],
    )
    assert (d.rx_layout.size, d.tx_layout.size) == (13, 14)
    assert d.od.entry(0x60B8).access == "rw" and d.od.entry(0x60B9).access == "ro"


def test_default_pdo_layout_round_trip():
    r = Rig()
    d = r.d
    rx, tx = d.rx_layout, d.tx_layout
    assert (rx.size, tx.size) == (11, 12)
    assert [(e.index, e.offset) for e in rx.data_entries] == [(0x6040, 0), (0x607A, 16), (0x60FF, 48), (0x6060, 80)]
    assert [(e.index, e.offset) for e in tx.data_entries] == [(0x6041, 0), (0x6064, 16), (0x606C, 48), (0x603F, 80)]

    def shape(layout):
        return [(e.index, e.sub, e.bits, e.dtype, e.offset) for e in layout.entries]

    assert shape(rx) == shape(PdoLayout(CIA402_RX)) and shape(tx) == shape(PdoLayout(CIA402_TX))
    d.write_outputs(rx.pack([0x0006, -123456, 7890, CSV]))
    assert (d.od[0x6040], d.od[0x607A], d.od[0x60FF], d.od[0x6060]) == (0x0006, -123456, 7890, CSV)
    r.run(1)
    r.run(1)
    raw = d.read_inputs()
    assert len(raw) == 12
    assert tx.unpack(raw) == [RTSO, d.od[0x6064], d.od[0x606C], 0]
    assert raw[:2] == b"\x31\x02"


def test_a_layouts_unpacker_gives_the_values_of_unpack():
    image = bytes.fromhex("0f00c0e2ffffd21e000008")  # 0x000F, -7488, 7890, CSP
    aligned = PdoLayout(CIA402_RX)
    assert tuple(aligned.unpacker()(image)) == tuple(aligned.unpack(image)) == (0x000F, -7488, 7890, 8)
    bits = PdoLayout([(0x7000, k, 1, "BOOL", "") for k in range(1, 9)])  # no struct: bit by bit
    assert bits.unpacker()(b"\x05") == bits.unpack(b"\x05") == [True, False, True] + [False] * 5


# ---------------------------------------------------------------------------------- digital I/O
def test_digital_io_bit_packing():
    io = DigitalIO()
    assert not io.has_mailbox and io.product_code == 0x07D83052 and io.vendor_id == 2
    assert (io.rx_layout.size, io.tx_layout.size) == (1, 1)
    io.set_input(0, True)
    io.set_input(7, True)
    assert io.read_inputs() == b"\x81"
    io.set_inputs([False, True, True])
    assert io.read_inputs() == b"\x86" and io.inputs == [False, True, True, False, False, False, False, True]
    io.write_outputs(b"\xa5")
    assert io.outputs == [True, False, True, False, False, True, False, True]
    with pytest.raises(IndexError):
        io.set_input(8, True)


def test_digital_io_sizes_and_padding():
    io = DigitalIO(n_inputs=12, n_outputs=3)
    assert (io.rx_layout.size, io.tx_layout.size) == (1, 2)
    io.set_input(11, True)
    io.set_input(8, True)
    assert io.read_inputs() == b"\x00\x09"
    io.write_outputs(b"\xfc")  # bits beyond channel 3 are padding
    assert io.outputs == [False, False, True]
    only_in = DigitalIO(n_inputs=4, n_outputs=0)
    assert (only_in.rx_layout.size, only_in.tx_layout.size) == (0, 1)
