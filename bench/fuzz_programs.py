"""Fuzz the compiler and the runtime with mutated example programs (st/testing/fuzz.py).

    python bench/fuzz_programs.py --mutants 20000 --seed 1 --timeout 10 --out /tmp/fuzz [--workers 2]

Mutant i of seed s is `st.testing.fuzz.mutant(s, i)`: the same text on every machine (given the
same programs/). Each is compiled and, when it compiles, run for --scans base ticks on virtual
time with a --watchdog budget per job, in --workers long-lived worker processes (a mutant that
outlasts --timeout seconds of wall-clock time is a `timeout` and its worker is replaced).

Prints progress, the count of each outcome, mutants per second and every defect signature with
its count; writes a shrunk reproducer per signature (DIR/NN.st, the unshrunk mutant beside it as
DIR/NN.orig.st), every defective mutant as a line of DIR/defects.jsonl, and DIR/summary.md.
Exit code 0 either way (a benchmark); the summary says whether a defect was found.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from st.testing.fuzz import DEFECTS, Worker, corpus, mutant, shrink  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mutants", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--start", type=int, default=0, help="first mutant index (to resume or split a run)")
    ap.add_argument("--timeout", type=float, default=10.0, help="wall-clock seconds per mutant")
    ap.add_argument("--workers", type=int, default=2, help="worker processes (at most 2 on a shared 2-core box)")
    ap.add_argument("--scans", type=int, default=20, help="base ticks run per mutant that compiles")
    ap.add_argument("--watchdog", default="100ms", help="the PLC's watchdog budget per job")
    ap.add_argument("--shrink-budget", type=int, default=200, help="runs per signature spent shrinking")
    ap.add_argument("--out", default="/tmp/st-fuzz")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    programs = corpus()
    counts: collections.Counter = collections.Counter()
    defects: dict = {}  # signature → [count, index, base, source, outcome]
    lock = threading.Lock()
    indexes = iter(range(args.start, args.start + args.mutants))
    log = (out / "defects.jsonl").open("w")
    t0 = time.perf_counter()
    done = [0, t0]  # mutants done, time of the last progress line
    restarts = [0]
    stop = threading.Event()  # Ctrl-C: finish the mutants under way, then report
    print(
        f"fuzz: {args.mutants} mutants of {len(programs)} programs, seed {args.seed}, {args.workers} worker(s), "
        f"timeout {args.timeout} s, {args.scans} scans, watchdog {args.watchdog}",
        flush=True,
    )

    def work():
        w = Worker(args.timeout, watchdog=args.watchdog, scans=args.scans)
        try:
            while True:
                with lock:
                    i = None if stop.is_set() else next(indexes, None)
                if i is None:
                    return
                base, src = mutant(args.seed, i, programs)
                o = w.classify(src)
                with lock:
                    counts[o.cls] += 1
                    done[0] += 1
                    if o.defect:
                        d = defects.setdefault(o.signature, [0, i, base, src, o])
                        d[0] += 1
                        log.write(
                            json.dumps(
                                {"index": i, "base": base, "class": o.cls, "signature": o.signature, "detail": o.detail}
                            )
                            + "\n"
                        )
                        log.flush()
                    now = time.perf_counter()
                    if done[0] % 500 == 0 or now - done[1] > 60 or done[0] == args.mutants:
                        done[1] = now
                        bad = sum(counts[c] for c in DEFECTS)
                        print(
                            f"{done[0]:6d}/{args.mutants} mutants, {done[0] / (now - t0):5.1f}/s, "
                            f"{counts['ok']} ok, {counts['diagnostics']} diagnostics, "
                            f"{sum(n for c, n in counts.items() if c.startswith('fault:'))} faults, "
                            f"{bad} defects in {len(defects)} signature(s)",
                            flush=True,
                        )
        finally:
            with lock:
                restarts[0] += w.restarts
            w.close()

    threads = [threading.Thread(target=work, daemon=True) for _ in range(max(1, args.workers))]
    for t in threads:
        t.start()
    try:
        while any(t.is_alive() for t in threads):
            for t in threads:
                t.join(0.5)
    except KeyboardInterrupt:
        print("interrupted: finishing the mutants under way", flush=True)
        stop.set()
        for t in threads:
            t.join(args.timeout + 10)
    log.close()
    elapsed = time.perf_counter() - t0
    total = done[0]
    rate = total / elapsed
    faults = sum(n for c, n in counts.items() if c.startswith("fault:"))
    print(
        f"\n{total} mutants (seed {args.seed}, indexes {args.start}..{args.start + total - 1}) "
        f"in {elapsed:.0f} s: {rate:.1f} mutants/s with {args.workers} worker(s)"
    )
    for cls, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
        print(f"  {cls:<20} {n:6d}  {100 * n / max(total, 1):5.1f} %")
    lines = [
        f"# Fuzz run: {total} mutants, seed {args.seed}"
        + ("" if total == args.mutants else f" (interrupted: {args.mutants} asked)"),
        "",
        f"`python bench/fuzz_programs.py --mutants {args.mutants} --seed {args.seed} --start {args.start} "
        f"--timeout {args.timeout:g} --workers {args.workers} --scans {args.scans} --watchdog {args.watchdog}`",
        "",
        f"{elapsed:.0f} s, {rate:.1f} mutants/s, {args.workers} worker(s) "
        f"({restarts[0]} worker restart(s)); {len(programs)} base programs",
        "",
        f"{counts['ok']} ran clean, {counts['diagnostics']} were refused with located diagnostics, "
        f"{faults} ended in a located PLC fault.",
        "",
        "| outcome | mutants | % |",
        "|---|---:|---:|",
    ]
    lines += [
        f"| {cls} | {n} | {100 * n / max(total, 1):.1f} |"
        for cls, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))
    ]
    total_bad = sum(counts[c] for c in DEFECTS)
    lines += [
        "",
        f"**{total_bad} defective mutant(s) in {len(defects)} signature(s)**" + (":" if defects else ": none found."),
        "",
    ]
    if defects:
        print(f"\n{total_bad} defective mutant(s) in {len(defects)} signature(s); shrinking:")
    w = Worker(args.timeout, watchdog=args.watchdog, scans=args.scans)
    try:
        ranked = sorted(defects.items(), key=lambda kv: (-kv[1][0], kv[0]))
        for k, (sig, (n, i, base, src, o)) in enumerate(ranked):
            budget = args.shrink_budget if o.cls != "timeout" else min(args.shrink_budget, 12)
            t1 = time.perf_counter()
            small = shrink(src, sig, w.classify, budget=budget)
            path = out / f"{k + 1:02d}.st"
            path.write_text(small)
            (out / f"{k + 1:02d}.orig.st").write_text(src)
            print(
                f"  [{k + 1:02d}] x{n} {o.cls}: {sig}\n       first: mutant {i} of {base}; shrunk to {path.name} "
                f"({len(src)} -> {len(small)} chars, {time.perf_counter() - t1:.0f} s)\n       {o.detail[:200]}",
                flush=True,
            )
            lines += [
                f"## {k + 1}. {o.cls}: `{sig}` (x{n})",
                "",
                f"first: mutant {i} of {base} (`mutant({args.seed}, {i})`); {o.detail[:300]}",
                "",
                f"shrunk ({path.name}):",
                "",
                "```",
                small[:3000],
                "```",
                "",
            ]
    finally:
        w.close()
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    print(f"summary: {out / 'summary.md'}")


if __name__ == "__main__":
    main()
