"""What compiling st's generated Python with Cython would give: a measurement, not a tier.

    python bench/bench_tier_cython.py [--scans N] [--runs R] [--workloads NAME ...] [--no-typed]

For each workload of bench/workloads/ (the openplc dialect, compiled as bench_native.py does),
the Python that st generates for the whole program (the library modules and the workload, the
code the PLC execs, concatenated in the same order) is built into one extension module by
Cython and gcc -O2, and timed against st as it runs today:

  (a) exec      st today: the code objects exec'd into the namespace
  (b) cython    the same source compiled by Cython unchanged (pure Python mode)
  (c) typed     (b) plus two things a code generator could emit: `range` instead of the
                namespace's `_range` alias (so Cython turns counted loops into C loops) and
                the directive infer_types=True (safe here only because every local of these
                workloads is a DINT whose arithmetic is wrapped explicitly; see the README)

`body` is ns per call of the program instance's `_body()` (with the FB bodies it calls),
`scan` ns per `PLC.scan()` (latch, body, publish, statistics). The checksum (the program's
`checksum` after N scans) must be the same in every variant.

How (b) and (c) run inside st without changing st: the module starts with a prelude that copies
the namespace st would build (helpers, the watchdog's `_wd_armed`/`_wd_check`) into its own
globals, and the bench replaces `build_namespace` so that the PLC's namespace *is* the
extension module's `__dict__` (the dict Cython reads its globals from): per-PLC values the
runtime writes there (`_now`, `_wd_armed`) are seen by the compiled code.
An extension module can be imported once per process, so later PLCs of the same variant reuse
the one import (sequentially: they share its dict); `--probe` also shows what breaks (a
second import, fault lines, the watchdog).

Skips with a message when Cython or a C compiler is missing. Never fails on a finding.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
import types
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bench_native import WORKLOADS, to_signed32  # noqa: E402

import st.runtime.build as st_build  # noqa: E402
from st import PLC  # noqa: E402
from st.api import compile_paths, compile_text  # noqa: E402
from st.runtime.helpers import BASE_NAMESPACE, make_f32  # noqa: E402
from st.runtime.messages import MessageLog  # noqa: E402
from st.runtime.namespace import build_namespace  # noqa: E402
from st.runtime.pointers import POINTER_HELPERS  # noqa: E402
from st.runtime.sfc import SfcDesc, SfcState  # noqa: E402

# native -O0 (OpenPLC as shipped) ns per scan, from bench_native.py on this machine (issue 20)
NATIVE_O0 = {"bool_timers": 433, "fb_heavy": 447, "int_arrays": 958, "real_math": 831}

HANDOFF = "_st_tier_handoff"
PRELUDE = f"""\
import sys as _st_sys
globals().update(_st_sys.modules[{HANDOFF!r}].ns)
del _st_sys
"""

# the helpers are unknown to Cython at compile time (they arrive in the prelude): allow that
CYTHON_MAIN = (
    "import sys; from Cython.Compiler import Options; Options.error_on_unknown_names = False; "
    "from Cython.Compiler.Main import setuptools_main; sys.exit(setuptools_main())"
)

VARIANTS = {
    "cython": {"directives": "language_level=3", "range": False},
    "typed": {"directives": "language_level=3,infer_types=True", "range": True},
}


def toolchain() -> str:
    """Why the tier cannot be built here, or '' when it can."""
    if importlib.util.find_spec("Cython") is None:
        return "Cython is not installed (pip install cython)"
    if shutil.which(os.environ.get("CC", "gcc")) is None:
        return "no C compiler (gcc, or $CC)"
    if not (Path(sysconfig.get_paths()["include"]) / "Python.h").exists():
        return "no Python headers (Python.h)"
    return ""


def module_source(compiled: Any, range_builtin: bool) -> str:
    """The generated Python of every module, in exec order, after the prelude."""
    parts = [PRELUDE]
    for path, _code in compiled.modules:
        text = compiled.python_source[path]
        if range_builtin:
            text = re.sub(r"\b_range\(", "range(", text)
        parts.append(text)
    return "\n".join(parts)


def build_extension(src: str, name: str, directives: str, work: Path) -> tuple[Path, float, float, Path]:
    """cython + gcc -O2: (the .so, cython seconds, gcc seconds, the .py that was compiled)."""
    py = work / f"{name}.py"
    c = work / f"{name}.c"
    so = work / f"{name}{sysconfig.get_config_var('EXT_SUFFIX')}"
    py.write_text(src)
    t0 = time.perf_counter()
    run = subprocess.run(
        [sys.executable, "-c", CYTHON_MAIN, "-X", directives, str(py), "-o", str(c)], capture_output=True, text=True
    )
    t1 = time.perf_counter()
    if run.returncode:
        raise RuntimeError(f"cython refused {name}:\n{run.stderr[-3000:]}")
    cc = os.environ.get("CC", "gcc")
    inc = sysconfig.get_paths()["include"]
    run = subprocess.run(
        [cc, "-shared", "-fPIC", "-O2", "-w", f"-I{inc}", str(c), "-o", str(so)], capture_output=True, text=True
    )
    t2 = time.perf_counter()
    if run.returncode:
        raise RuntimeError(f"gcc refused {name}:\n{run.stderr[-3000:]}")
    return so, t1 - t0, t2 - t1, py


def load_extension(so: Path, name: str) -> types.ModuleType:
    spec = importlib.util.spec_from_file_location(name, so)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class Tier:
    """A build_namespace whose namespace is the extension module's __dict__ (see the docstring)."""

    def __init__(self, so: Path, name: str):
        self.so, self.name = so, name
        self.mod: types.ModuleType | None = None

    def __call__(self, compiled: Any, install: Any = None) -> dict[str, Any]:
        ns: dict[str, Any] = dict(BASE_NAMESPACE)
        ns.update(POINTER_HELPERS)
        ns.update(compiled.helpers)
        ns.update({"_SfcDesc": SfcDesc, "_SfcState": SfcState, "_now": 0, "_st_namespace": True, "_f32": make_f32()})
        ns["_plc_log"] = MessageLog()
        if compiled.coverage_hits is not None:
            ns["_cov"] = compiled.coverage_hits
        if self.mod is None:
            sys.modules[HANDOFF] = types.SimpleNamespace(ns=ns)  # type: ignore[assignment]
            try:
                self.mod = load_extension(self.so, self.name)  # runs the module: classes, once
            finally:
                del sys.modules[HANDOFF]
        d = self.mod.__dict__
        d.update(ns)  # a later PLC: fresh helpers into the one module dict (shared: sequential only)
        d["_ns"] = d
        if install is not None:
            install(d)  # the watchdog writes _wd_armed into the dict the compiled code reads
        for key in sorted(k for k in d if k.startswith("_post_exec_")):
            d[key](d)
        return d


