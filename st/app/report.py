"""What `st run` leaves behind when it ends: statistics (JSON, plot, summary), variables, axis traces."""

from __future__ import annotations

import json
from pathlib import Path

from ..runtime.plc import PLC
from ..runtime.stats import plot_latency
from ..stdlib.plcopen import trace
from .options import RunOptions
from .output import err


def report(plc: PLC, o: RunOptions) -> None:
    stats = plc.stats()
    if o.stats_json:
        with open(o.stats_json, "w") as f:
            json.dump(
                {
                    "policy": plc.policy_name,
                    "clock": "virtual" if o.virtual else "real",
                    "plc_time_s": plc.time / 1e9,
                    "state": plc.state,
                    "faults": [str(x) for x in plc.faults],
                    "tasks": stats,
                    "io": io_stats(plc),
                },
                f,
                indent=1,
            )
    if o.stats_plot:
        try:
            plot_latency([t.stats for t in plc.tasks], o.stats_plot)
        except RuntimeError as e:
            err(f"error: {e}")
    if o.dump_json:
        print(json.dumps(plc.variables()))
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


def io_stats(plc: PLC) -> dict:
    """The counters of the named drivers that keep some."""
    out = {}
    for d in plc.io:
        s = d.stats() if d.name else None
        if s is not None:
            out[d.name] = s
    return out


def write_traces(traces: list, o: RunOptions) -> None:
    csv_path = o.trace_csv or (str(Path(o.trace_plot).with_suffix(".csv")) if o.trace_plot else "trace.csv")
    trace.write_csv(traces, csv_path)
    if not o.quiet:
        err(f"trace: {sum(len(t.rows) for t in traces)} samples of {', '.join(t.path for t in traces)} → {csv_path}")
    if o.trace_plot:
        try:
            trace.plot(traces, o.trace_plot, title=", ".join(Path(f).name for f in o.files))
        except RuntimeError as e:
            err(f"error: {e}")
