"""The options of one `st run` (the CLI's flags as one value)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class RunOptions:
    files: list = field(default_factory=list)
    scans: int | None = None
    duration: str | None = None
    cycle: str | None = None
    virtual: bool = False
    policy: str = "openplc"
    dump_json: bool = False
    stats_json: str | None = None
    stats_plot: str | None = None
    on_fault: str = "stop"
    watchdog: str | None = None
    retain_file: str | None = None
    no_retain: bool = False
    retain_interval: str = "1s"
    cold: bool = False
    watch: bool = False
    rt: bool = True
    rt_priority: int = 30
    cpu: int | None = None
    sim_cost: list = field(default_factory=list)
    safe_outputs: list = field(default_factory=list)  # ["%QX0.1=TRUE", "%QW3=100"]
    web: str | None = None  # "[HOST:]PORT" of the online mode's page
    web_read_only: bool = False
    web_password: str | None = None
    modbus: str | None = None  # "[HOST:]PORT"
    modbus_map: str | None = None
    modbus_read_only: bool = False
    modbus_writable: str | None = None
    modbus_max_connections: int = 16
    modbus_idle_timeout: float = 60.0
    modbus_rate: float = 1000.0
    modbus_unit_ids: str | None = None
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
    time_unit: str = "ms"
    f_trig_first_scan: bool = False
    compiled_mtimes: dict | None = None  # the sources as compiled (see --watch)


def safe_values(specs: list) -> dict:
    """["%QX0.1=TRUE", "%QW3=100"] → {"%QX0.1": True, "%QW3": 100}."""
    out = {}
    for spec in specs:
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
