"""CANopen over EtherCAT in the mailbox: SDO upload/download (expedited, normal, segmented,
complete access), aborts and emergencies — the slave's server and the master's client codec.

Mailbox header (6 bytes): length of what follows, address, channel/priority, type (low nibble,
3 = CoE) with a 3-bit counter in bits 4-6. CoE header (2 bytes): number (9 bits) and service
(bits 12-15: 1 emergency, 2 SDO request, 3 SDO response). Then the SDO command byte, index,
subindex and data as in CiA 301.
"""

from __future__ import annotations

import struct

from .od import ABORT_COMMAND, ABORT_GENERAL, ABORT_TOGGLE, SdoAbort

MBX_HDR = struct.Struct("<HHBB")
MBX_TYPE_ERR, MBX_TYPE_COE = 0, 3
COE_EMERGENCY, COE_SDO_REQ, COE_SDO_RES, COE_SDO_INFO = 1, 2, 3, 8


def mbx_frame(payload: bytes, counter: int = 0, address: int = 0, mtype: int = MBX_TYPE_COE) -> bytes:
    return MBX_HDR.pack(len(payload), address, 0, mtype | ((counter & 7) << 4)) + payload


def coe_sdo(service: int, body: bytes) -> bytes:
    return struct.pack("<H", service << 12) + body


def abort_body(index: int, sub: int, code: int) -> bytes:
    return struct.pack("<BHBI", 0x80, index, sub, code)


class SdoServer:
    """The slave side: one request in, zero or more mailbox frames out (responses, emergencies)."""

    def __init__(self, od, mbx_size: int):
        self.od = od
        self.mbx_size = mbx_size
        self.counter = 0
        self._up: list | None = None  # segmented upload in progress: [data, pos, toggle, index, sub]
        self._down: list | None = None  # segmented download: [buffer, size, toggle, index, sub, complete]

    def _out(self, payload: bytes) -> bytes:
        self.counter = self.counter % 7 + 1
        return mbx_frame(payload, self.counter)

    def emergency(self, code: int, register: int, data: bytes) -> bytes:
        return self._out(coe_sdo(COE_EMERGENCY, struct.pack("<HB", code, register) + data))

    def handle(self, frame: bytes) -> list:
        if len(frame) < 6:
            return []
        length, _addr, _prio, mtype = MBX_HDR.unpack_from(frame, 0)
        payload = frame[6 : 6 + length]
        if mtype & 0x0F != MBX_TYPE_COE:
            # mailbox error reply: unsupported protocol (type 0, service 1, detail 2)
            return [mbx_frame(struct.pack("<HH", 1, 2), 0, 0, MBX_TYPE_ERR)]
        if len(payload) < 2:
            return []
        service = struct.unpack_from("<H", payload, 0)[0] >> 12
        if service != COE_SDO_REQ:
            return [self._out(coe_sdo(COE_SDO_REQ, abort_body(0, 0, ABORT_COMMAND)))]
        body = payload[2:]
        try:
            res = self._sdo(body)
        except SdoAbort as a:
            idx, sub = struct.unpack_from("<HB", body, 1) if len(body) >= 4 else (0, 0)
            self._up = self._down = None
            res = abort_body(idx, sub, a.code)
        return [self._out(coe_sdo(COE_SDO_RES, res))]

    def _sdo(self, body: bytes) -> bytes:
        cmd = body[0]
        ccs = cmd >> 5
        if ccs == 3:  # upload segment request
            return self._upload_segment(cmd)
        if ccs == 0:  # download segment request
            return self._download_segment(cmd, body)
        index, sub = struct.unpack_from("<HB", body, 1)
        complete = bool(cmd & 0x10)
        if ccs == 2:  # initiate upload
            data = self.od.upload(index, sub, complete)
            head = struct.pack("<HB", index, sub)
            if len(data) <= 4 and not complete:
                return bytes([0x43 | ((4 - len(data)) << 2)]) + head + data.ljust(4, b"\0")
            room = self.mbx_size - 6 - 2 - 1 - 3 - 4
            flags = 0x41 | (0x10 if complete else 0)
            if len(data) <= room:
                return bytes([flags]) + head + struct.pack("<I", len(data)) + data
            self._up = [data, room, 0, index, sub]
            return bytes([flags]) + head + struct.pack("<I", len(data)) + data[:room]
        if ccs == 1:  # initiate download
            head_len = 4
            if cmd & 0x02:  # expedited
                n = 4 - ((cmd >> 2) & 3) if cmd & 0x01 else 4
                data = body[4 : 4 + n]
                self.od.download(index, sub, data, complete)
                return bytes([0x60 | (0x10 if complete else 0)]) + struct.pack("<HB", index, sub) + bytes(4)
            size = struct.unpack_from("<I", body, head_len)[0]
            data = bytes(body[8:])
            if len(data) >= size:
                self.od.download(index, sub, data[:size], complete)
            else:
                self._down = [bytearray(data), size, 0, index, sub, complete]
            return bytes([0x60 | (0x10 if complete else 0)]) + struct.pack("<HB", index, sub) + bytes(4)
        raise SdoAbort(ABORT_COMMAND)

    def _upload_segment(self, cmd: int) -> bytes:
        if self._up is None:
            raise SdoAbort(ABORT_COMMAND)
        data, pos, toggle, index, sub = self._up
        if (cmd >> 4) & 1 != toggle:
            self._up = None
            raise SdoAbort(ABORT_TOGGLE)
        room = self.mbx_size - 6 - 2 - 1
        chunk = data[pos : pos + room]
        pos += len(chunk)
        last = pos >= len(data)
        self._up = None if last else [data, pos, toggle ^ 1, index, sub]
        n = max(0, 7 - len(chunk))
        return bytes([(toggle << 4) | (n << 1) | (1 if last else 0)]) + chunk.ljust(7, b"\0")

    def _download_segment(self, cmd: int, body: bytes) -> bytes:
        if self._down is None:
            raise SdoAbort(ABORT_COMMAND)
        buf, size, toggle, index, sub, complete = self._down
        if (cmd >> 4) & 1 != toggle:
            self._down = None
            raise SdoAbort(ABORT_TOGGLE)
        last = bool(cmd & 1)
        seg = body[1:]
        if len(seg) <= 7:
            seg = seg[: 7 - ((cmd >> 1) & 7)]
        buf += seg
        if last or len(buf) >= size:
            self._down = None
            self.od.download(index, sub, bytes(buf[:size]), complete)
        else:
            self._down[2] = toggle ^ 1
        return bytes([0x20 | (toggle << 4)]) + bytes(7)


