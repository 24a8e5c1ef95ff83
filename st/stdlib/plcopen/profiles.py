"""Motion profiles: exact acceleration-limited (trapezoid) plans written here, jerk-limited via ruckig.

PLCopen's Acceleration bounds the *speed magnitude rising*, Deceleration the speed magnitude
falling, whatever the sign of the velocity. A profile is a list of constant-acceleration segments
(trapezoid) or a ruckig trajectory; both answer `sample(t) -> (position, velocity, acceleration)`
and have a `duration`. Plans always start from the axis's *set* state, never from the measured one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

EPS = 1e-12


@dataclass
class Segment:
    t0: float  # start time within the profile
    p0: float
    v0: float
    a: float
    dt: float

    def at(self, t: float):
        tau = t - self.t0
        return self.p0 + self.v0 * tau + 0.5 * self.a * tau * tau, self.v0 + self.a * tau, self.a


@dataclass
class Profile:
    """Constant-acceleration pieces, exact in closed form."""

    p0: float
    v0: float
    segments: list = field(default_factory=list)
    end_velocity: float = 0.0  # what the plan actually reaches (a blending hand-over may be lower)

    @property
    def duration(self) -> float:
        return self.segments[-1].t0 + self.segments[-1].dt if self.segments else 0.0

    @property
    def end(self):
        if not self.segments:
            return self.p0, self.v0, 0.0
        s = self.segments[-1]
        p, v, _ = s.at(s.t0 + s.dt)
        return p, v, 0.0

    def add(self, a: float, dt: float) -> None:
        if dt <= EPS:
            return
        p, v, _ = self.end
        t0 = self.duration
        self.segments.append(Segment(t0, p, v, a, dt))

    def sample(self, t: float):
        """(p, v, a) at time t; past the end the final velocity is held (MoveVelocity)."""
        if not self.segments:
            return self.p0 + self.v0 * max(t, 0.0), self.v0, 0.0
        if t <= 0:
            return self.p0, self.v0, 0.0
        for s in self.segments:
            if t < s.t0 + s.dt:
                return s.at(t)
        p, v, _ = self.end
        return p + v * (t - self.duration), v, 0.0

    def extrema(self):
        """(min, max) position over the profile (at segment ends and velocity zero crossings)."""
        pts = [self.p0, self.end[0]]
        for s in self.segments:
            pts.append(s.p0)
            if s.a != 0:
                tau = -s.v0 / s.a
                if 0 < tau < s.dt:
                    pts.append(s.at(s.t0 + tau)[0])
        return min(pts), max(pts)


def _speed_change(prof: Profile, target_v: float, acc: float, dec: float) -> None:
    """Append segments taking the velocity from its current value to target_v with PLCopen's
    acceleration (magnitude rising) and deceleration (magnitude falling) limits."""
    _, v, _ = prof.end
    if v != 0 and (target_v == 0 or (v > 0) != (target_v > 0)):
        prof.add(-math.copysign(dec, v), abs(v) / dec)  # through zero first, with Dec
        v = 0.0
    if abs(target_v) > abs(v):
        prof.add(math.copysign(acc, target_v), (abs(target_v) - abs(v)) / acc)
    elif abs(target_v) < abs(v):
        prof.add(-math.copysign(dec, v), (abs(v) - abs(target_v)) / dec)


def velocity_profile(p0: float, v0: float, target_v: float, acc: float, dec: float) -> Profile:
    """MoveVelocity, Halt (target 0) and Stop (target 0): ramp to target_v, then hold it."""
    prof = Profile(p0, v0)
    _speed_change(prof, target_v, acc, dec)
    prof.end_velocity = target_v
    return prof


def position_profile(
    p0: float, v0: float, target: float, vmax: float, acc: float, dec: float, end_v: float = 0.0
) -> Profile:
    """The time-optimal trapezoid from (p0, v0) to `target`, cruising at most at vmax, arriving with
    speed |end_v| in the direction of travel (0 for a stop at the target). A start faster than vmax
    first slows to vmax; a start moving away from the target, or too fast to stop in time, brakes to
    zero (overshooting) and comes back."""
    prof = Profile(p0, v0)
    _plan_position(prof, target, vmax, acc, dec, abs(end_v))
    return prof


def _plan_position(prof: Profile, target: float, vmax: float, acc: float, dec: float, ue: float) -> None:
    for _ in range(4):  # at most: brake, reverse, and the final trapezoid
        p, v, _ = prof.end
        d = target - p
        if abs(d) <= EPS and abs(v) <= EPS:
            prof.end_velocity = 0.0
            return
        s = 1.0 if d > 0 or (d == 0 and v > 0) else -1.0
        L, u0 = abs(d), s * v
        if u0 < 0:  # moving away from the target: stop first
            prof.add(s * dec, -u0 / dec)
            continue
        if u0 > vmax + EPS:  # faster than allowed: slow down to vmax first
            t = (u0 - vmax) / dec
            dist = (u0 + vmax) / 2 * t
            if dist <= L:
                prof.add(-s * dec, t)
                continue
        ue_eff = min(ue, vmax)
        brake = (u0 * u0 - ue_eff * ue_eff) / (2 * dec) if u0 > ue_eff else 0.0
        if brake > L + 1e-12:  # too fast to reach the hand-over speed (or a stop) in time
            if ue_eff > 0:  # blending: arrive faster than asked, braking all the way
                arrive = math.sqrt(u0 * u0 - 2 * dec * L)
                prof.add(-s * dec, (u0 - arrive) / dec)
                prof.end_velocity = s * arrive
                _snap(prof, target)
                return
            prof.add(-s * dec, u0 / dec)  # stop beyond the target, then come back
            continue
        if u0 < ue_eff and (ue_eff * ue_eff - u0 * u0) / (2 * acc) >= L:
            reach = math.sqrt(u0 * u0 + 2 * acc * L)  # accelerate all the way, arriving slower
            prof.add(s * acc, (reach - u0) / acc)
            prof.end_velocity = s * reach
            _snap(prof, target)
            return
        # peak speed: accelerate (acc) to up, cruise, decelerate (dec) to ue_eff
        up2 = (L + u0 * u0 / (2 * acc) + ue_eff * ue_eff / (2 * dec)) / (1 / (2 * acc) + 1 / (2 * dec))
        up = max(min(math.sqrt(max(up2, 0.0)), vmax), u0, ue_eff)
        d_acc = (up * up - u0 * u0) / (2 * acc) if up > u0 else 0.0
        d_dec = (up * up - ue_eff * ue_eff) / (2 * dec) if up > ue_eff else 0.0
        cruise = max(L - d_acc - d_dec, 0.0)
        if up > u0:
            prof.add(s * acc, (up - u0) / acc)
        if cruise > EPS and up > EPS:
            prof.add(0.0, cruise / up)
        if up > ue_eff:
            prof.add(-s * dec, (up - ue_eff) / dec)
        prof.end_velocity = s * ue_eff
        _snap(prof, target)
        return
    prof.end_velocity = 0.0


def _snap(prof: Profile, target: float) -> None:
    """Remove the rounding of the closed form: the last segment ends exactly at the target."""
    if prof.segments:
        s = prof.segments[-1]
        p_end = s.at(s.t0 + s.dt)[0]
        s.p0 += target - p_end


class RuckigProfile:
    """A jerk-limited plan through ruckig (Jerk > 0), staged so that PLCopen's Acceleration and
    Deceleration keep their meaning: while the speed must fall (or reverse) the stage uses Dec on
    both sides, then the final stage uses Acc rising / Dec falling for a move in one direction."""

    def __init__(self, p0, v0, a0, *, target=None, target_v=0.0, vmax=0.0, acc=1.0, dec=1.0, jerk=1.0, end_v=0.0):
        from ruckig import ControlInterface, InputParameter, Ruckig, Trajectory

        self.stages = []
        p, v, a = p0, v0, a0
        t0 = 0.0

        def plan(interface, tp=None, tv=0.0, max_a=1.0, min_a=-1.0, vlim=None):
            nonlocal p, v, a, t0
            inp = InputParameter(1)
            inp.current_position, inp.current_velocity, inp.current_acceleration = [p], [v], [a]
            inp.max_jerk = [jerk]
            inp.max_acceleration, inp.min_acceleration = [max_a], [min_a]
            if interface == "position":
                inp.target_position, inp.target_velocity = [tp], [tv]
                inp.max_velocity = [vlim]
            else:
                inp.control_interface = ControlInterface.Velocity
                inp.target_velocity = [tv]
                inp.max_velocity = [max(abs(tv), abs(v)) + 1.0]
            traj = Trajectory(1)
            Ruckig(1).calculate(inp, traj)
            self.stages.append((t0, traj))
            t0 += traj.duration
            p, v, a = (x[0] for x in traj.at_time(traj.duration))

        if target is None:  # velocity goal
            if v != 0 and (target_v == 0 or (v > 0) != (target_v > 0) or abs(target_v) < abs(v)):
                stop_at = 0.0 if (target_v == 0 or (v > 0) != (target_v > 0)) else target_v
                plan("velocity", tv=stop_at, max_a=dec, min_a=-dec)
            if abs(target_v - v) > 1e-12:
                plan("velocity", tv=target_v, max_a=acc, min_a=-acc)
        else:
            d = target - p
            if v * d < 0:  # moving away: brake to zero first
                plan("velocity", tv=0.0, max_a=dec, min_a=-dec)
                d = target - p
            up = d >= 0
            plan(
                "position",
                tp=target,
                tv=math.copysign(abs(end_v), d) if end_v else 0.0,
                max_a=acc if up else dec,
                min_a=-dec if up else -acc,
                vlim=vmax,
            )
        self.duration = t0
        self.end_velocity = v
        self.p0, self.v0 = p0, v0

    def sample(self, t: float):
        """(p, v, a) at time t; past the end the final velocity is held (MoveVelocity)."""
        if t > self.duration and self.stages:
            p, v, _ = self.sample(self.duration)
            return p + v * (t - self.duration), v, 0.0
        for t0, traj in reversed(self.stages):
            if t >= t0:
                pv = traj.at_time(min(t - t0, traj.duration))
                return pv[0][0], pv[1][0], pv[2][0]
        return self.p0 + self.v0 * max(t, 0.0), self.v0, 0.0

    @property
    def end(self):
        return self.sample(self.duration)

    def extrema(self):
        lo, hi = [], []
        for _, traj in self.stages:
            e = traj.position_extrema[0]
            lo.append(e.min)
            hi.append(e.max)
        return (min(lo), max(hi)) if lo else (self.p0, self.p0)
