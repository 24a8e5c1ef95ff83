"""An emulated EtherCAT slave controller (ESC): registers, SII, SyncManagers, FMMUs, AL states, DC.

One `SlaveController` answers datagrams the way an ET1100-class ESC does, as far as a master
uses it: register reads/writes with their side effects (AL control → the state machine, SII
control → EEPROM reads, 0x0900 → receive-time latch, 0x0910 → system time), SyncManagers with
mailbox semantics (a full write mailbox refuses writes, an empty read mailbox refuses reads: no
working-counter increment) and buffered process data (the last byte written commits the
outputs), FMMUs mapping the logical address space for LRD/LWR/LRW, and the SyncManager
watchdog. The application behind it is a `Device` (object dictionary, process data, physics).

Time: the segment passes the moment a datagram reaches the slave (seconds on its clock); the
device's physics is advanced lazily up to that moment, so each slave sees its own D_comm(n).
"""

from __future__ import annotations

import struct
from typing import Literal

from . import sii as siimod
from .coe import SdoServer
from .devices.base import (
    AL_BOOTSTRAP_UNSUPPORTED,
    AL_DC_SYNC0_CYCLE,
    AL_INVALID_INPUT_CONFIG,
    AL_INVALID_MAILBOX_CONFIG,
    AL_INVALID_OUTPUT_CONFIG,
    AL_INVALID_STATE_CHANGE,
    AL_OK,
    AL_SYNC_WATCHDOG,
    AL_UNKNOWN_STATE,
)

INIT, PREOP, BOOT, SAFEOP, OP = 1, 2, 3, 4, 8
STATE_NAMES = {INIT: "INIT", PREOP: "PREOP", BOOT: "BOOT", SAFEOP: "SAFEOP", OP: "OP"}

# register addresses
REG_TYPE, REG_STADR, REG_ALIAS, REG_DLSTAT = 0x0000, 0x0010, 0x0012, 0x0110
REG_ALCTL, REG_ALSTAT, REG_ALCODE = 0x0120, 0x0130, 0x0134
REG_WDDIV, REG_WDSM, REG_WDSTAT = 0x0400, 0x0420, 0x0440
REG_EEPCFG, REG_EEPCTL, REG_EEPADR, REG_EEPDAT = 0x0500, 0x0502, 0x0504, 0x0508
REG_FMMU, REG_SM = 0x0600, 0x0800
REG_DCRX, REG_DCSYS, REG_DCRXPU, REG_DCOFS, REG_DCDLY, REG_DCDIFF = 0x0900, 0x0910, 0x0918, 0x0920, 0x0928, 0x092C
REG_DCCUC, REG_DCACT, REG_DCSTART, REG_DCCYC0 = 0x0980, 0x0981, 0x0990, 0x09A0

# writable register ranges (end exclusive); the rest of 0x0000-0x0FFF is read-only
_WRITABLE_RANGES = (
    (0x0010, 0x0014),
    (0x0100, 0x0104),
    (0x0120, 0x0122),
    (0x0200, 0x0204),
    (0x0300, 0x0314),
    (0x0400, 0x0402),
    (0x0410, 0x0412),
    (0x0420, 0x0422),
    (0x0500, 0x0502),
    (0x0502, 0x0510),
    (0x0600, 0x0700),
    (0x0800, 0x0880),
    (0x0900, 0x0904),
    (0x0910, 0x0918),
    (0x0920, 0x0930),
    (0x0930, 0x0936),
    (0x0980, 0x09A8),
)

MBX_OUT, MBX_IN, PD_OUT, PD_IN = 0x1000, 0x1080, 0x1100, 0x1400
_U64, _U32 = struct.Struct("<Q"), struct.Struct("<I")
_SM_STATUS_MBX_FULL = 0x08


