"""The parts one `st run` starts, one function each: it starts one thing and registers its own
clean-up on the ExitStack it is given, so that a run that cannot start, at whatever point, closes
what had started before (session.py decides which stack each goes on, and so the order of the
clean-up).

A part that cannot start raises StartRefused with the one line the user sees (`error: …`); the
session prints it, the stacks close what had started, and the run ends with exit status 2.
"""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import signal
import threading
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from ..runtime.plc import PLC
from ..runtime.realtime import RealtimeSetup
from ..runtime.retain import RetainError
from ..stdlib.plcopen import configure_axes
from ..stdlib.plcopen.trace import start_traces
from .options import RunOptions, safe_values, unit_ids
from .output import err
from .params import is_loopback
from .status import StatusLine
from .watch import Watcher


class StartRefused(Exception):
    """A part of the run could not start: `str(self)` is the line the user sees."""


def check_options(o: RunOptions) -> None:
    """What the command line refuses already, refused again for a caller that builds RunOptions."""
    if o.virtual and o.scans is None and o.duration is None:
        raise StartRefused("error: --virtual needs --duration or --scans (virtual time runs as fast as the CPU allows)")
    if o.virtual and o.web:
        raise StartRefused("error: --web needs a run in real time (not --virtual)")
    if o.native and o.python:
        raise StartRefused(
            "error: --native and --python exclude each other (--native: C from the start; "
            "--python: never; neither: C once it is built)"
        )


# ---------------------------------------------------------------------------- retained data


def _has_retained(compiled) -> bool:
    p = compiled.project
    return any(
        v.retain or v.persistent for pou in p.pous.values() if not pou.library for v in pou.vars.values()
    ) or any(g.retain or g.persistent for g in p.globals.values())


def default_retain_path(files) -> Path:
    """Where a project's retained data is kept unless --retain says otherwise: a per-user data folder,
    `$XDG_DATA_HOME/st/retain/<name>-<hash>.db` (`~/.local/share/st/retain/…` when XDG_DATA_HOME is
    unset or not absolute), named after the project's first source file and keyed by a hash of the
    absolute paths of all of them, in any order: never a file beside the sources."""
    base = os.environ.get("XDG_DATA_HOME", "")
    root = Path(base) if base and os.path.isabs(base) else Path.home() / ".local" / "share"
    paths = sorted(str(Path(f).resolve()) for f in files)
    digest = hashlib.sha256("\n".join(paths).encode()).hexdigest()[:12]
    name = re.sub(r"[^A-Za-z0-9._-]", "_", Path(paths[0]).stem) if paths else "st"
    return root / "st" / "retain" / f"{name}-{digest}.db"


def retain_path(compiled, o: RunOptions) -> str | None:
    """The retained data file of this run, or None: only a program with RETAIN or PERSISTENT variables
    keeps any; --retain PATH chooses the file, else a --virtual run keeps none (a simulation must not
    change a plant's retained data) and a run in real time uses default_retain_path."""
    if o.no_retain or not _has_retained(compiled):
        return None
    if o.retain_file:
        return o.retain_file
    if o.virtual:
        return None
    return str(default_retain_path(o.files))


def retain_folder(compiled, o: RunOptions) -> str | None:
    """The retained data file (retain_path), its default folder created when it is the default one."""
    retain = retain_path(compiled, o)
    if retain is not None and not o.retain_file:
        folder = Path(retain).parent
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise StartRefused(
                f"error: cannot create the folder for retained data {folder}: {e.strerror or e}"
            ) from None
    return retain


def say_retained(plc: PLC, o: RunOptions, retain: str | None) -> None:
    if o.quiet:
        return
    if retain:
        err(f"retained data: {retain} ({'cold start' if o.cold else f'{plc.retain_restored} value(s) restored'})")
    elif o.retain_file and not o.no_retain:
        err("retained data: none (the program has no RETAIN or PERSISTENT variable)")


# ---------------------------------------------------------------------------- the PLC


def start_plc(stack: ExitStack, compiled, o: RunOptions, retain: str | None) -> PLC:
    """The PLC (its retained data restored), closed by `stack`: outputs safe, retained data
    committed, the store closed."""
    try:
        plc = PLC(
            compiled,
            o.cycle,
            watchdog=o.watchdog,
            policy=o.policy,
            retain=retain,
            retain_interval=o.retain_interval,
            cold=o.cold,
            safe_outputs=safe_values(o.safe_outputs),
        )
    except RetainError as e:
        raise StartRefused(f"error: {e}") from None
    except (ValueError, KeyError, MemoryError) as e:  # PLCStartError: the reason, located
        raise StartRefused(f"error: cannot start the PLC: {e or type(e).__name__}") from None
    stack.callback(plc.close)
    try:
        for spec in o.sim_cost:
            if isinstance(spec, tuple):  # (task, ns): checked by the command line
                plc.set_cost(*spec)
            else:
                name, _, cost = spec.partition("=")
                plc.set_cost(name.strip(), cost.strip())
    except (ValueError, KeyError, MemoryError) as e:
        raise StartRefused(f"error: cannot start the PLC: {e or type(e).__name__}") from None
    if not plc.instances:
        raise StartRefused("error: nothing to run: no PROGRAM and no CONFIGURATION")
    return plc


