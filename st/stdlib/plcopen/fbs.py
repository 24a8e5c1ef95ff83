"""The native bodies of the MC_* function blocks and the per-PLC motion registry.

`plcopen.st` declares the blocks (so the compiler checks every call against the standard's
interfaces); when a PLC's namespace is built, `install(ns)` replaces their `_body` with the
functions below and adds a `MotionRegistry`, which the PLC runs as an I/O driver: after each
task's job it advances the axes that task commands (the kernel phase).
"""

from __future__ import annotations

from typing import Any

from ...runtime.iodriver import IODriver, IODriverBase
from ...runtime.scheduler import Task
from .axis import (
    ABORTED,
    ACTIVE,
    CONTINUOUS,
    DISABLED,
    DISCRETE,
    DONE,
    ERROR,
    ERRORSTOP,
    HOMING,
    QUEUED,
    STANDSTILL,
    STOPPING,
    Axis,
    AxisConfig,
    Drive,
)
from .errors import E

DEFAULT_CYCLE_S = 0.001
VIRTUAL_HANDLES = 1 << 16  # the handles of virtual axes (AxisNo 0) start here, above every UINT AxisNo


class MotionRegistry(IODriverBase):
    """Every axis of one PLC, by handle; configurations by AxisNo. The motion kernel: an I/O driver
    of the PLC made with the program's namespace."""

    name = "motion"
    per_namespace = True

    def __init__(self):
        self.axes: dict = {}  # handle → Axis
        self.configs: dict = {}  # AxisNo → AxisConfig
        self.signals: dict = {}  # AxisNo → callable: the reference switch of MC_Home
        self.drives: dict = {}  # AxisNo → the Drive (EtherCAT) that claims the axis
        self.traces: list = []  # [AxisTrace]
        self.plc = None  # the PLC it joined (join)

    @property
    def task(self):
        """The task whose job is running: it claims the axes its blocks touch first."""
        return self.plc.job_task if self.plc is not None else None

    def axis(self, ref) -> Axis | None:
        """The Axis behind an AXIS_REF value, created on first use. Every AXIS_REF naming AxisNo n
        is the same axis (its Handle is n); an AXIS_REF with AxisNo 0 is a virtual axis of its
        own (its Handle one the registry issues above the AxisNo range). None, for which the
        blocks report INVALID_AXIS_REF, when the Handle is one the library never issued (-1, a
        value a program wrote, a virtual axis's handle from an earlier run), or when axes are
        configured (configure_axes, a drive claiming one) and AxisNo names none of them."""
        h, no = ref.Handle, ref.AxisNo
        if no:
            if h != no and h != 0 and h not in self.axes:
                return None
            ax = self.axes.get(no)
            if ax is None:
                if (self.configs or self.drives) and no not in self.configs and no not in self.drives:
                    return None
                ax = self._new_axis(no, no)
            if h != no:
                ref.Handle = no
        elif h == 0:
            ax = self._new_axis(max([VIRTUAL_HANDLES - 1, *self.axes]) + 1, 0)
            ref.Handle = ax.handle
        else:
            ax = self.axes.get(h)
            if ax is None:
                return None
            if ax.axis_no:  # the AXIS_REF was aimed at another AxisNo before: a virtual axis of its own
                ax = self._new_axis(max([VIRTUAL_HANDLES - 1, *self.axes]) + 1, 0)
                ref.Handle = ax.handle
        if ax.task is None and self.task is not None:
            ax.task = self.task
            ax.cycle = (self.task.interval or 0) / 1e9 or DEFAULT_CYCLE_S
        elif not ax.cycle:
            ax.cycle = DEFAULT_CYCLE_S
        return ax

    def _new_axis(self, handle: int, no: int) -> Axis:
        name = f"axis{no}" if no else f"virtual{handle - VIRTUAL_HANDLES + 1}"
        ax = Axis(handle, self.configs.get(no) or AxisConfig(name=name))
        ax.axis_no = no
        ax.home_signal = self.signals.get(no)
        self.axes[handle] = ax
        self.wake()
        link = self.drives.get(no)
        if link is not None:
            link.attach(ax)
        return ax

    def add_drive(self, link: Drive) -> None:
        """A drive claims the axis of its AxisNo: attached now if that axis exists (and is not
        attached to it yet), else when the axis is created."""
        self.drives[link.axis_no] = link
        if link.axis is None or link.axis.drive is not link:
            ax = next((a for a in self.axes.values() if a.axis_no == link.axis_no), None)
            if ax is not None:
                link.attach(ax)

    def adopt(self, old: IODriver) -> None:
        """Online change: the new program's AXIS_REFs carry their handles over, so keep the axes."""
        assert isinstance(old, MotionRegistry)  # the PLC hands over a driver of the same type
        self.axes, self.configs, self.traces, self.signals = old.axes, old.configs, old.traces, old.signals
        self.drives = old.drives
        for ax in self.axes.values():
            ax.task = None  # the new program's tasks claim their axes on the next call

    # the I/O driver interface
    def join(self, plc) -> None:
        """Into `plc.io` once there is an axis or a trace to step; until then (a program that has
        the PLCopen library but calls no MC_* block) the engine pays nothing for the kernel."""
        self.plc = plc
        if self.axes or self.traces:
            self.wake()

    def wake(self) -> None:
        """Join the PLC's drivers (first, before the drives that carry the axes' targets)."""
        plc = self.plc
        if plc is not None and self not in plc.io:
            plc.io.insert(0, self)

    def status(self) -> dict[str, Any] | None:
        """The online mode's view: {"axes": [...]}, each axis in AxisNo order with its state, actual
        position and velocity and its axis error (the code and its name); None before the first axis."""
        if not self.axes:
            return None
        axes = []
        for ax in sorted(self.axes.values(), key=lambda a: a.axis_no):
            code = ax.axis_error
            axes.append(
                {
                    "no": ax.axis_no,
                    "state": str(ax.state),
                    "position": float(ax.act_pos),
                    "velocity": float(ax.act_vel),
                    "error": bool(code),
                    "error_id": int(code),
                    "error_text": _error_name(code),
                }
            )
        return {"axes": axes}

    def after_job(self, task: Task | None = None) -> None:
        if task is None:
            return
        for ax in self.axes.values():
            if ax.task is task:
                ax.last_seen = ax.seen()  # what the blocks saw in this job (plc.axis)
                ax.step()
        for tr in self.traces:
            ax = tr.axis
            if ax is not None and ax.task is task:
                tr.sample()


