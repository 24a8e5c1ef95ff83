"""What object-oriented ST costs per call: ns per call of a FUNCTION, an FB call, a METHOD, a
METHOD through an INTERFACE (and through an interface array), a PROPERTY read and a call through
a REF_TO, each doing the same work (one INT addition into the instance).

    python bench/bench_oop.py [--calls 200] [--scans 2000] [--runs 5]

Each kind is a PROGRAM making --calls calls per scan in a FOR loop; the time per call is the
median over --runs of (scan time - the same loop's scan time with an empty body) / calls. Ratios
are to the plain FB call. Never fails: it prints what it measured and exits 0.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from st import PLC  # noqa: E402
from st.api import compile_text  # noqa: E402

COMMON = """
INTERFACE I_Acc
  METHOD Add : INT VAR_INPUT d : INT; END_VAR END_METHOD
  PROPERTY Total : INT GET END_GET END_PROPERTY
END_INTERFACE
FUNCTION_BLOCK Acc IMPLEMENTS I_Acc
  VAR_INPUT d : INT; END_VAR
  VAR_OUTPUT n : INT; END_VAR
  n := (n + d) MOD 1000;
  METHOD Add : INT
    VAR_INPUT d : INT; END_VAR
    n := (n + d) MOD 1000; Add := n;
  END_METHOD
  PROPERTY Total : INT
    GET Total := n; END_GET
  END_PROPERTY
END_FUNCTION_BLOCK
FUNCTION AddF : INT
  VAR_INPUT a, d : INT; END_VAR
  AddF := (a + d) MOD 1000;
END_FUNCTION
"""

KINDS = {
    "empty loop": "x := x;",
    "FUNCTION": "x := AddF(x, 1);",
    "FB call": "a(d := 1); x := a.n;",
    "METHOD": "x := a.Add(1);",
    "METHOD via interface": "x := it.Add(1);",
    "METHOD via interface array": "x := arr[i MOD 2].Add(1);",
    "PROPERTY read": "x := it.Total;",
    "METHOD via REF_TO": "x := r^.Add(1);",
}


def program(body: str, calls: int) -> str:
    return (
        COMMON
        + f"""
PROGRAM main
  VAR a, b : Acc; it : I_Acc; arr : ARRAY[0..1] OF I_Acc; r : REF_TO Acc; x, i : INT; END_VAR
  it := a; arr[0] := a; arr[1] := b; r := REF(a);
  FOR i := 1 TO {calls} DO
    {body}
  END_FOR;
END_PROGRAM
"""
    )


def scan_ns(src: str, scans: int, runs: int) -> float:
    plc = PLC(compile_text(src, "bench_oop.st"))
    plc.scan(50)
    times = []
    gc.disable()
    try:
        for _ in range(runs):
            t0 = time.perf_counter_ns()
            plc.scan(scans)
            times.append((time.perf_counter_ns() - t0) / scans)
    finally:
        gc.enable()
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--calls", type=int, default=200)
    ap.add_argument("--scans", type=int, default=2000)
    ap.add_argument("--runs", type=int, default=5)
    a = ap.parse_args()
    base = scan_ns(program(KINDS["empty loop"], a.calls), a.scans, a.runs)
    per_call = {
        k: (scan_ns(program(body, a.calls), a.scans, a.runs) - base) / a.calls
        for k, body in KINDS.items()
        if k != "empty loop"
    }
    ref = per_call["FB call"]
    print(
        f"{a.calls} calls per scan, {a.scans} scans, median of {a.runs} runs; "
        f"empty loop {base / a.calls:.0f} ns per iteration"
    )
    print(f"{'kind':28} {'ns/call':>8} {'vs FB call':>11}")
    for k, ns in per_call.items():
        print(f"{k:28} {ns:8.0f} {ns / ref:10.2f}x")


if __name__ == "__main__":
    main()
