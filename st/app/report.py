"""What `st run` leaves behind when it ends: statistics (JSON, plot, summary), variables, axis traces."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from ..runtime.plc import PLC
from ..runtime.stats import plot_latency
from ..stdlib.plcopen import trace
from .options import RunOptions
from .output import err


def report(plc: PLC, o: RunOptions) -> bool:
    """Write what the run was asked for; False when a file (or the standard output) could not be
    written, each failure said as `error: --option FILE: why`."""
    ok = True
    stats = plc.stats()
    if o.stats_json:
        doc = {
            "policy": plc.policy_name,
            "clock": "virtual" if o.virtual else "real",
            "plc_time_s": plc.time / 1e9,
            "state": plc.state,
            "faults": [str(x) for x in plc.faults],
            "tasks": stats,
            "io": io_stats(plc),
        }
        try:
            with open(o.stats_json, "w") as f:
                json.dump(doc, f, indent=1)
        except OSError as e:
            ok = _cannot_write("--stats-json", o.stats_json, e)
    if o.stats_plot:
        try:
            plot_latency([t.stats for t in plc.tasks], o.stats_plot)
        except RuntimeError as e:
            err(f"error: {e}")
            ok = False
        except OSError as e:
            ok = _cannot_write("--stats-plot", o.stats_plot, e)
    if o.dump_json:
        ok = _print_stdout(json.dumps(plc.variables(all=o.dump_all))) and ok
    if not o.quiet:
        err(f"stopped at PLC time {plc.time / 1e9:g} s, state {plc.state}")
        for d in plc.io:
            if d.name == "ethercat":
                c = d.stats()
                if c is None:
                    continue
                err(
                    f"  ethercat: {c['frames']} frames, {c['lost_frames']} lost, {c['wkc_errors']} working-counter "
                    f"errors, {c['outages']} outage(s)"
                )
        if not o.virtual:
            for s in stats:
                lat, ex = s["latency_us"], s["exec_us"]
                err(
                    f"  task {s['task']}: {s['jobs']} jobs, {s['overruns']} overruns, {s['skipped']} skipped; "
                    f"latency µs min {lat['min']:g} avg {lat['avg']:g} p99 {lat['p99']:g} p99.9 {lat['p99.9']:g} "
                    f"max {lat['max']:g}; exec µs avg {ex['avg']:g} max {ex['max']:g}"
                )
    return ok


def io_stats(plc: PLC) -> dict:
    """The counters of the named drivers that keep some."""
    out = {}
    for d in plc.io:
        s = d.stats() if d.name else None
        if s is not None:
            out[d.name] = s
    return out


def _cannot_write(option: str, path: str, e: OSError) -> bool:
    err(f"error: {option} {path}: cannot be written ({(e.strerror or str(e)).lower()})")
    return False


def _print_stdout(text: str) -> bool:
    """--dump-json's output; a standard output that cannot take it (a full disk, a closed pipe) is an
    error line, and the rest of the output is dropped rather than failing again at exit."""
    try:
        sys.stdout.write(text + "\n")
        sys.stdout.flush()
        return True
    except OSError as e:
        err(f"error: --dump-json: cannot write to the standard output ({(e.strerror or str(e)).lower()})")
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            os.close(devnull)
        except (OSError, ValueError):
            pass
        return False


def trace_csv_path(plot: str | None) -> str:
    """Where the trace's CSV goes without --trace-csv: beside the plot, else trace.csv here."""
    return str(Path(plot).with_suffix(".csv")) if plot else "trace.csv"


def write_traces(traces: list, o: RunOptions) -> bool:
    """Write the traces (CSV, and the plot); False when a file could not be written."""
    csv_path = o.trace_csv or trace_csv_path(o.trace_plot)
    try:
        trace.write_csv(traces, csv_path)
    except OSError as e:
        return _cannot_write("--trace-csv", csv_path, e)
    if not o.quiet:
        err(f"trace: {sum(len(t.rows) for t in traces)} samples of {', '.join(t.path for t in traces)} → {csv_path}")
    if o.trace_plot:
        try:
            trace.plot(traces, o.trace_plot, title=", ".join(Path(f).name for f in o.files))
        except RuntimeError as e:
            err(f"error: {e}")
            return False
        except OSError as e:
            return _cannot_write("--trace-plot", o.trace_plot, e)
    return True
