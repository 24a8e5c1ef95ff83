"""Wake-up latency of `st run` beside cyclictest's, at 1 ms and 4 ms, idle and under stress-ng load.

For each load and cycle time, in the same window: cyclictest (rt-tests: SCHED_FIFO, mlockall,
cpu_dma_latency 0) for N seconds, then `st run` of an example program with its task's interval set
to the cycle, at the same SCHED_FIFO priority, for N seconds. Prints min/avg/p99/p99.9/max wake-up
latency of both, the ratios st / cyclictest, overruns and st's CPU use (the sleep-then-spin
costs a share of a core).

The two count a stall differently: cyclictest records one (long) sample and skips the periods it
missed (shown as its overruns: expected minus recorded wake-ups); `st run`'s default `openplc`
policy runs every missed release late, back to back, and records each one's latency, so a 10 ms
stall at 1 ms adds ten samples between 10 and 1 ms. Under load that moves st's p99, not its max. Needs root for SCHED_FIFO (without it both run as SCHED_OTHER and the
numbers say so) and the Debian packages rt-tests and stress-ng.

The measuring code lives in st/experiments/latency.py (`st experiment latency` runs the thesis's
1/2/3/10-axis tables with it); `cpu` is the share of one core while scanning, start-up excluded.

    python bench/bench_latency.py                      # 1 ms and 4 ms, idle and loaded, 20 s each (~3 min)
    python bench/bench_latency.py --seconds 60 --cycles 1ms --loads idle
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from st.experiments.latency import run_cyclictest, run_st, start_load  # noqa: E402


def fmt(r: dict) -> str:
    return " ".join(f"{r[k]:>8.1f}" for k in ("min", "avg", "p99", "p99.9", "max"))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=int, default=20)
    ap.add_argument("--cycles", default="1ms,4ms")
    ap.add_argument("--loads", default="idle,stress")
    ap.add_argument("--priority", type=int, default=80)
    ap.add_argument("--program", default=str(ROOT / "programs" / "conveyor_sorter.st"))
    ap.add_argument("--json", help="also write the results here")
    a = ap.parse_args()
    missing = [t for t in ("cyclictest", "stress-ng") if shutil.which(t) is None]
    if missing:
        print(f"needs {' and '.join(missing)} (Debian: apt-get install rt-tests stress-ng)")
        return 0
    prio = a.priority if os.geteuid() == 0 else 0
    print(
        f"st run vs cyclictest, {a.seconds} s per run, {'SCHED_FIFO ' + str(prio) if prio else 'SCHED_OTHER (not root)'}, "
        f"{os.cpu_count()} CPUs, program {Path(a.program).name}; latency in µs"
    )
    print(
        f"{'load':6} {'cycle':5} {'tool':10} {'min':>8} {'avg':>8} {'p99':>8} {'p99.9':>8} {'max':>8}  "
        f"{'samples':>7} {'overruns':>8} {'cpu':>5}"
    )
    results = []
    for load in a.loads.split(","):
        stress = start_load() if load == "stress" else None
        try:
            if stress is not None:
                time.sleep(2)
            for cycle in a.cycles.split(","):
                us = int(float(cycle.removesuffix("ms")) * 1000)
                ct = run_cyclictest(us, a.seconds, prio)
                st = run_st(Path(a.program), a.seconds, prio, cycle=cycle)
                print(f"{load:6} {cycle:5} {'cyclictest':10} {fmt(ct)}  {ct['samples']:>7} {ct['overruns']:>8}")
                print(
                    f"{'':6} {'':5} {'st run':10} {fmt(st)}  {st['samples']:>7} {st['overruns']:>8} "
                    f"{st['cpu'] * 100:>4.0f}%"
                )
                ratio = {k: (st[k] / ct[k] if ct[k] else float("inf")) for k in ("p99", "p99.9", "max")}
                print(
                    f"{'':6} {'':5} {'ratio':10} {'':>8} {'':>8} {ratio['p99']:>8.2f} {ratio['p99.9']:>8.2f} "
                    f"{ratio['max']:>8.2f}   (goal: p99.9 ratio ≤ 2; exec avg {st['exec_avg']:.0f} µs)"
                )
                results.append({"load": load, "cycle": cycle, "cyclictest": ct, "st": st, "ratio": ratio})
        finally:
            if stress is not None:
                stress.terminate()
                stress.wait()
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
