"""A subset of the EtherCAT Slave Information (ESI) XML format (ETG.2000): identity, PDOs, mailbox, DC.

    <EtherCATInfo>
      <Vendor><Id>#x0000029C</Id><Name>…</Name></Vendor>
      <Descriptions><Devices><Device>
        <Type ProductCode="#x…" RevisionNo="#x…">type name</Type>
        <Name LcId="1033">…</Name>  <GroupType>…</GroupType>
        <RxPdo Fixed="1" Mandatory="1" Sm="2"><Index>#x1600</Index><Name>…</Name>
          <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen>
                 <Name>…</Name><DataType>UINT</DataType></Entry> …</RxPdo>
        <TxPdo …/>  <Mailbox><CoE …/></Mailbox>
        <Dc><OpMode><Name>DC</Name><AssignActivate>#x0300</AssignActivate>
            <CycleTimeSync0 Factor="1">0</CycleTimeSync0></OpMode></Dc>
      </Device></Devices></Descriptions>
    </EtherCATInfo>

Numbers are decimal or "#x"-prefixed hex. A PDO with an Sm attribute is assigned to that
SyncManager by default (Sm="2" outputs and Sm="3" inputs behind the two mailbox SyncManagers;
Sm="0"/"1" on a terminal without mailbox); one without is an alternative the master may assign
instead. An entry with Index 0 is padding. Namespaces on the tags are ignored.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

# ESI data type names → the CoE type names pdo.PdoLayout and od.DTYPES know
_DTYPE_ALIASES = {
    "BOOL": "BOOL",
    "BOOLEAN": "BOOL",
    "BIT": "BOOL",
    "SINT": "SINT",
    "INT": "INT",
    "DINT": "DINT",
    "LINT": "LINT",
    "USINT": "USINT",
    "UINT": "UINT",
    "UDINT": "UDINT",
    "ULINT": "ULINT",
    "REAL": "REAL",
    "LREAL": "LREAL",
    "BYTE": "USINT",
    "WORD": "UINT",
    "DWORD": "UDINT",
    "LWORD": "ULINT",
    "INT8": "SINT",
    "INT16": "INT",
    "INT32": "DINT",
    "INT64": "LINT",
    "UINT8": "USINT",
    "UINT16": "UINT",
    "UINT32": "UDINT",
    "UINT64": "ULINT",
    "REAL32": "REAL",
    "REAL64": "LREAL",
}


class EsiError(Exception):
    """An ESI file that cannot be used. line/column (1-based) are set for XML syntax errors."""

    def __init__(self, message: str, path: str = "", line: int | None = None, column: int | None = None):
        self.path, self.line, self.column = path, line, column
        where = path
        if line is not None:
            where += f":{line}" + (f":{column}" if column is not None else "")
        super().__init__(f"{where}: {message}" if where else message)


@dataclass
class EsiPdoEntry:
    index: int  # 0: padding
    sub: int
    bits: int
    dtype: str  # a CoE type name ("PAD" for padding)
    name: str = ""
    esi_type: str = ""  # the DataType text as written in the file

    def as_tuple(self) -> tuple:
        """The (index, sub, bits, dtype, name) form pdo.PdoLayout takes."""
        return (self.index, self.sub, self.bits, self.dtype, self.name)


@dataclass
class EsiPdo:
    index: int
    name: str
    entries: list
    sm: int | None = None  # the SyncManager it is assigned to by default; None: not assigned
    fixed: bool = False
    mandatory: bool = False
    excludes: list = field(default_factory=list)

    @property
    def assigned(self) -> bool:
        return self.sm is not None

    @property
    def bits(self) -> int:
        return sum(e.bits for e in self.entries)


@dataclass
class EsiOpMode:
    name: str
    desc: str = ""
    assign_activate: int = 0  # value for register 0x0980 (0x0300: SYNC0 on)
    cycle_time_sync0: int | None = None  # ns; 0 means "the master's cycle"
    cycle_time_sync0_factor: int | None = None
    shift_time_sync0: int | None = None
    cycle_time_sync1: int | None = None
    cycle_time_sync1_factor: int | None = None


@dataclass
class EsiDevice:
    vendor_id: int
    product_code: int
    revision: int
    name: str  # the Name element (the English one when several), else the Type text
    type_name: str  # the Type element's text
    group: str = ""
    vendor_name: str = ""
    rx_pdos: list = field(default_factory=list)
    tx_pdos: list = field(default_factory=list)
    mailbox: bool = False
    mailbox_protocols: tuple = ()  # e.g. ("CoE", "FoE")
    coe: bool = False
    coe_complete_access: bool = False
    dc_opmodes: list = field(default_factory=list)

    @property
    def assigned_rx(self) -> list:
        return [p for p in self.rx_pdos if p.assigned]

    @property
    def assigned_tx(self) -> list:
        return [p for p in self.tx_pdos if p.assigned]

    def rx_entries(self) -> list:
        """The default-assigned RxPDOs' entries, flattened in (index, sub, bits, dtype, name) form."""
        return [e.as_tuple() for p in self.assigned_rx for e in p.entries]

    def tx_entries(self) -> list:
        return [e.as_tuple() for p in self.assigned_tx for e in p.entries]

    def pdo(self, index: int) -> EsiPdo | None:
        for p in self.rx_pdos + self.tx_pdos:
            if p.index == index:
                return p
        return None


