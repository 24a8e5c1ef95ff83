"""One `st run`: the PLC with its real-time setup, live status, signals, online change and reports.

Ctrl-C and SIGTERM stop cleanly: the engine stops at a scan boundary, outputs go to their
safe values, retained data is committed. A fault leaves the PLC in FAULT (safe outputs, the
process alive until the run ends) or, with --on-fault restart, restarts it warm.
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from .plc import FAULT, PLC, OnlineChangeRefused, PLCFaultError
from .values import parse_duration_arg


@dataclass
class RunOptions:
    files: list = field(default_factory=list)
    scans: Optional[int] = None
    duration: Optional[str] = None
    cycle: Optional[str] = None
    virtual: bool = False
    policy: str = "openplc"
    dump_json: bool = False
    stats_json: Optional[str] = None
    stats_plot: Optional[str] = None
    on_fault: str = "stop"
    watchdog: Optional[str] = None
    retain_file: Optional[str] = None
    no_retain: bool = False
    retain_interval: str = "1s"
    cold: bool = False
    watch: bool = False
    rt: bool = True
    rt_priority: int = 30
    cpu: Optional[int] = None
    sim_cost: list = field(default_factory=list)
    safe_outputs: list = field(default_factory=list)      # ["%QX0.1=TRUE", "%QW3=100"]
    modbus: Optional[str] = None                          # "[HOST:]PORT"
    modbus_map: Optional[str] = None
    modbus_read_only: bool = False
    modbus_writable: Optional[str] = None
    modbus_max_connections: int = 16
    modbus_idle_timeout: float = 60.0
    modbus_rate: float = 1000.0
    modbus_unit_ids: Optional[str] = None
    axes: Optional[str] = None                            # axis configuration (TOML)
    trace: list = field(default_factory=list)             # AXIS_REF paths
    trace_plot: Optional[str] = None
    trace_csv: Optional[str] = None
    ethercat: Optional[str] = None                        # segment configuration (TOML)
    ethercat_backend: str = "sim"
    ethercat_iface: Optional[str] = None
    ethercat_capture: Optional[str] = None
    quiet: bool = False
    time_unit: str = "ms"
    f_trig_first_scan: bool = False
    compiled_mtimes: Optional[dict] = None                # the sources as compiled (see --watch)


def _err(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _has_retained(compiled) -> bool:
    p = compiled.project
    return any(v.retain or v.persistent for pou in p.pous.values() if not pou.library for v in pou.vars.values()) \
        or any(g.retain or g.persistent for g in p.globals.values())


def run_plc(compiled, o: RunOptions) -> int:
    """Returns the exit code: 0 after a clean stop, 3 when the run ended in FAULT, 2 when it could not start."""
    retain = None
    if not o.no_retain and (o.retain_file or _has_retained(compiled)):
        retain = o.retain_file or str(Path(o.files[0]).with_suffix(".retain.db"))
    try:
        plc = PLC(compiled, o.cycle, watchdog=o.watchdog, policy=o.policy, retain=retain,
                  retain_interval=o.retain_interval, cold=o.cold, safe_outputs=_safe_values(o.safe_outputs))
        for spec in o.sim_cost:
            name, _, cost = spec.partition("=")
            plc.set_cost(name.strip(), cost.strip())
    except (ValueError, KeyError, MemoryError) as e:     # PLCStartError: the reason, located
        _err(f"error: cannot start the PLC: {e or type(e).__name__}")
        return 2
    if not plc.instances:
        _err("error: nothing to run: no PROGRAM and no CONFIGURATION")
        return 2
    traces = []
    if o.axes or o.trace:
        from ..stdlib.plcopen import configure_axes
        from ..stdlib.plcopen.trace import start_traces
        try:
            if o.axes:
                configure_axes(plc, o.axes)
            traces = start_traces(plc, o.trace)
        except (KeyError, TypeError, ValueError) as e:
            _err(f"error: {e.args[0] if e.args else e}")
            plc.close()
            return 2
    ecat = None
    if o.ethercat:
        from ..io.ethercat import ConfigError, EtherCATDriver, MasterError, load_segment
        try:
            ecat = EtherCATDriver(plc, load_segment(o.ethercat), backend=o.ethercat_backend,
                                  iface=o.ethercat_iface or "", capture=o.ethercat_capture or "")
        except (ConfigError, MasterError) as e:
            _err(f"error: {e}")
            plc.close()
            return 2
        if not o.quiet:
            _err(f"ethercat: {len(ecat.master.slaves)} slave(s) in OP ({o.ethercat_backend} backend), "
                 f"{len(ecat.links)} drive(s) bound")
    slave = None
    if o.modbus:
        from ..io.modbus import MapError, ModbusSlave, parse_endpoint
        try:
            host, port = parse_endpoint(o.modbus)
            units = None if not o.modbus_unit_ids else [int(u) for u in o.modbus_unit_ids.split(",")]
            slave = ModbusSlave(plc, host, port, map_file=o.modbus_map, read_only=o.modbus_read_only,
                                writable=o.modbus_writable, max_connections=o.modbus_max_connections,
                                idle_timeout=o.modbus_idle_timeout, max_rate=o.modbus_rate, unit_ids=units).start()
        except MapError as e:
            _err(str(e))
            plc.close()
            return 2
        except (ValueError, OSError) as e:
            _err(f"error: cannot start the Modbus slave: {e}")
            plc.close()
            return 2
        if not o.quiet:
            _err(f"modbus: serving on {host}:{slave.port} (OpenPLC map" +
                 (f" + {o.modbus_map}" if o.modbus_map else "") + (", read-only" if o.modbus_read_only else "") + ")")
    if retain and not o.quiet:
        _err(f"retained data: {retain} ({'cold start' if o.cold else f'{plc.retain_restored} value(s) restored'})")
    stop = threading.Event()
    old_handlers = _install_signals(stop, plc)
    status = None if o.quiet or o.virtual else _Status(plc)
    watcher = _Watcher(plc, o) if o.watch else None
    rt_setup = None
    code = 0
    try:
        if o.virtual:
            code = _run_virtual(plc, o, stop)
        else:
            if o.rt:
                from .realtime import RealtimeSetup
                rt_setup = RealtimeSetup()
                granted = rt_setup.apply(o.rt_priority, o.cpu)
                if not o.quiet:
                    _err("real time: " + ", ".join(f"{k} {v}" for k, v in granted.items()))
            code = _run_real(plc, o, stop, status, watcher)
    finally:
        if status is not None:
            status.close()
        plc.close()
        if ecat is not None:
            ecat.close()
        if slave is not None:
            slave.stop()
        if rt_setup is not None:
            rt_setup.release()
        _restore_signals(old_handlers)
    _report(plc, o)
    if traces:
        _write_traces(traces, o)
    return code


def _write_traces(traces: list, o: RunOptions) -> None:
    from ..stdlib.plcopen import trace
    csv_path = o.trace_csv or (str(Path(o.trace_plot).with_suffix(".csv")) if o.trace_plot else "trace.csv")
    trace.write_csv(traces, csv_path)
    if not o.quiet:
        _err(f"trace: {sum(len(t.rows) for t in traces)} samples of {', '.join(t.path for t in traces)} → {csv_path}")
    if o.trace_plot:
        try:
            trace.plot(traces, o.trace_plot, title=", ".join(Path(f).name for f in o.files))
        except RuntimeError as e:
            _err(f"error: {e}")


def _safe_values(specs: list) -> dict:
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


def _run_virtual(plc: PLC, o: RunOptions, stop) -> int:
    try:
        if o.scans is None and o.duration is None:
            _err("--virtual needs --scans or --duration")
            return 2
        end = plc.time + (o.scans * plc.tick if o.scans is not None else parse_duration_arg(o.duration))
        while plc.time < end and not stop.is_set():
            try:
                plc.advance(min(end - plc.time, 1_000_000_000))
            except PLCFaultError as e:
                _err(str(e.fault))
                if o.on_fault == "restart" and not stop.is_set() and _restart(plc):
                    continue
                return 3
    except KeyboardInterrupt:
        pass
    return 3 if plc.state == FAULT else 0


def _run_real(plc: PLC, o: RunOptions, stop, status, watcher) -> int:
    end_time = None
    if o.duration is not None:
        end_time = plc.time + parse_duration_arg(o.duration)
    if o.scans is not None:
        t = plc.time + o.scans * plc.tick
        end_time = t if end_time is None else min(end_time, t)

    def on_idle(p):
        if status is not None:
            status.update()
        if watcher is not None:
            watcher.poll()

    while not stop.is_set():
        remaining = None if end_time is None else end_time - plc.time
        if remaining is not None and remaining <= 0:
            break
        try:
            if plc.state == FAULT:      # stay alive with safe outputs until the run ends
                _sleep_while_faulted(plc, stop, remaining, on_idle)
                break
            plc.run_realtime(duration=remaining, on_idle=on_idle, stop=stop)
        except PLCFaultError as e:
            if status is not None:
                status.clear()
            _err(str(e.fault))
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
        _err(f"restart failed: {e.fault}")
        return False
    _err("restarted (warm)")
    return True


def _sleep_while_faulted(plc, stop, remaining, on_idle) -> None:
    t0 = time.monotonic()
    while not stop.is_set() and (remaining is None or (time.monotonic() - t0) * 1e9 < remaining):
        on_idle(plc)
        time.sleep(0.1)


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
        except ValueError:         # not the main thread
            pass
    return old


def _restore_signals(old: dict) -> None:
    for sig, h in old.items():
        signal.signal(sig, h)


def _report(plc: PLC, o: RunOptions) -> None:
    stats = plc.stats()
    if o.stats_json:
        with open(o.stats_json, "w") as f:
            json.dump({"policy": plc.policy_name, "clock": "virtual" if o.virtual else "real",
                       "plc_time_s": plc.time / 1e9, "state": plc.state,
                       "faults": [str(x) for x in plc.faults], "tasks": stats,
                       "io": _io_stats(plc)},
                      f, indent=1)
    if o.stats_plot:
        from .stats import plot_latency
        try:
            plot_latency([t.stats for t in plc.tasks], o.stats_plot)
        except RuntimeError as e:
            _err(f"error: {e}")
    if o.dump_json:
        print(json.dumps(plc.variables()))
    if not o.quiet:
        _err(f"stopped at PLC time {plc.time / 1e9:g} s, state {plc.state}")
        for d in plc.io:
            if d.name == "ethercat":
                c = d.stats()
                _err(f"  ethercat: {c['frames']} frames, {c['lost_frames']} lost, {c['wkc_errors']} working-counter "
                     f"errors, {c['outages']} outage(s)")
        if not o.virtual:
            for s in stats:
                lat, ex = s["latency_us"], s["exec_us"]
                _err(f"  task {s['task']}: {s['jobs']} jobs, {s['overruns']} overruns, {s['skipped']} skipped; "
                     f"latency µs min {lat['min']:g} avg {lat['avg']:g} p99 {lat['p99']:g} p99.9 {lat['p99.9']:g} "
                     f"max {lat['max']:g}; exec µs avg {ex['avg']:g} max {ex['max']:g}")


def _io_stats(plc: PLC) -> dict:
    """The counters of the named drivers that keep some."""
    out = {}
    for d in plc.io:
        s = d.stats() if d.name else None
        if s is not None:
            out[d.name] = s
    return out


class _Status:
    """The live status line on a terminal: state, PLC time and each task's jobs, latency, execution
    time and overruns, styled with rich. It is drawn from idle time only, at most 4 times a second
    and only when the next release is more than 1 ms away (a line costs about 0.15 ms to render)."""

    def __init__(self, plc: PLC):
        self.plc = plc
        self.tty = sys.stderr.isatty()
        self.last = 0.0
        if self.tty:                  # import and warm up before the first scan, not inside one's slack
            self.text()

    def text(self):
        from rich.text import Text
        p = self.plc
        colour = {"RUN": "bold green", "STOP": "bold yellow"}.get(p.state, "bold red")
        out = Text.assemble((p.state, colour), f" t={p.time / 1e9:.1f}s")
        for t in p.tasks:
            s = t.stats
            avg = s.exec_sum / s.jobs / 1e3 if s.jobs else 0
            late = s.overruns + s.skipped
            out.append(f" | {t.name} {s.jobs} jobs, latency max {s.lat_max / 1e3:.0f} µs, exec {avg:.0f} µs, ")
            out.append(f"{late} overruns", style="red" if late else "")
        return out

    def update(self) -> None:
        now = time.monotonic()
        if not self.tty or now - self.last < 0.25 or self.plc.idle_slack < 1_000_000:
            return
        self.last = now
        import io
        from rich.console import Console
        width = shutil.get_terminal_size((120, 24)).columns or 120
        buf = io.StringIO()
        console = Console(file=buf, force_terminal=True, width=width)
        line = self.text()
        line.truncate(width - 1)
        console.print(line, end="", no_wrap=True, overflow="crop")
        sys.stderr.write("\r" + buf.getvalue() + "\x1b[K")
        sys.stderr.flush()

    def clear(self) -> None:
        if self.tty:
            sys.stderr.write("\r\n")
            sys.stderr.flush()

    def close(self) -> None:
        self.clear()


def source_mtimes(files) -> dict:
    """Modification times of the source files; an edit made while the PLC starts is not missed when
    these are taken before compiling."""
    out = {}
    for f in files:
        try:
            out[f] = os.stat(f).st_mtime_ns
        except OSError:
            out[f] = None
    return out


class _Watcher:
    """--watch: when a source changes, compile it and build the new program (namespace, instances,
    FB_init) in a background thread while the old one keeps scanning; carry the state over and swap
    at a scan boundary. Whatever fails leaves the old program running and says why."""

    def __init__(self, plc: PLC, o: RunOptions):
        self.plc = plc
        self.o = o
        self.mtimes = o.compiled_mtimes if o.compiled_mtimes is not None else source_mtimes(o.files)
        self.last_poll = 0.0
        self.result = None
        self.busy = False

    def poll(self) -> None:
        if self.result is not None:
            prepared, self.result = self.result, None
            self._swap(prepared)
        now = time.monotonic()
        if self.busy or now - self.last_poll < 0.5:
            return
        self.last_poll = now
        m = source_mtimes(self.o.files)
        if m != self.mtimes:
            self.mtimes = m
            self.busy = True
            threading.Thread(target=self._prepare, daemon=True).start()

    def _prepare(self) -> None:
        from ..api import compile_paths
        from ..diagnostics import CompileError
        try:
            compiled = compile_paths(self.o.files, time_unit=self.o.time_unit,
                                     f_trig_first_scan=self.o.f_trig_first_scan)
            self.result = self.plc.prepare_change(compiled)
        except CompileError as e:
            _err("\nonline change refused, the old program keeps running:\n" + e.render())
        except OnlineChangeRefused as e:
            _err(f"\n{e}")
        except Exception as e:  # noqa: BLE001 - an edit must never take the PLC down
            _err(f"\nonline change refused, the old program keeps running:\n  {type(e).__name__}: {e}")
        finally:
            self.busy = False

    def _swap(self, prepared) -> None:
        try:
            _err("\n" + self.plc.apply_change(prepared))
        except OnlineChangeRefused as e:
            _err(f"\n{e}")
