"""EtherCAT masters behind one interface: `FrameMaster` (ours, frames through any transport) and,
in `soem.py`, pysoem.

The interface (what the scan binding uses): open(), scan() → [SlaveInfo], configure(),
set_state(name) → reached, exchange() → working counter, sdo_read/sdo_write, the process image
as `outputs(i)` / `inputs(i)` memoryviews, expected_wkc, dc_time, close().

`FrameMaster` builds every frame itself (the same sequence SOEM uses: count with BRD, station
addresses with APWR, SII through the EEPROM interface, mailbox SyncManagers, PREOP, PDO
assignment read over CoE, process-data SyncManagers and FMMUs with outputs first then inputs in
one logical image, DC delay measurement, SAFEOP, OP) and hands each frame to a transport:
`Segment.exchange` for the `sim` backend, a raw socket for a real or served segment.
"""

from __future__ import annotations

import struct
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field

from . import coe, wire
from . import sii as siimod
from .esc import INIT, OP, STATE_NAMES
from .od import DTYPES
from .pdo import KNOWN_NAMES, KNOWN_TYPES, PdoLayout
from .wire import APWR, BRD, BWR, FPRD, FPWR, FRMW, LRW, Datagram

STATE_CODES = {v: k for k, v in STATE_NAMES.items()}
STATION_BASE = 0x1001
_ZERO8 = bytes(8)
_U16, _U64 = struct.Struct("<H"), struct.Struct("<Q")


class MasterError(Exception):
    pass


@dataclass
class SlaveInfo:
    position: int  # 0-based place on the line
    station: int
    vendor_id: int = 0
    product_code: int = 0
    revision: int = 0
    serial: int = 0
    name: str = ""
    alias: int = 0
    mailbox: bool = False
    mbx_out: tuple = (0, 0)
    mbx_in: tuple = (0, 0)
    coe_details: int = 0
    sms: tuple = ()
    dc: bool = False
    state: str = "INIT"
    al_status_code: int = 0
    out_bytes: int = 0
    in_bytes: int = 0
    out_offset: int = 0  # byte offsets in the logical image
    in_offset: int = 0
    rx_layout: PdoLayout | None = None
    tx_layout: PdoLayout | None = None
    delay_ns: int = 0
    sii_pdos: tuple = ((), ())  # the SII PDO categories (RxPDOs, TxPDOs)
    emergencies: list = field(default_factory=list)

    def describe(self) -> str:
        return (
            f"{self.position:>3}  {self.station:#06x}  {self.vendor_id:#010x}  {self.product_code:#010x}  "
            f"rev {self.revision:#x}  {self.name}  [{self.state}]  out {self.out_bytes} B  in {self.in_bytes} B"
        )


class Master(ABC):
    """What every backend offers."""

    slaves: list
    expected_wkc: int = 0
    dc_time: int = 0

    @abstractmethod
    def open(self) -> None: ...
    @abstractmethod
    def close(self) -> None: ...
    @abstractmethod
    def scan(self) -> list: ...
    @abstractmethod
    def configure(
        self,
        pdo_assign: dict | None = None,
        dc_cycle_ns: int = 0,
        dc_shift_ns: int = 0,
        preop_hook: Callable | None = None,
    ) -> None: ...
    @abstractmethod
    def set_state(self, state: str, timeout: float = 2.0) -> str: ...
    @abstractmethod
    def exchange(self) -> int: ...
    @abstractmethod
    def sdo_read(self, slave: int, index: int, sub: int, complete: bool = False) -> bytes: ...
    @abstractmethod
    def sdo_write(self, slave: int, index: int, sub: int, data: bytes, complete: bool = False) -> None: ...
    @abstractmethod
    def write_outputs(self, slave: int, data: bytes) -> None: ...
    @abstractmethod
    def read_inputs(self, slave: int) -> bytes: ...
    @abstractmethod
    def poll_emergencies(self, slave: int) -> list: ...
    @abstractmethod
    def states(self) -> list: ...


