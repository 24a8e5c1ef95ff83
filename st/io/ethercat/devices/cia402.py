"""An emulated CiA 402 servo drive (CoE), modelled on a Panasonic MINAS A6B with a 100 W motor.

The drive implements the CiA 402 power state machine (controlword 0x6040 → statusword 0x6041),
the cyclic synchronous modes CSP (8), CSV (9) and CST (10), following-error supervision, quick
stop and fault handling, and a remappable PDO configuration. The physics is `MotorModel`.

Timing conventions:
* `on_outputs()` only takes note of new process data (controlword edges, mode, targets); state
  transitions are taken at the start of `step()`, at most one per step, so a master sees the
  answer to a command in the next cycle. A fault (transition 13) is entered at once.
* In CSP the target is interpolated linearly over one cycle: the interpolation period 0x60C2
  once the master has written it, otherwise the measured interval between `on_outputs()` calls
  (1 ms before there is one). The demand therefore reaches 0x607A at the end of each cycle and
  0x60F4 (demand − actual) stays small while the drive follows.
* While not in Operation enabled a CSP master must copy 0x6064 into 0x607A. When the drive
  enters Operation enabled (or switches to CSP in it) with 0x607A further than the following
  error window from the actual position, it does not move but faults with 0x8611.

Statusword (bit 4 "voltage enabled" while `mains_on`, bit 9 "remote" always): not ready 0x0210,
switch on disabled 0x0250, ready 0x0231, switched on 0x0233, operation enabled 0x0237 plus bit 12
(drive follows the target), bit 10 (target reached: CSP within 0x6067, CSV within
`velocity_window`, CST within `torque_window`) and bit 11 (torque or speed limit active), so
0x1637 at rest; quick stop active 0x0217 (0x0617 once stopped), fault reaction active 0x021F,
fault 0x0218; bit 13 (CSP following error) stays set from a 0x8611 fault until the reset.
Every fault queues an emergency (code, error register 0x01); a successful reset queues the
CiA 301 "error reset" emergency (0x0000).

Positions, velocities and torques are in encoder increments, increments/s and per-mille of the
rated torque. 0x6064/0x607A are 32-bit and wrap; the drive follows target differences modulo
2**32, so long moves work. 0x6080 is in rev/min and 0x6085 in rev/min per second (the drive has
no factor group).
"""

from __future__ import annotations

from enum import IntEnum

from ..od import ABORT_NOT_MAPPABLE, ABORT_PDO_TOO_LONG, ABORT_VALUE_RANGE, DTYPES
from ..pdo import CIA402_RX, CIA402_TX
from .base import Device
from .motor import CSP, CST, CSV, MotorModel, MotorParams

RX_MAPPING, TX_MAPPING = 0x1600, 0x1A00
PDO_CAPACITY = 12  # entries a mapping object can hold
PDO_MAX_BYTES = 64

FAULT_FOLLOWING_ERROR = 0x8611
FAULT_UNDERVOLTAGE = 0x3220  # DC link under-voltage (mains lost while the power stage was on)
FAULT_GENERIC = 0x7500  # communication, the default of inject_fault


class State(IntEnum):
    NOT_READY_TO_SWITCH_ON = 0
    SWITCH_ON_DISABLED = 1
    READY_TO_SWITCH_ON = 2
    SWITCHED_ON = 3
    OPERATION_ENABLED = 4
    QUICK_STOP_ACTIVE = 5
    FAULT_REACTION_ACTIVE = 6
    FAULT = 7


# the states as module constants: `State.X` looks the member up on the enum class, which costs a
# step more than the state machine's own work
(
    _NOT_READY_TO_SWITCH_ON,
    _SWITCH_ON_DISABLED,
    _READY_TO_SWITCH_ON,
    _SWITCHED_ON,
    _OPERATION_ENABLED,
    _QUICK_STOP_ACTIVE,
    _FAULT_REACTION_ACTIVE,
    _FAULT,
) = State