def _error_name(code: int) -> str:
    """An ErrorID's name (FOLLOWING_ERROR), 16#XXXX for a code st does not name, "" for none."""
    if not code:
        return ""
    try:
        return E(code).name
    except ValueError:
        return f"16#{code:04X}"


# ---------------------------------------------------------------------------- output helpers


def _execute_outputs(fb, cmd, execute: bool, has_active=True, has_aborted=True) -> None:
    """Busy/Active/Done/CommandAborted/Error/ErrorID from the command's ledger entry (PLCopen §2.4.1):
    terminal outputs stay while Execute is TRUE, and show for exactly one call if it already fell."""
    busy = active = done = aborted = error = False
    code = 0
    if cmd is not None:
        st = cmd.status
        if st == QUEUED:
            busy = True
        elif st == ACTIVE:
            busy = active = True
        elif st == DONE:
            done = True
        elif st == ABORTED:
            aborted = True
        elif st == ERROR:
            error, code = True, cmd.error_id
        if cmd.terminal:
            if execute:
                cmd.shown = True
            elif cmd.shown:  # already reported while Execute was TRUE: cleared
                busy = active = done = aborted = error = False
                code = 0
                fb.CmdId = 0
            else:  # Execute fell before the end: this one call shows it
                fb.CmdId = 0
    fb.Busy, fb.Error, fb.ErrorID = busy, error, code
    if _outputs_of(type(fb))[0]:
        fb.Done = done
    if has_active:
        fb.Active = active
    if has_aborted:
        fb.CommandAborted = aborted


def _outputs_of(cls) -> tuple:
    """(has Done, has Active, has CommandAborted) of an FB class, looked up once per class."""
    got = cls.__dict__.get("_has_outputs")
    if got is None:
        names = cls.__slots__
        got = ("Done" in names, "Active" in names, "CommandAborted" in names)
        cls._has_outputs = got
    return got


def _edge(fb) -> bool:
    ex = bool(fb.Execute)
    rising = ex and not fb.PrevEdge
    fb.PrevEdge = ex
    return rising


