"""One `st run`: the PLC with its real-time setup, motion, EtherCAT, Modbus, signals, online change
and reports.

Ctrl-C and SIGTERM stop cleanly: the engine stops at a scan boundary, outputs go to their
safe values, retained data is committed. A fault leaves the PLC in FAULT (safe outputs, the
process alive until the run ends) or, with --on-fault restart, restarts it warm.
"""

from __future__ import annotations

import hashlib
import os
import re
import signal
import threading
import time
from pathlib import Path

from ..runtime.faults import PLCFaultError
from ..runtime.lifecycle import FAULT
from ..runtime.plc import PLC
from ..runtime.realtime import RealtimeSetup
from ..runtime.retain import RetainError
from ..runtime.values import parse_duration_arg
from ..stdlib.plcopen import configure_axes
from ..stdlib.plcopen.trace import start_traces
from .options import RunOptions, safe_values, unit_ids
from .output import err
from .params import is_loopback
from .report import report, write_traces
from .status import StatusLine
from .watch import Watcher


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


def run_plc(compiled, o: RunOptions) -> int:
    """Returns the exit code: 0 after a clean stop, 3 when the run ended in FAULT, 2 when it could not
    start (or a file it was asked to write could not be written)."""
    if o.virtual and o.scans is None and o.duration is None:  # (the command line refuses these first)
        err("error: --virtual needs --duration or --scans (virtual time runs as fast as the CPU allows)")
        return 2
    if o.virtual and o.web:
        err("error: --web needs a run in real time (not --virtual)")
        return 2
    retain = retain_path(compiled, o)
    if retain is not None and not o.retain_file:
        folder = Path(retain).parent
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            err(f"error: cannot create the folder for retained data {folder}: {e.strerror or e}")
            return 2
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
        for spec in o.sim_cost:
            if isinstance(spec, tuple):  # (task, ns): checked by the command line
                plc.set_cost(*spec)
            else:
                name, _, cost = spec.partition("=")
                plc.set_cost(name.strip(), cost.strip())
    except RetainError as e:
        err(f"error: {e}")
        return 2
    except (ValueError, KeyError, MemoryError) as e:  # PLCStartError: the reason, located
        err(f"error: cannot start the PLC: {e or type(e).__name__}")
        return 2
    if not plc.instances:
        err("error: nothing to run: no PROGRAM and no CONFIGURATION")
        return 2
    traces = []
    if o.axes or o.trace:
        try:
            if o.axes:
                configure_axes(plc, o.axes)
            traces = start_traces(plc, o.trace)
        except (KeyError, TypeError, ValueError) as e:
            err(f"error: {e.args[0] if e.args else e}")
            plc.close()
            return 2
    ecat = None
    if o.ethercat:  # the I/O packages are imported when used: each costs 0.1-0.2 s of start-up
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
            err(f"error: {e}")
            plc.close()
            return 2
        if not o.quiet:
            err(
                f"ethercat: {len(ecat.master.slaves)} slave(s) in OP ({o.ethercat_backend} backend), "
                f"{len(ecat.links)} drive(s) bound"
            )
    slave = None
    if o.modbus:
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
            ).start()
        except MapError as e:
            err(str(e))
            plc.close()
            return 2
        except (ValueError, OSError) as e:
            err(f"error: cannot start the Modbus slave: {e}")
            plc.close()
            return 2
        if not o.quiet:
            err(
                f"modbus: serving on {host}:{slave.port} (OpenPLC map"
                + (f" + {o.modbus_map}" if o.modbus_map else "")
                + (", read-only" if o.modbus_read_only else "")
                + ")"
            )
        if not is_loopback(host):  # printed even with -q
            err(modbus_warning(host, slave.port, o.modbus_read_only))
    web = None
    if o.web:
        web = _start_web(plc, o)
        if web is None:
            if slave is not None:
                slave.stop()
            plc.close()
            return 2
    if not o.quiet:
        if retain:
            err(f"retained data: {retain} ({'cold start' if o.cold else f'{plc.retain_restored} value(s) restored'})")
        elif o.retain_file and not o.no_retain:
            err("retained data: none (the program has no RETAIN or PERSISTENT variable)")
    stop = threading.Event()
    old_handlers = _install_signals(stop, plc)
    status = None if o.quiet or o.virtual else StatusLine(plc)
    watcher = Watcher(plc, o) if o.watch else None
    rt_setup = None
    code = 0
    try:
        if o.virtual:
            code = _run_virtual(plc, o, stop)
        else:
            if o.rt:
                rt_setup = RealtimeSetup()
                granted = rt_setup.apply(o.rt_priority, o.cpu)
                if not o.quiet:
                    err("real time: " + ", ".join(f"{k} {v}" for k, v in granted.items()))
            if not o.quiet:
                err(f"running in real time: {len(plc.tasks)} task(s), base tick {plc.tick / 1e6:g} ms; Ctrl-C stops")
                if watcher is not None:
                    err(f"watching {len(o.files)} file(s): an edit is compiled and swapped in at a scan boundary")
            code = _run_real(plc, o, stop, status, watcher, web)
    finally:
        if status is not None:
            status.close()
        if web is not None:
            web.stop()
        plc.close()
        if ecat is not None:
            ecat.close()
        if slave is not None:
            slave.stop()
        if rt_setup is not None:
            rt_setup.release()
        _restore_signals(old_handlers)
    written = report(plc, o)
    if traces:
        written = write_traces(traces, o) and written
    return code if written or code else 2


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