class SlaveController:
    forwarding_delay: float  # s per pass of a frame (its port-to-port delay): set by the segment it is in

    def __init__(self, device, mbx_size: int = 128, clock_base_ns: int = 0, alias: int = 0):
        self.device = device
        self.mem = bytearray(0x10000)
        m = self.mem
        m[0x0000], m[0x0001] = 0x11, 0x00  # ET1100-class
        struct.pack_into("<H", m, 0x0002, 0x0001)
        m[0x0004], m[0x0005], m[0x0006], m[0x0007] = 8, 8, 8, 0x0F
        struct.pack_into("<H", m, 0x0008, 0x01CC)  # DC, 64-bit DC, enhanced link detection …
        struct.pack_into("<H", m, REG_ALSTAT, INIT)
        struct.pack_into("<H", m, REG_EEPCTL, 0x0040)  # 8-byte reads
        struct.pack_into("<H", m, REG_WDDIV, 0x09C2)  # 100 µs watchdog unit
        struct.pack_into("<H", m, REG_WDSM, 1000)  # SM watchdog 100 ms
        m[0x0140] = 0x08
        self.mbx_size = mbx_size if device.has_mailbox else 0
        rx, tx = device.rx_layout.size, device.tx_layout.size
        sms = []
        if device.has_mailbox:
            sms += [siimod.SmConfig(MBX_OUT, mbx_size, 0x26, 1, 1), siimod.SmConfig(MBX_IN, mbx_size, 0x22, 1, 2)]
        else:
            sms += [siimod.SmConfig(0, 0, 0, 0, 0), siimod.SmConfig(0, 0, 0, 0, 0)]
        sms += [
            siimod.SmConfig(PD_OUT, rx, 0x64, 1 if rx else 0, 3),
            siimod.SmConfig(PD_IN, tx, 0x20, 1 if tx else 0, 4),
        ]
        self.sii_sms = sms
        self.sii = bytearray(
            siimod.build(
                device.vendor_id,
                device.product_code,
                device.revision,
                device.serial,
                device.name,
                device.group,
                device.name,
                sms,
                [1, 2, 3, 0],
                mailbox=device.has_mailbox,
                alias=alias,
                rx_pdos=_sii_pdos(device, device.rx_assign, 2),
                tx_pdos=_sii_pdos(device, device.tx_assign, 3),
            )
        )
        struct.pack_into("<H", m, REG_ALIAS, alias)
        self.sdo = SdoServer(device.od, mbx_size) if device.has_mailbox else None
        self.mbx_queue: list = []
        self.last_mbx = b""
        self.clock_base_ns = clock_base_ns
        self.t_dev = 0.0  # how far the device's physics has been advanced (s)
        self.rx_latch_ns = 0
        self.last_commit: float | None = None  # segment time of the last output commit (SM watchdog)
        self.has_downstream = False
        self.set_links(False)
        self.pending_outputs: tuple[float, bytes] | None = None  # (apply_at, bytes) when DC SYNC0 defers outputs
        self.stats = {"frames": 0, "commits": 0}
        self._sm_cache: list | None = None
        self._fmmu_cache: list | None = None
        self._plans: dict = {}  # (read, write, address, length) → a logical datagram's plan
        self._grid: tuple[float, float] | None | Literal[False] = False  # SYNC0 pulses (False: to compute)
        self._wd_limit = self._watchdog_limit()

    # ------------------------------------------------------------------ helpers
    @property
    def al_state(self) -> int:
        return struct.unpack_from("<H", self.mem, REG_ALSTAT)[0] & 0x0F

    @property
    def state_name(self) -> str:
        return STATE_NAMES.get(self.al_state, hex(self.al_state))

    @property
    def station(self) -> int:
        m = self.mem
        return m[REG_STADR] | (m[REG_STADR + 1] << 8)

    def set_links(self, downstream: bool) -> None:
        """DL status: port 0 link + communication; port 1 open to a next slave or closed (loop)."""
        self.has_downstream = downstream
        v = 0x0001 | 0x0010 | 0x0200 | 0x5000
        v |= (0x0020 | 0x0800) if downstream else 0x0400
        struct.pack_into("<H", self.mem, REG_DLSTAT, v)

    def local_ns(self, t: float) -> int:
        return (int(round(t * 1e9)) + self.clock_base_ns) & 0xFFFFFFFFFFFFFFFF

    def system_ns(self, t: float) -> int:
        ofs = _U64.unpack_from(self.mem, REG_DCOFS)[0]
        return (int(round(t * 1e9)) + self.clock_base_ns + ofs) & 0xFFFFFFFFFFFFFFFF  # local_ns(t) + offset

    def _sms(self) -> list:
        """Enabled SyncManagers as [(k, start, end, control)], cached until their registers change."""
        c = self._sm_cache
        if c is None:
            c = self._sm_cache = []
            for k in range(self.mem[0x0005]):
                start, length, ctl, _st, en = self.sm(k)
                if en and length:
                    c.append((k, start, start + length, ctl))
        return c

    def sm(self, k: int):
        """(start, length, control, status, enabled) of SyncManager k."""
        start, length, ctl, status, act = struct.unpack_from("<HHBBB", self.mem, REG_SM + 8 * k)
        return start, length, ctl, status, bool(act & 1)

    def _set_sm_status(self, k: int, full: bool) -> None:
        a = REG_SM + 8 * k + 5
        self.mem[a] = (self.mem[a] | _SM_STATUS_MBX_FULL) if full else (self.mem[a] & ~_SM_STATUS_MBX_FULL & 0xFF)

    def _sync_grid(self):
        """(first SYNC0 pulse, period) in segment seconds while SYNC0 is active, else None."""
        g = self._grid
        if g is False:
            g = None
            if self.mem[REG_DCACT] & 0x03 == 0x03:
                cyc = struct.unpack_from("<I", self.mem, REG_DCCYC0)[0]
                start = struct.unpack_from("<Q", self.mem, REG_DCSTART)[0]
                ofs = struct.unpack_from("<Q", self.mem, REG_DCOFS)[0]
                if cyc:
                    local = (start - ofs) & 0xFFFFFFFFFFFFFFFF
                    g = ((local - self.clock_base_ns) * 1e-9, cyc * 1e-9)
            self._grid = g
        return g

    def advance(self, t: float) -> None:
        """Bring the device to time t. With SYNC0 running the device works on the pulses, as a DC
        drive does: it steps to the last pulse at or before t, taking deferred outputs at their
        pulse, and its inputs are those of that pulse. Then the SyncManager watchdog."""
        grid = self._grid
        if grid is False:
            grid = self._sync_grid()
        if grid is not None:
            t0, cyc = grid
            if t < t0:
                return
            t = t0 + int((t - t0) / cyc + 1e-9) * cyc
        self._advance_to(t)

    def _advance_to(self, t: float) -> None:
        """advance(t) once t is a pulse (with SYNC0)."""
        if t <= self.t_dev:
            return
        device = self.device
        po = self.pending_outputs
        if po is not None and po[0] <= t + 1e-12:
            if po[0] > self.t_dev:
                device.step(po[0], po[0] - self.t_dev)
                self.t_dev = po[0]
            self.pending_outputs = None
            device.write_outputs(po[1])
        if t > self.t_dev:
            device.step(t, t - self.t_dev)
            self.t_dev = t
        last = self.last_commit
        if (
            last is not None
            and t - last > self._wd_limit
            and self._wd_limit > 0
            and self.mem[REG_ALSTAT] & 0x0F == OP
            and device.rx_layout.size
        ):
            self.mem[REG_WDSTAT] = 0
            self._enter(SAFEOP, AL_SYNC_WATCHDOG)

    def _watchdog_limit(self) -> float:
        div, wd = struct.unpack_from("<H", self.mem, REG_WDDIV)[0], struct.unpack_from("<H", self.mem, REG_WDSM)[0]
        return wd * (div + 2) * 40e-9

    # ------------------------------------------------------------------ the AL state machine
    def _enter(self, new: int, code: int = AL_OK) -> None:
        old = self.al_state
        if code:
            struct.pack_into("<H", self.mem, REG_ALSTAT, new | 0x10)
            struct.pack_into("<H", self.mem, REG_ALCODE, code)
        else:
            struct.pack_into("<H", self.mem, REG_ALSTAT, new)
            struct.pack_into("<H", self.mem, REG_ALCODE, 0)
        if new != old:
            self.device.on_state(STATE_NAMES[old], STATE_NAMES[new])
            if new < SAFEOP:
                self.last_commit = None
                self.pending_outputs = None
            if new == INIT:
                self.mbx_queue.clear()
                for k in range(2):
                    self._set_sm_status(k, False)

    def _al_control(self, value: int) -> None:
        req, ack = value & 0x0F, bool(value & 0x10)
        status = struct.unpack_from("<H", self.mem, REG_ALSTAT)[0]
        cur, err = status & 0x0F, bool(status & 0x10)
        order = [INIT, PREOP, SAFEOP, OP]
        if err and not ack and req in order and order.index(req) > order.index(cur):
            return  # an error must be acknowledged before going up
        if req not in STATE_NAMES:
            return self._enter(cur, AL_UNKNOWN_STATE)
        if req == BOOT:
            return self._enter(cur, AL_BOOTSTRAP_UNSUPPORTED)
        if req == cur:
            return self._enter(cur) if ack or not err else None
        if req < cur or req == INIT:  # going down is always allowed
            return self._enter(req)
        if order.index(req) != order.index(cur) + 1:
            return self._enter(cur, AL_INVALID_STATE_CHANGE)
        code = self._check(cur, req)
        if code:
            return self._enter(cur, code)
        self._enter(req)

    def _check(self, cur: int, req: int) -> int:
        d = self.device
        if req == PREOP and d.has_mailbox:
            for k in (0, 1):
                start, length, ctl, _st, en = self.sm(k)
                want = self.sii_sms[k]
                if not en or start != want.start or length != want.length or (ctl & 0x0F) != (want.control & 0x0F):
                    return AL_INVALID_MAILBOX_CONFIG
        if req == SAFEOP:
            code = d.check_transition(STATE_NAMES[cur], STATE_NAMES[req])
            if code:
                return code
            rx, tx = d.rx_layout.size, d.tx_layout.size
            for k, size, direction, code in (
                (2, rx, 0x04, AL_INVALID_OUTPUT_CONFIG),
                (3, tx, 0x00, AL_INVALID_INPUT_CONFIG),
            ):
                start, length, ctl, _st, en = self.sm(k)
                if size and (not en or length != size or (ctl & 0x0C) != direction):
                    return code
            act = self.mem[REG_DCACT]
            if act & 0x03 == 0x03 and struct.unpack_from("<I", self.mem, REG_DCCYC0)[0] == 0:
                return AL_DC_SYNC0_CYCLE
        if req == OP:
            code = d.check_transition(STATE_NAMES[cur], STATE_NAMES[req])
            if code:
                return code
        return AL_OK

    # ------------------------------------------------------------------ SII
    def _sii_command(self) -> None:
        ctl = struct.unpack_from("<H", self.mem, REG_EEPCTL)[0]
        cmd = (ctl >> 8) & 0x07
        addr = struct.unpack_from("<I", self.mem, REG_EEPADR)[0]
        status = 0x0040
        if cmd == 0x01:  # read 8 bytes at a word address
            a = addr * 2
            chunk = bytes(self.sii[a : a + 8]).ljust(8, b"\xff")
            self.mem[REG_EEPDAT : REG_EEPDAT + 8] = chunk
        elif cmd == 0x02:  # write one word (needs write enable)
            if ctl & 0x0001 and addr * 2 + 2 <= len(self.sii):
                self.sii[addr * 2 : addr * 2 + 2] = self.mem[REG_EEPDAT : REG_EEPDAT + 2]
            else:
                status |= 0x2000  # command error
        elif cmd == 0x04:  # reload
            pass
        elif cmd:
            status |= 0x2000
        struct.pack_into("<H", self.mem, REG_EEPCTL, status)

    # ------------------------------------------------------------------ mailbox
    def _mailbox_written(self, t: float) -> None:
        start, length, *_ = self.sm(0)
        req = bytes(self.mem[start : start + length])
        self._set_sm_status(0, False)  # the application consumed the request
        if self.sdo is not None:
            self.advance(t)
            self.mbx_queue.extend(self.sdo.handle(req))
            if any(k in (0x1C12, 0x1C13) or 0x1600 <= k < 0x1C00 for k in _touched(req)):
                self.device.remap()
        self._fill_mailbox()

    def _fill_mailbox(self) -> None:
        if self.sdo is not None:
            while self.device.emergencies:
                self.mbx_queue.append(self.sdo.emergency(*self.device.emergencies.pop(0)))
        start, length, _ctl, status, en = self.sm(1)
        if not en or status & _SM_STATUS_MBX_FULL or not self.mbx_queue:
            return
        msg = self.mbx_queue.pop(0)
        self.last_mbx = msg
        self.mem[start : start + length] = msg[:length].ljust(length, b"\0")
        self._set_sm_status(1, True)

    # ------------------------------------------------------------------ memory access with side effects
    def read(self, ado: int, n: int, t: float):
        """Bytes at ado for a read datagram, or None when a SyncManager refuses the access."""
        end = ado + n
        mem = self.mem
        if ado < REG_DCSYS + 8 and end > REG_DCSYS:
            _U64.pack_into(mem, REG_DCSYS, self.system_ns(t))
        if end > 0x1000:
            for k, start, stop, ctl in self._sms():
                if end <= start or ado >= stop or ctl & 0x0C:  # written by the master: reading is plain RAM
                    continue
                if ctl & 0x03 == 0x02:  # mailbox the master reads
                    if not mem[REG_SM + 8 * k + 5] & _SM_STATUS_MBX_FULL:
                        return None
                    data = bytes(mem[ado:end])
                    if end >= stop:
                        self._set_sm_status(k, False)
                        self._fill_mailbox()
                    return data
                self.advance(t)  # buffered inputs: the device's latest image
                mem[start:stop] = self.device.read_inputs()[: stop - start]
        return bytes(mem[ado:end])

    def write(self, ado: int, data, t: float) -> bool:
        """Store data at ado for a write datagram; False when a SyncManager refuses it."""
        n = len(data)
        end = ado + n
        mem = self.mem
        if ado == REG_DCSYS and n == 8:  # the cyclic FRMW of the reference clock's time
            mem[REG_DCSYS:end] = data
            self._dc_time_written(ado, end, t)
            return True
        if ado < 0x1000:
            stop = min(end, 0x1000)
            if _WRITABLE.find(0, ado, stop) < 0:  # all of it writable (the usual case)
                mem[ado:stop] = data[: stop - ado]
            else:
                for a in range(ado, stop):
                    if _WRITABLE[a]:
                        mem[a] = data[a - ado]
            if _EFFECTS.find(1, ado, stop) >= 0:
                self._register_effects(ado, end, t)
            if end <= 0x1000:
                return True
        commit: tuple | None = None
        for k, start, stop, ctl in self._sms():
            if end <= start or ado >= stop or not ctl & 0x04:  # read by the master: writes are plain RAM
                continue
            if ctl & 0x03 == 0x02:
                if mem[REG_SM + 8 * k + 5] & _SM_STATUS_MBX_FULL:
                    return False
                if end >= stop:
                    commit = ("mbx", k)
            elif end >= stop:
                commit = ("pd", k, start, stop - start)
        lo = max(ado, 0x1000)
        mem[lo:end] = data[lo - ado :]
        if commit is not None:
            if commit[0] == "mbx":
                self._set_sm_status(commit[1], True)
                self._mailbox_written(t)
            elif self.al_state == OP:
                _, k, start, length = commit
                self.last_commit = t
                self.stats["commits"] += 1
                self._outputs(bytes(mem[start : start + length]), t)
        return True

    def _outputs(self, data: bytes, t: float) -> None:
        grid = self._grid
        if grid is False:
            grid = self._sync_grid()
        if grid is not None:  # DC SYNC0: outputs take effect at the next pulse
            t0, cyc = grid
            if t < t0:
                apply_at = t0
            else:  # advance(t), with the pulse at or before t computed once
                k = int((t - t0) / cyc + 1e-9)
                apply_at = t0 + (k + 1) * cyc
                self._advance_to(t0 + k * cyc)
            self.pending_outputs = (apply_at, data)  # a newer frame before the pulse wins
            return
        self.advance(t)
        self.device.write_outputs(data)

    def _register_effects(self, ado: int, end: int, t: float) -> None:
        """The side effects of a register write that touched [ado, end)."""
        if ado >= REG_DCSYS and end <= REG_DCSYS + 8:  # the cyclic FRMW: nothing else is there
            return self._dc_time_written(ado, end, t)

        def hit(a, n=2):
            return ado < a + n and end > a

        if hit(REG_SM, 0x80):
            self._sm_cache = None
            self._plans.clear()
        if hit(REG_FMMU, 0x100):
            self._fmmu_cache = None
            self._plans.clear()
        if hit(REG_WDDIV) or hit(REG_WDSM):
            self._wd_limit = self._watchdog_limit()
        if hit(REG_DCOFS, 8) or hit(REG_DCCUC, 0x28):
            self._grid = False
        if hit(REG_ALCTL):
            self._al_control(struct.unpack_from("<H", self.mem, REG_ALCTL)[0])
        if hit(REG_EEPCTL):
            self._sii_command()
        if hit(REG_DCRX, 4):
            self.rx_latch_ns = self.local_ns(t)
        if hit(REG_DCSYS, 8):
            self._dc_time_written(ado, end, t)
        if hit(REG_SM + 8 + 6, 1):  # SM1 repeat request: resend the last mail
            act = self.mem[REG_SM + 8 + 6]
            pdi = self.mem[REG_SM + 8 + 7]
            if bool(act & 0x02) != bool(pdi & 0x02) and self.last_mbx:
                start, length, *_ = self.sm(1)
                self.mem[start : start + length] = self.last_mbx[:length].ljust(length, b"\0")
                self._set_sm_status(1, True)
                self.mem[REG_SM + 8 + 7] = (pdi & ~0x02 & 0xFF) | (act & 0x02)

    def _dc_time_written(self, ado: int, end: int, t: float) -> None:
        """The reference clock's time written by the master (ARMW/FRMW): correct this clock."""
        mem = self.mem
        written = (
            _U64.unpack_from(mem, REG_DCSYS)[0]
            if end - ado >= 8 or ado != REG_DCSYS
            else _U32.unpack_from(mem, REG_DCSYS)[0]
        )
        delay = _U32.unpack_from(mem, REG_DCDLY)[0]
        ofs = _U64.unpack_from(mem, REG_DCOFS)[0]
        mine = (round(t * 1e9) + self.clock_base_ns + ofs) & 0xFFFFFFFFFFFFFFFF  # system_ns(t)
        if end - ado < 8:  # a 32-bit write compares the low halves
            diff = ((mine & 0xFFFFFFFF) - ((written + delay) & 0xFFFFFFFF) + (1 << 31)) % (1 << 32) - (1 << 31)
        else:
            diff = mine - (written + delay)
        if diff:
            _U64.pack_into(mem, REG_DCOFS, (ofs - diff) & 0xFFFFFFFFFFFFFFFF)
            self._grid = False
            _U32.pack_into(mem, REG_DCDIFF, (min(abs(diff), 0x7FFFFFFF)) | (0x80000000 if diff < 0 else 0))
        else:  # in step (the emulated clocks do not drift)
            _U32.pack_into(mem, REG_DCDIFF, 0)

    def receive_times(self, t_port0: float, t_port1: float) -> None:
        """The 0x0900 latch: local times at which the frame passed port 0 (out) and port 1 (back)."""
        struct.pack_into(
            "<II", self.mem, REG_DCRX, self.local_ns(t_port0) & 0xFFFFFFFF, self.local_ns(t_port1) & 0xFFFFFFFF
        )
        struct.pack_into("<Q", self.mem, REG_DCRXPU, self.local_ns(t_port0))

    # ------------------------------------------------------------------ FMMUs
    def fmmus(self):
        """Active FMMUs: [(logical start, length, start bit, stop bit, physical start, phys bit, type)]."""
        if self._fmmu_cache is not None:
            return self._fmmu_cache
        out = self._fmmu_cache = []
        for k in range(self.mem[0x0004]):
            a = REG_FMMU + 16 * k
            lstart, ln, lsb, leb, pstart, psb, typ, act = struct.unpack_from("<IHBBHBBB", self.mem, a)
            if act & 1 and ln and typ & 3:
                out.append((lstart, ln, lsb, leb, pstart, psb, typ))
        return out

    def logical(self, cmd_read: bool, cmd_write: bool, addr: int, data: bytearray, t: float) -> int:
        """Apply an LRD/LWR/LRW to this slave: returns the working-counter increment."""
        key = (cmd_read, cmd_write, addr, len(data))
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plans[key] = self._plan(cmd_read, cmd_write, addr, len(data))
        if plan is False:
            return self._logical(cmd_read, cmd_write, addr, data, t)
        # the cyclic case: FMMUs that map whole buffered SyncManagers (the same effects as the
        # generic path, without looking every register up again)
        inc = 0
        both = cmd_read and cmd_write
        original = bytes(data) if both else data
        mem = self.mem
        advanced = False  # advance(t) ran: a second call with the same t does nothing
        for out, off, start, stop in plan:
            n = stop - start
            if out:
                chunk = bytes(original[off : off + n])
                mem[start:stop] = chunk
                if mem[REG_ALSTAT] & 0x0F == OP:
                    self.last_commit = t
                    self.stats["commits"] += 1
                    self._outputs(chunk, t)
                    advanced = True
                inc |= 2
            else:
                if not advanced:
                    self.advance(t)
                    advanced = True
                inp = self.device.read_inputs()
                if len(inp) != n:
                    inp = inp[:n]
                mem[start:stop] = inp
                data[off : off + n] = inp
                inc |= 1
        if both:
            return (inc & 1) + (inc & 2)
        return 1 if inc else 0

    def _plan(self, cmd_read: bool, cmd_write: bool, addr: int, length: int):
        """[(is output, offset in the datagram, SM start, SM end)] when every FMMU the datagram touches
        maps one whole buffered SyncManager byte for byte inside it; else False (the generic path)."""
        plan = []
        end = addr + length
        sms = self._sms()
        for lstart, ln, lsb, leb, pstart, psb, typ in self.fmmus():
            if max(addr, lstart) >= min(end, lstart + ln):
                continue
            if lsb or leb != 7 or psb or lstart < addr or lstart + ln > end:
                return False
            sm = next((x for x in sms if x[1] == pstart and x[2] - x[1] == ln), None)
            if sm is None or sm[3] & 0x03 == 0x02 or typ not in (1, 2):
                return False
            out = typ == 2
            if out != bool(sm[3] & 0x04):
                return False
            if (out and cmd_write) or (not out and cmd_read):
                plan.append((out, lstart - addr, sm[1], sm[2]))
        return plan

    def _logical(self, cmd_read: bool, cmd_write: bool, addr: int, data: bytearray, t: float) -> int:
        inc = 0
        end = addr + len(data)
        original = bytes(data) if cmd_read and cmd_write else data
        for lstart, ln, lsb, leb, pstart, psb, typ in self.fmmus():
            if lsb or leb != 7 or psb:
                inc |= self._logical_bits(
                    cmd_read, cmd_write, addr, data, original, t, lstart, ln, lsb, leb, pstart, psb, typ
                )
                continue
            lo, hi = max(addr, lstart), min(end, lstart + ln)
            if lo >= hi:
                continue
            phys = pstart + (lo - lstart)
            n = hi - lo
            off = lo - addr
            if typ & 0x02 and cmd_write:  # the slave takes outputs from the frame
                if self.write(phys, original[off : off + n], t):
                    inc |= 2
            if typ & 0x01 and cmd_read:  # the slave puts inputs into the frame
                got = self.read(phys, n, t)
                if got is not None:
                    data[off : off + n] = got
                    inc |= 1
        return (1 if inc & 1 else 0) + (2 if inc & 2 else 0) if cmd_read and cmd_write else (1 if inc else 0)

    def _logical_bits(self, cmd_read, cmd_write, addr, data, original, t, lstart, ln, lsb, leb, pstart, psb, typ):
        """A bit-granular FMMU: logical bits lstart·8+lsb … (lstart+ln-1)·8+leb ↔ physical bits from pstart·8+psb."""
        l0 = lstart * 8 + lsb
        nbits = (ln - 1) * 8 + leb - lsb + 1
        p0 = pstart * 8 + psb
        lo, hi = max(l0, addr * 8), min(l0 + nbits, (addr + len(data)) * 8)
        if lo >= hi:
            return 0
        width = hi - lo
        mask = (1 << width) - 1
        pb_lo = p0 + (lo - l0)
        pbyte, pshift = divmod(pb_lo, 8)
        pn = (pshift + width + 7) // 8
        dshift = lo - addr * 8
        inc = 0
        if typ & 0x02 and cmd_write:
            frame_bits = (int.from_bytes(original, "little") >> dshift) & mask
            cur = int.from_bytes(self.mem[pbyte : pbyte + pn], "little")
            new = (cur & ~(mask << pshift)) | (frame_bits << pshift)
            if self.write(pbyte, new.to_bytes(pn, "little"), t):
                inc |= 2
        if typ & 0x01 and cmd_read:
            got = self.read(pbyte, pn, t)
            if got is not None:
                bits = (int.from_bytes(got, "little") >> pshift) & mask
                cur = int.from_bytes(data, "little")
                cur = (cur & ~(mask << dshift)) | (bits << dshift)
                data[:] = cur.to_bytes(len(data), "little")
                inc |= 1
        return inc