def _lookup(ax: Axis, fb) -> object | None:
    return ax.commands.get(fb.CmdId) if fb.CmdId else None


def _motion_body(kind: str, params):
    """An Execute-type motion FB: submit on the rising edge, then report from the ledger."""

    def body(self, _reg=None):
        reg = self._motion
        ax = reg.axis(self.Axis)
        if ax is None:
            _edge(self)
            return _invalid_axis_ref(self)
        if _edge(self):
            old = _lookup(ax, self)
            if old is not None and old.terminal:
                ax.forget(old.id)
            cmd = ax.new_command(kind, params(self), int(getattr(self, "BufferMode", 0)))
            cmd.continuous_update = bool(getattr(self, "ContinuousUpdate", False))
            ax.submit(cmd)
            self.CmdId = cmd.id
        cmd = _lookup(ax, self)
        if cmd is not None and cmd.continuous_update and cmd.status in (ACTIVE, QUEUED) and self.ContinuousUpdate:
            _continuous_update(ax, cmd, params(self))
        if kind == "stop" and cmd is not None:
            ax.stop_execute(cmd, bool(self.Execute))
        _, has_active, has_aborted = _outputs_of(type(self))
        _execute_outputs(self, cmd, bool(self.Execute), has_active, has_aborted)
        if kind == "move_vel":
            self.InVelocity = bool(cmd is not None and cmd.status == ACTIVE and cmd.in_velocity)
            if self.InVelocity:
                self.Busy = self.Active = True
        if cmd is not None and cmd.terminal and not self.Execute and self.CmdId == 0:
            ax.forget(cmd.id)

    return body


def _continuous_update(ax: Axis, cmd, new: dict) -> None:
    """ContinuousUpdate: apply changed inputs to the running move (relative moves keep their start)."""
    changed = any(new.get(k) != cmd.params.get(k) for k in new)
    if not changed:
        return
    old = dict(cmd.params)
    cmd.params.update(new)
    if "_start" in old:
        cmd.params["_start"] = old["_start"]
    code = ax._validate(cmd)
    if code:  # the command ends with the error; the axis goes on as docs/motion.md says
        ax.update_failed(cmd, code, old)
    elif cmd.status == ACTIVE:
        ax._activate(cmd)


def _p_abs(fb):
    return {
        "pos": float(fb.Position),
        "vel": float(fb.Velocity),
        "acc": float(fb.Acceleration),
        "dec": float(fb.Deceleration),
        "jerk": float(fb.Jerk),
        "dir": int(fb.Direction),
    }


def _p_rel(fb):
    return {
        "dist": float(fb.Distance),
        "vel": float(fb.Velocity),
        "acc": float(fb.Acceleration),
        "dec": float(fb.Deceleration),
        "jerk": float(fb.Jerk),
    }


def _p_vel(fb):
    return {
        "vel": float(fb.Velocity),
        "acc": float(fb.Acceleration),
        "dec": float(fb.Deceleration),
        "jerk": float(fb.Jerk),
        "dir": int(fb.Direction),
    }


def _p_stop(fb):
    return {"dec": float(fb.Deceleration), "jerk": float(fb.Jerk)}


def _p_home(fb):
    return {"pos": float(fb.Position)}


def _p_setpos(fb):
    return {"position": float(fb.Position), "relative": bool(fb.Relative), "mode": int(fb.ExecutionMode)}


def _power_body(self):
    reg = self._motion
    ax = reg.axis(self.Axis)
    if ax is None:
        return _invalid_axis_ref(self, bool(self.Enable))
    en = bool(self.Enable)
    status, code = ax.power(id(self), en)
    self.Status = status
    self.Error = code != 0
    self.ErrorID = code
    self.Valid = en and not self.Error
    self.Busy = en


def _reset_body(self):
    reg = self._motion
    ax = reg.axis(self.Axis)
    if ax is None:
        _edge(self)
        return _invalid_axis_ref(self)
    if _edge(self):
        old = _lookup(ax, self)
        if old is not None:
            ax.forget(old.id)
        cmd = ax.new_command("reset", {})
        ax.reset(cmd)
        self.CmdId = cmd.id
    cmd = _lookup(ax, self)
    _execute_outputs(self, cmd, bool(self.Execute), False, False)