class FrameMaster(Master):
    """A master written here: every frame built and parsed in Python, sent through `transport`.

    transport(frame_bytes) → the returned frame bytes, or None when the frame was lost.
    `clock()` gives the time stamps the sim backend passes to the segment; `pause(seconds)` lets
    simulated time pass while the master polls (state changes, mailboxes)."""

    def __init__(self, transport: Callable, pause: Callable | None = None, now_ns: Callable | None = None):
        self.transport = transport
        self.pause = pause or (lambda s: time.sleep(s))
        self.now_ns = now_ns or (lambda: time.time_ns() - 946_684_800_000_000_000)  # DC epoch: 2000-01-01
        self.slaves: list = []
        self.image = bytearray()
        self.out_size = self.in_size = 0
        self.expected_wkc = 0
        self.dc_time = 0
        self.dc_ref: int | None = None
        self._idx = 0
        self.lost = 0
        self._lrw: Datagram | None = None
        self._cyclic: _CyclicFrame | None = None

    # ------------------------------------------------------------------ frames
    def _send(self, dgs) -> list | None:
        for d in dgs:
            self._idx = (self._idx + 1) & 0xFF
            d.idx = self._idx
        out = self.transport(wire.encode_frame(dgs))
        if out is None:
            self.lost += 1
            return None
        try:
            _, _, back = wire.decode_frame(out)
        except wire.FrameError:
            self.lost += 1
            return None
        return back

    def _one(self, cmd: int, adp: int, ado: int, data, retries: int = 3) -> Datagram:
        for _ in range(retries):
            back = self._send([Datagram(cmd, 0, adp, ado, bytearray(data))])
            if back is not None:
                return back[0]
        raise MasterError(f"no answer to {wire.NAMES[cmd]} {adp:#06x}:{ado:#06x} after {retries} frames")

    def _fprd(self, station: int, ado: int, n: int) -> Datagram:
        return self._one(FPRD, station, ado, bytes(n))

    def _fpwr(self, station: int, ado: int, data: bytes) -> Datagram:
        return self._one(FPWR, station, ado, data)

    # ------------------------------------------------------------------ scan
    def open(self) -> None:
        pass

    def close(self) -> None:
        pass

    def scan(self) -> list:
        n = self._one(BRD, 0, 0x0000, bytes(2)).wkc
        self._one(BWR, 0, 0x0120, struct.pack("<H", INIT | 0x10))  # everyone to INIT, errors acknowledged
        self._one(BWR, 0, 0x0600, bytes(256))  # FMMUs off
        self._one(BWR, 0, 0x0800, bytes(128))  # SyncManagers off
        self._one(BWR, 0, 0x0981, bytes(1))  # DC sync off
        self.slaves = []
        for pos in range(n):
            station = STATION_BASE + pos
            d = self._one(APWR, (-pos) & 0xFFFF, 0x0010, struct.pack("<H", station))
            if d.wkc != 1:
                raise MasterError(f"slave {pos} did not take its station address")
            info = SlaveInfo(pos, station)
            image = self._read_sii(station)
            si = siimod.parse(image)
            info.vendor_id, info.product_code, info.revision, info.serial = (
                si.vendor_id,
                si.product_code,
                si.revision,
                si.serial,
            )
            info.alias, info.name, info.coe_details, info.sms = si.alias, si.name, si.coe_details, si.sms
            info.sii_pdos = (si.rx_pdos, si.tx_pdos)
            info.mailbox = bool(si.mbx_protocols & siimod.MBX_COE) and si.mbx_out[1] > 0
            info.mbx_out, info.mbx_in = si.mbx_out, si.mbx_in
            feat = struct.unpack("<H", self._fprd(station, 0x0008, 2).data)[0]
            info.dc = bool(feat & 0x0004)
            self.slaves.append(info)
        self._read_states()
        return self.slaves

    def _read_sii(self, station: int, max_bytes: int = 4096) -> bytes:
        self._fpwr(station, 0x0500, b"\x00\x00")  # the master owns the EEPROM
        out = bytearray()
        addr = 0
        end = None
        while addr * 2 < max_bytes:
            self._fpwr(station, 0x0502, struct.pack("<HI", 0x0100, addr))
            for _ in range(10):
                st = struct.unpack("<H", self._fprd(station, 0x0502, 2).data)[0]
                if not st & 0x8000:
                    break
            if st & 0x2000:
                raise MasterError(f"SII read error at word {addr:#x} of station {station:#06x}")
            step = 8 if st & 0x0040 else 4
            out += self._fprd(station, 0x0508, step).data
            addr += step // 2
            if end is None and len(out) > 0x80:
                end = _sii_end(out)
            if end is not None and len(out) >= end:
                break
        return bytes(out)

    def _read_states(self) -> list:
        for s in self.slaves:
            d = self._fprd(s.station, 0x0130, 6)
            st, _, code = struct.unpack("<HHH", d.data)
            s.state = STATE_NAMES.get(st & 0x0F, hex(st & 0x0F)) + ("+ERR" if st & 0x10 else "")
            s.al_status_code = code
        return [s.state for s in self.slaves]

    def states(self) -> list:
        return self._read_states()

    # ------------------------------------------------------------------ state changes
    def set_state(self, state: str, timeout: float = 2.0, slaves=None) -> str:
        code = STATE_CODES[state]
        targets = self.slaves if slaves is None else [self.slaves[i] for i in slaves]
        for s in targets:
            ack = 0x10 if "ERR" in s.state else 0
            self._fpwr(s.station, 0x0120, struct.pack("<H", code | ack))
        waited = 0.0
        while True:
            if code == OP and self.out_size + self.in_size:
                self.exchange()
            self._read_states()
            bad = [s for s in targets if s.state != state]
            if not bad or any("ERR" in s.state for s in bad) or waited >= timeout:
                break
            self.pause(0.001)
            waited += 0.001
        if bad:
            s = bad[0]
            raise MasterError(
                f"slave {s.position} ({s.name}) refused {state}: it is {s.state}, AL status code "
                f"{s.al_status_code:#06x}"
            )
        return state

    # ------------------------------------------------------------------ mailbox / SDO
    def _mbx_send(self, s: SlaveInfo, payload: bytes) -> None:
        frame = coe.mbx_frame(payload, 1).ljust(s.mbx_out[1], b"\0")
        for _ in range(200):
            if self._fpwr(s.station, s.mbx_out[0], frame).wkc == 1:
                return
            self.pause(0.0005)
        raise MasterError(f"slave {s.position}: the write mailbox stays full")

    def _mbx_receive(self, s: SlaveInfo, timeout: float = 1.0) -> bytes:
        waited = 0.0
        while waited <= timeout:
            st = self._fprd(s.station, 0x080D, 1).data[0]
            if st & 0x08:
                d = self._fprd(s.station, s.mbx_in[0], s.mbx_in[1])
                if d.wkc == 1:
                    return bytes(d.data)
            self.pause(0.0005)
            waited += 0.0005
        raise MasterError(f"slave {s.position}: no mailbox answer within {timeout} s")

    def _sdo_exchange(self, s: SlaveInfo, payload: bytes) -> bytes:
        self._mbx_send(s, payload)
        while True:
            kind, body = coe.parse_response(self._mbx_receive(s))
            if kind == "emergency":
                s.emergencies.append(body)
                continue
            if kind == "error":
                raise MasterError(f"slave {s.position}: mailbox error {body}")
            return body

    def sdo_read(self, slave: int, index: int, sub: int, complete: bool = False) -> bytes:
        s = self.slaves[slave]
        if not s.mailbox:
            raise MasterError(f"slave {slave} ({s.name}) has no CoE mailbox")
        body = self._sdo_exchange(s, coe.upload_request(index, sub, complete))
        data, size, segmented = coe.upload_data(body)
        buf = bytearray(data)
        toggle = 0
        while segmented and len(buf) < size:
            seg, last = coe.upload_segment_data(self._sdo_exchange(s, coe.upload_segment_request(toggle)))
            buf += seg
            toggle ^= 1
            if last:
                break
        return bytes(buf[:size])

    def sdo_write(self, slave: int, index: int, sub: int, data: bytes, complete: bool = False) -> None:
        s = self.slaves[slave]
        if not s.mailbox:
            raise MasterError(f"slave {slave} ({s.name}) has no CoE mailbox")
        req, segs = coe.download_request(index, sub, bytes(data), complete, s.mbx_out[1])
        self._sdo_exchange(s, req)
        for seg in segs:
            self._sdo_exchange(s, seg)

    def poll_emergencies(self, slave: int) -> list:
        """Mailbox messages the slave sent on its own (emergencies)."""
        s = self.slaves[slave]
        if s.mailbox:
            st = self._fprd(s.station, 0x080D, 1).data[0]
            if st & 0x08:
                d = self._fprd(s.station, s.mbx_in[0], s.mbx_in[1])
                if d.wkc == 1:
                    kind, body = coe.parse_response(bytes(d.data))
                    if kind == "emergency":
                        s.emergencies.append(body)
        out, s.emergencies = s.emergencies, []
        return out

    # ------------------------------------------------------------------ configuration
    def configure(
        self,
        pdo_assign: dict | None = None,
        dc_cycle_ns: int = 0,
        dc_shift_ns: int = 0,
        preop_hook: Callable | None = None,
    ) -> None:
        """INIT → PREOP → PDO mapping, SyncManagers, FMMUs, DC → SAFEOP.

        pdo_assign: {slave: (rx_pdos, tx_pdos)} written to 0x1C12/0x1C13 before mapping;
        preop_hook(master): called in PREOP before the mapping is read (SDO setup, remapping)."""
        for s in self.slaves:
            if s.mailbox:
                self._fpwr(s.station, 0x0800, _sm_bytes(s.mbx_out[0], s.mbx_out[1], 0x26, 1))
                self._fpwr(s.station, 0x0808, _sm_bytes(s.mbx_in[0], s.mbx_in[1], 0x22, 1))
        self.set_state("PREOP")
        if preop_hook is not None:
            preop_hook(self)
        for s in self.slaves:
            if pdo_assign and s.position in pdo_assign and s.mailbox:
                rx, tx = pdo_assign[s.position]
                for idx, pdos in ((0x1C12, rx), (0x1C13, tx)):
                    if pdos is None:
                        continue
                    self.sdo_write(s.position, idx, 0, b"\0")
                    for k, p in enumerate(pdos, 1):
                        self.sdo_write(s.position, idx, k, struct.pack("<H", p))
                    self.sdo_write(s.position, idx, 0, bytes([len(pdos)]))
            s.rx_layout, s.tx_layout = self._read_layouts(s)
            s.out_bytes, s.in_bytes = s.rx_layout.size, s.tx_layout.size
        # one logical image: every slave's outputs, then every slave's inputs (as SOEM lays it out)
        off = 0
        for s in self.slaves:
            s.out_offset = off
            off += s.out_bytes
        self.out_size = off
        for s in self.slaves:
            s.in_offset = off
            off += s.in_bytes
        self.in_size = off - self.out_size
        self.image = bytearray(off)
        self.expected_wkc = 0
        for s in self.slaves:
            sm_out = next((x for x in s.sms if x.kind == 3), None)
            sm_in = next((x for x in s.sms if x.kind == 4), None)
            fm = 0
            if s.out_bytes and sm_out:
                self._fpwr(s.station, 0x0810, _sm_bytes(sm_out.start, s.out_bytes, sm_out.control, 1))
                self._fpwr(s.station, 0x0600 + 16 * fm, _fmmu_bytes(s.out_offset, s.out_bytes, sm_out.start, 2))
                fm += 1
                self.expected_wkc += 2
            if s.in_bytes and sm_in:
                self._fpwr(s.station, 0x0818, _sm_bytes(sm_in.start, s.in_bytes, sm_in.control, 1))
                self._fpwr(s.station, 0x0600 + 16 * fm, _fmmu_bytes(s.in_offset, s.in_bytes, sm_in.start, 1))
                self.expected_wkc += 1
        self._lrw = Datagram.logical_dg(LRW, 0, self.image)
        self.configure_dc(dc_cycle_ns, dc_shift_ns)
        self.set_state("SAFEOP")

    def _read_layouts(self, s: SlaveInfo):
        if not s.mailbox or not s.coe_details & siimod.COE_PDO_ASSIGN:
            return tuple(
                PdoLayout(
                    [
                        (
                            ix,
                            sx,
                            bits,
                            _TYPE_CODES.get(code) or _dtype(bits, ix, sx),
                            KNOWN_NAMES.get(ix, f"{ix:#06x}:{sx:02x}"),
                        )
                        for _pdo, _sm, entries in pdos
                        for ix, sx, bits, code in entries
                    ]
                )
                for pdos in s.sii_pdos
            )
        out = []
        for assign in (0x1C12, 0x1C13):
            items = []
            n = self.sdo_read(s.position, assign, 0)[0]
            for k in range(1, n + 1):
                pdo = struct.unpack("<H", self.sdo_read(s.position, assign, k)[:2])[0]
                m = self.sdo_read(s.position, pdo, 0)[0]
                for j in range(1, m + 1):
                    w = struct.unpack("<I", self.sdo_read(s.position, pdo, j)[:4])[0]
                    ix, sx, bits = w >> 16, (w >> 8) & 0xFF, w & 0xFF
                    items.append((ix, sx, bits, _dtype(bits, ix, sx), KNOWN_NAMES.get(ix, f"{ix:#06x}:{sx:02x}")))
            out.append(PdoLayout(items))
        return out[0], out[1]

    # ------------------------------------------------------------------ distributed clocks
    def configure_dc(self, cycle_ns: int = 0, shift_ns: int = 0) -> None:
        dcs = [s for s in self.slaves if s.dc]
        if not dcs:
            self.dc_ref = None
            return
        self._one(BWR, 0, 0x0900, bytes(4))  # latch receive times everywhere
        master_ns = self.now_ns()
        prev = None
        for s in dcs:
            t0, t1 = struct.unpack("<II", self._fprd(s.station, 0x0900, 8).data)
            rxpu = struct.unpack("<Q", self._fprd(s.station, 0x0918, 8).data)[0]
            s._rx = (t0, t1)
            if prev is None:
                s.delay_ns = 0
            else:
                p0, p1 = prev._rx
                mine = (t1 - t0) & 0xFFFFFFFF if s is not dcs[-1] else 0
                s.delay_ns = prev.delay_ns + (((p1 - p0) & 0xFFFFFFFF) - mine) // 2
            self._fpwr(s.station, 0x0920, struct.pack("<Q", (master_ns - rxpu) & 0xFFFFFFFFFFFFFFFF))
            self._fpwr(s.station, 0x0928, struct.pack("<I", s.delay_ns))
            prev = s
        self.dc_ref = dcs[0].station
        for _ in range(15):  # static drift compensation
            self._one(FRMW, self.dc_ref, 0x0910, bytes(8))
        if cycle_ns:
            now = struct.unpack("<Q", self._one(FRMW, self.dc_ref, 0x0910, bytes(8)).data)[0]
            start = (now // cycle_ns + 10) * cycle_ns + shift_ns
            for s in dcs:
                self._fpwr(s.station, 0x0981, b"\0")
                self._fpwr(s.station, 0x09A0, struct.pack("<I", cycle_ns))
                self._fpwr(s.station, 0x0990, struct.pack("<Q", start))
                self._fpwr(s.station, 0x0981, b"\x03")

    # ------------------------------------------------------------------ process data
    def exchange(self) -> int:
        lrw = self._lrw
        if lrw is None:
            return 0
        cyc = self._cyclic
        if cyc is None or cyc.key != (lrw, len(self.image), self.dc_ref):
            dgs = [Datagram.logical_dg(LRW, 0, self.image)]
            if self.dc_ref is not None:
                dgs.append(Datagram(FRMW, 0, self.dc_ref, 0x0910, bytearray(_ZERO8)))
            cyc = self._cyclic = _CyclicFrame((lrw, len(self.image), self.dc_ref), dgs)
        frame = cyc.template
        lo, hi = cyc.data_at[0]
        frame[lo:hi] = self.image
        for at in cyc.idx_at:  # the indices _send would give the datagrams
            self._idx = (self._idx + 1) & 0xFF
            frame[at] = self._idx
        out = self.transport(bytes(frame))
        if out is None:
            self.lost += 1
            return -1
        if not cyc.same_shape(out):  # not as sent: the general decoder (or a lost frame)
            return self._answer(out)
        self.image[self.out_size :] = out[lo + self.out_size : hi]
        if len(cyc.data_at) > 1:
            self.dc_time = _U64.unpack_from(out, cyc.data_at[1][0])[0]
        return _U16.unpack_from(out, hi)[0]

    def _answer(self, out) -> int:
        try:
            _, _, back = wire.decode_frame(out)
        except wire.FrameError:
            self.lost += 1
            return -1
        got = back[0]
        self.image[self.out_size :] = got.data[self.out_size :]
        if len(back) > 1:
            self.dc_time = struct.unpack_from("<Q", back[1].data)[0]
        return got.wkc

    def write_outputs(self, slave: int, data: bytes) -> None:
        s = self.slaves[slave]
        self.image[s.out_offset : s.out_offset + s.out_bytes] = data

    def read_inputs(self, slave: int) -> bytes:
        s = self.slaves[slave]
        return bytes(self.image[s.in_offset : s.in_offset + s.in_bytes])

    def outputs(self, slave: int) -> memoryview:
        s = self.slaves[slave]
        return memoryview(self.image)[s.out_offset : s.out_offset + s.out_bytes]

    def inputs(self, slave: int) -> memoryview:
        s = self.slaves[slave]
        return memoryview(self.image)[s.in_offset : s.in_offset + s.in_bytes]


class _CyclicFrame:
    """The process-data frame (LRW of the image, FRMW of the DC time) encoded once by the general
    encoder: each cycle only the datagram indices and the outputs change in it. An answer with
    the same EtherCAT header and datagram commands and lengths has its data at the same offsets;
    any other goes through the general decoder."""

    def __init__(self, key: tuple, dgs: list):
        self.key = key
        self.template = bytearray(wire.encode_frame(dgs))
        self.idx_at: list[int] = []
        self.data_at: list[tuple[int, int]] = []
        self.header = bytes(self.template[12:16])  # EtherType, EtherCAT header
        self.commands: list[tuple[int, int, bytes]] = []  # (offset, command, length field)
        pos = 16
        for d in dgs:
            self.idx_at.append(pos + 1)
            self.data_at.append((pos + 10, pos + 10 + len(d.data)))
            self.commands.append((pos, d.cmd, bytes(self.template[pos + 6 : pos + 8])))
            pos += 12 + len(d.data)
        self.end = pos

    def same_shape(self, frame) -> bool:
        if len(frame) < self.end or frame[12:16] != self.header:
            return False
        for at, cmd, length in self.commands:
            if frame[at] != cmd or frame[at + 6 : at + 8] != length:
                return False
        return True


def _sm_bytes(start: int, length: int, control: int, enable: int) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, enable, 0)


def _fmmu_bytes(logical: int, length: int, phys: int, typ: int) -> bytes:
    return struct.pack("<IHBBHBBB3x", logical, length, 0, 7, phys, 0, typ, 1)


_TYPE_CODES = {code: name for name, (_f, _b, code) in DTYPES.items()}


def _dtype(bits: int, index: int, sub: int) -> str:
    if index == 0:
        return "PAD"
    known = KNOWN_TYPES.get(index)
    if known and DTYPES[known][1] == bits:
        return known
    return {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT", 64: "ULINT"}.get(bits, "OCTETS")


def _sii_end(image: bytes | bytearray) -> int | None:
    """The byte length of the SII image once the category chain's end marker has been read."""
    pos = 0x80
    while pos + 2 <= len(image):
        kind = struct.unpack_from("<H", image, pos)[0]
        if kind == 0xFFFF:
            return pos + 2
        if pos + 4 > len(image):
            return None
        size = struct.unpack_from("<H", image, pos + 2)[0]
        pos += 4 + size * 2
    return None