class _LogPrinter:
    """Prints the PLC's new log messages (ADSLOGSTR, …) as `[12.5 ms] error: text` on stderr."""

    def __init__(self, plc: PLC):
        self.plc, self.seen = plc, 0

    def __call__(self) -> None:
        log = self.plc.log
        for m in log.since(self.seen):
            err(f"[{m.time / 1e6:g} ms] {m.kind}: {m.text}")
        self.seen = log.total


def _run_virtual(plc: PLC, o: RunOptions, stop) -> int:
    show = _LogPrinter(plc)
    try:
        end = plc.time + (o.scans * plc.tick if o.scans is not None else parse_duration_arg(o.duration))
        while plc.time < end and not stop.is_set():
            try:
                plc.advance(min(end - plc.time, 1_000_000_000))
                show()
            except PLCFaultError as e:
                show()
                err(str(e.fault))
                if o.on_fault == "restart" and not stop.is_set() and _restart(plc):
                    continue
                return 3
    except KeyboardInterrupt:
        pass
    return 3 if plc.state == FAULT else 0


def _start_web(plc: PLC, o: RunOptions):
    """The online mode's server (st/web), its URL with the token printed; None when it cannot start."""
    import secrets

    from ..io.modbus import parse_endpoint
    from ..web.link import WebLink

    try:
        host, port = parse_endpoint(o.web or "")
        token = secrets.token_urlsafe(18)
        name = ", ".join(Path(f).name for f in o.files)
        web = WebLink(plc, name, host, port, token, o.web_password or "", o.web_read_only).start()
    except (ValueError, OSError) as e:
        err(f"error: cannot start the web server: {e}")
        return None
    shown = f"[{host}]" if ":" in host else host
    err(
        f"web: http://{shown}:{web.port}/?token={token}"
        + (" (read-only)" if o.web_read_only else "")
        + ("" if is_loopback(host) else "  -- listening beyond this machine")
    )
    return web


def _run_real(plc: PLC, o: RunOptions, stop, status, watcher, web=None) -> int:
    end_time = None
    if o.duration is not None:
        end_time = plc.time + parse_duration_arg(o.duration)
    if o.scans is not None:
        t = plc.time + o.scans * plc.tick
        end_time = t if end_time is None else min(end_time, t)

    show = _LogPrinter(plc)

    def on_idle(p):
        if plc.log.total != show.seen:
            if status is not None:
                status.clear()
            show()
        if status is not None:
            status.update()
        if watcher is not None:
            watcher.poll()
        if web is not None:
            web.poll()

    while not stop.is_set():
        remaining = None if end_time is None else end_time - plc.time
        if remaining is not None and remaining <= 0:
            break
        try:
            if plc.state == FAULT:  # stay alive with safe outputs until the run ends (or a reset)
                if not _sleep_while_faulted(plc, stop, remaining, on_idle):
                    break
                continue
            plc.run_realtime(duration=remaining, on_idle=on_idle, stop=stop)
        except PLCFaultError as e:
            if status is not None:
                status.clear()
            err(str(e.fault))
            if o.on_fault == "restart" and not stop.is_set():
                _restart(plc)
            continue
        except KeyboardInterrupt:
            break
    return 3 if plc.state == FAULT else 0


def _restart(plc: PLC) -> bool:
    """--on-fault restart; a program whose instances fault again while being created stays in FAULT."""
    try:
        plc.restart()
    except PLCFaultError as e:
        err(f"restart failed: {e.fault}")
        return False
    err("restarted (warm)")
    return True


def _sleep_while_faulted(plc, stop, remaining, on_idle) -> bool:
    """Until the run ends (False), or the PLC leaves FAULT (True: a reset from the web page)."""
    t0 = time.monotonic()
    while not stop.is_set() and (remaining is None or (time.monotonic() - t0) * 1e9 < remaining):
        on_idle(plc)
        if plc.state != FAULT:
            return True
        time.sleep(0.05)
    return False


def _install_signals(stop: threading.Event, plc: PLC):
    """Ctrl-C and SIGTERM stop the PLC at the next scan boundary; a job still running is ended by its
    watchdog (so within one watchdog period), or at once when the signal comes a second time."""

    def handler(signum, frame):
        stop.set()
        plc.request_stop(signal.Signals(signum).name)

    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            old[sig] = signal.signal(sig, handler)
        except ValueError:  # not the main thread
            pass
    return old


def _restore_signals(old: dict) -> None:
    for sig, h in old.items():
        signal.signal(sig, h)
