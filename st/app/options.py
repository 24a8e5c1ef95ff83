"""The options of one `st run` (the CLI's flags as one value, each checked by its type in params.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class RunOptions:
    files: list = field(default_factory=list)
    scans: int | None = None
    duration: Any = None  # a duration: ns, or text such as "10s"
    cycle: Any = None
    virtual: bool = False
    policy: str = "openplc"
    dump_json: bool = False
    dump_all: bool = False  # --dump-json --all: block instances with their internal variables
    stats_json: str | None = None
    stats_plot: str | None = None
    on_fault: str = "stop"
    watchdog: Any = None
    retain_file: str | None = None  # --retain PATH; the default place: session.retain_path
    no_retain: bool = False
    retain_interval: Any = "1s"
    cold: bool = False
    watch: bool = False
    rt: bool = True
    rt_priority: int = 30
    cpu: int | None = None
    sim_cost: list = field(default_factory=list)  # [("fast", ns) or "fast=4ms"]
    safe_outputs: list = field(default_factory=list)  # [("%QX0.1", True)] or ["%QX0.1=TRUE", "%QW3=100"]
    web: str | None = None  # "[HOST:]PORT" of the online mode's page
    web_read_only: bool = False
    web_password: str | None = None
    web_hosts: list = field(default_factory=list)  # --web-host names
    web_insecure: bool = False  # --web beyond loopback without a password
    web_cert: str | None = None  # HTTPS
    web_key: str | None = None
    modbus: str | None = None  # "[HOST:]PORT"
    modbus_map: str | None = None
    opcua: str | None = None  # "[HOST:]PORT" of the OPC UA server
    opcua_map: str | None = None
    opcua_users: str | None = None
    opcua_anonymous: bool = False
    opcua_security: str = "sign,encrypt"
    opcua_pki: str | None = None
    modbus_read_only: bool = False
    modbus_writable: Any = None  # {table: [(first, end)]} or "holding:0-99,coil:0-15"
    modbus_max_connections: int = 16
    modbus_idle_timeout: float = 60.0
    modbus_rate: float = 1000.0
    modbus_unit_ids: Any = None  # [1, 255] or "1,255"
    axes: str | None = None  # axis configuration (TOML)
    trace: list = field(default_factory=list)  # AXIS_REF paths
    trace_plot: str | None = None
    trace_csv: str | None = None
    ethercat: str | None = None  # segment configuration (TOML)
    ethercat_backend: str = "sim"
    ethercat_iface: str | None = None
    ethercat_capture: str | None = None
    quiet: bool = False
    native: bool = False  # --native: loop bodies compiled to C (also for --watch's online changes)
    python: bool = False  # --python: no native build in the background (app/native_upgrade.py)
    time_unit: str = "ms"
    f_trig_first_scan: bool = False
    compiled_mtimes: dict | None = None  # the sources as compiled (see --watch)
    dialect: str | None = None  # --dialect, for --watch's compilations as for the first
    lib_path: tuple = ()  # --lib, likewise


def safe_values(specs: list) -> dict:
    """["%QX0.1=TRUE", "%QW3=100"] (or (address, value) pairs) → {"%QX0.1": True, "%QW3": 100}."""
    out = {}
    for spec in specs:
        if isinstance(spec, tuple):
            out[spec[0]] = spec[1]
            continue
        addr, sep, text = spec.partition("=")
        text = text.strip().upper()
        if not sep or not text:
            raise ValueError(f"--safe-output {spec!r}: expected ADDRESS=VALUE, e.g. %QX0.1=TRUE")
        if text in ("TRUE", "FALSE"):
            out[addr.strip()] = text == "TRUE"
            continue
        try:
            out[addr.strip()] = int(text, 0)
        except ValueError:
            raise ValueError(f"--safe-output {spec!r}: the value must be TRUE, FALSE or an integer") from None
    return out


def unit_ids(spec: Any) -> list[int] | None:
    """[1, 255] or "1,255" → [1, 255]; None: every unit id."""
    if spec is None or spec == "":
        return None
    if isinstance(spec, str):
        return [int(u) for u in spec.split(",")]
    return list(spec)