def patched(tier: Tier | None) -> Any:
    """Context: PLCs built inside use `tier` (None: st as it is)."""

    class _Ctx:
        def __enter__(self) -> None:
            if tier is not None:
                st_build.build_namespace = tier  # type: ignore[assignment]

        def __exit__(self, *exc: object) -> None:
            st_build.build_namespace = build_namespace

    return _Ctx()


def program_instance(plc: PLC) -> Any:
    return next(iter(plc.instances.values()))[1]


def time_body(compiled: Any, tier: Tier | None, scans: int) -> tuple[float, int]:
    with patched(tier):
        plc = PLC(compiled)
    obj = program_instance(plc)
    ns = plc.ns
    body = obj._body
    t0 = time.perf_counter()
    for i in range(scans):
        ns["_now"] = i * 1_000_000  # the task's release time, as the engine writes it (1 ms task)
        body()
    dt = time.perf_counter() - t0
    return dt / scans * 1e9, to_signed32(obj.checksum)


def time_scan(compiled: Any, tier: Tier | None, scans: int) -> tuple[float, int]:
    with patched(tier):
        plc = PLC(compiled)
    t0 = time.perf_counter()
    plc.scan(scans)
    dt = time.perf_counter() - t0
    return dt / scans * 1e9, to_signed32(int(plc["%QD0"]))


PROBE = """
PROGRAM main
VAR
  checksum AT %QD0 : DINT;
  n : DINT;
  d : DINT;
  x : DINT;
END_VAR
n := n + 1;
IF n = 3 THEN
  x := 100 / d;
END_IF;
IF n = 5 THEN
  WHILE TRUE DO
    x := x + 1;
  END_WHILE;
END_IF;
checksum := n;
END_PROGRAM
"""


