"""What an online change costs the running scan, by the size of the data it carries (issue 32).

    python bench/bench_online_change.py [--sizes 1e5,1e6,1e7] [--cycle 10ms] [--seconds 4]

A PROGRAM with `buf : ARRAY[0..N-1] OF LREAL` (and an array of N/100 structures) runs in real
time on a 10 ms task under `st run --watch`'s Watcher; one second in, the file is edited: the
change is compiled and prepared in a background thread and swapped in at a scan boundary. Two edits: a constant changed
elsewhere (every array carried over), and the LREAL array removed. Printed per size and edit: the
time the swap held the scan (apply_change), the longest start-to-start period of the task from the
edit on (the stall as the task saw it, against its 10 ms) and before the edit (the machine's own
noise), overruns and skipped releases, and how long the change took from the edit to the swap
(building beside the running scan).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import tempfile
import time
from pathlib import Path

from st import PLC
from st.api import compile_paths
from st.app.options import RunOptions
from st.app.watch import Watcher

SOURCE = """
TYPE Rec : STRUCT a : DINT; b : LREAL; END_STRUCT; END_TYPE
PROGRAM main
  VAR
    buf : ARRAY[0..{last}] OF LREAL;
    recs : ARRAY[0..{last_rec}] OF Rec;
    k : DINT;
    x : LREAL;
  END_VAR
  k := k + 1;
  {use_buf}
  recs[k MOD {n_rec}].a := k;
  x := {constant};
END_PROGRAM
"""


def source(n: int, constant: str, keep_buf: bool = True) -> str:
    n_rec = max(n // 100, 1)
    text = SOURCE.format(
        last=n - 1, last_rec=n_rec - 1, n_rec=n_rec, constant=constant, use_buf=f"buf[k MOD {n}] := k;"
    )
    if not keep_buf:
        text = text.replace(f"    buf : ARRAY[0..{n - 1}] OF LREAL;\n", "").replace(f"  buf[k MOD {n}] := k;\n", "")
    return text


def measure(n: int, edit: str, cycle: str, seconds: float, folder: Path) -> dict:
    """One real-time run with `st run --watch`'s Watcher; the edit written to the file one second in."""
    path = folder / f"online_{n}_{edit}.st"
    path.write_text(source(n, "1.0"))
    plc = PLC(compile_paths([str(path)], use_cache=False), cycle=cycle)
    watcher = Watcher(plc, RunOptions(files=[str(path)]))
    new_text = source(n, "2.0", keep_buf=(edit == "constant"))
    state: dict = {"swap_ms": None, "t_edit": None, "t_swap": None, "periods_before": 0}
    apply = plc.apply_change

    def timed_apply(change):
        t0 = time.perf_counter()
        try:
            return apply(change)
        finally:
            state["swap_ms"] = (time.perf_counter() - t0) * 1e3
            state["t_swap"] = time.monotonic()

    plc.apply_change = timed_apply  # type: ignore[method-assign]
    started = time.monotonic()

    def on_idle(p):
        now = time.monotonic()
        if state["t_edit"] is None and now - started > 1.0:
            state["t_edit"] = now
            state["periods_before"] = len(p.tasks[0].stats.periods)
            path.write_text(new_text)
            os.utime(path, ns=(time.time_ns(), time.time_ns() + 1_000_000_000))  # a new mtime, surely
        watcher.poll()

    with contextlib.redirect_stderr(io.StringIO()):  # the watcher's "online change: …" line
        plc.run_realtime(duration=f"{seconds}s", on_idle=on_idle)
    st = plc.tasks[0].stats
    periods = list(st.periods)
    summary = st.summary()
    return {
        "n": n,
        "edit": edit,
        "swap_ms": state["swap_ms"],
        "longest_period_ms": max(periods[state["periods_before"] :], default=0) / 1e6,
        "longest_before_ms": max(periods[: state["periods_before"]], default=0) / 1e6,
        "overruns": summary["overruns"],
        "skipped": summary["skipped"],
        "edit_to_swap_s": (state["t_swap"] - state["t_edit"]) if state["t_swap"] and state["t_edit"] else None,
        "changed": plc["main.x"] == 2.0,
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="1e5,1e6,1e7")
    ap.add_argument("--cycle", default="10ms")
    ap.add_argument("--seconds", type=float, default=4.0)
    args = ap.parse_args()
    print(f"{'elements':>10} {'edit':>9} {'swap ms':>9} {'longest period ms':>18} {'(before the edit)':>18} "
          f"{'overruns':>9} {'skipped':>8} {'edit→swap s':>12}")  # fmt: skip
    folder = Path(tempfile.mkdtemp(prefix="st-online-"))
    for size in args.sizes.split(","):
        n = int(float(size))
        for edit in ("constant", "remove"):
            r = measure(n, edit, args.cycle, args.seconds, folder)
            swap = f"{r['swap_ms']:.2f}" if r["swap_ms"] is not None else "-"
            e2s = f"{r['edit_to_swap_s']:.2f}" if r["edit_to_swap_s"] is not None else "-"
            print(
                f"{n:>10} {edit:>9} {swap:>9} {r['longest_period_ms']:>18.2f} {r['longest_before_ms']:>18.2f} "
                f"{r['overruns']:>9} {r['skipped']:>8} "
                f"{e2s:>12}" + ("" if r["changed"] else "  (the change did not happen)")
            )


if __name__ == "__main__":
    main()
