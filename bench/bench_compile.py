"""Compile-time benchmark on the generated ~20,000-line library.

    python bench/bench_compile.py [--lines 20000] [--repeat 3]

Prints the cold compile time (ST_NO_CACHE=1), the cached compile time (a filled ST_CACHE_DIR),
each the median of fresh processes timing only the `compile_paths` call, lines/s, the ratio to
the goals (cold < 5 s, cached < 0.3 s for 20,000 lines; ratio < 1 meets the goal, scaled
linearly for other sizes), and the split of one cold compile into its stages.
Never fails: it prints what it measured and exits 0.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile

_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, _HERE)
from gen_library import generate  # noqa: E402

GOAL_COLD_S = 5.0  # for 20,000 lines
GOAL_CACHED_S = 0.3

TIMED = """\
import sys, time
from st.api import compile_paths
t0 = time.perf_counter()
compile_paths([sys.argv[1]])
print(repr(time.perf_counter() - t0))
"""

# One cold compile, stage by stage, as st/compiler/driver.py `_compile_sources` does it.
SPLIT = """\
import gc, sys, time
from st import api
from st.compiler import driver
from st.compiler.check import Checker
from st.compiler.codegen import ModuleGen
from st.compiler.lower import lower
from st.diagnostics import DiagnosticSink
from st.source import SourceFile
gc.disable()                       # compile_sources does the same
T = {}
t = time.perf_counter()
libs = api.libraries()
sources = driver.load_files([sys.argv[1]])
T["load + libraries"] = time.perf_counter() - t
t = time.perf_counter()
driver._get_parser()
T["parser setup (Lark tables)"] = time.perf_counter() - t
sink = DiagnosticSink()
units, lib_paths = [], set()
t = time.perf_counter()
for lib in libs:
    for path, text in lib.sources:
        lib_paths.add(path)
        units.append(driver.parse_source(SourceFile(path, text), sink))
T["parse (standard library)"] = time.perf_counter() - t
t = time.perf_counter()
for s in sources:
    units.append(driver.parse_source(s, sink))
T["parse"] = time.perf_counter() - t
t = time.perf_counter()
project = Checker(sink, libs).run(units, lib_paths)
T["check"] = time.perf_counter() - t
assert not sink.has_errors, "the library has errors"
t = time.perf_counter()
lowered = lower(project)
T["lower"] = time.perf_counter() - t
t = time.perf_counter()
mods = ModuleGen(lowered, sink).generate()
T["codegen (Python ast)"] = time.perf_counter() - t
t = time.perf_counter()
codes = [compile(m, p, "exec") for p, m in mods]
T["Python compile()"] = time.perf_counter() - t
for k, v in T.items():
    print(k + "\\t" + repr(v))
"""


def _run(code: str, path: str, env: dict) -> str:
    r = subprocess.run([sys.executable, "-c", code, path], env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr.strip().splitlines()[-1] if r.stderr.strip() else f"exit {r.returncode}")
    return r.stdout


def _timed(path: str, env: dict, repeat: int) -> list:
    return [float(_run(TIMED, path, env).strip().splitlines()[-1]) for _ in range(repeat)]


def _fmt_ratio(t: float, goal: float) -> str:
    verdict = "meets the goal" if t < goal else "MISSES the goal"
    return f"{t / goal:5.2f} x goal ({verdict}: < {goal:.2f} s)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lines", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    text = generate(a.lines, a.seed)
    n = text.count("\n")
    scale = n / 20000.0
    goal_cold, goal_cached = GOAL_COLD_S * scale, GOAL_CACHED_S * scale
    with tempfile.TemporaryDirectory(prefix="st-bench-") as tmp:
        path = os.path.join(tmp, "plantlib.st")
        with open(path, "w") as f:
            f.write(text)
        print(f"library: {n} lines, {len(text) / 1024:.0f} KiB  ({sys.executable}, Python {sys.version.split()[0]})")
        base = {k: v for k, v in os.environ.items() if k not in ("ST_NO_CACHE", "ST_CACHE_DIR")}
        try:
            cold = _timed(path, dict(base, ST_NO_CACHE="1"), a.repeat)
            cache_env = dict(base, ST_CACHE_DIR=os.path.join(tmp, "cache"))
            _run(TIMED, path, cache_env)  # fill the cache
            cached = _timed(path, cache_env, a.repeat)
        except RuntimeError as e:
            print(f"compile failed: {e}")
            return 0
        mc, mk = statistics.median(cold), statistics.median(cached)
        print()
        print(f"{'':10} {'median s':>9} {'runs s':>24} {'lines/s':>10}   goal ratio")
        for name, runs, m, goal in (("cold", cold, mc, goal_cold), ("cached", cached, mk, goal_cached)):
            rs = " ".join(f"{x:.3f}" for x in runs)
            print(f"{name:10} {m:9.3f} {rs:>24} {n / m:10,.0f}   {_fmt_ratio(m, goal)}")
        print(f"(goals scaled to {n} lines; ratio = measured / goal, below 1 is good)")
        print()
        print("cold compile, stage by stage (one fresh process, gc disabled as in compile_sources):")
        try:
            out = _run(SPLIT, path, dict(base, ST_NO_CACHE="1"))
        except RuntimeError as e:
            print(f"  split failed: {e}")
            return 0
        rows = [line.split("\t") for line in out.strip().splitlines()]
        total = sum(float(v) for _, v in rows)
        for k, v in rows:
            v = float(v)
            print(f"  {k:28} {v:7.3f} s  {100 * v / total:5.1f} %")
        print(f"  {'total':28} {total:7.3f} s")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception as exc:  # a benchmark reports, it does not fail
        print(f"bench_compile: error: {type(exc).__name__}: {exc}")
        sys.exit(0)