def parse_number(text) -> int:
    """ESI numbers: decimal, or hex as "#x1A00" (also "0x1A00"). ValueError otherwise."""
    if text is None:
        raise ValueError("missing number")
    t = text.strip()
    if t[:2].lower() in ("#x", "0x"):
        return int(t[2:], 16)
    return int(t, 10)


def load_esi(path, product_code: int | None = None, revision: int | None = None) -> list:
    """The devices of an ESI file, optionally only those with this product code (and revision).

    EsiError with the file name if the file cannot be read or parsed, holds no device, a value
    cannot be read, or no device matches."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise EsiError(f"cannot read: {e.strerror or e}", path) from None
    devices = parse_esi(data, path)
    if product_code is not None or revision is not None:
        found = [
            d
            for d in devices
            if (product_code is None or d.product_code == product_code) and (revision is None or d.revision == revision)
        ]
        if not found:
            want = " ".join(
                x
                for x in (
                    f"product code {product_code:#010x}" if product_code is not None else "",
                    f"revision {revision:#010x}" if revision is not None else "",
                )
                if x
            )
            have = ", ".join(f"{d.product_code:#010x} rev {d.revision:#010x}" for d in devices)
            raise EsiError(f"no device with {want} (the file has: {have})", path)
        devices = found
    return devices


def parse_esi(data, path: str = "<esi>") -> list:
    """Parse ESI XML (bytes or str) → [EsiDevice]; path only names the source in errors."""
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        line, col = e.position
        msg = str(e).split(":")[0]  # "mismatched tag: line 3, column 2" → the cause
        raise EsiError(f"malformed XML: {msg}", path, line, col + 1) from None
    for el in root.iter():
        if isinstance(el.tag, str) and "}" in el.tag:
            el.tag = el.tag.rsplit("}", 1)[1]
    if root.tag != "EtherCATInfo":
        raise EsiError(f"not an ESI file: the root element is <{root.tag}>, not <EtherCATInfo>", path)

    vendor = root.find("Vendor")
    vendor_id_el = vendor.find("Id") if vendor is not None else None
    if vendor is None or vendor_id_el is None:
        raise EsiError("no Vendor/Id", path)
    vendor_id = _num(vendor_id_el.text, path, "Vendor/Id")
    vendor_name = _text(vendor.find("Name"))

    devices = []
    for i, dev in enumerate(root.iterfind("Descriptions/Devices/Device"), 1):
        devices.append(_device(dev, vendor_id, vendor_name, path, i))
    if not devices:
        raise EsiError("no Descriptions/Devices/Device in the file", path)
    return devices


def _text(el) -> str:
    return (el.text or "").strip() if el is not None else ""


def _num(text, path: str, what: str) -> int:
    try:
        return parse_number(text)
    except (ValueError, AttributeError):
        raise EsiError(f"{what}: {text!r} is not a number (decimal or #x hex)", path) from None


def _flag(el, attr: str) -> bool:
    return (el.get(attr) or "").strip().lower() in ("1", "true")


def _name(el) -> str:
    """The English Name child when several are given (LcId 1033), else the first."""
    names = el.findall("Name")
    for n in names:
        if n.get("LcId") == "1033":
            return _text(n)
    return _text(names[0]) if names else ""


def _dtype(esi_type: str, bits: int) -> str:
    t = esi_type.strip().upper()
    if t in _DTYPE_ALIASES:
        dt = _DTYPE_ALIASES[t]
        if dt == "BOOL" and bits != 1:
            return _by_bits(bits)
        return dt
    return _by_bits(bits)  # BIT2..BIT8, arrays, strings: an unsigned integer of that width


def _by_bits(bits: int) -> str:
    if bits == 1:
        return "BOOL"
    for limit, name in ((8, "USINT"), (16, "UINT"), (32, "UDINT"), (64, "ULINT")):
        if bits <= limit:
            return name
    return "OCTETS"


def _device(dev, vendor_id: int, vendor_name: str, path: str, pos: int) -> EsiDevice:
    typ = dev.find("Type")
    if typ is None:
        raise EsiError(f"device {pos}: no Type element", path)
    type_name = _text(typ)
    where = f"device {pos} ({type_name or 'unnamed'})"
    if typ.get("ProductCode") is None:
        raise EsiError(f"{where}: Type has no ProductCode", path)
    product = _num(typ.get("ProductCode"), path, f"{where}: ProductCode")
    revision = _num(typ.get("RevisionNo"), path, f"{where}: RevisionNo") if typ.get("RevisionNo") else 0
    d = EsiDevice(
        vendor_id, product, revision, _name(dev) or type_name, type_name, _text(dev.find("GroupType")), vendor_name
    )
    d.rx_pdos = [_pdo(p, path, f"{where}: RxPdo") for p in dev.findall("RxPdo")]
    d.tx_pdos = [_pdo(p, path, f"{where}: TxPdo") for p in dev.findall("TxPdo")]

    mbx = dev.find("Mailbox")
    if mbx is not None:
        d.mailbox = True
        d.mailbox_protocols = tuple(
            c.tag for c in mbx if isinstance(c.tag, str) and c.tag in ("AoE", "EoE", "CoE", "FoE", "SoE", "VoE")
        )
        coe = mbx.find("CoE")
        d.coe = coe is not None
        d.coe_complete_access = coe is not None and _flag(coe, "CompleteAccess")

    for om in dev.iterfind("Dc/OpMode"):
        mode = EsiOpMode(_text(om.find("Name")), _text(om.find("Desc")))
        ow = f"{where}: Dc/OpMode {mode.name!r}"
        aa = om.find("AssignActivate")
        if aa is not None:
            mode.assign_activate = _num(aa.text, path, f"{ow}: AssignActivate")
        for tag, attr, fattr in (
            ("CycleTimeSync0", "cycle_time_sync0", "cycle_time_sync0_factor"),
            ("CycleTimeSync1", "cycle_time_sync1", "cycle_time_sync1_factor"),
            ("ShiftTimeSync0", "shift_time_sync0", None),
        ):
            el = om.find(tag)
            if el is None:
                continue
            setattr(mode, attr, _num(el.text, path, f"{ow}: {tag}"))
            if fattr and el.get("Factor") is not None:
                setattr(mode, fattr, _num(el.get("Factor"), path, f"{ow}: {tag} Factor"))
        d.dc_opmodes.append(mode)
    return d


def _pdo(el, path: str, where: str) -> EsiPdo:
    ix = el.find("Index")
    if ix is None:
        raise EsiError(f"{where}: no Index", path)
    index = _num(ix.text, path, f"{where}: Index")
    where = f"{where} {index:#06x}"
    sm = _num(el.get("Sm"), path, f"{where}: Sm") if el.get("Sm") is not None else None
    entries = []
    for n, e in enumerate(el.findall("Entry"), 1):
        ew = f"{where}: Entry {n}"
        eix = _num(_text(e.find("Index")), path, f"{ew}: Index")
        bl = e.find("BitLen")
        if bl is None:
            raise EsiError(f"{ew}: no BitLen", path)
        bits = _num(bl.text, path, f"{ew}: BitLen")
        if eix == 0:
            entries.append(EsiPdoEntry(0, 0, bits, "PAD", "", _text(e.find("DataType"))))
            continue
        sub_el = e.find("SubIndex")
        sub = _num(sub_el.text, path, f"{ew}: SubIndex") if sub_el is not None else 0
        esi_type = _text(e.find("DataType"))
        entries.append(EsiPdoEntry(eix, sub, bits, _dtype(esi_type, bits), _text(e.find("Name")), esi_type))
    excludes = [_num(x.text, path, f"{where}: Exclude") for x in el.findall("Exclude")]
    return EsiPdo(index, _name(el), entries, sm, _flag(el, "Fixed"), _flag(el, "Mandatory"), excludes)
