"""EtherCAT as a PLC I/O driver: one process-data exchange per scan, drives bound to PLCopen axes.

`EtherCATDriver(plc, config, backend="sim"|"soem", iface=…)` brings the segment to OP and joins
`plc.io`. At the end of each job of its task (after the motion kernel advanced the axes) it packs
the outputs — located %Q variables bound to PDO entries, and for every drive the controlword
and CSP target position of its axis — exchanges one frame (LRW plus the DC system time), and
unpacks the inputs, which the next job latches (%I variables; the axes' actual values).

A `DriveLink` runs the CiA 402 side of MC_Power (0x06 → 0x07 → 0x0F, the target held at the
actual position until Operation Enabled), converts units (increments per user unit) and turns a
drive fault, an unexpected loss of Operation Enabled or `lost_frame_limit` consecutive lost
frames / wrong working counters into ErrorStop of the bound axis. When frames come back, slaves
that fell out of OP are brought back; the axes wait for MC_Reset as the standard wants.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ...runtime.iodriver import IODriverBase
from ...runtime.process_image import parse_address
from ...runtime.scheduler import Task
from ...stdlib.plcopen import registry
from ...stdlib.plcopen.errors import E
from .config import SegmentConfig, build_segment, from_dict
from .master import FrameMaster, Master, MasterError

if TYPE_CHECKING:
    from .segment import Segment

# CiA 402 statusword → state (mask, value), in the order they are tested
_SW_STATES = (
    (0x4F, 0x08, "FAULT"),
    (0x4F, 0x0F, "FAULT_REACTION_ACTIVE"),
    (0x4F, 0x00, "NOT_READY_TO_SWITCH_ON"),
    (0x4F, 0x40, "SWITCH_ON_DISABLED"),
    (0x6F, 0x21, "READY_TO_SWITCH_ON"),
    (0x6F, 0x23, "SWITCHED_ON"),
    (0x6F, 0x27, "OPERATION_ENABLED"),
    (0x6F, 0x07, "QUICK_STOP_ACTIVE"),
)
CSP = 8


def drive_state(statusword: int) -> str:
    name = _STATE_OF.get(statusword)
    if name is None:
        name = next((n for mask, value, n in _SW_STATES if statusword & mask == value), "UNKNOWN")
        if len(_STATE_OF) < 4096:  # a few dozen statuswords occur; bounded anyway
            _STATE_OF[statusword] = name
    return name


_STATE_OF: dict[int, str] = {}


class DriveLink:
    """The drive side of one PLCopen axis (attached as `Axis.drive`)."""

    def __init__(self, driver: EtherCATDriver, slave: int, axis_no: int, increments_per_rev: int):
        self.driver = driver
        self.slave = slave
        self.axis_no = axis_no
        self.axis = None
        self.increments_per_rev = increments_per_rev
        self.scale = 1.0  # increments per user unit, set when the axis is attached
        self.want = False
        self.reset_request = False  # MC_Reset: controlword bit 7 up until the drive leaves Fault
        self.status = 0
        self.state = "NOT_READY_TO_SWITCH_ON"
        self.was_enabled = False
        self.raw_pos: int | None = None  # the last 32-bit actual position, for unwrapping
        self.turns = 0  # multiples of 2**32 increments
        self.actual = 0  # unwrapped increments
        self.velocity = 0
        self.error_code = 0
        # its inputs are current: not during an outage (lost_frame_limit frames lost in a row, until
        # the slaves are back in OP)
        self.readable = False
        self.offset_s = 0.0  # delay compensation: how far ahead the setpoint is taken
        self.origin = 0.0  # axis units at the drive's increment 0 (MC_SetPosition, MC_Home move it)
        m = driver.master.slaves[slave]
        rx, tx = m.rx_layout, m.tx_layout
        self.rx_layout, self.tx_layout = rx, tx
        self._unpack_tx = tx.unpacker()
        keys_rx = [e.key for e in rx.data_entries]
        keys_tx = [e.key for e in tx.data_entries]
        need_rx, need_tx = [(0x6040, 0), (0x607A, 0)], [(0x6041, 0), (0x6064, 0)]
        for k in need_rx:
            if k not in keys_rx:
                raise MasterError(f"drive {m.name}: the RxPDO maps no {k[0]:#06x} (needed for CSP)")
        for k in need_tx:
            if k not in keys_tx:
                raise MasterError(f"drive {m.name}: the TxPDO maps no {k[0]:#06x} (needed for CSP)")
        self.i_cw, self.i_tp = keys_rx.index((0x6040, 0)), keys_rx.index((0x607A, 0))
        self.i_mode = keys_rx.index((0x6060, 0)) if (0x6060, 0) in keys_rx else None
        self.i_sw, self.i_ap = keys_tx.index((0x6041, 0)), keys_tx.index((0x6064, 0))
        self.i_av = keys_tx.index((0x606C, 0)) if (0x606C, 0) in keys_tx else None
        self.i_err = keys_tx.index((0x603F, 0)) if (0x603F, 0) in keys_tx else None
        self.out_values = [0] * len(rx.data_entries)
        if self.i_mode is not None:
            self.out_values[self.i_mode] = CSP

    # ------------------------------------------------------------------ what the axis calls
    def request_enable(self, on: bool) -> None:
        self.want = on

    @property
    def enabled(self) -> bool:
        return self.state == "OPERATION_ENABLED"

    @property
    def faulted(self) -> bool:
        return self.state in ("FAULT", "FAULT_REACTION_ACTIVE")

    def shift(self, delta: float) -> None:
        """The axis coordinate moves by delta units; the drive's increments stay where they are."""
        self.origin += delta

    def fault_reset(self) -> None:
        """MC_Reset: the rising edge of controlword bit 7 goes out with this cycle's frame (after a
        cycle with it low, if it was high), and bit 7 stays up until the drive has left Fault."""
        self.reset_request = self.faulted

    # ------------------------------------------------------------------ each cycle
    def attach(self, ax) -> None:
        self.axis = ax
        ax.drive = self
        c = ax.cfg
        self.scale = c.increments_per_unit or self.increments_per_rev / c.units_per_rev
        self._to_axis()
        ax.set_pos = ax.act_pos

    def _to_axis(self) -> None:
        ax = self.axis
        if ax is not None:
            ax.act_pos = self.actual / self.scale + self.origin
            ax.act_vel = self.velocity / self.scale

    def pack(self) -> bytes:
        st = self.state
        faulted = st == "FAULT" or st == "FAULT_REACTION_ACTIVE"
        if self.reset_request and not faulted:
            self.reset_request = False  # it left Fault
        ax = self.axis
        if self.reset_request and ax is not None and ax.reset_cmd is None:
            self.reset_request = False  # MC_Reset gave up (RESET_FAILED)
        if self.reset_request:  # bit 7 up (the cycle before it was down: the drive was in Fault)
            cw = 0x80
        elif faulted:
            cw = 0x00
        elif not self.want:
            # Shutdown (power stage off, ready) from the enabled side; Disable Voltage otherwise, and
            # once sent it stays until an enable request: the statusword is a cycle old, so deciding
            # on it alone could toggle a drive between Switch On Disabled and Ready To Switch On
            off = st in ("READY_TO_SWITCH_ON", "SWITCHED_ON", "OPERATION_ENABLED") and self.out_values[self.i_cw] != 0
            cw = 0x06 if off else 0x00
        elif st == "SWITCH_ON_DISABLED" or st == "NOT_READY_TO_SWITCH_ON":
            cw = 0x06
        elif st == "READY_TO_SWITCH_ON":
            cw = 0x07
        else:  # switched on, operation enabled, quick stop active
            cw = 0x0F
        if ax is not None and st == "OPERATION_ENABLED" and ax.power_on:
            pos = ax.set_pos - self.origin + ax.set_vel * self.offset_s
            target = int(round(pos * self.scale)) - self.turns * (1 << 32)
        else:
            target = self.raw_pos if self.raw_pos is not None else 0
        target = ((target + (1 << 31)) & 0xFFFFFFFF) - (1 << 31)
        v = self.out_values
        v[self.i_cw], v[self.i_tp] = cw, target
        return self.rx_layout.pack(v)

    def unpack(self, data: bytes) -> None:
        vals = self._unpack_tx(data)
        self.status = status = int(vals[self.i_sw])
        raw = int(vals[self.i_ap])
        last = self.raw_pos
        if last is not None and raw != last:
            d = (raw - last) & 0xFFFFFFFF
            if d >= 1 << 31:
                d -= 1 << 32
            if raw < last and d > 0:
                self.turns += 1
            elif raw > last and d < 0:
                self.turns -= 1
        self.raw_pos = raw
        self.actual = raw + self.turns * (1 << 32)
        self.velocity = int(vals[self.i_av]) if self.i_av is not None else 0
        self.error_code = int(vals[self.i_err]) if self.i_err is not None else 0
        self.state = state = _STATE_OF.get(status) or drive_state(status)
        self._to_axis()
        ax = self.axis
        if ax is None:
            return
        enabled = state == "OPERATION_ENABLED"
        if state == "FAULT" or state == "FAULT_REACTION_ACTIVE":  # faulted
            # statusword bit 13 in CSP: the drive's following error
            ax.lose_power(E.FOLLOWING_ERROR if status & 0x2000 else E.DRIVE_FAULT)
        elif self.was_enabled and not enabled and self.want and ax.power_on:
            ax.lose_power(E.POWER_STAGE_LOST)  # Safe Torque Off, or the drive switched itself off
        self.was_enabled = enabled
        if ax.reset_cmd is not None:  # MC_Reset: done in the exchange that shows the drive out of Fault
            ax.reset_progress()