def _invalid_axis_ref(fb, shown: bool = True) -> None:
    """An AXIS_REF that names no configured axis: Error INVALID_AXIS_REF, nothing else TRUE."""
    for name in ("Busy", "Active", "Done", "CommandAborted", "InVelocity", "Status", "Valid"):
        if name in type(fb).__slots__:
            setattr(fb, name, False)
    fb.Error = shown
    fb.ErrorID = int(E.INVALID_AXIS_REF) if shown else 0


def _read_outputs(self, ax: Axis | None, from_drive: bool) -> bool:
    """Valid/Busy/Error/ErrorID of a read block; TRUE when its values may be read now. The axis's
    state and its errors belong to the controller and are always known; what the drive reports
    (`from_drive`: actual position, velocity) is not while the drive cannot be read (communication
    lost, out of OP): Error COMMUNICATION_LOST, Valid FALSE, Valid again once the values come back."""
    en = bool(self.Enable)
    code = 0
    if en and ax is None:
        code = E.INVALID_AXIS_REF
    elif en and from_drive and ax is not None and ax.drive is not None and not ax.drive.readable:
        code = E.COMMUNICATION_LOST
    self.Busy = en
    self.Valid = en and not code
    self.Error, self.ErrorID = bool(code), int(code)
    return bool(self.Valid)


def _read_status_body(self):
    ax = self._motion.axis(self.Axis)
    st = ax.state if _read_outputs(self, ax, False) and ax is not None else None
    self.ErrorStop, self.Disabled, self.Stopping = st == ERRORSTOP, st == DISABLED, st == STOPPING
    self.Homing, self.Standstill = st == HOMING, st == STANDSTILL
    self.DiscreteMotion, self.ContinuousMotion, self.SynchronizedMotion = st == DISCRETE, st == CONTINUOUS, False


def _read_position_body(self):
    ax = self._motion.axis(self.Axis)
    if _read_outputs(self, ax, True) and ax is not None:
        self.Position = ax.actual_position()
    elif not self.Enable:
        self.Position = 0.0


def _read_velocity_body(self):
    ax = self._motion.axis(self.Axis)
    if _read_outputs(self, ax, True) and ax is not None:
        self.Velocity = ax.act_vel
    elif not self.Enable:
        self.Velocity = 0.0


def _read_axis_error_body(self):
    """AxisErrorID: the drive's own code (0x603F) when the axis error came from a drive that
    reports one and the drive can be read, else st's; StAxisErrorID: st's ErrorID of the axis error."""
    ax = self._motion.axis(self.Axis)
    if _read_outputs(self, ax, False) and ax is not None:
        own = int(ax.axis_error)
        d = ax.drive
        drive_code = d.error_code if d is not None and d.readable and own in (E.DRIVE_FAULT, E.FOLLOWING_ERROR) else 0
        self.AxisErrorID, self.StAxisErrorID = drive_code or own, own
    elif not self.Enable:
        self.AxisErrorID = self.StAxisErrorID = 0


BODIES = {
    "MC_Power": _power_body,
    "MC_MoveAbsolute": _motion_body("move_abs", _p_abs),
    "MC_MoveRelative": _motion_body("move_rel", _p_rel),
    "MC_MoveVelocity": _motion_body("move_vel", _p_vel),
    "MC_Halt": _motion_body("halt", _p_stop),
    "MC_Stop": _motion_body("stop", _p_stop),
    "MC_Home": _motion_body("home", _p_home),
    "MC_SetPosition": _motion_body("set_pos", _p_setpos),
    "MC_Reset": _reset_body,
    "MC_ReadStatus": _read_status_body,
    "MC_ReadActualPosition": _read_position_body,
    "MC_ReadActualVelocity": _read_velocity_body,
    "MC_ReadAxisError": _read_axis_error_body,
}


def install(ns: dict) -> None:
    """Namespace hook: native bodies for the MC_* classes of this namespace and its registry."""
    found = {name: ns.get("_fb_" + name) for name in BODIES}
    classes = {name: cls for name, cls in found.items() if cls is not None and cls._from_library}
    if not classes:  # no motion here, or the project's own blocks of these names
        return
    reg = MotionRegistry()
    ns["_motion"] = reg
    ns.setdefault("_io_drivers", []).append(reg)
    for name, cls in classes.items():
        cls._body = BODIES[name]
        cls._motion = reg
