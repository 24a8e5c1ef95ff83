"""Axis traces: set and actual position, velocity and acceleration per kernel cycle, as CSV and a plot.

`st run prog.st --trace main.axis1 --trace-plot motion.png` records every cycle of the axis
behind the AXIS_REF `main.axis1` and, when the run ends, writes `motion.csv` and draws
position, velocity and acceleration over time (matplotlib).
"""

from __future__ import annotations

import csv
from typing import TYPE_CHECKING

from . import registry

if TYPE_CHECKING:
    from .axis import Axis

MAX_SAMPLES = 2_000_000


class AxisTrace:
    def __init__(self, plc, path: str):
        self.plc = plc
        self.path = path
        self._axis: Axis | None = None
        self.rows: list = []  # (t, set_pos, set_vel, set_acc, act_pos, act_vel, state)

    @property
    def axis(self):
        """The traced Axis, once the program has used its AXIS_REF (an FB call assigns the handle)."""
        if self._axis is None:
            ref = self.plc.ref(self.path).get()
            reg = registry(self.plc)
            if reg is not None and getattr(ref, "Handle", 0) in reg.axes:
                self._axis = reg.axes[ref.Handle]
        return self._axis

    def sample(self) -> None:
        ax = self._axis
        assert ax is not None  # sampled once `axis` has found it (MotionRegistry.after_job)
        if len(self.rows) < MAX_SAMPLES:
            self.rows.append(
                (self.plc.time / 1e9, ax.set_pos, ax.set_vel, ax.set_acc, ax.act_pos, ax.act_vel, ax.state)
            )


def start_traces(plc, paths: list) -> list:
    """Trace the axes behind these AXIS_REF paths; raises KeyError/TypeError with a clear message."""
    reg = registry(plc)
    if reg is None:
        raise KeyError("--trace: the program uses no PLCopen motion block")
    out = []
    for p in paths:
        t = plc.ref(p).type
        if getattr(t, "name", "").upper() != "AXIS_REF":
            raise TypeError(f"--trace {p}: not an AXIS_REF (it is {t})")
        tr = AxisTrace(plc, p)
        reg.traces.append(tr)
        reg.wake()
        out.append(tr)
    return out


def write_csv(traces: list, path: str) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "time_s",
                "axis",
                "set_position",
                "set_velocity",
                "set_acceleration",
                "actual_position",
                "actual_velocity",
                "state",
            ]
        )
        for tr in traces:
            for row in tr.rows:
                w.writerow([f"{row[0]:.6f}", tr.path, *(f"{x:.9g}" for x in row[1:6]), row[6]])


def plot(traces: list, path: str, title: str | None = None) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise RuntimeError("--trace-plot needs matplotlib: pip install 'st-plc[plot]'") from None
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    for tr in traces:
        if not tr.rows:
            continue
        t = [r[0] for r in tr.rows]
        axes[0].plot(t, [r[1] for r in tr.rows], label=f"{tr.path} set")
        if any(r[4] != r[1] for r in tr.rows):
            axes[0].plot(t, [r[4] for r in tr.rows], "--", label=f"{tr.path} actual")
        axes[1].plot(t, [r[2] for r in tr.rows], label=tr.path)
        axes[2].plot(t, [r[3] for r in tr.rows], label=tr.path)
    for a, label in zip(axes, ("position [u]", "velocity [u/s]", "acceleration [u/s²]")):
        a.set_ylabel(label)
        a.grid(True, alpha=0.3)
    axes[0].legend(loc="best", fontsize="small")
    axes[2].set_xlabel("PLC time [s]")
    axes[0].set_title(title or "axis trace")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