def start_motion(plc: PLC, o: RunOptions) -> list:
    """--axes and --trace: the axes' configurations and the traces, kept by the PLC's motion
    registry (nothing to close); the traces are returned, to be written when the run ends."""
    if not (o.axes or o.trace):
        return []
    try:
        if o.axes:
            configure_axes(plc, o.axes)
        return start_traces(plc, o.trace)
    except (KeyError, TypeError, ValueError) as e:
        raise StartRefused(f"error: {e.args[0] if e.args else e}") from None


# ---------------------------------------------------------------------------- the field


def start_ethercat(stack: ExitStack, plc: PLC, o: RunOptions):
    """--ethercat: the segment in OP, its driver on `plc.io`, its master (and the emulated segment)
    closed by `stack`."""
    if not o.ethercat:
        return None
    # the I/O packages are imported when used: each costs 0.1-0.2 s of start-up
    from ..io.ethercat import ConfigError, EtherCATDriver, MasterError, load_segment

    try:
        ecat = EtherCATDriver(
            plc,
            load_segment(o.ethercat),
            backend=o.ethercat_backend,
            iface=o.ethercat_iface or "",
            capture=o.ethercat_capture or "",
        )
    except (ConfigError, MasterError) as e:
        raise StartRefused(f"error: {e}") from None
    stack.callback(ecat.close)
    if not o.quiet:
        err(
            f"ethercat: {len(ecat.master.slaves)} slave(s) in OP ({o.ethercat_backend} backend), "
            f"{len(ecat.links)} drive(s) bound"
        )
    return ecat


def start_modbus(stack: ExitStack, plc: PLC, o: RunOptions):
    """--modbus: the slave's server process and shared memory, stopped (and unlinked) by `stack`."""
    if not o.modbus:
        return None
    from ..io.modbus import MapError, ModbusSlave, parse_endpoint

    try:
        host, port = parse_endpoint(o.modbus)
        units = unit_ids(o.modbus_unit_ids)
        slave = ModbusSlave(
            plc,
            host,
            port,
            map_file=o.modbus_map,
            read_only=o.modbus_read_only,
            writable=o.modbus_writable,
            max_connections=o.modbus_max_connections,
            idle_timeout=o.modbus_idle_timeout,
            max_rate=o.modbus_rate,
            unit_ids=units,
        )
        stack.callback(slave.stop)  # (before start: an interrupted start leaves no process either)
        slave.start()
    except MapError as e:
        raise StartRefused(str(e)) from None
    except (ValueError, OSError) as e:
        raise StartRefused(f"error: cannot start the Modbus slave: {e}") from None
    if not o.quiet:
        err(
            f"modbus: serving on {host}:{slave.port} (OpenPLC map"
            + (f" + {o.modbus_map}" if o.modbus_map else "")
            + (", read-only" if o.modbus_read_only else "")
            + ")"
        )
    if not is_loopback(host):  # printed even with -q
        err(modbus_warning(host, slave.port, o.modbus_read_only))
    return slave


def modbus_warning(host: str, port: int, read_only: bool) -> str:
    """The warning for a Modbus server that other machines reach: it has no authentication."""
    where = f"[{host}]" if ":" in host else host
    if read_only:
        return (
            f"warning: the Modbus server on {where}:{port} is reachable from other machines, without "
            "authentication (read-only: writes are refused)"
        )
    return (
        f"warning: the Modbus server on {where}:{port} is reachable from other machines, without "
        "authentication, and accepts writes to the PLC (--modbus-read-only refuses them)"
    )


