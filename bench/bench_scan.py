"""Scan-time benchmark: ns per scan of the example programs and the generated library.

    python bench/bench_scan.py [--scans 2000] [--runs 5] [--lines 20000]

For each programs/*.st and the generated library's program0: PLC.from_files(path), a short
warm-up, then the median of `--runs` runs of `--scans` scans (plc.scan(n), virtual time, the
cyclic GC disabled while timing). Then a micro benchmark as in ../shared/notes/realtime.md:
a generated program of 200 assignments and 10 TON calls, in µs per scan, beside the notes'
13-16 µs for compiled Python. Never fails: it prints what it measured and exits 0.
"""

from __future__ import annotations

import argparse
import gc
import glob
import os
import random
import statistics
import sys
import tempfile
import time

_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, _HERE)
from gen_library import generate  # noqa: E402

NOTES_US = (13.0, 16.0)  # realtime.md: 200 assignments + 10 TON, ast + compile()


def micro_program(n_assign: int = 200, n_ton: int = 10, seed: int = 1) -> str:
    """A PROGRAM of n_assign assignments (70 % INT, 15 % REAL, 15 % BOOL) and n_ton TON calls."""
    rng = random.Random(seed)
    ni, nr, nb = 40, 10, 20
    decl = ["PROGRAM micro", "  VAR"]
    decl += [f"    i{k} : INT := {k};" for k in range(ni)]
    decl += [f"    r{k} : REAL := {k}.5;" for k in range(nr)]
    decl += [f"    b{k} : BOOL;" for k in range(nb)]
    decl += [f"    t{k} : TON;" for k in range(n_ton)]
    decl.append("  END_VAR")
    body = []
    ton_at = set(rng.sample(range(n_assign), n_ton))
    ton = 0
    for n in range(n_assign):
        if n in ton_at:  # a TON call, then an assignment reading its output
            body.append(f"  t{ton}(IN := b{ton}, PT := T#{rng.randrange(50, 500, 10)}ms);")
            body.append(f"  b{ton + 10} := t{ton}.Q;")
            ton += 1
            continue
        x = rng.random()
        a, b, c = (rng.randrange(ni) for _ in range(3))
        if x < 0.70:
            op = rng.choice(["+", "-", "+", "*"])
            rhs = f"i{b} {op} i{c} MOD 100" if op == "*" else f"i{b} {op} {rng.randint(1, 9)}"
            body.append(f"  i{a} := {rhs};")
        elif x < 0.85:
            body.append(f"  r{a % nr} := r{b % nr} * 0.5 + {rng.randint(0, 9)}.25;")
        else:
            body.append(f"  b{a % 10} := i{b} > {rng.randint(0, 50)} OR NOT b{c % nb};")
    return "\n".join(decl + body + ["END_PROGRAM", ""])


def time_scans(plc, scans: int, runs: int, warmup: int = 100) -> list:
    """ns per scan of each run."""
    plc.scan(warmup)
    out = []
    enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        for _ in range(runs):
            t0 = time.perf_counter_ns()
            plc.scan(scans)
            out.append((time.perf_counter_ns() - t0) / scans)
    finally:
        if enabled:
            gc.enable()
    return out


def time_body(plc, calls: int, runs: int) -> list:
    """ns per bare `_body()` call of the first program instance (no task dispatch, no watchdog)."""
    obj = next(iter(plc.instances.values()))[1]
    body = obj._body
    out = []
    gc.disable()
    try:
        for _ in range(runs):
            t0 = time.perf_counter_ns()
            for _ in range(calls):
                body()
            out.append((time.perf_counter_ns() - t0) / calls)
    finally:
        gc.enable()
    return out


def _count_lines(path: str) -> int:
    with open(path, encoding="utf-8", errors="replace") as f:
        return sum(1 for _ in f)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scans", type=int, default=2000)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--lines", type=int, default=20000, help="size of the generated library")
    a = ap.parse_args(argv)
    from st import PLC

    root = os.path.dirname(_HERE)
    with tempfile.TemporaryDirectory(prefix="st-bench-") as tmp:
        os.environ.setdefault("ST_CACHE_DIR", os.path.join(tmp, "cache"))  # keep ~/.cache clean
        lib = os.path.join(tmp, "plantlib.st")
        with open(lib, "w") as f:
            f.write(generate(a.lines))
        paths = sorted(
            p for p in glob.glob(os.path.join(root, "programs", "*.st")) if not os.path.basename(p).startswith("test_")
        ) + [lib]
        print(
            f"ns per scan: median of {a.runs} runs of {a.scans} scans, gc disabled (Python {sys.version.split()[0]})\n"
        )
        print(f"{'program':28} {'lines':>6} {'tick':>6} {'ns/scan':>10} {'min':>10} {'max':>10}")
        for path in paths:
            name = os.path.relpath(path, root) if path != lib else "generated library program0"
            try:
                plc = PLC.from_files(path)
                runs = time_scans(plc, a.scans, a.runs)
            except Exception as exc:  # a fault or a compile error is a result, not a failure
                print(f"{name:28} error: {type(exc).__name__}: {str(exc).splitlines()[0]}")
                continue
            print(
                f"{name:28} {_count_lines(path):6} {plc.tick // 1_000_000:4}ms "
                f"{statistics.median(runs):10,.0f} {min(runs):10,.0f} {max(runs):10,.0f}"
            )

        print("\nmicro benchmark (../shared/notes/realtime.md): 200 assignments + 10 TON calls")
        try:
            plc = PLC.from_source(micro_program(), cycle="10ms", name="micro.st")
            scan = statistics.median(time_scans(plc, a.scans * 5, a.runs)) / 1000
            body = statistics.median(time_body(plc, a.scans * 5, a.runs)) / 1000
        except Exception as exc:
            print(f"  error: {type(exc).__name__}: {exc}")
            return 0
        lo, hi = NOTES_US
        mid = (lo + hi) / 2
        print(f"  {'':34} {'µs/scan':>8}   ratio to the notes' {lo:.0f}-{hi:.0f} µs")
        print(
            f"  {'plc.scan() (task dispatch + body)':34} {scan:8.2f}   {scan / hi:.2f}-{scan / lo:.2f} (x{scan / mid:.2f} of the middle)"
        )
        print(
            f"  {'program body alone (_body())':34} {body:8.2f}   {body / hi:.2f}-{body / lo:.2f} (x{body / mid:.2f} of the middle)"
        )
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception as exc:  # a benchmark reports, it does not fail
        print(f"bench_scan: error: {type(exc).__name__}: {exc}")
        sys.exit(0)
