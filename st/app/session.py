"""One `st run`: its parts (the PLC, motion, EtherCAT, Modbus, the web server, signals, real time,
online change: subsystems.py) started in order on ExitStacks, the run loops, the report.

Ctrl-C and SIGTERM stop cleanly: the engine stops at a scan boundary, outputs go to their
safe values, retained data is committed. A fault leaves the PLC in FAULT (safe outputs, the
process alive until the run ends) or, with --on-fault restart, restarts it warm.
"""

from __future__ import annotations

import threading
import time
from contextlib import ExitStack

from ..runtime.faults import PLCFaultError
from ..runtime.lifecycle import FAULT
from ..runtime.plc import PLC
from ..runtime.values import parse_duration_arg
from .native_upgrade import start_native_upgrade
from .options import RunOptions
from .output import err
from .report import report, write_traces
from .subsystems import (
    StartRefused,
    check_options,
    default_retain_path,
    install_signals,
    modbus_warning,
    retain_folder,
    retain_path,
    say_retained,
    start_ethercat,
    start_modbus,
    start_motion,
    start_opcua,
    start_plc,
    start_realtime,
    start_status,
    start_watcher,
    start_web,
)

__all__ = ["run_plc", "default_retain_path", "retain_path", "modbus_warning"]


def run_plc(compiled, o: RunOptions) -> int:
    """Returns the exit code: 0 after a clean stop, 3 when the run ended in FAULT, 2 when it could not
    start (or a file it was asked to write could not be written).

    The run's parts (subsystems.py) start in this order and register their clean-up on three
    stacks, which close in this order, whatever ends the run (its end, a part that cannot start, an
    exception, Ctrl-C while starting):
      `front`    the status line, the web server, then the PLC (outputs safe, retained data committed)
      `drivers`  the Modbus slave, EtherCAT: after the PLC, whose last safe outputs go out through them
      `process`  real time, then the signal handlers: last, so Ctrl-C cannot cut the clean-up short
    """
    try:
        check_options(o)
        retain = retain_folder(compiled, o)
    except StartRefused as e:
        err(str(e))
        return 2
    with ExitStack() as process, ExitStack() as drivers, ExitStack() as front:
        try:
            plc = start_plc(front, compiled, o, retain)
            traces = start_motion(plc, o)
            start_ethercat(drivers, plc, o)
            start_modbus(drivers, plc, o)
            opcua = start_opcua(drivers, plc, o)
            web = start_web(front, plc, o)
        except StartRefused as e:
            err(str(e))
            return 2
        say_retained(plc, o, retain)
        stop = threading.Event()
        install_signals(process, stop, plc)
        status = start_status(front, plc, o)
        watcher = start_watcher(plc, o)
        upgrade = start_native_upgrade(front, plc, o)
        if o.virtual:
            code = _run_virtual(plc, o, stop, opcua)
        else:
            start_realtime(process, o)
            if not o.quiet:
                err(f"running in real time: {len(plc.tasks)} task(s), base tick {plc.tick / 1e6:g} ms; Ctrl-C stops")
                if watcher is not None:
                    err(f"watching {len(o.files)} file(s): an edit is compiled and swapped in at a scan boundary")
            code = _run_real(plc, o, stop, status, watcher, web, upgrade, opcua)
    written = report(plc, o)
    if traces:
        written = write_traces(traces, o) and written
    return code if written or code else 2


class _LogPrinter:
    """Prints the PLC's new log messages (ADSLOGSTR, …) as `[12.5 ms] error: text` on stderr."""

    def __init__(self, plc: PLC):
        self.plc, self.seen = plc, 0

    def __call__(self) -> None:
        log = self.plc.log
        for m in log.since(self.seen):
            err(f"[{m.time / 1e6:g} ms] {m.kind}: {m.text}")
        self.seen = log.total


def _run_virtual(plc: PLC, o: RunOptions, stop, opcua=None) -> int:
    show = _LogPrinter(plc)
    try:
        end = plc.time + (o.scans * plc.tick if o.scans is not None else parse_duration_arg(o.duration))
        while plc.time < end and not stop.is_set():
            try:
                plc.advance(min(end - plc.time, 1_000_000_000))
                if opcua is not None:
                    opcua.poll()
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


def _run_real(plc: PLC, o: RunOptions, stop, status, watcher, web=None, upgrade=None, opcua=None) -> int:
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
        if upgrade is not None:
            upgrade.poll()
        if web is not None:
            web.poll()
        if opcua is not None:
            opcua.poll()

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