def start_opcua(stack: ExitStack, plc: PLC, o: RunOptions):
    """--opcua: the OPC UA server's process and shared memory (st/opcua), stopped by `stack`."""
    if not o.opcua:
        return None
    from ..io.modbus import parse_endpoint
    from ..opcua import OpcUaServer
    from ..opcua.symbols import MapError
    from ..opcua.users import UsersError

    modes = tuple(m.strip().lower() for m in (o.opcua_security or "").split(",") if m.strip())
    try:
        host, port = parse_endpoint(o.opcua)
        server = OpcUaServer(
            plc,
            host,
            port,
            map_file=o.opcua_map,
            anonymous=o.opcua_anonymous,
            users=o.opcua_users,
            security=modes,
            pki=o.opcua_pki,
            name=Path(o.files[0]).stem if o.files else "st",
        )
        stack.callback(server.stop)
        server.start()
    except (MapError, UsersError) as e:
        raise StartRefused(str(e)) from None
    except (ValueError, OSError) as e:
        raise StartRefused(f"error: cannot start the OPC UA server: {e}") from None
    if not o.quiet:
        offered = ", ".join(
            {"none": "None", "sign": "Basic256Sha256 Sign", "encrypt": "Basic256Sha256 SignAndEncrypt"}[m]
            for m in modes
        )
        who = ("users of " + o.opcua_users if o.opcua_users else "") + (
            " and " if o.opcua_users and o.opcua_anonymous else ""
        )
        who += "anonymous (read)" if o.opcua_anonymous else ""
        err(f"opcua: {server.endpoint} ({offered}; {who}); client certificates: {server.cfg.pki}/trusted")
    if not is_loopback(host) and ("none" in modes or o.opcua_anonymous):
        err(
            f"warning: the OPC UA server on {host}:{server.port} is reachable from other machines "
            + ("without security (--opcua-security none)" if "none" in modes else "with anonymous access")
        )
    return server


# ---------------------------------------------------------------------------- around the scan


def start_web(stack: ExitStack, plc: PLC, o: RunOptions):
    """--web: the online mode's server process and shared memory (st/web), stopped by `stack`; its
    URL, with the token, printed."""
    if not o.web:
        return None
    from ..io.modbus import parse_endpoint
    from ..web.link import WebLink

    try:
        host, port = parse_endpoint(o.web or "")
    except ValueError as e:
        raise StartRefused(f"error: cannot start the web server: {e}") from None
    if not is_loopback(host) and not o.web_password and not o.web_insecure:
        raise StartRefused(
            f"error: --web {o.web} serves the PLC beyond this machine: give it a --web-password (and "
            "--web-cert/--web-key for HTTPS, docs/web.md), or --web-insecure to serve it without"
        )
    if bool(o.web_cert) != bool(o.web_key):
        raise StartRefused("error: --web-cert and --web-key go together (a certificate and its private key)")
    try:
        token = secrets.token_urlsafe(18)
        name = ", ".join(Path(f).name for f in o.files)
        web = WebLink(
            plc,
            name,
            host,
            port,
            token,
            o.web_password or "",
            o.web_read_only,
            names=tuple(o.web_hosts),
            cert=o.web_cert or "",
            key=o.web_key or "",
        )
        stack.callback(web.stop)
        web.start()
    except (ValueError, OSError) as e:
        raise StartRefused(f"error: cannot start the web server: {e}") from None
    shown = f"[{host}]" if ":" in host else host
    scheme = "https" if o.web_cert else "http"
    beyond = "" if is_loopback(host) else "  -- listening beyond this machine"
    if beyond and scheme == "http":
        beyond += " over plain HTTP (--web-cert/--web-key serve HTTPS)"
    err(f"web: {scheme}://{shown}:{web.port}/?token={token}" + (" (read-only)" if o.web_read_only else "") + beyond)
    return web


def install_signals(stack: ExitStack, stop: threading.Event, plc: PLC) -> None:
    """Ctrl-C and SIGTERM stop the PLC at the next scan boundary; a job still running is ended by its
    watchdog (so within one watchdog period), or at once when the signal comes a second time. The
    previous handlers are put back by `stack`."""

    def handler(signum, frame):
        stop.set()
        plc.request_stop(signal.Signals(signum).name)

    old: dict[signal.Signals, Any] = {}

    def restore() -> None:
        for sig, h in old.items():
            signal.signal(sig, h)

    stack.callback(restore)
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            old[sig] = signal.signal(sig, handler)
        except ValueError:  # not the main thread
            pass


def start_status(stack: ExitStack, plc: PLC, o: RunOptions) -> StatusLine | None:
    """The live status line of a run in real time on a terminal, ended by `stack`."""
    if o.quiet or o.virtual:
        return None
    status = StatusLine(plc)
    stack.callback(status.close)
    return status


def start_watcher(plc: PLC, o: RunOptions) -> Watcher | None:
    """--watch (its compilations are daemon threads: nothing to close)."""
    return Watcher(plc, o) if o.watch else None


def start_realtime(stack: ExitStack, o: RunOptions) -> None:
    """--rt: SCHED_FIFO, locked memory, CPU affinity, cpu_dma_latency, as far as they are granted
    (said unless -q); given back by `stack`."""
    if not o.rt:
        return
    rt = RealtimeSetup()
    stack.callback(rt.release)
    granted = rt.apply(o.rt_priority, o.cpu)
    if not o.quiet:
        err("real time: " + ", ".join(f"{k} {v}" for k, v in granted.items()))
