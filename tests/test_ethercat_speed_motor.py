"""The motor model's shortcuts give the same bits as the plain loop: a following step that left
the state as it found it (an axis holding still) is skipped the next time, and only then."""

from __future__ import annotations

from st.io.ethercat.devices.motor import CSP, CSV, MotorModel


def _state(m: MotorModel) -> tuple:
    return (m.omega, m.turns, m.torque_nm, m._integ, m._torque_ref, m._demand, m._ip_elapsed, m.limited)


def _run(skip: bool) -> list:
    m = MotorModel(substep=125e-6)
    m.enable(CSP)
    out = []
    target = 0.0
    for k in range(3000):
        if not skip:  # forget every fixed point: the loop always runs
            m._rest_state, m._rest_inputs = None, {}
        if k < 300:
            target += 40.0
            m.command_position(target, 0.001)
        elif k == 1500:
            m.load_torque = 0.01  # a disturbance at standstill: the loop must run again
        elif k == 2000:
            m.torque_limit = 5  # the limit changes an input: no skip with the old one
        elif k == 2500:
            m.set_mode(CSV)
            m.target_velocity = 0
        # DC pulse times vary in their last bits: the step length with them
        m.step(0.001 + (1e-18 if k % 3 == 0 else 0.0))
        out.append(_state(m))
    return out


def test_skipping_fixed_points_changes_nothing():
    assert _run(skip=True) == _run(skip=False)


def test_an_axis_holding_still_is_skipped():
    m = MotorModel(substep=125e-6)
    m.enable(CSP)
    calls = []
    for _ in range(200):
        m.step(0.001)
        calls.append(m._rest_state is not None)
    assert calls[-1]  # it came to rest and the rest was recognised


class _NoNoise:
    """A noise source that adds nothing: it sends the motor through its general loop."""

    def gauss(self, mu: float, sigma: float) -> float:
        return 0.0


def _scenario(m: MotorModel) -> list:
    """CSP moves into the current and speed limits, a load, then CSV: every branch of the loop."""
    out = []
    target = 0.0
    m.enable(CSP)
    for k in range(1200):
        if k < 200:
            target += 30_000.0 if k < 100 else -45_000.0  # far beyond what the current allows
            m.command_position(target, 0.001)
        if k == 300:
            m.torque_limit = 50
        if k == 400:
            m.speed_limit = 20.0
            m.load_torque = -0.05
        if k == 700:
            m.set_mode(CSV)
            m.target_velocity = 400_000
        if k == 900:
            m.target_velocity = -900_000
            m.torque_offset = 30
        m.step(0.001)
        out.append(_state(m))
    return out


def test_the_following_loop_matches_the_general_loop_bit_for_bit():
    general = MotorModel(substep=125e-6)
    general._rng = _NoNoise()  # type: ignore[assignment]
    assert _scenario(MotorModel(substep=125e-6)) == _scenario(general)