# ---------------------------------------------------------------------------- the master's client


class SdoError(Exception):
    def __init__(self, message: str, abort: int = 0):
        super().__init__(message)
        self.abort = abort


def upload_request(index: int, sub: int, complete: bool = False) -> bytes:
    return coe_sdo(COE_SDO_REQ, struct.pack("<BHBI", 0x40 | (0x10 if complete else 0), index, sub, 0))


def upload_segment_request(toggle: int) -> bytes:
    return coe_sdo(COE_SDO_REQ, bytes([0x60 | (toggle << 4)]) + bytes(7))


def download_request(index: int, sub: int, data: bytes, complete: bool, mbx_size: int):
    """The initiate request and the segment requests that must follow it."""
    ca = 0x10 if complete else 0
    if len(data) <= 4 and not complete:
        n = 4 - len(data)
        return coe_sdo(COE_SDO_REQ, struct.pack("<BHB", 0x23 | (n << 2), index, sub) + data.ljust(4, b"\0")), []
    room = mbx_size - 6 - 2 - 1 - 3 - 4
    first = data[:room]
    req = coe_sdo(COE_SDO_REQ, struct.pack("<BHBI", 0x21 | ca, index, sub, len(data)) + first)
    segs = []
    pos, toggle = len(first), 0
    seg_room = mbx_size - 6 - 2 - 1
    while pos < len(data):
        chunk = data[pos : pos + seg_room]
        pos += len(chunk)
        last = pos >= len(data)
        n = max(0, 7 - len(chunk))
        segs.append(
            coe_sdo(COE_SDO_REQ, bytes([(toggle << 4) | (n << 1) | (1 if last else 0)]) + chunk.ljust(7, b"\0"))
        )
        toggle ^= 1
    return req, segs


def parse_response(frame: bytes):
    """A mailbox frame from the slave → ("sdo", body) | ("emergency", (code, reg, data)) | ("error", detail)."""
    length, _a, _p, mtype = MBX_HDR.unpack_from(frame, 0)
    payload = frame[6 : 6 + length]
    if mtype & 0x0F == MBX_TYPE_ERR:
        return "error", struct.unpack_from("<H", payload, 2)[0] if len(payload) >= 4 else 0
    service = struct.unpack_from("<H", payload, 0)[0] >> 12
    if service == COE_EMERGENCY:
        code, reg = struct.unpack_from("<HB", payload, 2)
        return "emergency", (code, reg, bytes(payload[5:10]))
    body = payload[2:]
    if body and body[0] == 0x80:
        _, index, sub, code = struct.unpack_from("<BHBI", body, 0)
        raise SdoError(f"SDO {index:#06x}:{sub} aborted with {code:#010x}", code)
    return "sdo", bytes(body)


def upload_data(body: bytes):
    """The initiate upload response → (data or partial data, total size, segmented?)."""
    cmd = body[0]
    if cmd >> 5 != 2:
        raise SdoError(f"unexpected SDO response command {cmd:#04x}", ABORT_GENERAL)
    if cmd & 0x02:  # expedited
        n = 4 - ((cmd >> 2) & 3) if cmd & 0x01 else 4
        return bytes(body[4 : 4 + n]), n, False
    size = struct.unpack_from("<I", body, 4)[0]
    data = bytes(body[8:])
    return data[:size], size, len(data) < size


def upload_segment_data(body: bytes):
    cmd = body[0]
    if cmd >> 5 != 0:
        raise SdoError(f"unexpected SDO segment response {cmd:#04x}", ABORT_GENERAL)
    seg = bytes(body[1:])
    if len(seg) <= 7:
        seg = seg[: 7 - ((cmd >> 1) & 7)]
    return seg, bool(cmd & 1)