def probe_plc(compiled: Any, tier: Tier | None) -> PLC:
    with patched(tier):
        plc = PLC(compiled, watchdog="50ms")
    plc.scan(2)
    return plc


def try_scan(plc: PLC, scans: int) -> str:
    try:
        plc.scan(scans)
        return "no fault"
    except Exception as e:  # noqa: BLE001 - the finding is what happens
        return f"{type(e).__name__}: {str(e).splitlines()[0][:110]}"


def probe(work: Path) -> None:
    """What breaks: fault lines, the watchdog through module globals, a second import."""
    print("\n## probes (a DINT division by zero at ST line 11, an endless loop at line 14)")
    compiled = compile_text(PROBE, "probe.st", dialect="openplc", emit_python=True, use_cache=False)
    so, *_ = build_extension(module_source(compiled, False), "_st_probe", VARIANTS["cython"]["directives"], work)
    tier = Tier(so, "_st_probe")
    for label, t in (("exec", None), ("cython", tier)):
        print(f"{label:7} division by zero -> {try_scan(probe_plc(compiled, t), 1)}")
    print(f"exec    endless loop, 50 ms watchdog -> {try_scan(_endless(None, 'watchdog'), 1)}")
    for mode, what in (
        ("abort", "_wd_armed raised (abort pending) before the job"),
        ("watchdog", "endless loop, 50 ms watchdog"),
    ):
        try:
            out = subprocess.run(
                [sys.executable, __file__, "--endless-child", str(so), mode], capture_output=True, text=True, timeout=15
            )
            print(f"cython  {what} -> " + (out.stdout.strip() or out.stderr.strip()[-200:]))
        except subprocess.TimeoutExpired:
            print(f"cython  {what} -> still running after 15 s (killed): no WATCHDOG fault")
    try:
        again = load_extension(so, "_st_probe")
        same = again is tier.mod or again.__dict__ is tier.mod.__dict__  # type: ignore[union-attr]
        print(f"second import of the same .so: accepted; the same module and dict again: {same}")
    except Exception as e:  # noqa: BLE001
        print(f"second import of the same .so: {type(e).__name__}: {e}")


def _endless(so: str | None, mode: str) -> Any:
    """The probe's PLC one scan before its endless loop (exec, or the Cython build at `so`);
    mode "abort": with an abort pending and `_wd_armed` raised, as Watchdog.abort does."""
    compiled = compile_text(PROBE, "probe.st", dialect="openplc", emit_python=True, use_cache=False)
    plc = probe_plc(compiled, Tier(Path(so), "_st_probe") if so else None)
    program_instance(plc).d = 1  # no division fault on the way
    plc.scan(2)
    if mode == "abort":
        plc._wd.abort_reason, plc.ns["_wd_armed"] = "aborted by the probe", True
    return plc


