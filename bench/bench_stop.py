"""What stops a runaway job, and how fast; what the loop guard costs.

1. `st run` of a program whose sixth scan never ends (a FOR over 2e9), real time, 10 ms cycle:
   the time from a signal to the process's exit, for SIGTERM and SIGINT with --watchdog 2s and
   5s (the job ends when its budget is spent: at most one watchdog period), and for a second
   signal 0.3 s after the first (the job is ended at once); and SIGTERM to a healthy program
   (the engine stops at the next scan boundary).
2. ns per iteration of an ST FOR loop with the watchdog guard and with the guard removed.

    python bench/bench_stop.py [--runs 3]
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

RUNAWAY = """PROGRAM main
VAR n : DINT; i : DINT; x : DINT; END_VAR
VAR RETAIN kept : DINT; END_VAR
n := n + 1;
kept := n;
IF n > 5 THEN
  FOR i := 0 TO 2000000000 DO x := x + 1; END_FOR;
END_IF;
END_PROGRAM
"""

HEALTHY = """PROGRAM main
VAR n : DINT; END_VAR
n := n + 1;
END_PROGRAM
"""


def _stop_latency(src: str, watchdog: str, sig: signal.Signals, twice: bool) -> float:
    with tempfile.TemporaryDirectory() as d:
        prog = Path(d) / "p.st"
        prog.write_text(src)
        child = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "st.cli",
                "run",
                str(prog),
                "--no-rt",
                "--cycle",
                "10ms",
                "--watchdog",
                watchdog,
                "--retain",
                str(Path(d) / "r.db"),
                "--duration",
                "600s",
                "-q",
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            cwd=ROOT,
        )
        time.sleep(2.0)  # start-up, then the runaway scan is under way
        t0 = time.perf_counter()
        child.send_signal(sig)
        if twice:
            time.sleep(0.3)
            child.send_signal(sig)
        rc = child.wait(timeout=120)
        took = time.perf_counter() - t0
        if rc not in (0, 3):
            raise SystemExit(f"st run exited with {rc}: the benchmark's program did not run")
        return took


def _loop_ns(guarded: bool, n: int = 2_000_000) -> float:
    from st import PLC
    from st.compiler.lower import loops

    src = f"PROGRAM main\nVAR i, x : DINT; END_VAR\nFOR i := 1 TO {n} DO x := x + i MOD 7; END_FOR;\nEND_PROGRAM\n"
    saved = loops.guard_loops
    if not guarded:
        loops.guard_loops = lambda body: None
    try:
        plc = PLC.from_source(src, name=f"loop_{guarded}.st", use_cache=False, watchdog="60s")
    finally:
        loops.guard_loops = saved
    best = float("inf")
    for _ in range(5):
        t = time.perf_counter()
        plc.scan()
        best = min(best, time.perf_counter() - t)
    return best / n * 1e9


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    print("signal to exit, `st run` at 10 ms with a job that never ends (median of", args.runs, "runs):")
    for wd in ("2s", "5s"):
        for sig in (signal.SIGTERM, signal.SIGINT):
            ts = [_stop_latency(RUNAWAY, wd, sig, False) for _ in range(args.runs)]
            print(f"  --watchdog {wd:>3}  {sig.name:<7}  {statistics.median(ts):6.2f} s  (max {max(ts):.2f} s)")
    ts = [_stop_latency(RUNAWAY, "120s", signal.SIGTERM, True) for _ in range(args.runs)]
    print(f"  --watchdog 120s  SIGTERM twice (0.3 s apart): {statistics.median(ts):.2f} s after the first")
    ts = [_stop_latency(HEALTHY, "100ms", signal.SIGTERM, False) for _ in range(args.runs)]
    print(f"  a healthy program, SIGTERM: {statistics.median(ts) * 1e3:.0f} ms (process exit included)")
    g, u = _loop_ns(True), _loop_ns(False)
    print(
        f"FOR loop iteration (x := x + i MOD 7): {g:.1f} ns guarded, {u:.1f} ns without the guard "
        f"(+{g - u:.1f} ns, {g / u:.2f}x)"
    )


if __name__ == "__main__":
    os.environ.setdefault("ST_NO_CACHE", "1")
    main()
