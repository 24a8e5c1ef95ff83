"""The segment configuration (TOML): slaves, their PDO mapping and bindings, cycle, DC, delays.

    [segment]
    cycle = "1ms"                 # the process-data cycle (default: the task's interval)
    task = "fast"                 # the task whose scans exchange process data (default: the fastest)
    dc = true                     # SYNC0 in every drive: outputs take effect together
    host_delay_us = 5.0           # t_host: master to the first slave (eq. 4.7)
    forwarding_delay_us = 1.0     # t_drive: per slave (eq. 4.7); a slave may override it
    cable_m = 1.0
    lost_frame_limit = 3          # consecutive lost frames / wrong working counters → axes ErrorStop
    compensate_delay = false      # shift each drive's setpoint by its D_comm(n) (thesis 6.2)

    [[slave]]
    name = "x"
    type = "cia402"               # cia402 | dio | esi
    axis = 1                      # the AXIS_REF (AxisNo := 1) this drive moves
    encoder_bits = 23
    esi = "drive.xml"             # optional: the PDO layout (and ids) from an ESI file
    [slave.motor]                 # MotorParams fields
    rated_torque = 0.32

    [[slave]]
    name = "io"
    type = "dio"
    inputs = 8                    # bits
    outputs = 8
    inputs_at = "%IX0.0"          # consecutive located bits
    outputs_at = "%QX0.0"
    [slave.bind]                  # or any entry → a located variable
    "0x6000:01" = "%IX1.0"

Errors name the file and the slave; TOML syntax errors carry the line and column.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field


class ConfigError(ValueError):
    pass


@dataclass
class SlaveConfig:
    name: str
    type: str = "cia402"
    axis: int = 0
    encoder_bits: int = 23
    esi: str = ""
    product_code: int | None = None
    vendor_id: int | None = None
    forwarding_delay_us: float | None = None
    inputs: int = 8
    outputs: int = 8
    inputs_at: str = ""
    outputs_at: str = ""
    bind: dict = field(default_factory=dict)  # "0xIIII:SS" or entry name → "%I…"/"%Q…"
    motor: dict = field(default_factory=dict)
    rx_pdos: list | None = None
    tx_pdos: list | None = None
    enable_delay: float = 0.0
    # an ideal drive (tests): follows each controlword in the next exchange and its position is
    # the CSP target exactly, no motor dynamics
    ideal: bool = False


@dataclass
class SegmentConfig:
    slaves: list
    cycle_s: float = 0.0
    task: str = ""
    dc: bool = True
    host_delay_us: float = 5.0
    forwarding_delay_us: float = 1.0
    cable_m: float = 1.0
    lost_frame_limit: int = 3
    compensate_delay: bool = False
    path: str = ""


_DUR = re.compile(r"^\s*(\d+(?:\.\d*)?)\s*(ns|us|µs|ms|s)\s*$")
_SCALE = {"ns": 1e-9, "us": 1e-6, "µs": 1e-6, "ms": 1e-3, "s": 1.0}


def parse_duration(v, where: str) -> float:
    if isinstance(v, (int, float)):
        return float(v)
    m = _DUR.match(str(v))
    if not m:
        raise ConfigError(f'{where}: \'{v}\' is not a duration like "1ms" or "250us"')
    return float(m.group(1)) * _SCALE[m.group(2)]


def load(path: str) -> SegmentConfig:
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except OSError as e:
        raise ConfigError(f"{path}: cannot read the segment configuration: {e.strerror}") from None
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{path}: {e}") from None
    return from_dict(doc, path)


def from_dict(doc: dict, path: str = "<segment>") -> SegmentConfig:
    seg = dict(doc.get("segment", {}))
    known = {
        "cycle",
        "task",
        "dc",
        "host_delay_us",
        "forwarding_delay_us",
        "cable_m",
        "lost_frame_limit",
        "compensate_delay",
    }
    for k in seg:
        if k not in known:
            raise ConfigError(f"{path}: [segment]: unknown setting '{k}' (known: {', '.join(sorted(known))})")
    slaves = []
    fields = set(SlaveConfig.__dataclass_fields__)
    for i, item in enumerate(doc.get("slave", []), 1):
        item = dict(item)
        name = item.get("name") or f"slave{i}"
        item["name"] = name
        where = f"{path}: slave {i} ({name})"
        unknown = set(item) - fields
        if unknown:
            raise ConfigError(f"{where}: unknown setting '{sorted(unknown)[0]}'")
        sc = SlaveConfig(**item)
        if sc.type not in ("cia402", "dio", "esi"):
            raise ConfigError(f"{where}: type must be cia402, dio or esi, not '{sc.type}'")
        if sc.type == "esi" and not sc.esi:
            raise ConfigError(f'{where}: type esi needs esi = "file.xml"')
        for key, addr in list(sc.bind.items()) + [("inputs_at", sc.inputs_at), ("outputs_at", sc.outputs_at)]:
            if addr and not re.match(r"^%[IQM][XBWDL]?\d+(\.\d+)?$", addr.strip(), re.I):
                raise ConfigError(f"{where}: '{addr}' (for {key}) is not a located address like %IX0.0 or %QW4")
        if sc.axis and sc.type == "dio":
            raise ConfigError(f"{where}: a digital terminal cannot move axis {sc.axis}")
        slaves.append(sc)
    axes = [s.axis for s in slaves if s.axis]
    dup = {a for a in axes if axes.count(a) > 1}
    if dup:
        raise ConfigError(f"{path}: axis {sorted(dup)[0]} is bound to more than one drive")
    cfg = SegmentConfig(slaves, path=path)
    if "cycle" in seg:
        cfg.cycle_s = parse_duration(seg["cycle"], f"{path}: [segment] cycle")
    for k in ("task",):
        if k in seg:
            cfg.task = str(seg[k])
    for k in ("dc", "compensate_delay"):
        if k in seg:
            setattr(cfg, k, bool(seg[k]))
    for k in ("host_delay_us", "forwarding_delay_us", "cable_m"):
        if k in seg:
            setattr(cfg, k, float(seg[k]))
    if "lost_frame_limit" in seg:
        cfg.lost_frame_limit = int(seg["lost_frame_limit"])
        if cfg.lost_frame_limit < 1:
            raise ConfigError(f"{path}: [segment] lost_frame_limit must be at least 1")
    return cfg


def build_devices(cfg: SegmentConfig) -> list:
    """The emulated devices of a configuration (the `sim` backend and `st ethercat serve`)."""
    from .devices import CiA402Drive, DigitalIO
    from .devices.base import Device

    out: list[Device] = []
    for sc in cfg.slaves:
        kw = {}
        if sc.vendor_id is not None:
            kw["vendor_id"] = sc.vendor_id
        if sc.product_code is not None:
            kw["product_code"] = sc.product_code
        if sc.type == "dio":
            out.append(DigitalIO(sc.name, n_inputs=sc.inputs, n_outputs=sc.outputs, **kw))
            continue
        if sc.esi:
            from .esi import EsiError, load_esi

            try:
                dev = load_esi(sc.esi, product_code=sc.product_code)[0]
            except EsiError as e:
                raise ConfigError(f"{cfg.path}: slave {sc.name}: {e}") from None
            kw.setdefault("vendor_id", dev.vendor_id)
            kw.setdefault("product_code", dev.product_code)
            kw["rx_mapping"] = dev.rx_entries()
            kw["tx_mapping"] = dev.tx_entries()
        from .devices.motor import MotorParams

        try:
            params = MotorParams(**{"encoder_bits": sc.encoder_bits, **sc.motor})
        except TypeError as e:
            raise ConfigError(f"{cfg.path}: slave {sc.name}: [slave.motor]: {e}") from None
        drive = CiA402Drive(sc.name, motor=params, **kw)
        if sc.enable_delay:
            drive.enable_delay = sc.enable_delay
        drive.ideal = sc.ideal
        out.append(drive)
    return out


def build_segment(cfg: SegmentConfig):
    from .segment import Segment

    seg = Segment(
        build_devices(cfg),
        host_delay=cfg.host_delay_us * 1e-6,
        forwarding_delay=cfg.forwarding_delay_us * 1e-6,
        cable_m=cfg.cable_m,
    )
    for sc, s in zip(cfg.slaves, seg.slaves):
        if sc.forwarding_delay_us is not None:
            s.forwarding_delay = sc.forwarding_delay_us * 1e-6
    return seg
