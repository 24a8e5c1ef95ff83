"""One PLCopen axis: the state machine, the command ledger, the buffer and the per-cycle kernel.

Execution model (pinned by tests): in each cycle the programs run first; an FB call submits its
command to the axis, which changes state at once (a later MC_ReadStatus in the same scan sees
it). After the task's job the kernel advances every axis of that task by one cycle: the active
profile is sampled at k × cycle; when it has run ceil(T / cycle) cycles it is finished, its
command is Done and a buffered successor becomes active in the same cycle. A profile of
duration T started in cycle n therefore reports Done in the FB call of cycle n + ceil(T / cycle).

Positions are user units, times seconds. A virtual axis's actual values follow its set values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from .errors import E
from .profiles import Profile, RuckigProfile, position_profile, velocity_profile

DISABLED, STANDSTILL, HOMING, DISCRETE, CONTINUOUS, STOPPING, ERRORSTOP = (
    "Disabled",
    "Standstill",
    "Homing",
    "DiscreteMotion",
    "ContinuousMotion",
    "Stopping",
    "ErrorStop",
)

ABORTING, BUFFERED, BLEND_LOW, BLEND_PREVIOUS, BLEND_NEXT, BLEND_HIGH = range(6)
IMMEDIATE_MODE, DELAYED_MODE, QUEUED_MODE = range(3)  # MC_EXECUTION_MODE
POSITIVE, SHORTEST, NEGATIVE, CURRENT = range(4)

QUEUED, ACTIVE, DONE, ABORTED, ERROR = "queued", "active", "done", "aborted", "error"


class Drive(Protocol):
    """A drive that moves an axis (EtherCAT's DriveLink): claimed for its AxisNo with
    MotionRegistry.add_drive, attached as `Axis.drive`. An axis without one is virtual."""

    axis_no: int
    axis: Axis | None

    @property
    def enabled(self) -> bool: ...  # the power stage is on (CiA 402 Operation Enabled)

    @property
    def faulted(self) -> bool: ...  # the drive is in Fault (or its fault reaction)

    @property
    def readable(self) -> bool: ...  # its actual values came with the last exchange (frames, OP)

    @property
    def error_code(self) -> int: ...  # the drive's own error code (CiA 402 0x603F), 0 if none

    def attach(self, ax: Axis) -> None: ...

    def request_enable(self, on: bool) -> None: ...

    def fault_reset(self) -> None: ...

    def shift(self, delta: float) -> None: ...  # the axis coordinate moves by delta units, the motor does not


@dataclass
class AxisConfig:
    """What a project file (or the defaults) says about one axis."""

    name: str = ""
    units_per_rev: float = 360.0  # user units per motor revolution (drives)
    increments_per_unit: float = 0.0  # drive increments per user unit (0: encoder increments / units_per_rev)
    modulo: float = 0.0  # period of a modulo axis (0: linear)
    max_velocity: float = math.inf
    max_acceleration: float = math.inf
    max_deceleration: float = math.inf
    stop_deceleration: float = 0.0  # the ramp used on entering ErrorStop (0: max_deceleration or 10 × the last)
    sw_limit_min: float = -math.inf
    sw_limit_max: float = math.inf
    following_error_window: float = math.inf
    enable_timeout: float = 2.0  # s
    reset_timeout: float = 1.0  # s: MC_Reset on a drive waits this long for it to leave Fault
    enable_delay: float = 0.0  # simulated drive: seconds until the power stage is on (inf: never)
    buffer_size: int = 8
    # MC_SetPosition during a motion: "keep_target" (PLCopen: the commanded position of an absolute
    # move is kept, now in the shifted coordinates, and the rest of the move is planned from where
    # the axis is) or "keep_trajectory" (CODESYS SM3: the drive is sent what it would have been sent
    # without the shift; the absolute target moves with the coordinate)
    set_position_in_motion: str = "keep_target"
    # MC_Home: "current" references at the current position; "switch" moves at home_velocity in
    # home_direction (+1/-1) until a reference switch changes, latches there, brakes and shifts
    # the coordinates so that the switch edge is at MC_Home.Position. The switch is a BOOL variable
    # (home_switch = "prog.var") or, on a virtual axis, a cam at home_switch_position that is
    # active on the side the search moves towards. If the switch is already active at the start,
    # the search runs the other way to the edge where it goes inactive (CiA 402 homing on a switch).
    homing: str = "current"
    home_switch: str = ""
    home_switch_position: float = math.nan
    home_direction: int = -1
    home_velocity: float = 10.0
    home_acceleration: float = 100.0
    home_search_distance: float = math.inf  # no edge within this distance: ErrorStop HOMING_FAILED


class _Shifted:
    """A planned profile moved by `delta` units (MC_SetPosition during a motion): the same
    trajectory in the new coordinates."""

    def __init__(self, inner, delta: float):
        self.inner, self.delta = inner, delta

    def sample(self, t: float) -> tuple[float, float, float]:
        p, v, a = self.inner.sample(t)
        return p + self.delta, v, a

    def __getattr__(self, name: str):
        return getattr(self.inner, name)


@dataclass(eq=False)
class Command:
    id: int
    kind: str  # move_abs, move_rel, move_vel, halt, stop, home, set_pos
    params: dict
    buffer_mode: int = ABORTING
    status: str = QUEUED
    error_id: int = 0
    in_velocity: bool = False
    profile: Profile | RuckigProfile | _Shifted | None = None
    steps: int = 0  # kernel cycles run
    total_steps: int = 0  # cycles the profile needs
    target: float = 0.0
    end_v: float = 0.0
    execute_low: bool = False  # MC_Stop: its Execute has been seen FALSE
    shown: bool = False  # the terminal status was reported while Execute was TRUE
    continuous_update: bool = False

    @property
    def terminal(self) -> bool:
        return self.status in (DONE, ABORTED, ERROR)


@dataclass(frozen=True)
class AxisView:
    """One axis as the blocks saw it in a scan: taken when the job that commands it ends, before
    the kernel advances it, so a read block called at the end of that job shows the same."""

    name: str
    axis_no: int
    state: str  # PLCopen state: Disabled, Standstill, Homing, DiscreteMotion, ContinuousMotion, Stopping, ErrorStop
    set_position: float
    set_velocity: float
    set_acceleration: float
    actual_position: float
    actual_velocity: float
    power: bool  # MC_Power.Status
    axis_error: int  # st's ErrorID of the axis error (MC_ReadAxisError.StAxisErrorID), 0 if none
    drive_error: int  # the drive's own error code (CiA 402 0x603F), 0 without a drive or an error
    drive_state: str  # the drive's CiA 402 state ("" on a virtual axis)
    readable: bool  # the drive's values are current (False during a communication outage)


class Axis:
    def __init__(self, handle: int, config: AxisConfig | None = None):
        self.handle = handle
        self.cfg = config or AxisConfig()
        self.state = DISABLED
        self.set_pos = self.set_vel = self.set_acc = 0.0
        self.act_pos = self.act_vel = 0.0
        self.active: Command | None = None
        self.queue: list = []
        self.stop_cmd: Command | None = None
        self.power_owner = 0  # id of the MC_Power instance that owns the axis
        self.power_on = False  # MC_Power.Status
        self.power_request = False
        self.power_wait = 0.0  # seconds waited for the power stage
        self.axis_error = 0  # ErrorID of the pending axis error (MC_ReadAxisError)
        self.last_dir = 1.0
        self.cycle = 0.0  # s, set by the task that calls the axis's FBs
        self.task = None
        self._next_id = 1
        self.commands: dict = {}  # id → Command, for the FBs' ledgers
        self.drive: Drive | None = None  # an attached drive (EtherCAT); None: virtual axis
        self.home_signal = None  # callable → bool: the reference switch (config home_switch)
        self.axis_no = 0
        self.last_seen: tuple | None = None  # the view's fields at the end of the last job that commanded it
        self.reset_cmd: Command | None = None  # MC_Reset waiting for the drive to leave Fault
        self.reset_wait = 0.0
        self.delayed: list = []  # MC_SetPosition mcDelayed: (command, the motion it waits for)

    # ------------------------------------------------------------------ helpers
    def new_command(self, kind: str, params: dict, buffer_mode: int = ABORTING) -> Command:
        cmd = Command(self._next_id, kind, params, buffer_mode)
        self._next_id += 1
        self.commands[cmd.id] = cmd
        return cmd

    def forget(self, cmd_id: int) -> None:
        self.commands.pop(cmd_id, None)

    def _fail(self, cmd: Command, code: int) -> Command:
        cmd.status, cmd.error_id = ERROR, code
        return cmd

    def _abort_all(self, status=ABORTED, code=0) -> None:
        for c in ([self.active] if self.active else []) + self.queue:
            if not c.terminal:
                c.status, c.error_id, c.in_velocity = status, code, False
        self.active = None
        self.queue = []

    @property
    def modulo(self) -> float:
        return self.cfg.modulo

    def position(self) -> float:
        """The set position as the user sees it (wrapped on a modulo axis)."""
        return self.set_pos % self.modulo if self.modulo else self.set_pos

    def actual_position(self) -> float:
        return self.act_pos % self.modulo if self.modulo else self.act_pos

    def view(self) -> AxisView:
        return AxisView(*self.seen())

    @property
    def last_view(self) -> AxisView | None:
        """The view at the end of the last job that commanded the axis (built when asked for)."""
        return AxisView(*self.last_seen) if self.last_seen is not None else None

    def seen(self) -> tuple:
        """The fields of `view()`, as a tuple (the kernel keeps one per job; few are looked at)."""
        d = self.drive
        m = self.cfg.modulo
        return (
            self.cfg.name,
            self.axis_no,
            self.state,
            self.set_pos % m if m else self.set_pos,  # position()
            self.set_vel,
            self.set_acc,
            self.act_pos % m if m else self.act_pos,  # actual_position()
            self.act_vel,
            d.enabled if d is not None else self.power_on,  # _power_status()
            int(self.axis_error),
            d.error_code if d is not None else 0,
            str(getattr(d, "state", "")) if d is not None else "",
            d.readable if d is not None else True,
        )

    # ------------------------------------------------------------------ power, reset, errors
    def power(self, fb_id: int, enable: bool):
        """MC_Power, every call: returns (status, error_id). In ErrorStop the power stage is kept if
        it is on but never switched on: after a loss of the power stage (a drive fault, Safe Torque
        Off, the drive dropping out of Operation Enabled, lost communication) it comes back only
        once MC_Reset has left ErrorStop and Enable is (still or again) TRUE."""
        if self.power_owner and self.power_owner != fb_id:
            return False, E.POWER_ALREADY_ACTIVE if enable else 0
        if not enable:
            if self.power_owner == fb_id:
                self.power_owner = 0
            self.power_request = False
            if self.drive is not None:
                self.drive.request_enable(False)
            if self.power_on or self.state != DISABLED:
                self.power_on = False
                if self.state != ERRORSTOP:
                    self._abort_all()
                    if self.stop_cmd is not None and self.stop_cmd.status in (ACTIVE, DONE):
                        self.stop_cmd.status = ABORTED  # decelerating, or held with Done showing
                    self.stop_cmd = None
                    self.state = DISABLED
                self.set_vel = self.set_acc = 0.0
            return self._power_status(), 0
        self.power_owner = fb_id
        if self.state == ERRORSTOP:
            if self.drive is not None:
                self.drive.request_enable(self.power_on)  # held if on, never switched on
            return self._power_status(), 0
        if self.drive is not None:
            self.drive.request_enable(True)
        if not self.power_on:
            if not self.power_request:
                self.power_request, self.power_wait = True, 0.0
            ready = self.drive.enabled if self.drive is not None else self.power_wait >= self.cfg.enable_delay - 1e-9
            if ready:
                self.power_on = True
                self.set_pos, self.set_vel, self.set_acc = self.act_pos, 0.0, 0.0
                if self.state == DISABLED:
                    self.state = STANDSTILL
            elif self.power_wait >= self.cfg.enable_timeout - 1e-9:
                return self._power_status(), E.ENABLE_TIMEOUT
        return self._power_status(), 0

    def _power_status(self) -> bool:
        """MC_Power.Status: the power stage as it is, on a drive its statusword (Operation
        Enabled), which lags the Enable request by the drive's own transitions."""
        return self.drive.enabled if self.drive is not None else self.power_on

    def error_stop(self, code: int) -> None:
        """An axis error: ErrorStop now; the active and every buffered command report Error."""
        if self.state == ERRORSTOP:
            return
        self._abort_all(ERROR, E.AXIS_ERRORSTOP)
        if self.stop_cmd is not None and self.stop_cmd.status in (ACTIVE, DONE):
            self._fail(self.stop_cmd, E.AXIS_ERRORSTOP)  # decelerating, or held with Done showing
        self.stop_cmd = None
        for sp, _motion in self.delayed:  # a SetPosition waiting for the motion's end: not applied
            self._fail(sp, E.AXIS_ERRORSTOP)
        self.delayed = []
        self.axis_error = code
        self.state = ERRORSTOP
        self.power_request = False  # a power stage lost now is switched on again only after MC_Reset
        if self.drive is not None and not self.power_on:
            self.drive.request_enable(False)
        dec = self.cfg.stop_deceleration or (
            self.cfg.max_deceleration if math.isfinite(self.cfg.max_deceleration) else 0.0
        )
        self._ramp = velocity_profile(self.set_pos, self.set_vel, 0.0, 1.0, dec) if dec and self.set_vel else None
        self._ramp_t = 0.0
        if not self._ramp:
            self.set_vel = self.set_acc = 0.0

    def lose_power(self, code: int) -> None:
        """The power stage is gone (a drive fault, Safe Torque Off, the drive out of Operation
        Enabled, lost communication): ErrorStop with `code` (kept if already in ErrorStop), and
        the drive is told to stay off until MC_Reset."""
        self.power_on = False
        if self.drive is not None:
            self.drive.request_enable(False)
        self.error_stop(code)

    def reset(self, cmd: Command) -> Command:
        """MC_Reset. A virtual axis leaves ErrorStop at once; on a drive the fault reset goes out in
        this cycle and the command stays Busy until the drive has left Fault (the axis is then
        Disabled, and Standstill once MC_Power has the power stage on again), or ends with
        RESET_FAILED after `reset_timeout`, the axis staying in ErrorStop."""
        if self.state != ERRORSTOP:
            return self._fail(cmd, E.NO_ERROR_TO_RESET)
        if self.reset_cmd is not None and not self.reset_cmd.terminal:
            self.reset_cmd.status = ABORTED  # a new Execute edge takes over
        if self.drive is not None:
            self.drive.fault_reset()
            cmd.status = ACTIVE
            self.reset_cmd, self.reset_wait = cmd, 0.0
            self.reset_progress()
            return cmd
        self._leave_errorstop()
        cmd.status = DONE
        return cmd

    def _leave_errorstop(self) -> None:
        self.axis_error = 0
        self._ramp = None
        self.set_vel = self.set_acc = 0.0
        if self.drive is not None and not self.drive.enabled:
            self.power_on = False
        self.state = STANDSTILL if self.power_on else DISABLED

    def reset_progress(self) -> None:
        """A pending MC_Reset on a drive: Done as soon as an exchange shows the drive out of Fault
        (the drive link calls this when it has read the statusword, so the program sees the axis
        Disabled in the scan whose inputs show Switch On Disabled), failed at the timeout."""
        cmd, drive = self.reset_cmd, self.drive
        if cmd is None or cmd.terminal or drive is None:
            self.reset_cmd = None
            return
        if not drive.faulted:
            self._leave_errorstop()
            cmd.status = DONE
            self.reset_cmd = None
        elif self.reset_wait >= self.cfg.reset_timeout - 1e-9:
            self._fail(cmd, E.RESET_FAILED)
            self.reset_cmd = None

    # ------------------------------------------------------------------ submitting commands
    def submit(self, cmd: Command) -> Command:
        """Validate, then reject, abort-and-take-over, or buffer. The state changes at once."""
        code = self._validate(cmd)
        if code:
            return self._fail(cmd, code)
        st = self.state
        if cmd.kind == "stop":
            if st == ERRORSTOP:
                return self._fail(cmd, E.AXIS_ERRORSTOP)
            if st == DISABLED:
                return self._fail(cmd, E.AXIS_DISABLED)
            if st == STOPPING and self.stop_cmd is not None:
                return self._fail(cmd, E.STOP_ALREADY_ACTIVE)
            self._abort_all()
            self.stop_cmd = cmd
            self.state = STOPPING
            self._activate(cmd)
            return cmd
        if cmd.kind == "set_pos":
            if st not in (DISABLED, STANDSTILL, DISCRETE, CONTINUOUS, STOPPING):
                return self._fail(cmd, E.INVALID_STATE)  # not while homing, not in ErrorStop
            mode = cmd.params["mode"]
            moving = self.active is not None or bool(self.queue)
            if mode == QUEUED_MODE and moving and st in (DISCRETE, CONTINUOUS):
                cmd.buffer_mode = BUFFERED  # mcQueued: when the motion commanded before has ended
                if len(self.queue) >= self.cfg.buffer_size:
                    return self._fail(cmd, E.BUFFER_FULL)
                self.queue.append(cmd)
                return cmd
            ongoing = self.stop_cmd if st == STOPPING else self.active
            if mode == DELAYED_MODE and ongoing is not None and not ongoing.terminal:
                self.delayed.append((cmd, ongoing))  # mcDelayed: when the ongoing motion ends
                return cmd
            self._set_position(cmd)
            return cmd
        blocked = {
            DISABLED: E.AXIS_DISABLED,
            ERRORSTOP: E.AXIS_ERRORSTOP,
            STOPPING: E.AXIS_STOPPING,
            HOMING: E.AXIS_HOMING,
        }.get(st)
        if blocked:
            return self._fail(cmd, blocked)
        if cmd.kind == "home":
            if st != STANDSTILL:
                return self._fail(cmd, E.INVALID_STATE)
            self.state = HOMING
            self._activate(cmd)
            return cmd
        if cmd.buffer_mode == ABORTING or self.active is None:
            self._abort_all()
            self._activate(cmd)
            return cmd
        if len(self.queue) >= self.cfg.buffer_size:
            return self._fail(cmd, E.BUFFER_FULL)
        self.queue.append(cmd)
        if cmd.buffer_mode != BUFFERED and len(self.queue) == 1:
            self._replan_for_blend()
        return cmd

    def update_failed(self, cmd: Command, code: int, valid: dict) -> None:
        """ContinuousUpdate with an invalid input: the command ends with Error `code`. Buffered,
        it leaves the queue; active, its buffered successor starts now, as after the end of the
        command, or without one the axis halts with the command's last valid deceleration and
        jerk (DiscreteMotion, then Standstill)."""
        self._fail(cmd, code)
        if cmd in self.queue:
            self.queue.remove(cmd)
            return
        if cmd is not self.active:
            return
        self.active = None
        if self.queue:
            self._next()
            return
        halt = Command(0, "halt", {"dec": valid.get("dec", 0.0), "jerk": valid.get("jerk", 0.0)}, ABORTING)
        if self._validate(halt):  # no valid deceleration to use: the axis's own stop ramp
            halt.params["dec"] = self.cfg.stop_deceleration or self.cfg.max_deceleration
        if self._validate(halt):  # none configured either: the set velocity stops at once
            self.set_vel = self.set_acc = 0.0
            self.state = STANDSTILL
            return
        self.state = DISCRETE
        self._activate(halt)

    def _set_position(self, cmd: Command) -> None:
        """MC_SetPosition: the commanded coordinate becomes Position (or moves by it, Relative), and
        the actual one with it; the motor stays."""
        p = cmd.params
        self.shift_coordinates(p["position"] if p["relative"] else p["position"] - self.set_pos)
        cmd.status = DONE

    def shift_coordinates(self, delta: float) -> None:
        """Move the axis's coordinate system by `delta` units: set and actual positions change
        together and a drive only changes the offset between its increments and the axis's
        units, so its target and its position do not jump. A motion under way goes on from where
        the axis is: an absolute move to its commanded position, now in the new coordinates
        (PLCopen; re-planned from the set state, so nothing jumps), unless the axis is configured
        `set_position_in_motion = "keep_trajectory"` (CODESYS SM3: the same trajectory, moved with
        the coordinate); every other motion keeps its trajectory (a relative move its distance)."""
        if not delta:
            return
        self.set_pos += delta
        self.act_pos += delta
        if self.drive is not None:
            self.drive.shift(delta)
        keep_target = self.cfg.set_position_in_motion != "keep_trajectory"
        for cmd in (self.active, self.stop_cmd):
            if cmd is None or cmd.terminal or cmd.profile is None:
                continue
            if keep_target and cmd.kind == "move_abs":
                self._replan_to_target(cmd)
                continue
            cmd.profile = _Shifted(cmd.profile, delta)
            if cmd.kind in ("move_abs", "move_rel"):
                cmd.target += delta
                if "_start" in cmd.params:
                    cmd.params["_start"] += delta

    def _replan_to_target(self, cmd: Command) -> None:
        """An active absolute move planned again from the set state to its commanded position (on a
        modulo axis: the way its Direction says, from where the axis is now)."""
        cmd.target = self._target(cmd, self.set_pos)
        vmax, acc, dec, jerk = self._limits(cmd)
        if cmd.end_v:  # blending into a successor: the hand-over speed stays
            vmax = max(vmax, abs(cmd.end_v))
        cmd.profile = self._plan_position(cmd.target, vmax, acc, dec, jerk, cmd.end_v)
        cmd.end_v = cmd.profile.end_velocity
        cmd.steps = 0
        cmd.total_steps = self._steps(cmd.profile.duration)

    def _apply_delayed(self) -> None:
        """MC_SetPosition mcDelayed: applied once the motion it waits for has ended (Done, or
        aborted by another command or by Enable FALSE); ErrorStop fails it (error_stop)."""
        if not self.delayed:
            return
        waiting = []
        for sp, motion in self.delayed:
            if motion.terminal:
                self._set_position(sp)
            else:
                waiting.append((sp, motion))
        self.delayed = waiting

    def _validate(self, cmd: Command) -> int:
        p = cmd.params
        for key, code in (("acc", E.INVALID_ACCELERATION), ("dec", E.INVALID_DECELERATION)):
            if key in p and not (p[key] > 0 and math.isfinite(p[key])):
                return code
        if "jerk" in p and not (p["jerk"] >= 0 and not math.isnan(p["jerk"])):
            return E.INVALID_JERK
        if cmd.kind in ("move_abs", "move_rel"):
            if not (p["vel"] > 0 and math.isfinite(p["vel"])):
                return E.INVALID_VELOCITY
        if cmd.kind == "move_vel" and not math.isfinite(p["vel"]):
            return E.INVALID_VELOCITY
        if cmd.kind == "move_abs":
            pos = p["pos"]
            if not math.isfinite(pos) or (self.modulo and not 0 <= pos < self.modulo):
                return E.INVALID_POSITION
            if p["dir"] not in (POSITIVE, SHORTEST, NEGATIVE, CURRENT):
                return E.INVALID_DIRECTION
        if cmd.kind == "move_rel" and not math.isfinite(p["dist"]):
            return E.INVALID_POSITION
        if cmd.kind == "move_vel" and p.get("dir", POSITIVE) not in (POSITIVE, NEGATIVE, CURRENT):
            return E.INVALID_DIRECTION
        if not 0 <= cmd.buffer_mode <= 5:
            return E.INVALID_BUFFER_MODE
        if cmd.kind == "set_pos" and p["mode"] not in (IMMEDIATE_MODE, DELAYED_MODE, QUEUED_MODE):
            return E.INVALID_EXECUTION_MODE
        if cmd.kind == "home":
            if not math.isfinite(p["pos"]):
                return E.INVALID_POSITION
            if self.cfg.homing == "switch" and self.home_signal is None and math.isnan(self.cfg.home_switch_position):
                return E.HOMING_NOT_CONFIGURED
        if cmd.kind in ("move_abs", "move_rel"):
            tgt = self._target(cmd, self._start_pos_for(cmd))
            lo, hi = self.cfg.sw_limit_min, self.cfg.sw_limit_max
            if not self.modulo and not lo <= tgt <= hi:
                return E.SW_LIMIT_TARGET
        return 0

    def _start_pos_for(self, cmd: Command) -> float:
        """Where a command starts: now (aborting), or where the last queued/active command ends."""
        if cmd.buffer_mode == ABORTING or self.active is None:
            return self.set_pos
        last = self.queue[-1] if self.queue else self.active
        return last.target if last.kind in ("move_abs", "move_rel") else self.set_pos

    def _target(self, cmd: Command, start: float) -> float:
        p = cmd.params
        if cmd.kind == "move_rel":
            return start + p["dist"]
        if not self.modulo:
            return p["pos"]
        period = self.modulo
        cur = start % period
        fwd = (p["pos"] - cur) % period
        back = fwd - period if fwd else 0.0
        d = p["dir"]
        if d == CURRENT:
            d = POSITIVE if (self.set_vel or self.last_dir) > 0 else NEGATIVE
        if d == POSITIVE:
            delta = fwd
        elif d == NEGATIVE:
            delta = back
        else:  # shortest; exactly half a period goes positive
            delta = fwd if fwd <= period / 2 else back
        return start + delta

    def _limits(self, cmd: Command):
        p = cmd.params
        c = self.cfg
        return (
            min(abs(p.get("vel", 0.0)) or c.max_velocity, c.max_velocity),
            min(p.get("acc", math.inf), c.max_acceleration),
            min(p.get("dec", math.inf), c.max_deceleration),
            p.get("jerk", 0.0),
        )

    def _activate(self, cmd: Command, end_v: float = 0.0) -> None:
        """Plan `cmd` from the current set state and make it the active command."""
        if self.delayed:  # the motion before has ended: a delayed SetPosition first
            self._apply_delayed()
        cmd.status = ACTIVE
        cmd.steps = 0
        vmax, acc, dec, jerk = self._limits(cmd)
        k = cmd.kind
        if k in ("move_abs", "move_rel"):
            if k == "move_rel":  # measured from the set position where the command starts
                cmd.params.setdefault("_start", self.set_pos)
                cmd.target = cmd.params["_start"] + cmd.params["dist"]
            else:
                cmd.target = self._target(cmd, self.set_pos)
            cmd.end_v = end_v
            cmd.profile = self._plan_position(cmd.target, vmax, acc, dec, jerk, end_v)
            self.state = DISCRETE
        elif k == "move_vel":
            v = cmd.params["vel"]
            d = cmd.params.get("dir", POSITIVE)
            if d == NEGATIVE:
                v = -v
            elif d == CURRENT:
                v = math.copysign(abs(v), self.set_vel or self.last_dir)
            cmd.target = v
            cmd.profile = self._plan_velocity(v, acc, dec, jerk)
            self.state = CONTINUOUS
        elif k in ("halt", "stop"):
            cmd.profile = self._plan_velocity(0.0, dec, dec, jerk)
            if k == "halt":
                self.state = DISCRETE
        elif k == "home":
            if self.cfg.homing == "switch":
                self._start_homing_search(cmd)
            else:
                cmd.profile = Profile(self.set_pos, 0.0)
        assert cmd.profile is not None  # every kind plans one (homing: its search ramp)
        cmd.total_steps = self._steps(cmd.profile.duration)
        self.active = cmd if k != "stop" else None
        if k == "stop":
            self.stop_cmd = cmd

    def _plan_position(self, target, vmax, acc, dec, jerk, end_v) -> Profile | RuckigProfile:
        if jerk > 0:
            return RuckigProfile(
                self.set_pos,
                self.set_vel,
                self.set_acc,
                target=target,
                vmax=vmax,
                acc=acc,
                dec=dec,
                jerk=jerk,
                end_v=end_v,
            )
        return position_profile(self.set_pos, self.set_vel, target, vmax, acc, dec, end_v)

    def _plan_velocity(self, v, acc, dec, jerk) -> Profile | RuckigProfile:
        if jerk > 0:
            return RuckigProfile(self.set_pos, self.set_vel, self.set_acc, target_v=v, acc=acc, dec=dec, jerk=jerk)
        return velocity_profile(self.set_pos, self.set_vel, v, acc, dec)

    # ------------------------------------------------------------------ homing on a switch
    def _switch(self) -> bool:
        if self.home_signal is not None:
            return bool(self.home_signal())
        x = self.cfg.home_switch_position
        return self.act_pos >= x if self.cfg.home_direction > 0 else self.act_pos <= x

    def _start_homing_search(self, cmd: Command) -> None:
        c = self.cfg
        direction = 1.0 if c.home_direction > 0 else -1.0
        want = True  # look for the switch becoming active
        if self._switch():  # already on it: leave it the other way
            direction, want = -direction, False
        cmd.params.update(_phase="search", _want=want, _from=self.act_pos)
        cmd.profile = velocity_profile(
            self.set_pos, self.set_vel, direction * abs(c.home_velocity), c.home_acceleration, c.home_acceleration
        )
        cmd.steps = 0

    def _step_homing(self, cmd: Command) -> None:
        """One cycle of a search for the reference switch, then the braking ramp, then the shift."""
        p = cmd.params
        cmd.steps += 1
        prev_act = self.act_pos
        assert cmd.profile is not None  # the search ramp, then the braking one
        self.set_pos, self.set_vel, self.set_acc = cmd.profile.sample(cmd.steps * self.cycle)
        self._follow()
        if p["_phase"] == "search":
            if self._switch() == p["_want"]:
                x = self.cfg.home_switch_position
                latch = (
                    x
                    if (self.home_signal is None and min(prev_act, self.act_pos) <= x <= max(prev_act, self.act_pos))
                    else self.act_pos
                )
                p["_shift"] = p["pos"] - latch
                p["_phase"] = "brake"
                cmd.profile = velocity_profile(
                    self.set_pos, self.set_vel, 0.0, self.cfg.home_acceleration, self.cfg.home_acceleration
                )
                cmd.steps = 0
            elif abs(self.act_pos - p["_from"]) > self.cfg.home_search_distance:
                self.error_stop(E.HOMING_FAILED)
            return
        if cmd.steps >= self._steps(cmd.profile.duration):
            self.shift_coordinates(p["_shift"])
            self.set_vel = self.set_acc = 0.0
            cmd.status = DONE
            self.active = None
            self.state = STANDSTILL

    def _steps(self, duration: float) -> int:
        if not self.cycle:
            return 0
        return max(0, math.ceil(duration / self.cycle - 1e-9))

    def _handover_velocity(self, prev: Command, nxt: Command) -> float:
        """The standard's hand-over speeds for the blending modes (signed in prev's direction)."""
        if prev.kind not in ("move_abs", "move_rel") or nxt.kind not in ("move_abs", "move_rel"):
            return 0.0
        start = prev.target
        d1 = prev.target - (prev.profile.p0 if prev.profile else self.set_pos)
        d2 = self._target(nxt, start) - start
        if d1 == 0 or d2 == 0 or (d1 > 0) != (d2 > 0):
            return 0.0  # opposite directions: degrade to Buffered
        v1, v2 = abs(prev.params["vel"]), abs(nxt.params["vel"])
        v = {BLEND_LOW: min(v1, v2), BLEND_PREVIOUS: v1, BLEND_NEXT: v2, BLEND_HIGH: max(v1, v2)}[nxt.buffer_mode]
        return math.copysign(v, d1)

    def _replan_for_blend(self) -> None:
        """The active move must arrive at its target with the hand-over speed of its blending successor."""
        cur, nxt = self.active, self.queue[0]
        if cur is None or cur.kind not in ("move_abs", "move_rel") or nxt.buffer_mode == BUFFERED:
            return
        vh = self._handover_velocity(cur, nxt)
        if vh == 0.0:
            return
        vmax, acc, dec, jerk = self._limits(cur)
        vmax = max(vmax, abs(vh))
        cur.profile = self._plan_position(cur.target, vmax, acc, dec, jerk, vh)
        cur.end_v = cur.profile.end_velocity
        cur.steps = 0
        cur.total_steps = self._steps(cur.profile.duration)

    # ------------------------------------------------------------------ the kernel
    def step(self) -> None:
        """Advance the set state by one cycle (the kernel phase)."""
        dt = self.cycle
        if self.power_request and not self.power_on:
            self.power_wait += dt
        if self.reset_cmd is not None:
            self.reset_wait += dt
            self.reset_progress()
        if self.state == ERRORSTOP:
            ramp = getattr(self, "_ramp", None)
            if ramp is not None:
                self._ramp_t += dt
                self.set_pos, self.set_vel, self.set_acc = ramp.sample(self._ramp_t)
                if self._ramp_t >= ramp.duration:
                    self._ramp = None
                    self.set_vel = self.set_acc = 0.0
            self._follow()
            return
        cmd = self.stop_cmd if self.state == STOPPING else self.active
        if cmd is not None and cmd.kind == "home" and "_phase" in cmd.params and cmd.status == ACTIVE:
            self._step_homing(cmd)
            return
        if cmd is not None and cmd.status == ACTIVE:
            cmd.steps += 1
            t = cmd.steps * dt
            finished = cmd.steps >= cmd.total_steps
            assert cmd.profile is not None  # an active command has its plan
            p, v, a = cmd.profile.sample(t)  # past its end a velocity profile holds the speed
            if finished and cmd.kind in ("move_abs", "move_rel"):
                p = cmd.target  # exactly, without the closed form's rounding
            elif finished and cmd.kind != "move_vel":
                v = a = 0.0
            self.set_pos, self.set_vel, self.set_acc = p, v, a
            if v:
                self.last_dir = 1.0 if v > 0 else -1.0
            if cmd.kind == "move_vel":
                cmd.in_velocity = finished
                if finished and self.queue:
                    self._next()
            elif finished:
                self._finish(cmd)
        elif cmd is not None and cmd.kind == "move_vel" and self.queue:
            self._next()
        elif self.state == STOPPING and self.stop_cmd is None:
            self.state = STANDSTILL
        if self.delayed:
            self._apply_delayed()
        self._check_limits()
        self._follow()

    def _finish(self, cmd: Command) -> None:
        cmd.status = DONE
        if cmd.kind == "stop":
            self.set_vel = self.set_acc = 0.0
            if cmd.execute_low:
                self.stop_cmd = None
                self.state = STANDSTILL
            return
        if cmd.kind == "home":  # referencing at the current position: the coordinate, not the motor
            self.shift_coordinates(cmd.params["pos"] - self.set_pos)
        self.active = None
        if self.queue:
            self._next()
        else:
            self.set_vel = self.set_acc = 0.0
            self.state = STANDSTILL

    def _next(self) -> None:
        prev = self.active
        if prev is not None and prev.status == ACTIVE:
            prev.status = ABORTED  # MoveVelocity (no Done output) hands over at InVelocity
            prev.in_velocity = False
        nxt = self.queue.pop(0)
        self.active = None
        if nxt.kind == "set_pos":  # mcQueued: the motion before it has ended
            self._set_position(nxt)
            if self.queue:
                self._next()
            else:
                self.set_vel = self.set_acc = 0.0
                self.state = STANDSTILL
            return
        self._activate(nxt, 0.0)
        if self.queue and self.queue[0].buffer_mode != BUFFERED:
            self._replan_for_blend()

    def _check_limits(self) -> None:
        """Moving further out past a software limit is an axis error (the stop ramp then overshoots
        by its braking distance; after MC_Reset the axis may move back inside)."""
        c = self.cfg
        if self.modulo:
            return
        if (self.set_pos > c.sw_limit_max and self.set_vel > 0) or (self.set_pos < c.sw_limit_min and self.set_vel < 0):
            self.error_stop(E.SW_LIMIT_REACHED)

    def _follow(self) -> None:
        if self.drive is None:  # a virtual axis: the actual value follows the set value
            self.act_pos, self.act_vel = self.set_pos, self.set_vel
        elif not self.power_on:  # a drive without power: the set value follows the actual
            self.set_pos, self.set_vel, self.set_acc = self.act_pos, 0.0, 0.0
            self._ramp = None
        elif abs(self.set_pos - self.act_pos) > self.cfg.following_error_window and self.state != ERRORSTOP:
            self.error_stop(E.FOLLOWING_ERROR)

    # ------------------------------------------------------------------ stop release
    def stop_execute(self, cmd: Command, execute: bool) -> None:
        """MC_Stop's Execute, every call: Stopping is released when Done and Execute is FALSE."""
        if not execute:
            cmd.execute_low = True
            if cmd is self.stop_cmd and cmd.status == DONE and self.state == STOPPING:
                self.stop_cmd = None
                self.state = STANDSTILL
        else:
            cmd.execute_low = False
