"""The thesis's scheduling simulation (ch. 6.3, Table 6.5) on st's engine: three device tasks at
1×, 2× and 4× a 10 ms minimum period, overloaded, on virtual time.

    python bench/bench_policies.py [--runs 1000] [--seconds 6] [--costs 4,6,14] [--jitter 0.2]

Each task runs a small ST program (a device's computing task); its execution time on virtual
time is drawn per job from cost × U(1 − jitter, 1 + jitter) (seeded, so a run is reproducible).
The default costs 4, 6 and 14 ms load the CPU to 0.40 + 0.30 + 0.35 = 1.05 of its capacity.
For each policy the script prints the executions per task (averaged over the runs) beside the
ideal counts and the thesis's figures, the overruns, the skipped releases and the (m,k)-firm
time utility U(T_i) with k = 10. Never fails: it prints what it measured.

The simulation lives in st/experiments/scheduling.py (`st experiment scheduling` writes it up
with CSV, plots and a summary); this script prints the table only.
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from st.experiments.scheduling import LABEL, PERIODS_MS, POLICIES, THESIS, averages, compare  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--costs", default="4,6,14", help="execution times in ms of thread_1..3")
    ap.add_argument("--jitter", type=float, default=0.2)
    a = ap.parse_args()
    costs = [float(x) for x in a.costs.split(",")]
    ideal = [int(a.seconds * 1000 / p) for p in PERIODS_MS]
    load = sum(c / p for c, p in zip(costs, PERIODS_MS))
    print(
        f"three tasks at 10/20/40 ms, execution times {a.costs} ms (±{a.jitter:.0%}), CPU load {load:.2f}; "
        f"{a.seconds:g} s of virtual time, mean of {a.runs} runs"
    )
    print(
        f"{'policy':<26}{'thread_1':>10}{'thread_2':>10}{'thread_3':>10}   {'overruns':>18}   {'skipped':>14}"
        f"   {'U(T_i), k=10':>18}   thesis (Table 6.5)"
    )
    print(f"{'ideal (no overload)':<26}{ideal[0]:>10}{ideal[1]:>10}{ideal[2]:>10}")
    results = compare(runs=a.runs, seconds=a.seconds, costs_ms=costs, jitter=a.jitter)
    for policy in POLICIES:
        avg = averages(results[policy])
        jobs = [f"{x['jobs']:>10.1f}" for x in avg]
        ovr = "/".join(f"{x['overruns']:.0f}" for x in avg)
        skp = "/".join(f"{x['skipped']:.0f}" for x in avg)
        util = "/".join(f"{x['u_end']:.2f}" for x in avg)
        thesis = "/".join(str(v) for v in THESIS[policy]) if policy in THESIS else "-"
        print(f"{LABEL[policy]:<26}{''.join(jobs)}   {ovr:>18}   {skp:>14}   {util:>18}   {thesis}")


if __name__ == "__main__":
    main()
