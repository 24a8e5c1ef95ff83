"""A deterministic servo motor with its drive's control cascade, for emulated CiA 402 drives.

The cascade is the usual one of a servo amplifier: an optional position loop (P, plus velocity
feed-forward) produces a velocity reference, a PI velocity loop turns the velocity error into a
torque (current) reference, the reference is clamped to the current limit, a first-order lag
stands in for the current loop, and the torque accelerates the rotor and load inertia against
viscous and Coulomb friction. An incremental encoder quantises the shaft angle.

Everything runs in float64 in fixed-size substeps (62.5 µs by default, a 16 kHz loop), so the
same sequence of inputs always gives the same trajectory. Units: the mechanics work in SI
(rad/s, N·m); the interface speaks the drive's units: positions in encoder increments, velocities
in increments/s, torques in per-mille of the rated torque.

Defaults are modelled on a Panasonic MINAS A6 100 W motor (MSMF012): 0.32 N·m rated, about 3×
peak, 6000 rev/min, rotor inertia 0.051e-4 kg·m², 23-bit encoder.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

TWO_PI = 2.0 * math.pi

# modes the model understands (the CiA 402 numbers of the cyclic synchronous modes)
CSP, CSV, CST = 8, 9, 10
_STOP, _HOLD = -1, -2  # internal: a deceleration ramp, then holding the stop position


@dataclass(frozen=True)
class MotorParams:
    """Fixed for the life of a model (frozen): `MotorModel` derives its step constants from them
    once per step length and limits."""

    rated_torque: float = 0.32  # N·m
    max_torque: float = 0.95  # N·m, the current limit (≈ 3× rated)
    max_speed_rpm: float = 6000.0  # rev/min
    rotor_inertia: float = 0.051e-4  # kg·m²
    load_inertia: float = 0.051e-4  # kg·m² (1:1 load by default)
    viscous_friction: float = 5e-6  # N·m per rad/s
    coulomb_friction: float = 0.002  # N·m; lets a coasting motor come to rest in finite time
    torque_constant: float = 0.29  # N·m/A (only used for `current`)
    encoder_bits: int = 23
    velocity_bandwidth_hz: float = 500.0  # used when velocity_kp / velocity_ki are None
    velocity_kp: float | None = None  # N·m per rad/s
    velocity_ki: float | None = None  # N·m per rad (integral gain, per second)
    position_kp: float = 300.0  # 1/s (velocity reference per position error)
    current_tau: float = 1e-4  # s, first-order lag of the current loop (0 = ideal)
    torque_noise: float = 0.0  # N·m standard deviation per substep; 0 = no randomness
    seed: int = 0  # seed of the noise generator (only used if torque_noise > 0)

    @property
    def inertia(self) -> float:
        return self.rotor_inertia + self.load_inertia

    @property
    def counts_per_rev(self) -> int:
        return 1 << self.encoder_bits


def _coulomb_step(w: float, drive: float, tc: float, J: float, h: float) -> float:
    """One semi-implicit Euler step of the shaft speed under `drive` torque and Coulomb friction
    tc, which never reverses the motion and holds a shaft at rest while |drive| <= tc."""
    if w > 0.0:
        w_new = w + (drive - tc) / J * h
        return 0.0 if w_new < 0.0 and abs(drive) <= tc else w_new
    if w < 0.0:
        w_new = w + (drive + tc) / J * h
        return 0.0 if w_new > 0.0 and abs(drive) <= tc else w_new
    if drive > tc:
        return (drive - tc) / J * h
    if drive < -tc:
        return (drive + tc) / J * h
    return 0.0  # sticking


class MotorModel:
    """Inputs: `enabled`, `mode` (CSP / CSV / CST), `command_position()`, `target_velocity`,
    `target_torque`, offsets and limits. Outputs: `position`, `velocity`, `torque` (drive units)
    and the SI state `turns`, `omega`, `torque_nm`."""

    def __init__(self, params: MotorParams | None = None, substep: float = 62.5e-6):
        p = self.params = params or MotorParams()
        if substep <= 0:
            raise ValueError("substep must be positive")
        self.substep = substep
        self.cpr = p.counts_per_rev
        self.k = self.cpr / TWO_PI  # increments per rad
        J = p.inertia
        wc = TWO_PI * p.velocity_bandwidth_hz
        # PI tuned for a critically damped loop around the inertia: ω_n = ωc/2, ζ = 1
        self.kv = p.velocity_kp if p.velocity_kp is not None else J * wc
        self.ki = p.velocity_ki if p.velocity_ki is not None else J * wc * wc / 4.0
        self.max_speed = p.max_speed_rpm * TWO_PI / 60.0  # rad/s
        self._rng = random.Random(p.seed) if p.torque_noise > 0 else None
        # mechanical state
        self.turns = 0.0  # shaft angle in revolutions (exact encoder maths: cpr is a power of 2)
        self.omega = 0.0  # rad/s
        self.torque_nm = 0.0  # torque produced by the motor (after the current loop), N·m
        self.load_torque = 0.0  # external torque on the shaft, N·m (positive accelerates forwards)
        self.time = 0.0
        # inputs
        self.enabled = False
        self.mode = CSP
        self.target_velocity = 0  # increments/s (CSV)
        self.target_torque = 0  # per-mille of rated torque (CST)
        self.velocity_offset = 0  # increments/s, added to the velocity reference (CSP/CSV)
        self.torque_offset = 0  # per-mille, added to the torque reference
        self.torque_limit = None  # per-mille; None = max_torque
        self.speed_limit = None  # rad/s; None = max_speed
        # controller state
        self._integ = 0.0  # velocity-loop integrator, N·m
        self._torque_ref = 0.0
        self._demand = 0.0  # position demand, increments (float)
        self._ip_start = 0.0
        self._ip_target = 0.0
        self._ip_period = 0.0
        self._ip_elapsed = 0.0
        self._stop_v = 0.0  # ramp velocity during a stop, rad/s
        self._stop_decel: float | None = None  # rad/s² or None = at the current limit
        self._stop_done = False
        self._resume_mode = CSP
        self.limited = False  # a torque or speed limit was active during the last step()
        # a state that following steps left as they found it, and for which inputs (→ `limited`)
        self._rest_state: tuple | None = None
        self._rest_inputs: dict = {}
        # (dt, torque limit, speed limit) → the constants of a step (see _constants)
        self._constants_of: dict = {}

    # ------------------------------------------------------------------ outputs
    @property
    def position(self) -> int:
        """Actual position in encoder increments (the encoder's count: floor of the angle)."""
        return math.floor(self.turns * self.cpr)

    @property
    def velocity(self) -> int:
        """Actual velocity in increments/s."""
        return int(round(self.omega * self.k))

    @property
    def torque(self) -> int:
        """Actual torque in per-mille of the rated torque."""
        return int(round(self.torque_nm / self.params.rated_torque * 1000.0))

    @property
    def current(self) -> float:
        return self.torque_nm / self.params.torque_constant

    @property
    def rpm(self) -> float:
        return self.omega * 60.0 / TWO_PI

    @property
    def position_demand(self) -> float:
        """The interpolated position the position loop is following (increments)."""
        if self.enabled and self.mode in (CSP, _HOLD):
            return self._demand
        return float(self.position)

    @property
    def following_error(self) -> int:
        """Position demand − actual position, increments (0 when no position loop is closed)."""
        if self.enabled and self.mode in (CSP, _HOLD):
            return int(round(self._demand)) - self.position
        return 0

    def readings(self) -> tuple:
        """(position, rounded position demand, velocity, torque, following error) at once: the
        values of the properties, for a drive that publishes them all every step."""
        pos = math.floor(self.turns * self.cpr)
        if self.enabled and (self.mode == CSP or self.mode == _HOLD):
            demand = round(self._demand)  # an int: round() of a float is one
            fe = demand - pos
        else:
            demand = pos
            fe = 0
        vel = round(self.omega * self.k)
        torque = round(self.torque_nm / self.params.rated_torque * 1000.0)
        return pos, demand, vel, torque, fe

    @property
    def commanded_position(self) -> float:
        """The last position target given to `command_position`."""
        return self._ip_target

    @property
    def stopped(self) -> bool:
        """A stop ramp has finished and the shaft is (nearly) at rest."""
        return self.mode in (_STOP, _HOLD) and self._stop_done

    # ------------------------------------------------------------------ inputs
    def enable(self, mode: int | None = None) -> None:
        """Switch the power stage on. The position demand starts at the actual position, the
        integrator at zero (no jump on enabling)."""
        if mode is not None:
            self.mode = mode
        if not self.enabled:
            self.enabled = True
            self._integ = 0.0
            self._reset_demand()

    def disable(self) -> None:
        """Power stage off: no torque; the motor coasts down by friction."""
        self.enabled = False
        self._integ = 0.0
        self._torque_ref = 0.0
        self.torque_nm = 0.0
        if self.mode in (_STOP, _HOLD):
            self.mode = self._resume_mode

    def set_mode(self, mode: int) -> None:
        """Change the operating mode bumplessly: CSP restarts from the actual position, and the
        integrator is preset with the present torque when a velocity loop takes over from CST."""
        if mode == self.mode:
            return
        if mode in (CSV, CSP, _STOP, _HOLD) and self.mode == CST:
            self._integ = self._torque_ref
        self.mode = mode
        if mode == CSP:
            self._reset_demand()

    def command_position(self, target: float, period: float = 0.0) -> None:
        """A new CSP target (increments). The demand moves there linearly within `period` seconds,
        which also gives the velocity feed-forward; period 0 jumps at once (no feed-forward)."""
        self._ip_start = self._demand if (self.enabled and self.mode == CSP) else float(self.position)
        self._ip_target = float(target)
        period = float(period)
        self._ip_period = period if period > 0.0 else 0.0  # max(0.0, period), NaN too
        self._ip_elapsed = 0.0
        if self._ip_period == 0.0:
            self._demand = self._ip_target

    def stop(self, decel: float | None = None) -> None:
        """Decelerate to rest, `decel` in increments/s² (None: at the current limit), then hold
        the position where the shaft came to rest."""
        if self.mode in (_STOP, _HOLD):
            self._stop_decel = None if decel is None else decel / self.k
            return
        self._resume_mode = self.mode
        self.mode = _STOP
        self._stop_v = self.omega
        self._stop_decel = None if decel is None else decel / self.k
        self._stop_done = False
        if self._resume_mode == CST:
            self._integ = max(-self.params.max_torque, min(self.params.max_torque, self._torque_ref))

    def set_position(self, increments: int) -> None:
        """Place the shaft (while at rest, e.g. for a test); the demand follows."""
        self.turns = increments / self.cpr
        self._reset_demand()

    def _reset_demand(self) -> None:
        pos = float(self.position)
        self._demand = self._ip_start = self._ip_target = pos
        self._ip_period = self._ip_elapsed = 0.0

    # ------------------------------------------------------------------ simulation
    def step(self, dt: float) -> None:
        """Advance by dt seconds in ceil(dt / substep) equal substeps."""
        if dt <= 0:
            return
        self.limited = False
        if self.enabled and self._rng is None and (self.mode == CSP or self.mode == CSV):
            self._step_following(self._constants(dt))
            self.time += dt
            return
        n, h, J, b, tc, cpr, k, kv, ki, kp, vmax, tmax, rated, alpha = self._constants(dt)
        p = self.params
        if (
            not self.enabled
            and self.omega == 0.0
            and abs(self.load_torque) <= tc
            and self._rng is None
            and self.torque_nm == 0.0
        ):
            self.time += dt  # at rest and unpowered: nothing changes
            return
        standstill = TWO_PI / 60.0  # 1 rev/min
        for _ in range(n):
            w = self.omega
            if self.enabled:
                mode = self.mode
                toff = self.torque_offset * rated / 1000.0
                if mode == CST:
                    u = self.target_torque * rated / 1000.0 + toff
                    if (w > vmax and u > 0) or (w < -vmax and u < 0):
                        u = 0.0  # speed limit in torque mode
                        self.limited = True
                else:
                    if mode == CSP or mode == _HOLD:
                        # the error uses the demand at the start of the substep; the feed-forward
                        # carries it to where the demand will be at the end
                        count = math.floor(self.turns * cpr)
                        err = self._demand - count
                        ff = 0.0
                        if mode == CSP and self._ip_period > 0.0 and self._ip_elapsed < self._ip_period:
                            span = self._ip_target - self._ip_start
                            before = self._ip_elapsed
                            self._ip_elapsed = before + h
                            frac = min(self._ip_elapsed / self._ip_period, 1.0)
                            self._demand = self._ip_start + span * frac
                            ff = span / self._ip_period * (min(h, self._ip_period - before) / h)
                        elif mode == CSP:
                            self._demand = self._ip_target
                        vref = (ff + kp * err + (self.velocity_offset if mode == CSP else 0)) / k
                    elif mode == CSV:
                        vref = (self.target_velocity + self.velocity_offset) / k
                    else:  # _STOP: ramp the reference to zero
                        d = self._stop_decel
                        v0 = self._stop_v
                        if d is None:
                            self._stop_v = 0.0
                        elif v0 > 0:
                            self._stop_v = max(0.0, v0 - d * h)
                        else:
                            self._stop_v = min(0.0, v0 + d * h)
                        vref = self._stop_v
                        if d is not None:  # torque feed-forward of the ramp: no overshoot at its end
                            toff += (self._stop_v - v0) / h * J
                        if vref == 0.0 and abs(w) <= standstill:
                            self._stop_done = True
                            self.mode = _HOLD
                            self._demand = float(math.floor(self.turns * cpr))
                    if vref > vmax:
                        vref = vmax
                        self.limited = True
                    elif vref < -vmax:
                        vref = -vmax
                        self.limited = True
                    e = vref - w
                    integ = self._integ + ki * e * h
                    u = kv * e + integ + toff
                    # conditional integration: freeze the integrator while it would push further
                    # into the limit (anti-windup)
                    if (u > tmax and e > 0) or (u < -tmax and e < 0):
                        integ = self._integ
                    self._integ = max(-tmax, min(tmax, integ))
                    u = kv * e + self._integ + toff
                if u > tmax:
                    u = tmax
                    self.limited = True
                elif u < -tmax:
                    u = -tmax
                    self.limited = True
                self._torque_ref = u
                self.torque_nm += (u - self.torque_nm) * alpha
            else:
                self.torque_nm = 0.0
            # mechanics: semi-implicit Euler with Coulomb friction that never reverses the motion
            drive = self.torque_nm + self.load_torque - b * w
            if self._rng is not None:
                drive += self._rng.gauss(0.0, p.torque_noise)
            w_new = _coulomb_step(w, drive, tc, J, h)
            self.omega = w_new
            self.turns += w_new * h / TWO_PI
        self.time += dt

    def _constants(self, dt: float) -> tuple:
        """(n, h, J, b, tc, cpr, k, kv, ki, kp, vmax, tmax, rated, alpha) of a step of dt seconds:
        n substeps of h, the parameters, the speed and torque limits in effect and the current
        loop's factor. They depend on dt and the limits only (the parameters are frozen), so
        they are computed once per (dt, limits); DC pulse times vary in their last bits, so a
        few step lengths are kept."""
        key = (dt, self.torque_limit, self.speed_limit)
        c = self._constants_of.get(key)
        if c is None:
            if len(self._constants_of) >= 8:
                self._constants_of.clear()
            c = self._constants_of[key] = self._compute_constants(dt)
        return c

    def _compute_constants(self, dt: float) -> tuple:
        n = max(1, math.ceil(dt / self.substep - 1e-9))
        h = dt / n
        p = self.params
        vmax = self.max_speed if self.speed_limit is None else min(self.max_speed, self.speed_limit)
        tmax = p.max_torque
        if self.torque_limit is not None:
            tmax = min(tmax, max(0.0, self.torque_limit) * p.rated_torque / 1000.0)
        alpha = 1.0 if p.current_tau <= 0 else 1.0 - math.exp(-h / p.current_tau)
        J, b, tc, kp, rated = p.inertia, p.viscous_friction, p.coulomb_friction, p.position_kp, p.rated_torque
        return (n, h, J, b, tc, self.cpr, self.k, self.kv, self.ki, kp, vmax, tmax, rated, alpha)

    def _step_following(self, constants: tuple) -> None:
        """The loop of `step` for an enabled motor in CSP or CSV without noise, with the state in
        locals and `_coulomb_step` inlined (the common case of a running axis; the same arithmetic
        in the same order, so the same bits, about three times as fast).

        A step that leaves the state as it found it is a fixed point (an axis holding still): a
        later step with the same inputs from that state changes nothing either, and is skipped.
        (The inputs are kept for a few step lengths: DC pulse times vary in their last bits.)"""
        state: tuple = (self.omega, self.turns, self.torque_nm, self._integ, self._torque_ref, self._demand)
        state += (self._ip_start, self._ip_target, self._ip_period, self._ip_elapsed)
        inputs: tuple | None = None
        if self._rest_state is not None:
            if self._rest_state == state:
                inputs = (constants, self.mode, self.torque_offset, self.velocity_offset, self.load_torque)
                inputs += (self.target_velocity,)
                limited = self._rest_inputs.get(inputs)
                if limited is not None:
                    self.limited = limited
                    return
            else:
                self._rest_state = None
                self._rest_inputs = {}
        n, h, J, b, tc, cpr, k, kv, ki, kp, vmax, tmax, rated, alpha = constants
        csp = self.mode == CSP
        w, turns, torque, integ0 = self.omega, self.turns, self.torque_nm, self._integ
        demand, ip_start, ip_target = self._demand, self._ip_start, self._ip_target
        ip_period, ip_elapsed = self._ip_period, self._ip_elapsed
        toff = self.torque_offset * rated / 1000.0
        voff = self.velocity_offset
        load = self.load_torque
        vtarget = (self.target_velocity + voff) / k
        span = ip_target - ip_start
        slope = span / ip_period if ip_period > 0.0 else 0.0
        limited = False
        u = self._torque_ref
        floor = math.floor
        two_pi, nvmax, ntmax, ntc = TWO_PI, -vmax, -tmax, -tc
        interpolating = ip_period > 0.0
        for _ in range(n):
            if csp:
                err = demand - floor(turns * cpr)
                if interpolating and ip_elapsed < ip_period:
                    before = ip_elapsed
                    ip_elapsed = before + h
                    frac = ip_elapsed / ip_period
                    demand = ip_start + span * (frac if frac < 1.0 else 1.0)
                    rest = ip_period - before  # slope · min(h, rest) / h; h / h is exactly 1
                    vref = ((slope if h < rest else slope * (rest / h)) + kp * err + voff) / k
                else:
                    demand = ip_target
                    vref = (0.0 + kp * err + voff) / k
            else:
                vref = vtarget
            if vref > vmax:
                vref = vmax
                limited = True
            elif vref < nvmax:
                vref = nvmax
                limited = True
            e = vref - w
            kve = kv * e
            integ = integ0 + ki * e * h
            u = kve + integ + toff
            # anti-windup: the integrator frozen while pushing into the limit, and clamped; the
            # torque is computed again only when that changed the integrator
            if (u > tmax and e > 0) or (u < ntmax and e < 0):
                integ0 = ntmax if integ0 < ntmax else (tmax if integ0 > tmax else integ0)
                u = kve + integ0 + toff
            elif integ < ntmax or integ > tmax:
                integ0 = ntmax if integ < ntmax else tmax
                u = kve + integ0 + toff
            else:
                integ0 = integ
            if u > tmax:
                u = tmax
                limited = True
            elif u < ntmax:
                u = ntmax
                limited = True
            torque += (u - torque) * alpha
            drive = torque + load - b * w
            # _coulomb_step(w, drive, tc, J, h), inline
            if w > 0.0:
                w = w + (drive - tc) / J * h
                if w < 0.0 and ntc <= drive <= tc:
                    w = 0.0
            elif w < 0.0:
                w = w + (drive + tc) / J * h
                if w > 0.0 and ntc <= drive <= tc:
                    w = 0.0
            elif drive > tc:
                w = (drive - tc) / J * h
            elif drive < ntc:
                w = (drive + tc) / J * h
            else:
                w = 0.0
            turns += w * h / two_pi
        self.omega, self.turns, self.torque_nm, self._integ, self._torque_ref = w, turns, torque, integ0, u
        self._demand, self._ip_elapsed = demand, ip_elapsed
        self.limited = limited
        if w == state[0] and turns == state[1] and (torque, integ0, u, demand, ip_elapsed) == state[2:6] + state[9:]:
            if inputs is None:
                inputs = (constants, self.mode, self.torque_offset, self.velocity_offset, self.load_torque)
                inputs += (self.target_velocity,)
            if self._rest_state != state or len(self._rest_inputs) >= 8:
                self._rest_state, self._rest_inputs = state, {}
            self._rest_inputs[inputs] = limited
