"""The thesis's experiments, reproduced on the emulated EtherCAT segment and st's runtime:
`st experiment NAME [--out DIR] [--quick]` writes CSV files, PNG plots and a Markdown summary.

    single-axis   thesis 6.1: velocity commands, rotate-and-stop cycles with and without PI calibration
    multi-axis    thesis 6.2: offset between two axes versus network delay and acceleration, compensated
    scheduling    thesis 6.3: executions per task under frame / FCFS / RMS, (m,k)-firm utility
    latency       thesis 6.1-6.2: wake-up latency and CPU use in real time beside cyclictest
"""

from __future__ import annotations

import importlib

EXPERIMENTS = {
    "single-axis": ("single_axis", "velocity commands and rotate-and-stop cycles (thesis 6.1, Table 6.1)"),
    "multi-axis": ("multi_axis", "offset between two axes vs delay and acceleration, compensation (6.2, Fig. 6.8-6.9)"),
    "scheduling": ("scheduling", "executions per task under frame / FCFS / RMS, (m,k)-firm utility (6.3, Table 6.5)"),
    "latency": ("latency", "wake-up latency and CPU use for 1-10 axes beside cyclictest (Tables 6.2-6.4)"),
}


def run(name: str, out_dir, quick: bool = False, seed: int = 1):
    """Run one experiment; returns its Report (summary at report.dir / 'summary.md')."""
    if name not in EXPERIMENTS:
        raise KeyError(f"unknown experiment '{name}' (known: {', '.join(EXPERIMENTS)})")
    module = importlib.import_module(f".{EXPERIMENTS[name][0]}", __name__)
    return module.run(out_dir, quick=quick, seed=seed)
