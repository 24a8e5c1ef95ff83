"""The command line's start-up: how long `st --version`, `st --help` and `st check` of a small file
take as whole processes (issue 36: ≤ 0.15 s, ≤ 0.15 s and ≤ 0.25 s on this machine, with the
bytecode caches written and the file's compile in st's cache), beside `python -c pass`.

    python bench/bench_cli.py             # 10 runs each: min, median, max (s)
    python bench/bench_cli.py --runs 30
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SMALL = "PROGRAM p\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n"
GOALS = {"st --version": 0.15, "st --help": 0.15, "st check small.st": 0.25}


def timed(argv: list[str], runs: int) -> list[float]:
    subprocess.run(argv, capture_output=True, check=False)  # warm: bytecode and st's compile cache
    out = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=False)
        out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=10)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        small = Path(tmp) / "small.st"
        small.write_text(SMALL)
        st = [sys.executable, "-m", "st"]
        cases = {
            "python -c pass": [sys.executable, "-c", "pass"],
            "st --version": [*st, "--version"],
            "st --help": [*st, "--help"],
            "st check small.st": [*st, "check", str(small)],
        }
        print(f"{'command':<20} {'min':>7} {'median':>7} {'max':>7}  goal")
        for name, argv in cases.items():
            t = timed(argv, args.runs)
            goal = GOALS.get(name)
            verdict = "" if goal is None else f"≤ {goal:.2f} s: {'met' if statistics.median(t) <= goal else 'NOT met'}"
            print(f"{name:<20} {min(t):7.3f} {statistics.median(t):7.3f} {max(t):7.3f}  {verdict}")


if __name__ == "__main__":
    main()
