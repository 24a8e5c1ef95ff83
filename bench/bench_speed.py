"""Issue 20's figures from one run: st beside OpenPLC's native build, the engine's cost per job,
the 4-axis EtherCAT simulation's real-time factor, and the test suite's duration.

    python bench/bench_speed.py --matiec DIR [--scans 20000] [--runs 5] [--seconds 10] [--suite]

1. bench_native.py's table: ns per scan of each workload in st and in MatIEC's C (-O0 as OpenPLC
   ships it, and -O2), with the ratios and the checksums.
2. The engine's own cost per job on virtual time: a program whose body is one increment, run for
   200,000 jobs (goal ≤ 1 µs), and that body's call alone.
3. bench_ethercat.py's 4-axis program on the sim backend: scans per wall second at a 1 ms task
   (goal ≥ 10× real time).
4. With --suite: the README's test command (`python -m pytest -q`) timed as a subprocess, and its
   day-to-day subset (`-m "not slow"`).
Never fails: it prints what it measured and exits 0.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE))
import bench_ethercat  # noqa: E402
import bench_native  # noqa: E402

ENGINE_PROGRAM = """PROGRAM main
VAR x : DINT; END_VAR
x := x + 1;
END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK t(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM p WITH t : main;
  END_RESOURCE
END_CONFIGURATION
"""


def engine_cost(jobs: int = 200_000, runs: int = 5) -> tuple[float, float]:
    """(ns per job of the whole engine, ns per call of the body alone), the best of `runs`."""
    from st import PLC
    from st.api import compile_text

    plc = PLC(compile_text(ENGINE_PROGRAM, "engine.st"))
    plc.advance("10ms")
    body = plc.instances["p"][1]._body
    per_job, per_body = [], []
    gc.collect()
    gc.disable()
    try:
        for _ in range(runs):
            t0 = time.perf_counter_ns()
            plc.advance(f"{jobs}ms")
            per_job.append((time.perf_counter_ns() - t0) / jobs)
            t0 = time.perf_counter_ns()
            for _ in range(jobs):
                body()
            per_body.append((time.perf_counter_ns() - t0) / jobs)
    finally:
        gc.enable()
    return min(per_job), min(per_body)


def suite_seconds(args: list[str]) -> tuple[float, str]:
    """Wall seconds of `python -m pytest -q ARGS` in the repository, and its summary line."""
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *args],
        cwd=_HERE.parent,
        capture_output=True,
        text=True,
    )
    tail = [ln for ln in done.stdout.splitlines() if ln.strip()][-1:] or ["(no output)"]
    return time.perf_counter() - t0, tail[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--matiec", type=Path, default=os.environ.get("ST_MATIEC"), help="a built MatIEC (iec2c, lib/)")
    ap.add_argument("--scans", type=int, default=20000)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=10.0, help="PLC time of each 4-axis run")
    ap.add_argument("--suite", action="store_true", help="also time the test suite (minutes)")
    a = ap.parse_args()
    print(f"# st speed, one run: {time.strftime('%Y-%m-%d %H:%M')}, Python {platform.python_version()}, ", end="")
    print(f"{os.cpu_count()} cores, {platform.machine()}\n")

    rows, labels = bench_native.measure(a.matiec, a.scans, a.runs)
    if not labels:
        print("(no MatIEC build (--matiec DIR or ST_MATIEC) or no g++: st's numbers only)\n")
    print(f"## Scans: {a.scans} per run, median of {a.runs}; ns per scan\n")
    print(bench_native.table(rows, labels) + "\n")
    if labels:
        worst = max(row["st"] / row[labels[0]][0] for row in rows)
        print(f"worst ratio to OpenPLC as shipped, Python tier: {worst:.0f}x (goal ≤ 10x)")
        if any(row.get("st --native") for row in rows):
            worst = max(bench_native.best_st(row) / row[labels[0]][0] for row in rows)
            print(f"worst ratio to OpenPLC as shipped, the faster tier per workload: {worst:.0f}x")
        print()

    job, body = engine_cost(runs=a.runs)
    print("## The engine on virtual time (a one-statement program, 200,000 jobs, best of runs)\n")
    print(f"- ns per job: {job:,.0f} (goal ≤ 1,000); the body alone: {body:,.0f}; the engine: {job - body:,.0f}\n")

    rate, final = bench_ethercat.scans_per_second(4, a.seconds, 3)
    print(f"## 4 axes on the emulated EtherCAT segment, 1 ms task, {a.seconds:g} s of PLC time, median of 3\n")
    print(f"- {rate:,.0f} scans/s = {rate / 1000:.1f}x real time (goal ≥ 10x)\n")

    if a.suite:
        print("## The test suite (the README's command)\n")
        for label, extra in (("python -m pytest -q", []), ('python -m pytest -q -m "not slow"', ["-m", "not slow"])):
            secs, summary = suite_seconds(extra)
            print(f"- `{label}`: {secs:.0f} s ({summary})")
        print()


if __name__ == "__main__":
    try:
        main()
    except Exception as exc:  # a benchmark reports, it does not fail
        print(f"bench_speed: error: {type(exc).__name__}: {exc}")
