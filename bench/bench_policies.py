"""The thesis's scheduling simulation (ch. 6.3, Table 6.5) on st's engine: three device tasks at
1×, 2× and 4× a 10 ms minimum period, overloaded, on virtual time.

    python bench/bench_policies.py [--runs 1000] [--seconds 6] [--costs 4,6,14] [--jitter 0.2]

Each task runs a small ST program (a device's computing task); its execution time on virtual
time is drawn per job from cost × U(1 − jitter, 1 + jitter) (seeded, so a run is reproducible).
The default costs 4, 6 and 14 ms load the CPU to 0.40 + 0.30 + 0.35 = 1.05 of its capacity.
For each policy the script prints the executions per task (averaged over the runs) beside the
ideal counts and the thesis's figures, the overruns, the skipped releases and the (m,k)-firm
time utility U(T_i) with k = 10. Never fails: it prints what it measured.
"""
from __future__ import annotations

import argparse
import random
import sys
import os

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from st import PLC  # noqa: E402
from st.api import compile_text  # noqa: E402

SOURCE = """
PROGRAM Device
  VAR_INPUT id : INT; END_VAR
  VAR count : DINT; position : LREAL; END_VAR
  count := count + 1;
  position := position + 0.001 * INT_TO_LREAL(id);
END_PROGRAM

CONFIGURATION Cell
  RESOURCE cpu ON PLC
    TASK thread_1 (INTERVAL := T#10ms, PRIORITY := 1);
    TASK thread_2 (INTERVAL := T#20ms, PRIORITY := 2);
    TASK thread_3 (INTERVAL := T#40ms, PRIORITY := 3);
    PROGRAM device_1 WITH thread_1 : Device (id := 1);
    PROGRAM device_2 WITH thread_2 : Device (id := 2);
    PROGRAM device_3 WITH thread_3 : Device (id := 3);
  END_RESOURCE
END_CONFIGURATION
"""
THESIS = {"frame": (600, 300, 202), "openplc": (600, 295, 158), "priority": (554, 297, 151)}
LABEL = {"frame": "frame (semaphore-based)", "openplc": "openplc (FCFS)", "priority": "priority (RMS)",
         "edf": "edf"}


def simulate(compiled, policy, costs_ms, jitter, seconds, seed):
    plc = PLC(compiled, policy=policy)
    rng = random.Random(seed)
    for task, c in zip(("thread_1", "thread_2", "thread_3"), costs_ms):
        base = c * 1_000_000
        plc.set_cost(task, (lambda b=base: int(b * rng.uniform(1 - jitter, 1 + jitter))) if jitter else base)
    plc.advance(f"{seconds}s")
    return [t.stats for t in plc.tasks]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--costs", default="4,6,14", help="execution times in ms of thread_1..3")
    ap.add_argument("--jitter", type=float, default=0.2)
    a = ap.parse_args()
    costs = [float(x) for x in a.costs.split(",")]
    compiled = compile_text(SOURCE, "cell.st")
    periods = (10, 20, 40)
    ideal = [int(a.seconds * 1000 / p) for p in periods]
    load = sum(c / p for c, p in zip(costs, periods))
    print(f"three tasks at 10/20/40 ms, execution times {a.costs} ms (±{a.jitter:.0%}), CPU load {load:.2f}; "
          f"{a.seconds:g} s of virtual time, mean of {a.runs} runs")
    print(f"{'policy':<26}{'thread_1':>10}{'thread_2':>10}{'thread_3':>10}   {'overruns':>18}   {'skipped':>14}"
          f"   {'U(T_i), k=10':>18}   thesis (Table 6.5)")
    print(f"{'ideal (no overload)':<26}{ideal[0]:>10}{ideal[1]:>10}{ideal[2]:>10}")
    for policy in ("frame", "openplc", "priority", "edf"):
        tot = [[0, 0, 0, 0.0] for _ in range(3)]
        for r in range(a.runs):
            for acc, s in zip(tot, simulate(compiled, policy, costs, a.jitter, a.seconds, seed=r)):
                acc[0] += s.jobs
                acc[1] += s.overruns
                acc[2] += s.skipped
                acc[3] += s.utility
        n = a.runs
        jobs = [f"{x[0] / n:>10.1f}" for x in tot]
        ovr = "/".join(f"{x[1] / n:.0f}" for x in tot)
        skp = "/".join(f"{x[2] / n:.0f}" for x in tot)
        util = "/".join(f"{x[3] / n:.2f}" for x in tot)
        thesis = "/".join(str(v) for v in THESIS[policy]) if policy in THESIS else "-"
        print(f"{LABEL[policy]:<26}{''.join(jobs)}   {ovr:>18}   {skp:>14}   {util:>18}   {thesis}")


if __name__ == "__main__":
    main()
