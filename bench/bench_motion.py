"""Motion benchmark: cost of the PLCopen kernel per axis per cycle, of planning, and of a whole scan.

    python bench/bench_motion.py [--cycles 2000] [--runs 5]

1. Kernel: N axes (1, 10, 100) each in the middle of a long move, jerk 0 (exact trapezoid) and
   jerk > 0 (ruckig); `Axis.step()` for every axis, `--cycles` times; µs per axis per cycle
   (median of `--runs`), against the goal of 20 µs.
2. Planning: µs to plan one command from a moving state (MoveAbsolute with Aborting), both profiles.
3. Whole scan: an ST program with N axes, each with MC_Power, MC_MoveAbsolute back and forth,
   MC_ReadStatus and MC_ReadActualPosition, on virtual time at 1 ms; µs per scan and per axis.
   The same program without the motion blocks gives the ST part's cost.
Never fails: it prints what it measured and exits 0.
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time

from st import PLC
from st.api import compile_text
from st.stdlib.plcopen.axis import Axis, AxisConfig

GOAL_US = 20.0
CYCLE = 0.001


def _moving_axes(n: int, jerk: float) -> list:
    """n axes in DiscreteMotion on a move long enough to outlast the measurement."""
    axes = []
    for i in range(n):
        ax = Axis(i + 1, AxisConfig(name=f"axis{i + 1}"))
        ax.cycle = CYCLE
        ax.power(1, True)
        cmd = ax.new_command(
            "move_abs", {"pos": 1e6, "vel": 100.0 + i, "acc": 1000.0, "dec": 1000.0, "jerk": jerk, "dir": 0}
        )
        ax.submit(cmd)
        for _ in range(50):  # into the profile: accelerating, then cruising
            ax.step()
        axes.append(ax)
    return axes


def kernel_us(n: int, jerk: float, cycles: int, runs: int) -> float:
    results = []
    for _ in range(runs):
        axes = _moving_axes(n, jerk)
        steps = [ax.step for ax in axes]
        gc.disable()
        t0 = time.perf_counter()
        for _ in range(cycles):
            for s in steps:
                s()
        t = time.perf_counter() - t0
        gc.enable()
        results.append(t / (cycles * n) * 1e6)
    return statistics.median(results)


def planning_us(jerk: float, runs: int, n: int = 300) -> float:
    results = []
    for _ in range(runs):
        ax = _moving_axes(1, jerk)[0]
        t0 = time.perf_counter()
        for i in range(n):
            cmd = ax.new_command(
                "move_abs", {"pos": 500.0 + (i % 7), "vel": 80.0, "acc": 900.0, "dec": 700.0, "jerk": jerk, "dir": 0}
            )
            ax.submit(cmd)
            ax.forget(cmd.id)
        results.append((time.perf_counter() - t0) / n * 1e6)
    return statistics.median(results)


def program(n: int, motion: bool = True) -> str:
    v = ["PROGRAM main", "  VAR", "    t : TON; go : BOOL;"]
    body = ["  t(IN := NOT t.Q, PT := T#500ms);", "  IF t.Q THEN go := NOT go; END_IF;"]
    for i in range(1, n + 1):
        if motion:
            v.append(
                f"    ax{i} : AXIS_REF := (AxisNo := {i}); pw{i} : MC_Power; mv{i} : MC_MoveAbsolute;"
                f" rs{i} : MC_ReadStatus; rp{i} : MC_ReadActualPosition; pos{i} : LREAL;"
            )
            body += [
                f"  pw{i}(Axis := ax{i}, Enable := TRUE);",
                f"  mv{i}(Axis := ax{i}, Execute := t.Q, Position := SEL(go, 0.0, 100.0), Velocity := 400.0,"
                f" Acceleration := 4000.0, Deceleration := 4000.0);",
                f"  rs{i}(Axis := ax{i}, Enable := TRUE);",
                f"  rp{i}(Axis := ax{i}, Enable := TRUE);",
                f"  pos{i} := rp{i}.Position;",
            ]
        else:
            v.append(f"    pos{i} : LREAL; b{i} : BOOL;")
            body += [f"  b{i} := t.Q;", f"  pos{i} := SEL(go, 0.0, 100.0);"]
    v.append("  END_VAR")
    return (
        "\n".join(
            v
            + body
            + [
                "END_PROGRAM",
                "CONFIGURATION c RESOURCE r ON PLC",
                "  TASK tk (INTERVAL := T#1ms, PRIORITY := 1);",
                "  PROGRAM main WITH tk : main;",
                "END_RESOURCE END_CONFIGURATION",
            ]
        )
        + "\n"
    )


def scan_us(n: int, cycles: int, runs: int, motion: bool = True) -> float:
    plc = PLC(compile_text(program(n, motion), f"bench_motion_{n}.st"))
    plc.scan(600)  # powered, first moves under way
    results = []
    for _ in range(runs):
        gc.disable()
        t0 = time.perf_counter()
        plc.scan(cycles)
        t = time.perf_counter() - t0
        gc.enable()
        results.append(t / cycles * 1e6)
    if motion:
        from st.stdlib.plcopen import axis_of

        assert axis_of(plc, "main.ax1").state in ("DiscreteMotion", "Standstill")
    return statistics.median(results)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=2000)
    ap.add_argument("--runs", type=int, default=5)
    a = ap.parse_args()

    print(f"Kernel: Axis.step() per axis per cycle, median of {a.runs} × {a.cycles} cycles (goal < {GOAL_US:g} µs)")
    print(f"{'axes':>6} {'profile':>10} {'µs/axis/cycle':>14} {'ratio to goal':>14}")
    for jerk, name in ((0.0, "trapezoid"), (1e5, "ruckig")):
        for n in (1, 10, 100):
            cycles = max(200, a.cycles // max(1, n // 10))
            us = kernel_us(n, jerk, cycles, a.runs)
            print(f"{n:>6} {name:>10} {us:>14.2f} {us / GOAL_US:>14.2f}")

    print("\nPlanning one Aborting MoveAbsolute from a moving state (µs per command)")
    for jerk, name in ((0.0, "trapezoid"), (1e5, "ruckig")):
        print(f"{name:>10} {planning_us(jerk, a.runs):>10.1f}")

    print(f"\nWhole scan on virtual time at 1 ms, median of {a.runs} × {a.cycles} scans")
    print(f"{'axes':>6} {'µs/scan':>9} {'without motion':>15} {'motion µs/axis':>15}")
    for n in (1, 10, 100):
        cycles = max(200, a.cycles // max(1, n // 10))
        with_m = scan_us(n, cycles, a.runs, True)
        without = scan_us(n, cycles, a.runs, False)
        print(f"{n:>6} {with_m:>9.1f} {without:>15.1f} {(with_m - without) / n:>15.2f}")


if __name__ == "__main__":
    main()
