"""EtherCAT benchmark: the emulator's cost per frame and a 4-axis program on the `sim` backend.

    python bench/bench_ethercat.py [--seconds 10] [--runs 3]

1. Per frame: the process-data frame (LRW of the whole image + FRMW of the DC time) through
   FrameMaster and the emulated segment with 1, 4 and 16 CiA 402 drives in OP, drives enabled
   and following a ramp: µs per frame, split into the master's frame work, the slave
   controllers and the drive models (each measured by leaving the later parts out).
2. Scans per second: a 4-axis ST program (MC_Power, MC_MoveAbsolute back and forth, status and
   position reads per axis) bound to 4 emulated drives with DC, on virtual time at a 1 ms task,
   for `--seconds` of PLC time: scans per wall second and the ratio to real time (goal ≥ 10×).
Never fails: it prints what it measured and exits 0.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import sys
import tempfile
import time

from st import PLC
from st.api import compile_text
from st.io.ethercat.config import build_segment, from_dict
from st.io.ethercat.driver import EtherCATDriver
from st.io.ethercat.master import FrameMaster
from st.io.ethercat.pdo import CIA402_RX, PdoLayout
from st.stdlib.plcopen import configure_axes

GOAL_RATIO = 10.0


def segment_cfg(n: int, dio: bool = False) -> dict:
    slaves = [{"name": f"d{i + 1}", "type": "cia402", "axis": i + 1} for i in range(n)]
    if dio:
        slaves.append({"name": "io", "type": "dio", "inputs_at": "%IX0.0", "outputs_at": "%QX0.0"})
    return {"segment": {"cycle": "1ms", "dc": True}, "slave": slaves}


def per_frame_us(n: int, frames: int, runs: int):
    """(total, without drive physics, master only) µs per process-data frame."""
    results = {"total": [], "no_physics": [], "master": []}
    for _ in range(runs):
        seg = build_segment(from_dict(segment_cfg(n)))
        clock = [0.0]

        def transport(frame, seg=seg, clock=clock):
            return seg.exchange(frame, clock[0])

        m = FrameMaster(
            transport,
            pause=lambda s, clock=clock: clock.__setitem__(0, clock[0] + s),
            now_ns=lambda clock=clock: int(clock[0] * 1e9),
        )
        m.scan()
        m.configure(dc_cycle_ns=1_000_000)
        m.set_state("OP")
        rx = PdoLayout(CIA402_RX)
        # enable every drive: 0x06, 0x07, 0x0F, a few cycles each, once SYNC0 runs (the drives take
        # their outputs on its pulses, which start 10 cycles after the DC setup)
        for cw in (0x00,) * 4 + (0x06, 0x07, 0x0F, 0x0F, 0x0F):
            for _ in range(3):
                clock[0] += 0.001
                for i in range(n):
                    m.write_outputs(i, rx.pack([cw, 0, 0, 8]))
                m.exchange()
        states = {s.device.state_name for s in seg.slaves}
        if states != {"OPERATION_ENABLED"}:
            print(f"  (warning: the drives are {sorted(states)}, not enabled)")
        gc.disable()
        t0 = time.perf_counter()
        for k in range(frames):
            clock[0] += 0.001
            for i in range(n):
                m.write_outputs(i, rx.pack([0x0F, 20 * k, 0, 8]))
            m.exchange()
        results["total"].append((time.perf_counter() - t0) / frames * 1e6)
        # the same frames with the drive physics left out (the devices do not step)
        steps = [s.device.step for s in seg.slaves]
        for s in seg.slaves:
            s.device.step = lambda t, dt: None
        t0 = time.perf_counter()
        for _ in range(frames):
            clock[0] += 0.001
            m.exchange()
        results["no_physics"].append((time.perf_counter() - t0) / frames * 1e6)
        for s, st in zip(seg.slaves, steps):
            s.device.step = st
        # the master's frame work alone: encode and decode without a segment behind it
        m.transport = lambda frame: frame
        t0 = time.perf_counter()
        for _ in range(frames):
            m.exchange()
        results["master"].append((time.perf_counter() - t0) / frames * 1e6)
        gc.enable()
    return {k: statistics.median(v) for k, v in results.items()}


PROGRAM = """
PROGRAM main
  VAR
{decl}
    t : TON; go : BOOL; strokes : DINT;
  END_VAR
  t(IN := NOT t.Q, PT := T#400ms);
  IF t.Q THEN go := NOT go; strokes := strokes + 1; END_IF;
{body}
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK motion (INTERVAL := T#1ms, PRIORITY := 1);
  PROGRAM main WITH motion : main;
END_RESOURCE END_CONFIGURATION
"""


def program(n: int) -> str:
    decl, body = [], []
    for i in range(1, n + 1):
        decl.append(
            f"    ax{i} : AXIS_REF := (AxisNo := {i}); pw{i} : MC_Power; mv{i} : MC_MoveAbsolute;"
            f" rs{i} : MC_ReadStatus; rp{i} : MC_ReadActualPosition; pos{i} : LREAL;"
        )
        body += [
            f"  pw{i}(Axis := ax{i}, Enable := TRUE);",
            f"  mv{i}(Axis := ax{i}, Execute := t.Q AND pw{i}.Status, Position := SEL(go, 0.0, 90.0),"
            f" Velocity := 720.0, Acceleration := 7200.0, Deceleration := 7200.0);",
            f"  rs{i}(Axis := ax{i}, Enable := TRUE);",
            f"  rp{i}(Axis := ax{i}, Enable := TRUE);",
            f"  pos{i} := rp{i}.Position;",
        ]
    return PROGRAM.format(decl="\n".join(decl), body="\n".join(body))


def scans_per_second(n: int, seconds: float, runs: int):
    results = []
    final = None
    for _ in range(runs):
        plc = PLC(compile_text(program(n), f"bench_ethercat_{n}.st"))
        configure_axes(plc, {i: {"following_error_window": 5.0} for i in range(1, n + 1)})
        drv = EtherCATDriver(plc, from_dict(segment_cfg(n)), backend="sim")
        plc.scan(200)  # enable sequence, first moves
        scans = int(seconds * 1000)
        gc.collect()
        t0 = time.perf_counter()
        plc.scan(scans)
        wall = time.perf_counter() - t0
        results.append(scans / wall)
        final = (plc["main.strokes"], [round(plc[f"main.pos{i}"], 3) for i in range(1, n + 1)], drv.stats())
    return statistics.median(results), final


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--frames", type=int, default=2000)
    a = ap.parse_args()
    print("Emulator cost per process-data frame (LRW + FRMW), drives enabled and following a ramp")
    print(f"{'drives':>7} {'µs/frame':>9} {'without physics':>16} {'master only':>12} {'physics µs/drive':>17}")
    for n in (1, 4, 16):
        r = per_frame_us(n, a.frames if n < 16 else a.frames // 4, a.runs)
        print(
            f"{n:>7} {r['total']:>9.1f} {r['no_physics']:>16.1f} {r['master']:>12.1f} "
            f"{(r['total'] - r['no_physics']) / n:>17.1f}"
        )
    n = 4
    sps, (strokes, pos, stats) = scans_per_second(n, a.seconds, a.runs)
    print(f"\n{n}-axis program on the sim backend, 1 ms task, {a.seconds:g} s of PLC time, median of {a.runs}")
    print(
        f"  {sps:,.0f} scans/s = {sps / 1000:.1f}× real time (goal ≥ {GOAL_RATIO:g}×: "
        f"{'met' if sps / 1000 >= GOAL_RATIO else 'missed'})"
    )
    print(
        f"  strokes {strokes}, final positions {pos}, frames {stats['frames']}, lost {stats['lost_frames']}, "
        f"wkc errors {stats['wkc_errors']}"
    )


if __name__ == "__main__":
    os.environ.setdefault("ST_CACHE_DIR", tempfile.mkdtemp())
    sys.exit(main())
