"""Python-side tests of traffic_light.st: the whole CONFIGURATION (one 20 ms task) on virtual time,
driven through the `plc` fixture of st's pytest plugin, plus a hypothesis property."""

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

SOURCE = Path(__file__).with_name("traffic_light.st")


def test_request_is_served_after_minimum_green(plc):
    p = plc(SOURCE)
    p.pulse("instance0.ped_button")  # pressed for one 20 ms scan at t = 0
    assert p["instance0.wait_lamp"] is True
    waited = p.run_until("instance0.car_amber", timeout="11s")
    assert p.time == 10_020_000_000  # amber is set in the scan released at t = 10 s
    assert waited == 10_000_000_000  # from the end of the press scan (t = 20 ms)
    assert p["instance0.phase"] == "CARS_AMBER"


def test_phase_sequence_trace(plc):
    p = plc(SOURCE)
    p.pulse("instance0.ped_button")
    rows = p.trace(["instance0.phase"], "30s")
    changes = [(t, v["instance0.phase"]) for (t, v), (_, prev) in zip(rows[1:], rows) if v != prev]
    # (the time after the scan that changed phase, the new phase)
    assert changes == [
        (10_020_000_000, "CARS_AMBER"),
        (13_020_000_000, "ALL_RED"),
        (14_020_000_000, "PED_WALK"),
        (20_020_000_000, "PED_CLEAR"),
        (24_020_000_000, "CARS_RED_AMBER"),
        (26_020_000_000, "CARS_GREEN"),
    ]
    assert p["%MW0"] == 1  # crossings, as the HMI reads it


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(presses=hs.lists(hs.integers(min_value=0, max_value=60_000), max_size=6))
def test_cars_and_pedestrians_never_both_have_green(plc, presses):
    p = plc(SOURCE)
    press_scans = {t // 20 for t in presses}  # press times in ms → scan numbers
    for scan in range(3000):  # 60 s
        p["instance0.ped_button"] = scan in press_scans
        p.scan()
        car_go = p["instance0.car_green"] or p["instance0.car_amber"] and not p["instance0.car_red"]
        assert not (car_go and p["instance0.walk_signal"])
        assert p["instance0.walk_signal"] != p["instance0.dont_walk_signal"]
