"""Fuzz the compiler and the runtime with mutated example programs (st/testing/fuzz.py).

    python bench/fuzz_programs.py --mutants 20000 --seed 1 --timeout 10 --out /tmp/fuzz [--workers 2]

Prints progress, the count of each outcome, mutants per second and every defect signature
with its count; writes a shrunk reproducer per signature (DIR/<n>.st) and DIR/summary.md.
Exit code 0 either way (a benchmark), but the summary says whether any defect was found.
"""
from __future__ import annotations

import argparse
import collections
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from st.testing.fuzz import Worker, corpus, mutant, shrink  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mutants", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=10.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="/tmp/st-fuzz")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    programs = corpus()
    counts: collections.Counter = collections.Counter()
    defects: dict = {}                      # signature → [count, index, base, source, outcome]
    lock = threading.Lock()
    next_index = iter(range(args.mutants))
    t0 = time.perf_counter()
    done = [0]

    def work():
        w = Worker(args.timeout)
        try:
            while True:
                with lock:
                    i = next(next_index, None)
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
                    if done[0] % 500 == 0:
                        rate = done[0] / (time.perf_counter() - t0)
                        print(f"{done[0]:6d} mutants, {rate:5.1f}/s, defects {sum(v[0] for v in defects.values())}",
                              flush=True)
        finally:
            w.close()

    threads = [threading.Thread(target=work) for _ in range(args.workers)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    elapsed = time.perf_counter() - t0
    print(f"\n{args.mutants} mutants (seed {args.seed}) in {elapsed:.0f} s: {args.mutants / elapsed:.1f} mutants/s")
    for cls, n in counts.most_common():
        print(f"  {cls:<20} {n:6d}")
    lines = [f"# Fuzz run: {args.mutants} mutants, seed {args.seed}", "",
             f"{elapsed:.0f} s, {args.mutants / elapsed:.1f} mutants/s, {args.workers} worker(s), "
             f"timeout {args.timeout} s", "", "| outcome | mutants |", "|---|---|"]
    lines += [f"| {cls} | {n} |" for cls, n in counts.most_common()]
    lines += ["", f"{len(defects)} defect signature(s)" + (":" if defects else " - none found."), ""]
    w = Worker(args.timeout)
    try:
        for k, (sig, (n, i, base, src, o)) in enumerate(sorted(defects.items(), key=lambda kv: -kv[1][0])):
            small = shrink(src, sig, w.classify)
            path = out / f"{k + 1:02d}.st"
            path.write_text(small)
            print(f"  DEFECT x{n}: {o.cls}: {sig}\n    mutant {i} of {base}; shrunk to {path} "
                  f"({len(small)} chars)\n    {o.detail[:200]}")
            lines += [f"## {k + 1}. {o.cls}: {sig} (x{n})", "", f"mutant {i} of {base}: {o.detail[:300]}", "",
                      "```", small[:2000], "```", ""]
    finally:
        w.close()
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    print(f"summary: {out / 'summary.md'}")


if __name__ == "__main__":
    main()
