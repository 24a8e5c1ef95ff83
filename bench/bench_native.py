"""st against OpenPLC's native path on the same ST: ns per scan and the ratio, with checksums.

    python bench/bench_native.py --matiec DIR [--scans N] [--workloads NAME ...] [--dir DIR]

DIR is a built MatIEC (OpenPLC's fork: `autoreconf -i && ./configure && make` in a checkout of
github.com/thiagoralves/matiec, outside this repository): its `iec2c` and `lib/`. Each workload
of bench/workloads/ is compiled as OpenPLC v3 compiles a program — `iec2c -f -l -p -r -R -a`,
then `g++ -I lib -c Config0.c` and `Res0.c` without optimisation (its compile_program.sh) — and
again with -O2, linked with a harness that calls `config_run__(tick)` once per tick as OpenPLC's
main loop does (no I/O, no sleeping) and prints ns per call and the workload's checksum (its
`checksum AT %QD0 : DINT`). st runs the same file under the openplc preset on virtual time
(`PLC.scan`, the whole job: latch, body, publish, statistics). The checksums after the same
number of scans must be equal, which shows both computed the same thing.

Without `--matiec` (or `ST_MATIEC`), or without g++, only st's numbers are printed, with a message.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from st import PLC  # noqa: E402
from st.api import compile_paths  # noqa: E402
from st.compiler.native.toolchain import missing  # noqa: E402

WORKLOADS = ROOT / "bench" / "workloads"

HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "iec_types_all.h"
TIME __CURRENT_TIME;
BOOL __DEBUG;
#define __LOCATED_VAR(type, name, ...) type __##name; type *name = &__##name;
#include "LOCATED_VARIABLES.h"
#undef __LOCATED_VAR
void config_init__(void);
void config_run__(unsigned long tick);
extern unsigned long long common_ticktime__;
static long long now_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1000000000LL + t.tv_nsec;
}
int main(int argc, char **argv) {
  long n = argc > 1 ? atol(argv[1]) : 100000;
  config_init__();
  long long t0 = now_ns();
  for (long tick = 0; tick < n; tick++) {
    config_run__(tick);
    __CURRENT_TIME.tv_nsec += common_ticktime__;
    if (__CURRENT_TIME.tv_nsec >= 1000000000) {
      __CURRENT_TIME.tv_nsec -= 1000000000;
      __CURRENT_TIME.tv_sec += 1;
    }
  }
  long long t1 = now_ns();
  printf("%.1f %lld\n", (double)(t1 - t0) / n, (long long)*__QD0);
  return 0;
}
"""


def native_builds(workload: Path, matiec: Path, work: Path) -> dict[str, Path]:
    """The workload built as OpenPLC ships it (-O0) and with -O2: {label: executable}."""
    out = work / workload.stem
    out.mkdir()
    lib = matiec / "lib"
    run = subprocess.run(
        [str(matiec / "iec2c"), "-f", "-l", "-p", "-r", "-R", "-a", "-I", str(lib), str(workload)],
        cwd=out,
        capture_output=True,
        text=True,
    )
    if run.returncode:
        raise RuntimeError(f"iec2c refused {workload.name}: {run.stdout}{run.stderr}")
    (out / "harness.cpp").write_text(HARNESS)
    exes = {}
    for label, opt in (("OpenPLC (as shipped, -O0)", []), ("MatIEC at -O2", ["-O2"])):
        objs = []
        for src in ("Config0.c", "Res0.c"):
            obj = out / f"{src}.{len(opt)}.o"
            subprocess.run(
                ["g++", *opt, "-w", "-I", str(lib / "C"), "-I", str(out), "-c", src, "-o", str(obj)],
                cwd=out,
                check=True,
            )
            objs.append(str(obj))
        exe = out / f"run{len(opt)}"
        subprocess.run(
            ["g++", *opt, "-w", "-I", str(lib / "C"), "-I", str(out), "harness.cpp", *objs, "-o", str(exe)],
            cwd=out,
            check=True,
        )
        exes[label] = exe
    return exes


def native_run(exe: Path, scans: int) -> tuple[float, int]:
    text = subprocess.run([str(exe), str(scans)], capture_output=True, text=True, check=True).stdout.split()
    return float(text[0]), int(text[1])