class EtherCATDriver(IODriverBase):
    """The scan binding (an I/O driver on `plc.io`)."""

    name = "ethercat"

    def __init__(self, plc, config: SegmentConfig | dict, backend: str = "sim", iface: str = "", capture: str = ""):
        """`config`: a SegmentConfig (load_segment), or the same as a dict ({"segment": {...},
        "slave": [{"name": "d1", "type": "cia402", "axis": 1}, ...]})."""
        if isinstance(config, dict):
            config = from_dict(config)
        self.plc = plc
        self.cfg = config
        self.backend = backend
        self.segment: Segment | None = None
        self.task = None
        self.links: list = []
        self.io_in: list = []  # (slave, entry index, table, index, kind)
        self.io_out: list = []
        self.counters = {"frames": 0, "lost_frames": 0, "wkc_errors": 0, "outages": 0, "recoveries": 0}
        self.bad_run = 0
        self.outage = False
        self._cycles = 0
        self._t_offset = 0.0
        self.iface = iface
        self._choose_task()
        cycle_ns = int(
            round((config.cycle_s or (self.task.interval / 1e9 if self.task and self.task.interval else 0.001)) * 1e9)
        )
        self.cycle_ns = cycle_ns
        if backend == "sim":
            self.segment = build_segment(config)
            if capture:
                self.segment.open_capture(capture)
            self._setup_t = 0.0
            self.master: Master = FrameMaster(
                self._sim_transport, pause=self._sim_pause, now_ns=lambda: int(round(self._now() * 1e9))
            )
        elif backend == "soem":
            from .soem import SoemMaster

            if not iface:
                raise MasterError("the soem backend needs --ethercat-iface (a network interface)")
            self.master = SoemMaster(iface)
        else:
            raise MasterError(f"unknown EtherCAT backend '{backend}' (sim or soem)")
        try:
            self._start()
        except BaseException:  # a segment that cannot start leaves nothing open (the master, a capture)
            self.close()
            raise

    # ------------------------------------------------------------------ the sim transport
    def _now(self) -> float:
        return self.plc.clock.now() / 1e9 + self._setup_t

    def _sim_transport(self, frame: bytes):
        assert self.segment is not None  # the sim backend's
        return self.segment.exchange(frame, self._now())

    def _sim_pause(self, s: float) -> None:
        self._setup_t += s  # polling during setup lets simulated time pass

    # ------------------------------------------------------------------ startup
    def _choose_task(self) -> None:
        tasks = self.plc.tasks
        if self.cfg.task:
            for t in tasks:
                if t.name.lower() == self.cfg.task.lower():
                    self.task = t
                    return
            raise MasterError(
                f"{self.cfg.path}: [segment] task '{self.cfg.task}' is not a task of the program "
                f"({', '.join(t.name for t in tasks)})"
            )
        cyclic = [t for t in tasks if t.interval]
        self.task = min(cyclic, key=lambda t: t.interval) if cyclic else (tasks[0] if tasks else None)

    def _start(self) -> None:
        m = self.master
        m.open()
        found = m.scan()
        cfg = self.cfg
        if len(found) != len(cfg.slaves):
            raise MasterError(
                f"{cfg.path}: {len(cfg.slaves)} slave(s) configured but {len(found)} found on the segment"
            )
        assign = {}
        for i, (sc, info) in enumerate(zip(cfg.slaves, found)):
            if sc.product_code is not None and info.product_code != sc.product_code:
                raise MasterError(
                    f"{cfg.path}: slave {i} ({sc.name}) is product {info.product_code:#x}, "
                    f"configured {sc.product_code:#x}"
                )
            if sc.rx_pdos is not None or sc.tx_pdos is not None:
                assign[i] = (sc.rx_pdos, sc.tx_pdos)
        m.configure(pdo_assign=assign, dc_cycle_ns=self.cycle_ns if cfg.dc else 0)
        for i, sc in enumerate(cfg.slaves):
            if sc.axis:
                incr = 1 << sc.encoder_bits
                try:
                    incr = int.from_bytes(m.sdo_read(i, 0x608F, 1)[:4], "little") or incr
                except Exception:  # noqa: BLE001 - no 0x608F: the configured encoder resolution
                    pass
                link = DriveLink(self, i, sc.axis, incr)
                if cfg.compensate_delay and self.segment is not None:
                    link.offset_s = self.segment.d_comm(i) - self.segment.d_comm(0)
                self.links.append(link)
            self._bind_io(i, sc)
        self._exchange()  # the first inputs, so the axes start where the drives are
        m.set_state("OP")
        self._exchange()
        self._claim_axes()
        self.plc.io.append(self)

    def _bind_io(self, i: int, sc) -> None:
        info = self.master.slaves[i]
        image = self.plc.image
        pairs = []
        if sc.inputs_at:
            bits = [e for e in info.tx_layout.data_entries if e.bits == 1]
            pairs += [(e, _next_bit(sc.inputs_at, k)) for k, e in enumerate(bits)]
        if sc.outputs_at:
            bits = [e for e in info.rx_layout.data_entries if e.bits == 1]
            pairs += [(e, _next_bit(sc.outputs_at, k)) for k, e in enumerate(bits)]
        for key, addr in sc.bind.items():
            e = _find_entry(info, key)
            if e is None:
                raise MasterError(f"{self.cfg.path}: slave {sc.name}: no PDO entry '{key}' to bind to {addr}")
            pairs.append((e, addr))
        for e, addr in pairs:
            area, size, idx = parse_address(addr)
            table = image.tables[(area, size)]
            lay = info.tx_layout if area == "I" else info.rx_layout
            if e not in lay.data_entries:
                raise MasterError(
                    f"{self.cfg.path}: slave {sc.name}: {addr} is an "
                    f"{'input' if area == 'I' else 'output'} but entry {e.index:#06x}:{e.sub:02x} is "
                    f"{'an output' if area == 'I' else 'an input'}"
                )
            pos = lay.data_entries.index(e)
            (self.io_in if area == "I" else self.io_out).append((i, pos, table, idx, size))
        self._slave_io = sorted({x[0] for x in self.io_in + self.io_out})

    # ------------------------------------------------------------------ the I/O driver interface
    def _claim_axes(self) -> None:
        """Register the drive links with the motion registry: an axis is bound when it is created,
        or now if it exists."""
        reg = registry(self.plc)
        if reg is None:
            return
        for link in self.links:
            reg.add_drive(link)

    def after_job(self, task: Task | None = None) -> None:
        if task is None:  # stop or fault: outputs safe, drives disabled
            for link in self.links:
                link.want = False
            self._exchange()
            return
        if task is not self.task:
            return
        self._exchange()

    def rebind(self) -> None:
        for link in self.links:
            link.axis = None
        self._claim_axes()

    # ------------------------------------------------------------------ one cycle
    def _exchange(self) -> None:
        m = self.master
        if not self.io_out:  # drives only: each link's image straight into the frame
            for link in self.links:
                m.write_outputs(link.slave, link.pack())
        else:
            self._outputs_with_io(m)
        wkc = m.exchange()
        self.counters["frames"] += 1
        ok = wkc == m.expected_wkc
        if wkc < 0:
            self.counters["lost_frames"] += 1
        elif not ok:
            self.counters["wkc_errors"] += 1
        if ok:
            for link in self.links:
                link.unpack(m.read_inputs(link.slave))
            for i, pos, table, idx, size in self.io_in:
                v = m.slaves[i].tx_layout.unpack(m.read_inputs(i))[pos]
                table[idx] = bool(v) if size == "X" else int(v)
            if self.outage:
                self._recover()
            for link in self.links:  # up to lost_frame_limit lost frames keep the last values
                link.readable = not self.outage
            self.bad_run = 0
        else:
            self.bad_run += 1
            if self.bad_run >= self.cfg.lost_frame_limit and not self.outage:
                self.outage = True
                self.counters["outages"] += 1
                for link in self.links:
                    link.state = "UNKNOWN"
                    link.readable = False
                    ax = link.axis
                    if ax is not None:
                        ax.lose_power(E.COMMUNICATION_LOST)
        self._cycles += 1

    def _outputs_with_io(self, m: Master) -> None:
        """The drives' images with the bound %Q variables put into their entries."""
        outs = {}
        for link in self.links:
            outs[link.slave] = link.pack()
        per: dict[int, list] = {}
        for i, pos, table, idx, _size in self.io_out:
            lay = m.slaves[i].rx_layout
            vals = per.get(i)
            if vals is None:
                vals = per[i] = list(lay.unpack(outs[i])) if i in outs else [0] * len(lay.data_entries)
            vals[pos] = table[idx]
        for i, vals in per.items():
            outs[i] = m.slaves[i].rx_layout.pack(vals)
        for i, data in outs.items():
            m.write_outputs(i, data)

    def _recover(self) -> None:
        """Frames come back: bring slaves that fell out of OP back to it."""
        m = self.master
        try:
            states = m.states()
            if any(s != "OP" for s in states):
                for i, s in enumerate(states):
                    if s.startswith("INIT") or s.startswith("PREOP"):
                        raise MasterError(f"slave {i} fell back to {s}: restart the segment")
                m.set_state("SAFEOP")
                m.set_state("OP")
            self.outage = False
            self.counters["recoveries"] += 1
        except MasterError:
            pass

    def stats(self) -> dict:
        out: dict[str, Any] = dict(self.counters)
        out["expected_wkc"] = self.master.expected_wkc
        out["slaves"] = [f"{s.name}:{s.state}" for s in self.master.slaves]
        out["drives"] = {f"axis{l.axis_no}": l.state for l in self.links}
        return out

    def status(self) -> dict[str, Any]:
        """The online mode's view: lost frames, working-counter errors and each slave's AL state.
        One LRW datagram serves every slave: a working-counter error belongs to the segment, so no
        slave has a count of its own (None)."""
        c = self.counters
        slaves = [
            {"position": i + 1, "name": s.name, "state": s.state, "wkc_errors": None}
            for i, s in enumerate(self.master.slaves)
        ]
        return {"lost_frames": c.get("lost_frames", 0), "wkc_errors": c.get("wkc_errors", 0), "slaves": slaves}

    def close(self) -> None:
        try:
            self.master.close()
        finally:
            if self.segment is not None:
                self.segment.close()


def _next_bit(addr: str, k: int) -> str:
    area, size, idx = parse_address(addr)
    byte, bit = divmod(idx + k, 8)
    return f"%{area}X{byte}.{bit}"


def _find_entry(info, key: str):
    key = key.strip().lower()
    for lay in (info.rx_layout, info.tx_layout):
        for e in lay.data_entries:
            if key == f"{e.index:#06x}:{e.sub:02x}" or key == f"{e.index:#06x}:{e.sub}" or key == e.name.lower():
                return e
    return None
