"""struckig (ruckig's trajectory generator ported to TwinCAT ST) run by st computes what the ruckig
package computes for the same inputs: the same duration and the same states at sampled times
(issue 34). The struckig repository is read outside the tree, as the conformance sweep reads it:
the test is skipped, with the reason, where it is absent."""

from __future__ import annotations

import math
import os
import random
from pathlib import Path

import pytest

ruckig = pytest.importorskip("ruckig")

CORPORA = Path(os.environ.get("ST_CORPORA", "/work/scratch/corpora"))
LIBRARY = CORPORA / "stefanbesler-struckig" / "Struckig" / "Struckig" / "Struckig" / "Struckig.plcproj"

pytestmark = pytest.mark.skipif(
    not LIBRARY.exists(), reason=f"struckig is not checked out at {LIBRARY} (set ST_CORPORA to the corpora folder)"
)

SAMPLES = 11
MAIN = f"""
PROGRAM MAIN
VAR
  otg : Struckig.Otg1(0.001);
  duration : LREAL;
  t, p, v, a, j : ARRAY[0..{SAMPLES - 1}] OF LREAL;
  i : INT;
  otg3 : Struckig.Otg(cycletime := 0.001, dofs := 3);
  duration3 : LREAL;
  t3 : ARRAY[0..{SAMPLES - 1}] OF LREAL;
  p3, v3, a3, j3 : ARRAY[0..{SAMPLES - 1}, 0..2] OF LREAL;
  section : INT;
END_VAR
otg();
duration := otg.Duration;
FOR i := 0 TO {SAMPLES - 1} DO
  t[i] := duration * i / {SAMPLES - 1};
  otg.AtTime1(t[i], p[i], v[i], a[i], j[i]);
END_FOR
otg3();
duration3 := otg3.Duration;
FOR i := 0 TO {SAMPLES - 1} DO
  t3[i] := duration3 * i / {SAMPLES - 1};
  otg3.AtTime(t3[i], ADR(p3[i, 0]), ADR(v3[i, 0]), ADR(a3[i, 0]), ADR(j3[i, 0]), ADR(section));
END_FOR
END_PROGRAM
"""


@pytest.fixture(scope="module")
def plc(tmp_path_factory):
    from st import PLC
    from st.api import compile_paths

    main = tmp_path_factory.mktemp("struckig") / "main.st"
    main.write_text(MAIN)
    return PLC(compile_paths([str(LIBRARY), str(main)], dialect="twincat"))


def _cases(n: int, seed: int) -> list[dict[str, float]]:
    """Random 1-DoF problems within ruckig's usual ranges: a state at rest or moving, limits > 0."""
    rnd = random.Random(seed)
    out = []
    for _ in range(n):
        out.append(
            {
                "CurrentPosition": rnd.uniform(-2, 2),
                "CurrentVelocity": rnd.choice([0.0, rnd.uniform(-0.5, 0.5)]),
                "CurrentAcceleration": rnd.choice([0.0, rnd.uniform(-0.5, 0.5)]),
                "TargetPosition": rnd.uniform(-2, 2),
                "TargetVelocity": rnd.choice([0.0, rnd.uniform(-0.3, 0.3)]),
                "TargetAcceleration": 0.0,
                "MaxVelocity": rnd.uniform(0.5, 2.0),
                "MaxAcceleration": rnd.uniform(0.5, 3.0),
                "MaxJerk": rnd.uniform(1.0, 10.0),
            }
        )
    return out


def _ruckig(*cases: dict[str, float]):
    """ruckig's trajectory for one DoF per case (time-synchronized, its default, as struckig's Otg)."""
    n = len(cases)
    inp = ruckig.InputParameter(n)
    for name, attr in (
        ("CurrentPosition", "current_position"),
        ("CurrentVelocity", "current_velocity"),
        ("CurrentAcceleration", "current_acceleration"),
        ("TargetPosition", "target_position"),
        ("TargetVelocity", "target_velocity"),
        ("TargetAcceleration", "target_acceleration"),
        ("MaxVelocity", "max_velocity"),
        ("MaxAcceleration", "max_acceleration"),
        ("MaxJerk", "max_jerk"),
    ):
        setattr(inp, attr, [c[name] for c in cases])
    traj = ruckig.Trajectory(n)
    result = ruckig.Ruckig(n).calculate(inp, traj)
    return result, traj


def _close(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-9)


@pytest.mark.parametrize(
    "case", _cases(30, 34), ids=lambda c: f"p{c['CurrentPosition']:+.2f}->{c['TargetPosition']:+.2f}"
)
def test_struckig_and_ruckig_compute_the_same_trajectory(plc, case):
    result, traj = _ruckig(case)
    assert result in (ruckig.Result.Working, ruckig.Result.Finished)
    for name, value in case.items():
        plc[f"MAIN.otg.{name}"] = value
    plc.scan(1)
    assert _close(plc["MAIN.duration"], traj.duration), (plc["MAIN.duration"], traj.duration)
    for i in range(SAMPLES):
        t = plc["MAIN.t"][i]
        pos, vel, acc = traj.at_time(t)
        got = (plc["MAIN.p"][i], plc["MAIN.v"][i], plc["MAIN.a"][i])
        assert all(_close(g, w[0]) for g, w in zip(got, (pos, vel, acc), strict=True)), (t, got, (pos, vel, acc))


@pytest.mark.parametrize("seed", range(12))
def test_struckig_and_ruckig_synchronize_three_dofs_alike(plc, seed):
    cases = _cases(3, 1000 + seed)
    result, traj = _ruckig(*cases)
    assert result in (ruckig.Result.Working, ruckig.Result.Finished)
    for dof, case in enumerate(cases):
        for name, value in case.items():
            plc[f"MAIN.otg3.{name}[{dof}]"] = value
    plc.scan(1)
    assert _close(plc["MAIN.duration3"], traj.duration), (plc["MAIN.duration3"], traj.duration)
    for i in range(SAMPLES):
        t = plc["MAIN.t3"][i]
        pos, vel, acc = traj.at_time(t)
        for dof in range(3):
            got = (plc["MAIN.p3"][i][dof], plc["MAIN.v3"][i][dof], plc["MAIN.a3"][i][dof])
            want = (pos[dof], vel[dof], acc[dof])
            assert all(_close(g, w) for g, w in zip(got, want, strict=True)), (t, dof, got, want)