# statusword bits 0-3, 5, 6 per state (bit 5, quick stop, is 1 where the profile requires it)
STATE_BITS = {
    State.NOT_READY_TO_SWITCH_ON: 0x0000,
    State.SWITCH_ON_DISABLED: 0x0040,
    State.READY_TO_SWITCH_ON: 0x0021,
    State.SWITCHED_ON: 0x0023,
    State.OPERATION_ENABLED: 0x0027,
    State.QUICK_STOP_ACTIVE: 0x0007,
    State.FAULT_REACTION_ACTIVE: 0x000F,
    State.FAULT: 0x0008,
}
SW_VOLTAGE, SW_WARNING, SW_REMOTE = 0x0010, 0x0080, 0x0200
SW_TARGET_REACHED, SW_INTERNAL_LIMIT, SW_FOLLOWING, SW_FOLLOWING_ERROR = 0x0400, 0x0800, 0x1000, 0x2000

# device control commands decoded from the controlword
CMD_NONE, CMD_DISABLE_VOLTAGE, CMD_QUICK_STOP, CMD_SHUTDOWN, CMD_SWITCH_ON, CMD_ENABLE = range(6)


def decode_command(cw: int) -> int:
    """The device control command of a controlword (bits 7, 3, 2, 1, 0). A word with bit 7 set
    is a fault reset, which is no command outside Fault."""
    if cw & 0x80:
        return CMD_NONE
    if not cw & 0x02:
        return CMD_DISABLE_VOLTAGE
    if not cw & 0x04:
        return CMD_QUICK_STOP
    if not cw & 0x01:
        return CMD_SHUTDOWN
    if not cw & 0x08:
        return CMD_SWITCH_ON  # also "disable operation" from Operation enabled
    return CMD_ENABLE


# the command of every controlword, by the bits decode_command reads (7, 3, 2, 1, 0)
_COMMAND_OF = tuple(decode_command(cw) for cw in range(0x90))
_COMMAND_BITS = 0x8F


def wrap32(x: int) -> int:
    return ((int(x) + 0x80000000) & 0xFFFFFFFF) - 0x80000000