def st_run(workload: Path, scans: int, native: bool = False) -> tuple[float, int]:
    compiled = compile_paths([str(workload)], dialect="openplc", use_cache=False, native=native)
    if native and not compiled.native and compiled.native_skipped:
        raise RuntimeError(f"{workload.stem}: no body for the native tier ({compiled.native_skipped})")
    plc = PLC(compiled)
    t0 = time.perf_counter()
    plc.scan(scans)
    dt = time.perf_counter() - t0
    return dt / scans * 1e9, int(plc["%QD0"])


def to_signed32(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v >= 1 << 31 else v


def measure(
    matiec: Path | None, scans: int, runs: int, names: list[str] | None = None, where: Path = WORKLOADS
) -> tuple[list[dict], list[str]]:
    """(one row per workload, the native columns' labels): st's ns per scan and checksum, and each
    native build's (ns per scan, checksum) when MatIEC and g++ are there (else no native column)."""
    files = sorted(where.glob("*.st"))
    if names:
        files = [f for f in files if f.stem in names]
    native = matiec is not None and (matiec / "iec2c").exists() and shutil.which("g++") is not None
    tier = missing() is None  # the native tier (st --native) can be built here
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for wl in files:
            st_times, st_sum = [], None
            for _ in range(runs):
                ns, st_sum = st_run(wl, scans)
                st_times.append(ns)
            row = {"workload": wl.stem, "st": statistics.median(st_times), "checksum": to_signed32(st_sum or 0)}
            if tier:
                try:
                    times, sums = zip(*(st_run(wl, scans, native=True) for _ in range(runs)), strict=True)
                    row["st --native"] = (statistics.median(times), to_signed32(sums[0]))
                except RuntimeError:
                    row["st --native"] = None  # nothing to compile: the Python tier's figure holds
            if native:
                assert matiec is not None
                for label, exe in native_builds(wl, matiec, Path(tmp)).items():
                    times, sums = zip(*(native_run(exe, scans) for _ in range(runs)), strict=True)
                    row[label] = (statistics.median(times), to_signed32(sums[0]))
            rows.append(row)
    return rows, (["OpenPLC (as shipped, -O0)", "MatIEC at -O2"] if native else [])


def best_st(row: dict) -> float:
    """st's ns per scan with the faster tier that runs this workload (--native where it compiles)."""
    tier = row.get("st --native")
    return min(row["st"], tier[0]) if tier else row["st"]


def table(rows: list[dict], labels: list[str]) -> str:
    """The rows as a markdown table: ns per scan, st's ratio to each native build, the checksums.
    With the native tier: its column, and the ratios of the faster of st's two tiers."""
    tier = any("st --native" in row for row in rows)
    head = "| workload | st | " + ("st --native | " if tier else "")
    lines = [head + " | ".join(f"{lab} | st / it" for lab in labels) + " | checksums |"]
    # (st / it: the faster tier of st for this workload)
    lines.append("|---|---:|" + ("---:|" if tier else "") + "---:|---:|" * len(labels) + "---|")
    for row in rows:
        cells = [row["workload"], f"{row['st']:,.0f}"]
        same = True
        if tier:
            t = row.get("st --native")
            cells.append(f"{t[0]:,.0f}" if t else "(no loop: Python)")
            same = t is None or t[1] == row["checksum"]
        for lab in labels:
            ns, chk = row[lab]
            cells += [f"{ns:,.0f}", f"{best_st(row) / ns:,.1f}x"]
            same = same and chk == row["checksum"]
        cells.append(
            ("equal" if same else "DIFFER") + f" ({row['checksum']})" if labels or tier else str(row["checksum"])
        )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--matiec", type=Path, default=os.environ.get("ST_MATIEC"), help="a built MatIEC (iec2c, lib/)")
    ap.add_argument("--scans", type=int, default=20000, help="scans per run (the checksums are compared after them)")
    ap.add_argument("--runs", type=int, default=3, help="runs of each; the median is shown")
    ap.add_argument("--workloads", nargs="*", default=None, help="names in bench/workloads (default: all)")
    ap.add_argument(
        "--dir",
        type=Path,
        default=WORKLOADS,
        help="another directory of workloads (each a program with a `checksum AT %%QD0 : DINT`)",
    )
    args = ap.parse_args()
    rows, labels = measure(args.matiec, args.scans, args.runs, args.workloads, args.dir)
    if not labels:
        print("no MatIEC build (--matiec DIR or ST_MATIEC) or no g++: st's numbers only\n")
    print(f"{args.scans} scans per run, median of {args.runs}; ns per scan\n")
    print(table(rows, labels))


if __name__ == "__main__":
    main()