def _writable(a: int) -> bool:
    for lo, hi in _WRITABLE_RANGES:
        if lo <= a < hi:
            return not (REG_SM <= a < REG_SM + 0x80 and (a - REG_SM) % 8 == 5)  # SM status is read-only
    return False


_WRITABLE = bytes(_writable(a) for a in range(0x1000))
# registers whose write has a side effect (see _register_effects)
_EFFECTS = bytes(
    any(
        lo <= a < hi
        for lo, hi in (
            (REG_SM, REG_SM + 0x80),
            (REG_FMMU, REG_FMMU + 0x100),
            (REG_WDDIV, REG_WDDIV + 2),
            (REG_WDSM, REG_WDSM + 2),
            (REG_ALCTL, REG_ALCTL + 2),
            (REG_EEPCTL, REG_EEPCTL + 2),
            (REG_DCRX, REG_DCRX + 4),
            (REG_DCSYS, REG_DCSYS + 8),
            (REG_DCOFS, REG_DCOFS + 8),
            (REG_DCCUC, REG_DCCUC + 0x28),
        )
    )
    for a in range(0x1000)
)


def _sii_pdos(device, assign: int, sm: int) -> list:
    """The assigned PDOs of a device for the SII PDO categories."""
    from .od import DTYPES

    od = device.od
    if not od.has(assign):
        return []
    out = []
    for k in range(1, int(od[assign, 0]) + 1):
        pdo = int(od[assign, k])
        entries = []
        for j in range(1, int(od[pdo, 0]) + 1):
            w = int(od[pdo, j])
            ix, sx, bits = w >> 16, (w >> 8) & 0xFF, w & 0xFF
            e = od.entries.get((ix, sx))
            entries.append((ix, sx, bits, DTYPES[e.dtype][2] if e is not None else 0))
        out.append((pdo, sm, entries))
    return out


def _touched(req: bytes):
    """Object indices an SDO request addresses (to notice PDO mapping changes)."""
    if len(req) >= 6 + 2 + 4:
        yield struct.unpack_from("<H", req, 6 + 2 + 1)[0]
