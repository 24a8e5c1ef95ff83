"""EtherCAT frames as on the wire: Ethernet II, EtherType 0x88A4, the EtherCAT header, datagrams.

    Ethernet: dst(6) src(6) type(2)=0x88A4
    EtherCAT header (2, LE): length of the datagrams (11 bits), reserved (1), type (4) = 1
    datagram: cmd(1) idx(1) address(4: ADP+ADO or a 32-bit logical address)
              len(2: 11 bits length, bit 14 circulating, bit 15 more follow) irq(2) data(len) wkc(2)

The length in the EtherCAT header is trusted, not the frame length (SOEM sends unpadded frames
on a veth). `PcapWriter` writes a capture Wireshark/tshark opens (link type Ethernet).
"""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass, field

ETHERTYPE = 0x88A4
BROADCAST = b"\xff" * 6
MASTER_MAC = b"\x01\x01\x01\x01\x01\x01"  # SOEM's primary source address

NOP, APRD, APWR, APRW, FPRD, FPWR, FPRW, BRD, BWR, BRW, LRD, LWR, LRW, ARMW, FRMW = range(15)
NAMES = [
    "NOP",
    "APRD",
    "APWR",
    "APRW",
    "FPRD",
    "FPWR",
    "FPRW",
    "BRD",
    "BWR",
    "BRW",
    "LRD",
    "LWR",
    "LRW",
    "ARMW",
    "FRMW",
]
READS = {APRD, FPRD, BRD, LRD}
WRITES = {APWR, FPWR, BWR, LWR}
READ_WRITES = {APRW, FPRW, BRW, LRW}
AUTO_INC = {APRD, APWR, APRW, ARMW}
CONFIGURED = {FPRD, FPWR, FPRW, FRMW}
BROADCASTS = {BRD, BWR, BRW}
LOGICAL = {LRD, LWR, LRW}

_DG = struct.Struct("<BBHHHH")  # cmd, idx, adp, ado, len|flags, irq
_DG_LOG = struct.Struct("<BBIHH")  # cmd, idx, logical address, len|flags, irq
_WKC = struct.Struct("<H")  # also the EtherCAT header
_ETYPE = struct.Struct(">H")


class FrameError(ValueError):
    pass


@dataclass(slots=True)
class Datagram:
    cmd: int
    idx: int = 0
    adp: int = 0  # position (auto-increment, as a 16-bit value) or station address
    ado: int = 0  # register offset
    data: bytearray = field(default_factory=bytearray)
    wkc: int = 0
    irq: int = 0
    circulating: bool = False

    @property
    def logical(self) -> int:
        return self.adp | (self.ado << 16)

    @classmethod
    def logical_dg(cls, cmd: int, addr: int, data, idx: int = 0) -> Datagram:
        return cls(cmd, idx, addr & 0xFFFF, (addr >> 16) & 0xFFFF, bytearray(data))

    def __repr__(self):
        return (
            f"Datagram({NAMES[self.cmd] if self.cmd < len(NAMES) else self.cmd}, idx={self.idx}, "
            f"adp={self.adp:#06x}, ado={self.ado:#06x}, len={len(self.data)}, wkc={self.wkc})"
        )


def encode_datagrams(dgs) -> bytes:
    buf = bytearray(sum(12 + len(d.data) for d in dgs))
    encode_datagrams_into(buf, 0, dgs)
    return bytes(buf)


def encode_datagrams_into(buf: bytearray, pos: int, dgs) -> int:
    """Encode dgs into buf from byte pos on, over what is there; returns where they end.
    FrameError if they do not fit (buf is then partly written)."""
    size = len(buf)
    last = len(dgs) - 1
    pack_header, pack_wkc = _DG.pack_into, _WKC.pack_into
    for i, d in enumerate(dgs):
        data = d.data
        n = len(data)
        if pos + 12 + n > size:
            raise FrameError(f"datagram {i} ({n} bytes) does not fit {size} bytes from {pos}")
        ln = n & 0x7FF
        if d.circulating:
            ln |= 0x4000
        if i < last:
            ln |= 0x8000
        pack_header(buf, pos, d.cmd, d.idx, d.adp & 0xFFFF, d.ado & 0xFFFF, ln, d.irq)
        pos += 10
        buf[pos : pos + n] = data
        pos += n
        pack_wkc(buf, pos, d.wkc & 0xFFFF)
        pos += 2
    return pos


def encode_frame(dgs, src: bytes = MASTER_MAC, dst: bytes = BROADCAST, pad: bool = True) -> bytes:
    body = encode_datagrams(dgs)
    if len(body) > 0x7FF:
        raise FrameError(f"datagrams of {len(body)} bytes do not fit one frame (at most 2047)")
    frame = dst + src + struct.pack(">H", ETHERTYPE) + struct.pack("<H", len(body) | 0x1000) + body
    if pad and len(frame) < 60:
        frame += bytes(60 - len(frame))
    return frame


def decode_datagrams(body, length: int) -> list:
    dgs: list[Datagram] = []
    pos = 0
    unpack_header, unpack_wkc = _DG.unpack_from, _WKC.unpack_from
    while True:
        if pos + 12 > length:
            raise FrameError(f"datagram header truncated at byte {pos}")
        cmd, idx, adp, ado, ln, irq = unpack_header(body, pos)
        n = ln & 0x7FF
        pos += 10
        if pos + n + 2 > length:
            raise FrameError(f"datagram {len(dgs)} ({n} bytes) runs past the EtherCAT length {length}")
        data = bytearray(body[pos : pos + n])
        pos += n
        (wkc,) = unpack_wkc(body, pos)
        pos += 2
        dgs.append(Datagram(cmd, idx, adp, ado, data, wkc, irq, bool(ln & 0x4000)))
        if not ln & 0x8000:
            return dgs


def decode_frame(frame):
    """frame bytes → (dst, src, [Datagram]); FrameError if it is not an EtherCAT command frame."""
    if len(frame) < 16:
        raise FrameError(f"frame of {len(frame)} bytes is too short")
    (etype,) = _ETYPE.unpack_from(frame, 12)
    off = 14
    if etype == 0x8100:  # a VLAN tag
        (etype,) = _ETYPE.unpack_from(frame, 16)
        off = 18
    if etype != ETHERTYPE:
        raise FrameError(f"EtherType {etype:#06x} is not EtherCAT")
    (hdr,) = _WKC.unpack_from(frame, off)
    length, ftype = hdr & 0x7FF, hdr >> 12
    if ftype != 1:
        raise FrameError(f"EtherCAT frame type {ftype} is not 1 (commands)")
    body = memoryview(frame)[off + 2 :]
    if length > len(body):
        raise FrameError(f"EtherCAT length {length} exceeds the frame ({len(body)} bytes)")
    return bytes(frame[:6]), bytes(frame[6:12]), decode_datagrams(body, length)


class PcapWriter:
    """A classic pcap file (microsecond timestamps, link type 1 = Ethernet)."""

    def __init__(self, path: str):
        self.f = open(path, "wb")
        self.f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))

    def write(self, frame: bytes, t: float | None = None) -> None:
        t = time.time() if t is None else t
        sec = int(t)
        usec = int(round((t - sec) * 1e6))
        if usec >= 1_000_000:
            sec, usec = sec + 1, usec - 1_000_000
        self.f.write(struct.pack("<IIII", sec, usec, len(frame), len(frame)))
        self.f.write(frame)

    def close(self) -> None:
        if not self.f.closed:
            self.f.close()
