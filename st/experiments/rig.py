"""A PLC with its EtherCAT segment on virtual time, as the motion experiments use it: the thesis's
programs from programs/thesis/, their axis file, and a segment configuration that an experiment
may adjust (delays, compensation) before the segment is built."""

from __future__ import annotations

import tomllib
from pathlib import Path

from ..api import compile_paths
from ..facade import PLC
from ..io.ethercat.config import from_dict
from ..io.ethercat.driver import EtherCATDriver
from ..stdlib.plcopen import axis_of, configure_axes

THESIS_DIR = Path(__file__).resolve().parents[2] / "programs" / "thesis"
_COMPILED: dict = {}


def thesis_file(name: str) -> Path:
    p = THESIS_DIR / name
    if not p.exists():
        raise FileNotFoundError(f"{p}: the thesis programs are missing (a checkout of the project is needed)")
    return p


def load_segment_dict(name: str) -> dict:
    with open(thesis_file(name), "rb") as f:
        return tomllib.load(f)


class Rig:
    """One program instance bound to an emulated segment; `scan(n, each=callback)`."""

    def __init__(self, program: str, segment: dict, instance: str, axes_file: str = "axes.toml"):
        path = str(thesis_file(program))
        if path not in _COMPILED:
            _COMPILED[path] = compile_paths([path])
        self.plc = PLC(_COMPILED[path])
        configure_axes(self.plc, str(thesis_file(axes_file)))
        self.driver = EtherCATDriver(self.plc, from_dict(segment, str(thesis_file(program))), backend="sim")
        emulated = self.driver.segment
        assert emulated is not None  # the sim backend's
        self.segment = emulated
        self.instance = instance

    def __getitem__(self, var: str):
        return self.plc[f"{self.instance}.{var}"]

    def __setitem__(self, var: str, value) -> None:
        self.plc[f"{self.instance}.{var}"] = value

    def axis(self, ref: str):
        return axis_of(self.plc, f"{self.instance}.{ref}")

    def drive(self, i: int):
        return self.segment.slaves[i].device

    @property
    def t(self) -> float:
        return self.plc.time / 1e9

    def scan(self, n: int = 1, each=None) -> None:
        if each is None:
            self.plc.scan(n)
            return
        for _ in range(n):
            self.plc.scan()
            each()

    def run_until(self, cond, limit_s: float, each=None) -> bool:
        """Scan until cond() (checked after every scan) or limit_s seconds of PLC time pass."""
        end = self.plc.time + int(limit_s * 1e9)
        while self.plc.time < end:
            self.plc.scan()
            if each is not None:
                each()
            if cond():
                return True
        return False

    def drive_positions_at_one_instant(self):
        """Every drive's position (increments) at the same moment: each drive has been advanced to
        the moment its last frame reached it, so the others are carried to the latest of those
        moments at their current speed."""
        slaves = self.segment.slaves
        tc = max(s.t_dev for s in slaves)
        return [s.device.position + s.device.velocity * (tc - s.t_dev) for s in slaves], tc