class CiA402Drive(Device):
    vendor_id = 0x0000066F
    product_code = 0x60380004
    revision = 1
    name = "MINAS-A6B"
    group = "Drive"
    has_mailbox = True

    def __init__(
        self,
        name: str = "",
        *,
        vendor_id: int | None = None,
        product_code: int | None = None,
        revision: int | None = None,
        serial: int | None = None,
        motor: MotorParams | None = None,
        encoder_bits: int | None = None,
        rx_mapping: list | None = None,
        tx_mapping: list | None = None,
        enable_delay: float = 0.0,
        substep: float = 125e-6,
        modes: tuple = (CSP, CSV, CST),
    ):
        """`motor`: the motor's parameters (the model itself is `self.motor`); `encoder_bits`
        overrides theirs. `rx_mapping` / `tx_mapping`: the default contents of 0x1600 / 0x1A00 as
        [(index, sub, bits, dtype, name)] (index 0 = padding), CIA402_RX / CIA402_TX if None.
        Objects the drive does not implement (e.g. touch probe, from an ESI file) are created as
        plain process data that the drive carries but ignores."""
        if vendor_id is not None:
            self.vendor_id = vendor_id
        if product_code is not None:
            self.product_code = product_code
        if revision is not None:
            self.revision = revision
        if serial is not None:
            self.serial = serial
        super().__init__(name)
        params = motor or MotorParams()
        if encoder_bits is not None and encoder_bits != params.encoder_bits:
            from dataclasses import replace

            params = replace(params, encoder_bits=encoder_bits)
        self.motor = MotorModel(params, substep)
        self.modes = tuple(modes)
        self.enable_delay = float(enable_delay)
        self.state = _NOT_READY_TO_SWITCH_ON
        self.mode = CSP if CSP in self.modes else self.modes[0]  # the mode in effect (0x6061)
        self.mains_on = True  # DC link supplied: statusword bit 4; switch-on needs it
        self.sto = False  # Safe Torque Off active: the power stage is cut and cannot be switched on
        # ideal (tests): every transition the controlword asks for in one step, the position the
        # CSP target exactly (no motor dynamics, no following error)
        self.ideal = False
        self.warning = False  # statusword bit 7, for tests
        self.velocity_window = int(10 * self.motor.cpr / 60)  # target reached in CSV: 10 rev/min
        self.torque_window = 10  # per-mille, target reached in CST
        self.t = 0.0  # segment time of the last step
        self.error_code = 0
        self._persistent = False  # an injected fault that a reset cannot clear yet
        self._fe_latched = False  # statusword bit 13 until the fault is reset
        self._fe_time = 0.0
        self._prev_bit7 = False
        self._reset_edge = False
        self._enable_req_t: float | None = None
        self._fra_steps = 0
        self._in_step = False
        self._taken = -1  # od.writes when the outputs were last taken (_take_outputs)
        self._last_t32: int | None = None  # last 0x607A seen while following (CSP)
        self._target = 0  # the unwrapped CSP target (increments)
        self._last_outputs_t: float | None = None
        self._cycle: float | None = None  # measured interval between on_outputs() calls
        self._ip_written = False
        self._build_od(CIA402_RX if rx_mapping is None else rx_mapping, CIA402_TX if tx_mapping is None else tx_mapping)
        # the entries _publish writes every step, in its order
        self._published = tuple(self.od.entry(i) for i in (0x6041, 0x6061, 0x6064, 0x6062, 0x606C, 0x6077, 0x60F4))
        self._published += (self.od.entry(0x603F), self.od.entry(0x1001))
        self._publish()

    # ------------------------------------------------------------------ object dictionary
    def _build_od(self, rx: list, tx: list) -> None:
        od = self.od
        p = self.motor.params
        cpr = self.motor.cpr
        od[0x1000] = 0x00020192  # CiA 402, servo drive
        od.add(0x1001, 0, "Error register", "USINT", 0, "ro")
        od.add(0x1C00, 0, "Sync manager type", "USINT", 4, "ro")
        for sub, kind in enumerate((1, 2, 3, 4), 1):
            od.add(0x1C00, sub, f"SM{sub - 1} type", "USINT", kind, "ro")
        pd = ("PREOP", "SAFEOP", "OP")
        od.add(0x603F, 0, "Error code", "UINT", 0, "ro", pdo=True)
        od.add(0x6040, 0, "Controlword", "UINT", 0, "rw", pdo=True, writable_in=pd)
        od.add(0x6041, 0, "Statusword", "UINT", 0, "ro", pdo=True)
        od.add(
            0x605A,
            0,
            "Quick stop option code",
            "INT",
            2,
            "rw",
            on_write=lambda e, v: 0 if 0 <= v <= 8 else ABORT_VALUE_RANGE,
        )
        od.add(
            0x605E,
            0,
            "Fault reaction option code",
            "INT",
            0,
            "rw",
            on_write=lambda e, v: 0 if 0 <= v <= 4 else ABORT_VALUE_RANGE,
        )
        od.add(
            0x6060,
            0,
            "Modes of operation",
            "SINT",
            self.mode,
            "rw",
            pdo=True,
            writable_in=pd,
            on_write=lambda e, v: 0 if v in self.modes else ABORT_VALUE_RANGE,
        )
        od.add(0x6061, 0, "Modes of operation display", "SINT", self.mode, "ro", pdo=True)
        od.add(0x6062, 0, "Position demand value", "DINT", 0, "ro", pdo=True)
        od.add(0x6064, 0, "Position actual value", "DINT", 0, "ro", pdo=True)
        od.add(0x6065, 0, "Following error window", "UDINT", cpr >> 3, "rw", pdo=True, writable_in=pd)
        od.add(0x6066, 0, "Following error time out", "UINT", 10, "rw", pdo=True, writable_in=pd)
        od.add(0x6067, 0, "Position window", "UDINT", max(1, cpr >> 13), "rw", pdo=True, writable_in=pd)
        od.add(0x606C, 0, "Velocity actual value", "DINT", 0, "ro", pdo=True)
        od.add(0x6071, 0, "Target torque", "INT", 0, "rw", pdo=True, writable_in=pd)
        max_pm = int(round(p.max_torque / p.rated_torque * 1000))
        od.add(0x6072, 0, "Max torque", "UINT", max_pm, "rw", pdo=True, writable_in=pd)
        od.add(0x6077, 0, "Torque actual value", "INT", 0, "ro", pdo=True)
        od.add(0x607A, 0, "Target position", "DINT", 0, "rw", pdo=True, writable_in=pd)
        max_rpm = int(round(p.max_speed_rpm))
        od.add(
            0x6080,
            0,
            "Max motor speed",
            "UDINT",
            max_rpm,
            "rw",
            on_write=lambda e, v: 0 if 0 < v <= max_rpm else ABORT_VALUE_RANGE,
        )
        od.add(
            0x6085,
            0,
            "Quick stop deceleration",
            "UDINT",
            60000,
            "rw",
            on_write=lambda e, v: 0 if v > 0 else ABORT_VALUE_RANGE,
        )
        od.add(0x608F, 0, "Position encoder resolution", "USINT", 2, "ro")
        od.add(0x608F, 1, "Encoder increments", "UDINT", cpr, "ro")
        od.add(0x608F, 2, "Motor revolutions", "UDINT", 1, "ro")
        od.add(0x60B1, 0, "Velocity offset", "DINT", 0, "rw", pdo=True, writable_in=pd)
        od.add(0x60B2, 0, "Torque offset", "INT", 0, "rw", pdo=True, writable_in=pd)
        od.add(0x60C2, 0, "Interpolation time period", "USINT", 2, "ro")
        od.add(
            0x60C2,
            1,
            "Interpolation time period value",
            "USINT",
            1,
            "rw",
            writable_in=("PREOP", "SAFEOP"),
            on_write=self._ip_write,
        )
        od.add(
            0x60C2,
            2,
            "Interpolation time index",
            "SINT",
            -3,
            "rw",
            writable_in=("PREOP", "SAFEOP"),
            on_write=self._ip_write,
        )
        od.add(0x60F4, 0, "Following error actual value", "DINT", 0, "ro", pdo=True)
        od.add(0x60FF, 0, "Target velocity", "DINT", 0, "rw", pdo=True, writable_in=pd)
        od.add(0x6502, 0, "Supported drive modes", "UDINT", sum(1 << (m - 1) for m in self.modes), "ro")
        for index, name, mapped in ((RX_MAPPING, "RxPDO mapping", rx), (TX_MAPPING, "TxPDO mapping", tx)):
            words = []
            for ix, sx, bits, dtype, ename in mapped:
                if ix and not od.has(ix, sx):
                    if dtype not in DTYPES or DTYPES[dtype][1] != bits:
                        dtype = {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT", 64: "ULINT"}.get(bits)
                        if dtype is None:
                            raise ValueError(f"{name}: {ix:#06x}:{sx} ({ename}): no data type of {bits} bits")
                    od.add(
                        ix,
                        sx,
                        ename or f"object {ix:#06x}:{sx}",
                        dtype,
                        0,
                        "rw" if index == RX_MAPPING else "ro",
                        pdo=True,
                    )
                if ix and self._check_word(index, (ix << 16) | (sx << 8) | bits):
                    raise ValueError(f"{name}: {ix:#06x}:{sx} ({ename}) cannot be mapped with {bits} bits")
                words.append((ix, sx, bits))
            capacity = max(PDO_CAPACITY, len(words))
            od.add_pdo_mapping(index, name, words)
            for k in range(len(words) + 1, capacity + 1):
                od.add(index, k, f"entry {k}", "UDINT", 0, "rw", writable_in=("PREOP",))
            count = od.entry(index, 0)
            count.on_write = self._mapping_count_check(index, count.on_write)
            for k in range(1, capacity + 1):
                od.entry(index, k).on_write = (lambda i: lambda e, v: self._check_word(i, v))(index)
        od.add_assignment(self.rx_assign, "RxPDO assign", [RX_MAPPING])
        od.add_assignment(self.tx_assign, "TxPDO assign", [TX_MAPPING])
        for assign, lo in ((self.rx_assign, 0x1600), (self.tx_assign, 0x1A00)):
            count = od.entry(assign, 0)
            count.on_write = self._assign_count_check(assign, lo, count.on_write)
            od.entry(assign, 1).on_write = (lambda lo_: lambda e, v: self._check_assigned(lo_, v, True))(lo)

    def _check_word(self, pdo_index: int, word: int) -> int:
        """0 if a mapping entry 0xIIIISSBB may stand in mapping object pdo_index."""
        word = int(word)
        if word == 0:
            return 0
        ix, sx, bits = word >> 16, (word >> 8) & 0xFF, word & 0xFF
        if ix == 0:
            return 0 if bits else ABORT_NOT_MAPPABLE  # padding
        e = self.od.entries.get((ix, sx))
        if e is None or not e.pdo or e.bits != bits:
            return ABORT_NOT_MAPPABLE
        rxpdo = 0x1600 <= pdo_index < 0x1800
        if (rxpdo and e.access == "ro") or (not rxpdo and e.access == "wo"):
            return ABORT_NOT_MAPPABLE
        return 0

    def _mapping_count_check(self, index: int, base):
        def check(entry, value):
            code = base(entry, value)
            if code:
                return code
            total = 0
            for k in range(1, int(value) + 1):
                word = int(self.od[(index, k)])
                code = self._check_word(index, word)
                if code:
                    return code
                total += word & 0xFF
            if total > PDO_MAX_BYTES * 8:
                return ABORT_PDO_TOO_LONG
            self.remap()
            return 0

        return check

    def _check_assigned(self, lo: int, value: int, allow_zero: bool) -> int:
        value = int(value)
        if value == 0:
            return 0 if allow_zero else ABORT_VALUE_RANGE
        if not (lo <= value < lo + 0x200) or not self.od.has(value, 0):
            return ABORT_VALUE_RANGE
        return 0

    def _assign_count_check(self, assign: int, lo: int, base):
        def check(entry, value):
            code = base(entry, value)
            if code:
                return code
            for k in range(1, int(value) + 1):
                code = self._check_assigned(lo, self.od[(assign, k)], False)
                if code:
                    return code
            self.remap()
            return 0

        return check

    def _ip_write(self, entry, value) -> int:
        if entry.sub == 2 and not -6 <= value <= 0:
            return ABORT_VALUE_RANGE
        self._ip_written = True
        return 0

    # ------------------------------------------------------------------ python API
    @property
    def state_name(self) -> str:
        return self.state.name

    @property
    def statusword(self) -> int:
        return int(self.od[0x6041])

    @property
    def controlword(self) -> int:
        return int(self.od[0x6040])

    @property
    def position(self) -> int:
        """Actual position in increments, not wrapped to 32 bits (0x6064 is)."""
        return self.motor.position

    @property
    def velocity(self) -> int:
        return self.motor.velocity

    @property
    def torque(self) -> int:
        return self.motor.torque

    @property
    def following_error(self) -> int:
        return self.motor.following_error

    @property
    def interpolation_period(self) -> float:
        """Seconds: 0x60C2 if the master wrote it, else the measured output cycle, else 0x60C2."""
        if not self._ip_written and self._cycle is not None:
            return self._cycle
        return self.od[(0x60C2, 1)] * 10.0 ** self.od[(0x60C2, 2)]

    def inject_fault(self, code: int = FAULT_GENERIC, persistent: bool = False) -> None:
        """Raise a drive fault now (transition 13). A persistent one survives fault resets until
        `clear_fault()`."""
        self._persistent = self._persistent or persistent
        self._fault(code)

    def clear_fault(self) -> None:
        """The injected condition is gone; the next fault-reset edge will succeed."""
        self._persistent = False

    def safe_torque_off(self, active: bool = True) -> None:
        """Safe Torque Off (the safety circuit opens): the power stage is cut at once, the motor
        coasts, the drive drops to Switch On Disabled without a fault and cannot be switched on
        again until STO is released (`safe_torque_off(False)`)."""
        self.sto = active
        if active and self.state in (_SWITCHED_ON, _OPERATION_ENABLED, _QUICK_STOP_ACTIVE):
            self.motor.disable()
            self._set_state(_SWITCH_ON_DISABLED)
            self._publish()

    # ------------------------------------------------------------------ Device hooks
    def on_outputs(self) -> None:
        if self._last_outputs_t is not None:
            interval = self.t - self._last_outputs_t
            if 1e-6 <= interval <= 0.1:
                self._cycle = interval
        self._last_outputs_t = self.t
        self._take_outputs()

    def step(self, t: float, dt: float) -> None:
        self._in_step = True
        try:
            if self.od.writes != self._taken:  # else the last outputs are applied already
                self._take_outputs()
            mo = self.motor
            was = (self.state, self.mode, mo.enabled)
            self._transition(t, dt)
            if self.ideal:  # what the controlword asks for, at once
                for _ in range(4):
                    before = self.state
                    self._transition(t, dt)
                    if self.state == before:
                        break
            if (self.state, self.mode, mo.enabled) != was:  # else they are applied already
                self._apply_setpoints()
            mo.step(dt)
            if self.ideal:
                self._ideal_motion(dt)
            self.t = t
            now = mo.readings()
            readings = None if self._supervise(dt, now[4]) else now  # a fault changes the motor
        finally:
            self._in_step = False
        self._publish(readings)

    # ------------------------------------------------------------------ internals
    def _take_outputs(self) -> None:
        """Latch the fault-reset edge, the mode and (when following) the setpoints."""
        self._taken = self.od.writes
        E = self.od._by_key
        cw = int(E[0x6040].value)
        bit7 = bool(cw & 0x80)
        if bit7 and not self._prev_bit7:
            self._reset_edge = True
        self._prev_bit7 = bit7
        m = E[0x6060].value
        if m in self.modes and m != self.mode:
            self.mode = m
            if self.state == _OPERATION_ENABLED:
                self._start_mode()
        self._apply_setpoints()

    def _apply_setpoints(self) -> None:
        E = self.od._by_key
        mo = self.motor
        mo.torque_limit = E[0x6072].value
        mo.speed_limit = E[0x6080].value * 6.283185307179586 / 60.0
        if self.state != _OPERATION_ENABLED or not mo.enabled:
            return
        mo.velocity_offset = E[0x60B1].value
        mo.torque_offset = E[0x60B2].value
        if self.mode == CSP:
            t32 = int(E[0x607A].value)
            if self._last_t32 is not None and t32 != self._last_t32:
                self._target += wrap32(t32 - self._last_t32)
                self._last_t32 = t32
                mo.command_position(self._target, self.interpolation_period)
        elif self.mode == CSV:
            mo.target_velocity = E[0x60FF].value
        else:
            mo.target_torque = E[0x6071].value

    def _start_mode(self) -> bool:
        """Close the loop of the current mode in Operation enabled; in CSP refuse (fault 0x8611)
        a target that is further than the following error window from the actual position."""
        mo = self.motor
        if self.mode == CSP:
            actual = mo.position
            t32 = int(self.od[0x607A])
            target = actual + wrap32(t32 - wrap32(actual))
            window = int(self.od[0x6065])
            if window != 0xFFFFFFFF and abs(target - actual) > window:
                self._fault(FAULT_FOLLOWING_ERROR, following=True)
                return False
            self._last_t32, self._target = t32, target
        else:
            self._last_t32 = None
        if mo.enabled:
            mo.set_mode(self.mode)
        else:
            mo.enable(self.mode)
        if self.mode == CSP:
            mo.command_position(self._target, self.interpolation_period)
        self._fe_time = 0.0
        return True

    def _set_state(self, new: State) -> None:
        old = self.state
        self.state = new
        if new != _SWITCHED_ON:
            self._enable_req_t = None
        if old in (_OPERATION_ENABLED, _QUICK_STOP_ACTIVE) and new not in (
            _OPERATION_ENABLED,
            _QUICK_STOP_ACTIVE,
            _FAULT_REACTION_ACTIVE,
        ):
            self.motor.disable()
        if new == _OPERATION_ENABLED:
            self._start_mode()

    def _fault(self, code: int, following: bool = False) -> None:
        self.error_code = code & 0xFFFF
        self._fe_latched = self._fe_latched or following
        self.emergency(code & 0xFFFF, 0x01)
        if self.state not in (_FAULT, _FAULT_REACTION_ACTIVE):
            self.state = _FAULT_REACTION_ACTIVE
            self._enable_req_t = None
            # the reaction is shown for at least one published step: a fault found during a
            # step counts that step, an injected one waits for the next
            self._fra_steps = 1 if self._in_step else 0
            mo = self.motor
            option = int(self.od[0x605E])
            if mo.enabled and option in (1, 2):
                mo.stop(self._qs_decel())
            elif mo.enabled and option in (3, 4):
                mo.stop(None)
            else:
                mo.disable()
        self._publish()

    def _qs_decel(self) -> float:
        """Quick stop deceleration in increments/s² (0x6085 is in rev/min per second)."""
        E = self.od._by_key
        return E[0x6085].value * self.motor.cpr / 60.0

    def _transition(self, t: float, dt: float) -> None:
        """At most one state transition, at the start of a step."""
        E = self.od._by_key
        s = self.state
        reset, self._reset_edge = self._reset_edge, False
        if s == _OPERATION_ENABLED and _COMMAND_OF[int(E[0x6040].value) & _COMMAND_BITS] == CMD_ENABLE:
            return  # a running axis: nothing to do
        mo = self.motor
        if s == _NOT_READY_TO_SWITCH_ON:
            self._set_state(_SWITCH_ON_DISABLED)  # 1 (after the self test)
            return
        if s == _FAULT_REACTION_ACTIVE:
            if self._fra_steps >= 1 and (not mo.enabled or mo.stopped):
                mo.disable()
                self._set_state(_FAULT)  # 14
            else:
                self._fra_steps += 1
            return
        if s == _FAULT:
            if reset and not self._persistent:  # 15
                self.error_code = 0
                self._fe_latched = False
                self.emergency(0x0000, 0x00)  # CiA 301: error reset
                self._set_state(_SWITCH_ON_DISABLED)
            return
        cmd = _COMMAND_OF[int(E[0x6040].value) & _COMMAND_BITS]
        qs_option = int(E[0x605A].value)
        if s == _SWITCH_ON_DISABLED:
            if cmd == CMD_SHUTDOWN:
                self._set_state(_READY_TO_SWITCH_ON)  # 2
        elif s == _READY_TO_SWITCH_ON:
            if cmd in (CMD_SWITCH_ON, CMD_ENABLE) and self.mains_on and not self.sto:
                self._set_state(_SWITCHED_ON)  # 3
            elif cmd in (CMD_DISABLE_VOLTAGE, CMD_QUICK_STOP):
                self._set_state(_SWITCH_ON_DISABLED)  # 7
        elif s == _SWITCHED_ON:
            if cmd == CMD_ENABLE:
                start = t - dt
                if self._enable_req_t is None:
                    self._enable_req_t = start
                if start - self._enable_req_t >= self.enable_delay - 1e-12:
                    self._set_state(_OPERATION_ENABLED)  # 4
                return
            self._enable_req_t = None
            if cmd == CMD_SHUTDOWN:
                self._set_state(_READY_TO_SWITCH_ON)  # 6
            elif cmd in (CMD_DISABLE_VOLTAGE, CMD_QUICK_STOP):
                self._set_state(_SWITCH_ON_DISABLED)  # 10
        elif s == _OPERATION_ENABLED:
            if cmd == CMD_SWITCH_ON:
                self._set_state(_SWITCHED_ON)  # 5
            elif cmd == CMD_SHUTDOWN:
                self._set_state(_READY_TO_SWITCH_ON)  # 8
            elif cmd == CMD_DISABLE_VOLTAGE:
                self._set_state(_SWITCH_ON_DISABLED)  # 9
            elif cmd == CMD_QUICK_STOP:  # 11
                self.state = _QUICK_STOP_ACTIVE
                if qs_option == 0:
                    mo.disable()
                elif qs_option in (1, 2, 5, 6):
                    mo.stop(self._qs_decel())
                else:
                    mo.stop(None)
        elif s == _QUICK_STOP_ACTIVE:
            if cmd == CMD_DISABLE_VOLTAGE:
                self._set_state(_SWITCH_ON_DISABLED)  # 12
            elif qs_option in (5, 6, 7, 8):
                if cmd == CMD_ENABLE:
                    self._set_state(_OPERATION_ENABLED)  # 16
            elif not mo.enabled or mo.stopped:
                self._set_state(_SWITCH_ON_DISABLED)  # 12 (after the ramp)

    def _ideal_motion(self, dt: float) -> None:
        """The ideal drive: in CSP with the power stage on, the shaft is at the target."""
        mo = self.motor
        if self.state == _OPERATION_ENABLED and self.mode == CSP and mo.enabled:
            before = mo.position
            mo.set_position(self._target)
            mo.omega = (self._target - before) / dt / mo.k if dt > 0 else 0.0

    def _supervise(self, dt: float, following_error: int) -> bool:
        """After the physics: following error, DC link, fault reaction progress. True when it
        raised a fault."""
        E = self.od._by_key
        if not self.mains_on and self.state in (_SWITCHED_ON, _OPERATION_ENABLED, _QUICK_STOP_ACTIVE):
            self._fault(FAULT_UNDERVOLTAGE)
            return True
        if self.state == _OPERATION_ENABLED and self.mode == CSP and self.motor.enabled:
            window = int(E[0x6065].value)
            if window != 0xFFFFFFFF and abs(following_error) > window:
                self._fe_time += dt
                if self._fe_time > E[0x6066].value / 1000.0 + 1e-12:
                    self._fault(FAULT_FOLLOWING_ERROR, following=True)
                    return True
            else:
                self._fe_time = 0.0
        return False

    def _publish(self, readings: tuple | None = None) -> None:
        """The statusword and the actual values into the object dictionary; `readings`: the
        motor's, if the caller has them."""
        mo, s = self.motor, self.state
        pos, demand, vel, torque, fe = mo.readings() if readings is None else readings
        sw = STATE_BITS[s] | SW_REMOTE
        if self.mains_on:
            sw |= SW_VOLTAGE
        if self.warning:
            sw |= SW_WARNING
        if s == _OPERATION_ENABLED and mo.enabled:
            sw |= SW_FOLLOWING
            if self._target_reached(pos, vel, torque):
                sw |= SW_TARGET_REACHED
        elif s == _QUICK_STOP_ACTIVE and (mo.stopped or (not mo.enabled and mo.omega == 0.0)):
            sw |= SW_TARGET_REACHED
        if mo.enabled and mo.limited:
            sw |= SW_INTERNAL_LIMIT
        if self._fe_latched and self.mode == CSP:
            sw |= SW_FOLLOWING_ERROR
        e_sw, e_mode, e_pos, e_demand, e_vel, e_torque, e_fe, e_code, e_register = self._published
        e_sw.value = sw
        e_mode.value = self.mode
        e_pos.value = ((pos + 0x80000000) & 0xFFFFFFFF) - 0x80000000  # wrap32
        e_demand.value = ((demand + 0x80000000) & 0xFFFFFFFF) - 0x80000000
        e_vel.value = -0x80000000 if vel < -0x80000000 else (0x7FFFFFFF if vel > 0x7FFFFFFF else vel)
        e_torque.value = -0x8000 if torque < -0x8000 else (0x7FFF if torque > 0x7FFF else torque)
        e_fe.value = -0x80000000 if fe < -0x80000000 else (0x7FFFFFFF if fe > 0x7FFFFFFF else fe)
        e_code.value = self.error_code
        e_register.value = 0x01 if s == _FAULT or s == _FAULT_REACTION_ACTIVE else 0x00

    def _target_reached(self, pos: int, vel: int, torque: int) -> bool:
        E = self.od._by_key
        if self.mode == CSP:
            return abs(self._target - pos) <= E[0x6067].value
        if self.mode == CSV:
            mo = self.motor
            goal = max(-mo.max_speed * mo.k, min(mo.max_speed * mo.k, E[0x60FF].value))
            return abs(goal - vel) <= self.velocity_window
        return abs(E[0x6071].value - torque) <= self.torque_window