def typed_sketch(scans: int, runs: int) -> None:
    """bench/workloads/typed/int_arrays.pyx (int_arrays.st by hand as a typed generator would emit
    it) built with cython + gcc -O2: ns per body call, and its checksum beside st's."""
    pyx = WORKLOADS / "typed" / "int_arrays.pyx"
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        c = work / "int_arrays.c"
        so = work / f"int_arrays{sysconfig.get_config_var('EXT_SUFFIX')}"
        t0 = time.perf_counter()
        for cmd in (
            [sys.executable, "-c", CYTHON_MAIN, str(pyx), "-o", str(c)],
            [os.environ.get("CC", "gcc"), "-shared", "-fPIC", "-O2", "-w", f"-I{sysconfig.get_paths()['include']}"]
            + [str(c), "-o", str(so)],
        ):
            run = subprocess.run(cmd, capture_output=True, text=True)
            if run.returncode:
                print(f"typed sketch: build failed:\n{run.stderr[-2000:]}")
                return
        built = time.perf_counter() - t0
        mod = load_extension(so, "int_arrays")
        best = math.inf
        for _ in range(runs):
            m = mod.Main()
            t = time.perf_counter_ns()
            for _ in range(scans):
                m.body()
            best = min(best, (time.perf_counter_ns() - t) / scans)
        compiled = compile_paths([str(WORKLOADS / "int_arrays.st")], dialect="openplc", use_cache=False)
        plc = PLC(compiled)
        plc.scan(scans)
        nat = NATIVE_O0["int_arrays"]
        same = "equal" if to_signed32(int(plc["%QD0"])) == m.checksum else "DIFFER"
        print(f"typed sketch of int_arrays: {best:,.0f} ns per body call ({best / nat:.1f}x native -O0 {nat:,} ns),")
        print(f"  checksum after {scans} scans {m.checksum} ({same} to st's), built in {built:.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scans", type=int, default=20000, help="scans (body calls) per run")
    ap.add_argument("--runs", type=int, default=3, help="runs of each; the best is shown (a shared machine)")
    ap.add_argument("--workloads", nargs="*", default=None, help="names in bench/workloads (default: all)")
    ap.add_argument("--no-typed", action="store_true", help="skip variant (c)")
    ap.add_argument("--probe", action="store_true", help="also show what breaks (faults, watchdog, re-import)")
    ap.add_argument("--endless-child", nargs=2, help=argparse.SUPPRESS)
    ap.add_argument(
        "--typed-sketch",
        action="store_true",
        help="only the hand-typed int_arrays (bench/workloads/typed/): what a typed tier could reach",
    )
    args = ap.parse_args()
    if args.endless_child:
        print(try_scan(_endless(*args.endless_child), 1))
        return
    why = toolchain()
    if why:
        print(f"skipped: {why}")
        return
    if args.typed_sketch:
        typed_sketch(args.scans, args.runs)
        return
    files = sorted(WORKLOADS.glob("*.st"))
    if args.workloads:
        files = [f for f in files if f.stem in args.workloads]
    variants = ["cython"] if args.no_typed else ["cython", "typed"]
    rows, builds = [], []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for wl in files:
            compiled = compile_paths([str(wl)], dialect="openplc", use_cache=False, emit_python=True)
            tiers: dict[str, Tier | None] = {"exec": None}
            for v in variants:
                name = f"_st_tier_{wl.stem}_{v}"
                try:
                    so, t_cy, t_cc, _py = build_extension(
                        module_source(compiled, bool(VARIANTS[v]["range"])), name, str(VARIANTS[v]["directives"]), work
                    )
                except RuntimeError as e:
                    print(f"{wl.stem} {v}: {e}")
                    continue
                builds.append((wl.stem, v, t_cy, t_cc, so.stat().st_size))
                tiers[v] = Tier(so, name)
            row: dict[str, Any] = {"workload": wl.stem}
            for v, tier in tiers.items():
                try:
                    body = min(time_body(compiled, tier, args.scans) for _ in range(args.runs))
                    scan = min(time_scan(compiled, tier, args.scans) for _ in range(args.runs))
                except Exception as e:  # noqa: BLE001 - a finding, reported
                    print(f"{wl.stem} {v}: {type(e).__name__}: {e}")
                    continue
                row[v] = (body, scan)
            rows.append(row)
        print(f"\n{args.scans} scans per run, best of {args.runs}; ns per call; xN = times native -O0\n")
        names = list(tiers)
        print("| workload | " + " | ".join(f"{v} body | {v} scan" for v in names) + " | native -O0 | checksums |")
        print("|---|" + "---:|---:|" * len(names) + "---:|---|")
        for row in rows:
            nat = NATIVE_O0.get(row["workload"])
            cells, sums = [row["workload"]], set()
            for v in names:
                if v not in row:
                    cells += ["-", "-"]
                    continue
                (b_ns, b_sum), (s_ns, s_sum) = row[v]
                sums |= {b_sum, s_sum}
                rb = f" ({b_ns / nat:.1f}x)" if nat else ""
                rs = f" ({s_ns / nat:.1f}x)" if nat else ""
                cells += [f"{b_ns:,.0f}{rb}", f"{s_ns:,.0f}{rs}"]
            cells.append(f"{nat:,}" if nat else "-")
            cells.append(("equal " if len(sums) == 1 else "DIFFER ") + ",".join(map(str, sorted(sums))))
            print("| " + " | ".join(cells) + " |")
        print("\n| workload | variant | cython s | gcc -O2 s | .so KiB |")
        print("|---|---|---:|---:|---:|")
        for wl_name, v, t_cy, t_cc, size in builds:
            print(f"| {wl_name} | {v} | {t_cy:.1f} | {t_cc:.1f} | {size / 1024:,.0f} |")
        if args.probe:
            probe(work)


if __name__ == "__main__":
    main()
