"""The Slave Information Interface (SII) EEPROM image of an emulated slave, and a reader for it.

Layout (word addresses): 0x00-0x07 ESC configuration with its CRC-8 in word 7; 0x08 vendor id,
0x0A product code, 0x0C revision, 0x0E serial (32-bit each); 0x18-0x1B the standard mailbox
offsets and sizes; 0x1C supported mailbox protocols; 0x3E size, 0x3F version; from 0x40 the
categories (type word, size in words, data) ending with 0xFFFF: strings (10), general (30),
FMMU (40), SyncManager (41). A master (SOEM, or ours) takes names, mailbox and SyncManager
addresses and the CoE details from here.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass

CAT_STRINGS, CAT_GENERAL, CAT_FMMU, CAT_SM, CAT_TXPDO, CAT_RXPDO, CAT_DC, CAT_END = 10, 30, 40, 41, 50, 51, 60, 0xFFFF
MBX_COE = 0x0004

# CoE details of the general category
COE_SDO, COE_SDO_INFO, COE_PDO_ASSIGN, COE_PDO_CONFIG, COE_UPLOAD_AT_START, COE_COMPLETE_ACCESS = (
    0x01,
    0x02,
    0x04,
    0x08,
    0x10,
    0x20,
)


@dataclass
class SmConfig:
    start: int
    length: int
    control: int
    enable: int
    kind: int  # 1 mailbox out (master → slave), 2 mailbox in, 3 process data out, 4 process data in


def _sm_config(data: bytes, k: int) -> SmConfig:
    """The SyncManager category's k-th byte: start, length, control, (status), enable, type."""
    start, length, control = struct.unpack_from("<HHB", data, k)
    return SmConfig(start, length, control, data[k + 6], data[k + 7])


def crc8(data: bytes) -> int:
    """The SII checksum over words 0-6: CRC-8, polynomial x^8 + x^2 + x + 1, initial value 0xFF."""
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def build(
    vendor_id: int,
    product_code: int,
    revision: int,
    serial: int,
    name: str,
    group: str,
    order: str,
    sms: list,
    fmmus: list,
    mailbox: bool = True,
    alias: int = 0,
    coe_details: int = COE_SDO | COE_SDO_INFO | COE_PDO_ASSIGN | COE_PDO_CONFIG | COE_COMPLETE_ACCESS,
    size_bytes: int = 2048,
    rx_pdos: Sequence = (),
    tx_pdos: Sequence = (),
) -> bytes:
    """rx_pdos/tx_pdos: [(pdo index, SyncManager, [(index, sub, bits, CoE type code)])] for the PDO
    categories (a master without CoE sizes the process data from them)."""
    cfg = struct.pack("<HHHHHHH", 0x0C08, 0x0000, 0x0000, 0x0000, alias, 0, 0)
    img = bytearray(cfg + struct.pack("<H", crc8(cfg)))
    img += struct.pack("<IIII", vendor_id, product_code, revision, serial)
    img += bytes(8)  # 0x10-0x13 reserved (delays)
    img += bytes(8)  # 0x14-0x17 bootstrap mailbox: none
    mo = next((s for s in sms if s.kind == 1), None)
    mi = next((s for s in sms if s.kind == 2), None)
    img += struct.pack(
        "<HHHH", mo.start if mo else 0, mo.length if mo else 0, mi.start if mi else 0, mi.length if mi else 0
    )
    img += struct.pack("<H", MBX_COE if mailbox else 0)
    img += bytes((0x3E - 0x1D) * 2)
    img += struct.pack("<HH", size_bytes * 8 // 1024 - 1, 1)
    assert len(img) == 0x80
    strings = [s.encode("latin-1")[:255] for s in (name, group, order)]

    def category(kind: int, data: bytes) -> bytes:
        if len(data) % 2:
            data += b"\0"
        return struct.pack("<HH", kind, len(data) // 2) + data

    sdata = bytes([len(strings)]) + b"".join(bytes([len(s)]) + s for s in strings)
    img += category(CAT_STRINGS, sdata)
    general = bytearray(32)
    general[0], general[1], general[2], general[3] = 2, 0, 3, 1  # group, image, order, name string indices
    general[5] = coe_details if mailbox else 0
    general[0x0E] = 0  # flags
    struct.pack_into("<h", general, 0x0C, 0)  # current on E-bus (mA)
    general[0x10] = 2
    struct.pack_into("<H", general, 0x12, 0x0011)  # physical ports: 0 = MII, 1 = MII
    img += category(CAT_GENERAL, bytes(general))
    img += category(CAT_FMMU, bytes(fmmus))
    img += category(
        CAT_SM, b"".join(struct.pack("<HHBBBB", s.start, s.length, s.control, 0, s.enable, s.kind) for s in sms)
    )
    for kind, pdos in ((CAT_TXPDO, tx_pdos), (CAT_RXPDO, rx_pdos)):
        for index, sm, entries in pdos:
            data = struct.pack("<HBBBBH", index, len(entries), sm, 0, 0, 0)
            data += b"".join(struct.pack("<HBBBBH", ix, sx, 0, code, bits, 0) for ix, sx, bits, code in entries)
            img += category(kind, data)
    img += struct.pack("<H", CAT_END)
    if len(img) > size_bytes:
        raise ValueError(f"SII image of {len(img)} bytes exceeds the EEPROM ({size_bytes})")
    return bytes(img.ljust(size_bytes, b"\xff"))


@dataclass
class SiiInfo:
    vendor_id: int
    product_code: int
    revision: int
    serial: int
    alias: int
    mbx_out: tuple  # (start, length)
    mbx_in: tuple
    mbx_protocols: int
    name: str = ""
    group: str = ""
    coe_details: int = 0
    fmmus: tuple = ()
    sms: tuple = ()  # SmConfig
    rx_pdos: tuple = ()  # (pdo index, SyncManager, [(index, sub, bits, CoE type code)])
    tx_pdos: tuple = ()


def parse(image: bytes) -> SiiInfo:
    """What a master reads from an image (for our own master and for tests)."""
    w = lambda a: struct.unpack_from("<H", image, a * 2)[0]  # noqa: E731
    d = lambda a: struct.unpack_from("<I", image, a * 2)[0]  # noqa: E731
    info = SiiInfo(d(0x08), d(0x0A), d(0x0C), d(0x0E), w(0x04), (w(0x18), w(0x19)), (w(0x1A), w(0x1B)), w(0x1C))
    pos = 0x40 * 2
    strings = [""]
    general = None
    while pos + 4 <= len(image):
        kind, size = struct.unpack_from("<HH", image, pos)
        if kind == CAT_END:
            break
        data = image[pos + 4 : pos + 4 + size * 2]
        if kind == CAT_STRINGS:
            n, p = data[0], 1
            for _ in range(n):
                ln = data[p]
                strings.append(data[p + 1 : p + 1 + ln].decode("latin-1"))
                p += 1 + ln
        elif kind == CAT_GENERAL:
            general = data
        elif kind == CAT_FMMU:
            info.fmmus = tuple(b for b in data if b not in (0xFF,))
        elif kind == CAT_SM:
            info.sms = tuple(_sm_config(data, k) for k in range(0, len(data) - 7, 8))
        elif kind in (CAT_TXPDO, CAT_RXPDO) and len(data) >= 8:
            index, n, sm = struct.unpack_from("<HBB", data, 0)
            entries = [struct.unpack_from("<HBBBB", data, 8 + 8 * k) for k in range(n) if 16 + 8 * k <= len(data)]
            pdo = (index, sm, [(ix, sx, bits, code) for ix, sx, _name, code, bits in entries])
            if kind == CAT_TXPDO:
                info.tx_pdos += (pdo,)
            else:
                info.rx_pdos += (pdo,)
        pos += 4 + size * 2
    if general is not None:
        get = lambda i: strings[i] if i < len(strings) else ""  # noqa: E731
        info.group, info.name, info.coe_details = get(general[0]), get(general[3]), general[5]
    return info
