"""Behaviour tests for the example programs in programs/.

Every program runs one task every 20 ms, so the base tick is 20 ms: the
k-th scan runs at PLC time (k-1) * 20 ms and sees the inputs as they are
when it starts. The helpers below express times in milliseconds:

    run_to(plc, ms)   run scans until the next scan is the one at `ms`
    scan_at(plc, ms)  run scans up to and including the one at `ms`
    trace(plc, ms, *paths)
                      run scans up to (not including) `ms`, recording
                      (t_ms, value, ...) after each scan
"""

from pathlib import Path

import pytest

from st import PLC

PROGRAMS = Path(__file__).resolve().parent.parent / "programs"
MS = 1_000_000
TICK_MS = 20


def load(name):
    return PLC.from_files(str(PROGRAMS / name))


def run_to(plc, ms):
    """Run scans until the next scan is the one at `ms` milliseconds."""
    assert plc.time <= ms * MS, "cannot go back in time"
    assert (ms * MS - plc.time) % (TICK_MS * MS) == 0
    n = (ms * MS - plc.time) // (TICK_MS * MS)
    if n:
        plc.scan(n=n)
    assert plc.time == ms * MS


def scan_at(plc, ms):
    """Run scans up to and including the one at `ms`; its results can then be read."""
    run_to(plc, ms)
    plc.scan()


def trace(plc, until_ms, *paths):
    """Scan until the next scan would be at `until_ms`; one row (t_ms, values...) per scan."""
    rows = []
    while plc.time < until_ms * MS:
        t = plc.time // MS
        plc.scan()
        rows.append((t, *(plc[p] for p in paths)))
    return rows


def changes(rows):
    """[(t, value)] for the first row and every row whose value differs from the one before."""
    out = []
    for t, value in rows:
        if not out or out[-1][1] != value:
            out.append((t, value))
    return out


def times_on(rows):
    """The times at which a traced boolean was TRUE."""
    return [t for t, value in rows if value]


# ============================================================================ blink


@pytest.fixture
def blink():
    plc = load("blink.st")
    plc["%IX0.0"] = True  # enable
    return plc


def test_blink_lamp_stays_off_while_disabled():
    plc = load("blink.st")
    rows = trace(plc, 3000, "%QX0.0")
    assert len(rows) == 150
    assert times_on(rows) == []
    assert plc["instance0.flash_count"] == 0


def test_blink_lamp_is_on_from_t0_for_500ms(blink):
    rows = trace(blink, 500, "instance0.lamp")
    assert [t for t, _ in rows] == list(range(0, 500, 20))
    assert all(lamp for _, lamp in rows)
    scan_at(blink, 500)
    assert blink["instance0.lamp"] is False


def test_blink_lamp_is_off_for_500ms_then_on_again(blink):
    run_to(blink, 500)
    rows = trace(blink, 1000, "%QX0.0")
    assert [t for t, _ in rows] == list(range(500, 1000, 20))
    assert times_on(rows) == []
    scan_at(blink, 1000)
    assert blink["%QX0.0"] is True


def test_blink_period_stays_exactly_one_second(blink):
    rows = trace(blink, 10_000, "instance0.lamp")
    assert [lamp for _, lamp in rows] == [t % 1000 < 500 for t, _ in rows]
    assert changes(rows)[-2:] == [(9000, True), (9500, False)]


def test_blink_disable_turns_lamp_off_and_enable_restarts_with_full_on_phase(blink):
    run_to(blink, 300)  # in the on phase
    blink["%IX0.0"] = False
    scan_at(blink, 300)
    assert blink["%QX0.0"] is False
    run_to(blink, 700)  # would have been the off phase
    blink["%IX0.0"] = True
    rows = trace(blink, 2700, "%QX0.0")
    assert changes(rows) == [(700, True), (1200, False), (1700, True), (2200, False)]


def test_blink_counts_flashes(blink):
    blink.advance("2.5s")  # scans at 0 .. 2480 ms: flashes start at 0, 1000 and 2000 ms
    assert blink.time == 2500 * MS
    assert blink["%MW0"] == 3
    assert blink["instance0.flash_counter.CV"] == 3


def test_blink_flash_count_restarts_when_disabled(blink):
    blink.advance("2.5s")
    assert blink["%MW0"] == 3
    blink["%IX0.0"] = False
    blink.scan()
    assert blink["%MW0"] == 0
    blink["%IX0.0"] = True
    blink.scan()
    assert blink["%MW0"] == 1


def test_blink_on_and_off_times_are_adjustable():
    plc = load("blink.st")
    assert plc["instance0.on_time"] == 500 * MS
    plc["instance0.on_time"] = 200 * MS
    plc["instance0.off_time"] = 300 * MS
    plc["%IX0.0"] = True
    rows = trace(plc, 2000, "instance0.lamp")
    assert [lamp for _, lamp in rows] == [t % 500 < 200 for t, _ in rows]


# ============================================================================ traffic light

CAR_RED, CAR_AMBER, CAR_GREEN, DONT_WALK, WALK, WAIT = ("%QX0.0", "%QX0.1", "%QX0.2", "%QX0.3", "%QX0.4", "%QX0.5")
SIGNALS = (CAR_RED, CAR_AMBER, CAR_GREEN, DONT_WALK, WALK)

# (car red, car amber, car green, don't walk, walk) for every phase
LAMPS = {
    "CARS_GREEN": (False, False, True, True, False),
    "CARS_AMBER": (False, True, False, True, False),
    "ALL_RED": (True, False, False, True, False),
    "PED_WALK": (True, False, False, False, True),
    "PED_CLEAR": (True, False, False, True, False),
    "CARS_RED_AMBER": (True, True, False, True, False),
}

# a request pressed at 2 s (during the minimum green) is served at 10 s
CYCLE_FROM_10S = [
    (0, "CARS_GREEN"),
    (10_000, "CARS_AMBER"),
    (13_000, "ALL_RED"),
    (14_000, "PED_WALK"),
    (20_000, "PED_CLEAR"),
    (24_000, "CARS_RED_AMBER"),
    (26_000, "CARS_GREEN"),
]


def press(plc, at_ms, *paths, hold_ms=200):
    """Press the pedestrian button at `at_ms` for `hold_ms`; returns the trace of `paths`
    (default: the phase) from the current time until the button is released."""
    paths = paths or ("instance0.phase",)
    rows = trace(plc, at_ms, *paths)
    plc["%IX0.0"] = True
    rows += trace(plc, at_ms + hold_ms, *paths)
    plc["%IX0.0"] = False
    return rows


@pytest.fixture
def traffic():
    return load("traffic_light.st")


def test_traffic_cars_stay_green_without_request(traffic):
    rows = trace(traffic, 60_000, "instance0.phase", *SIGNALS)
    assert len(rows) == 3000
    assert {row[1:] for row in rows} == {("CARS_GREEN",) + LAMPS["CARS_GREEN"]}


def test_traffic_request_runs_phase_sequence_with_exact_timing(traffic):
    rows = press(traffic, 2000)
    rows += trace(traffic, 40_000, "instance0.phase")
    assert changes(rows) == CYCLE_FROM_10S


def test_traffic_lamps_in_every_phase(traffic):
    press(traffic, 2000)
    seen = {}
    for t, phase in CYCLE_FROM_10S[1:]:
        scan_at(traffic, t)  # the first scan of each phase
        assert traffic["instance0.phase"] == phase
        seen[phase] = tuple(traffic[s] for s in SIGNALS)
    assert seen == LAMPS


def test_traffic_request_after_min_green_is_served_at_once(traffic):
    traffic.advance("20s")
    traffic["%IX0.0"] = True
    traffic.scan()  # the scan at 20 s
    assert traffic["instance0.phase"] == "CARS_AMBER"
    assert traffic[CAR_GREEN] is False
    assert traffic[CAR_AMBER] is True


def test_traffic_wait_lamp_shows_request_until_walk(traffic):
    rows = press(traffic, 2000, WAIT)
    rows += trace(traffic, 16_000, WAIT)
    assert changes(rows) == [(0, False), (2000, True), (14_000, False)]
    assert traffic["instance0.request"] is False


def test_traffic_holding_the_button_gives_one_crossing(traffic):
    traffic["%IX0.0"] = True  # held from power-up for a whole minute
    rows = trace(traffic, 60_000, "instance0.phase")
    assert changes(rows) == CYCLE_FROM_10S
    assert traffic["%MW0"] == 1


def test_traffic_press_during_walk_is_ignored(traffic):
    rows = press(traffic, 2000)
    rows += press(traffic, 16_000)  # pedestrians are already walking
    assert traffic[WAIT] is False
    rows += trace(traffic, 60_000, "instance0.phase")
    assert changes(rows) == CYCLE_FROM_10S
    assert traffic["%MW0"] == 1


def test_traffic_press_during_clearance_is_served_after_next_min_green(traffic):
    rows = press(traffic, 2000)
    rows += press(traffic, 21_000)  # don't walk is already shown
    assert traffic[WAIT] is True
    rows += trace(traffic, 60_000, "instance0.phase")
    assert changes(rows) == CYCLE_FROM_10S + [
        (36_000, "CARS_AMBER"),
        (39_000, "ALL_RED"),
        (40_000, "PED_WALK"),
        (46_000, "PED_CLEAR"),
        (50_000, "CARS_RED_AMBER"),
        (52_000, "CARS_GREEN"),
    ]
    assert traffic["%MW0"] == 2
    assert traffic["instance0.crossing_counter.CV"] == 2


def test_traffic_walk_only_while_cars_have_red(traffic):
    rows = press(traffic, 2000, *SIGNALS)
    rows += press(traffic, 21_000, *SIGNALS)
    rows += press(traffic, 47_000, *SIGNALS)
    rows += trace(traffic, 90_000, *SIGNALS)
    assert len(rows) == 4500
    walk_scans = 0
    for t, red, amber, green, dont_walk, walk in rows:
        assert red or amber or green, t
        assert not (green and (red or amber)), t
        assert walk != dont_walk, t
        if walk:
            walk_scans += 1
            assert red and not amber, t
    assert walk_scans == 3 * 300  # three walk phases of 6 s


# ============================================================================ tank level

PUMP1, PUMP2, LEVEL_ALARM, DRY_RUN = "%QX0.0", "%QX0.1", "%QX0.2", "%QX0.3"


@pytest.fixture
def tank():
    plc = load("tank_level.st")
    plc["%IX0.0"] = True  # auto
    plc["%IX0.1"] = True  # water in the well
    plc["%IW0"] = 5000  # 50.00 %
    plc.scan()
    return plc


def set_level(plc, raw):
    plc["%IW0"] = raw
    plc.scan()
    return plc[PUMP1], plc[PUMP2]


def test_tank_level_is_scaled_to_percent_and_clamped(tank):
    for raw, percent in [(0, 0.0), (2500, 25.0), (5050, 50.5), (10000, 100.0), (-200, 0.0), (12000, 100.0)]:
        set_level(tank, raw)
        assert tank["instance0.level"] == percent, raw


def test_tank_lead_pump_starts_below_low_level_and_stops_above_high_level(tank):
    assert (tank[PUMP1], tank[PUMP2]) == (False, False)
    assert set_level(tank, 4000) == (False, False)  # 40.00 % is not below 40 %
    assert set_level(tank, 3999) == (True, False)
    assert set_level(tank, 6000) == (True, False)  # hysteresis: keeps filling
    assert set_level(tank, 8000) == (True, False)  # 80.00 % is not above 80 %
    assert set_level(tank, 8001) == (False, False)
    assert set_level(tank, 6000) == (False, False)  # hysteresis: stays off
    assert set_level(tank, 4000) == (False, False)


def test_tank_lag_pump_assists_below_low_low_level(tank):
    assert set_level(tank, 3000) == (True, False)
    assert set_level(tank, 2000) == (True, False)
    assert set_level(tank, 1999) == (True, True)
    assert set_level(tank, 5000) == (True, True)
    assert set_level(tank, 8001) == (False, False)


def test_tank_lead_pump_alternates_every_fill_cycle(tank):
    cycles = []
    for _ in range(4):
        lead = set_level(tank, 3000)
        both = set_level(tank, 1500)
        cycles.append((lead, both))
        assert set_level(tank, 9000) == (False, False)
    assert cycles == [
        ((True, False), (True, True)),
        ((False, True), (True, True)),
        ((True, False), (True, True)),
        ((False, True), (True, True)),
    ]
    assert tank["instance0.lead_pump"] == 1


def test_tank_pump_starts_are_counted_in_pump_state(tank):
    for raw in (3000, 9000, 3000, 1500, 9000, 3000, 9000):
        set_level(tank, raw)
    # cycle 1: pump 1; cycle 2: pump 2 lead + pump 1 assist; cycle 3: pump 1
    assert tank["instance0.pumps[1].starts"] == 3
    assert tank["instance0.pumps[2].starts"] == 1
    pump2 = {k.lower(): v for k, v in tank["instance0.pumps[2]"].items()}
    assert pump2 == {"available": True, "demand": False, "running": False, "starts": 1}


def test_tank_standby_pump_takes_over_from_faulted_lead_pump(tank):
    tank["%IX0.2"] = True  # pump 1 motor protection tripped
    assert set_level(tank, 3000) == (False, True)
    assert set_level(tank, 1500) == (False, True)
    assert tank["instance0.pumps[1].available"] is False
    tank["%IX0.2"] = False  # repaired: pump 1 is the lead pump again
    assert set_level(tank, 1500) == (True, True)


def test_tank_dry_run_stops_pumps_and_latches_until_reset(tank):
    assert set_level(tank, 1500) == (True, True)
    tank["%IX0.1"] = False  # the well runs dry
    tank.scan()
    assert (tank[PUMP1], tank[PUMP2], tank[DRY_RUN]) == (False, False, True)
    tank["%IX0.4"] = True  # reset is refused while there is no water
    tank.scan()
    assert (tank[PUMP1], tank[PUMP2], tank[DRY_RUN]) == (False, False, True)
    tank["%IX0.4"] = False
    tank["%IX0.1"] = True  # water is back: still latched
    tank.scan(n=10)
    assert (tank[PUMP1], tank[PUMP2], tank[DRY_RUN]) == (False, False, True)
    tank["%IX0.4"] = True  # reset
    tank.scan()
    assert (tank[PUMP1], tank[PUMP2], tank[DRY_RUN]) == (True, True, False)


def test_tank_auto_off_stops_both_pumps(tank):
    assert set_level(tank, 1500) == (True, True)
    tank["%IX0.0"] = False
    tank.scan()
    assert (tank[PUMP1], tank[PUMP2]) == (False, False)
    tank["%IX0.0"] = True
    tank.scan()
    assert (tank[PUMP1], tank[PUMP2]) == (True, True)


def test_tank_level_alarm_after_5s_delay(tank):
    run_to(tank, 1000)
    tank["%IW0"] = 999  # 9.99 %: below the alarm level
    rows = trace(tank, 7000, LEVEL_ALARM)
    assert changes(rows) == [(1000, False), (6000, True)]
    set_level(tank, 1000)  # 10.00 %: alarm clears at once
    assert tank[LEVEL_ALARM] is False
    run_to(tank, 10_000)
    tank["%IW0"] = 9501  # 95.01 %: above the high alarm level
    rows = trace(tank, 16_000, LEVEL_ALARM)
    assert changes(rows) == [(10_000, False), (15_000, True)]


def test_tank_short_level_dip_gives_no_alarm(tank):
    run_to(tank, 1000)
    tank["%IW0"] = 500
    rows = trace(tank, 5980, LEVEL_ALARM)  # 4.98 s below the alarm level
    tank["%IW0"] = 5000
    rows += trace(tank, 12_000, LEVEL_ALARM)
    assert times_on(rows) == []


def test_tank_stop_level_is_a_configuration_global(tank):
    assert tank["instance0.stop_level"] == 80.0
    tank["instance0.stop_level"] = 60.0
    assert set_level(tank, 3000) == (True, False)
    assert set_level(tank, 6000) == (True, False)
    assert set_level(tank, 6001) == (False, False)


# ============================================================================ conveyor sorter

MOTOR, SMALL_PUSHER, MEDIUM_PUSHER, JAM, BIN_FULL = "%QX0.0", "%QX0.1", "%QX0.2", "%QX0.3", "%QX0.4"


@pytest.fixture
def conveyor():
    plc = load("conveyor_sorter.st")
    plc["%IX0.0"] = True  # run
    return plc


def feed(plc, at_ms, height_mm, block_ms=100):
    """A part of the given height passes the entry eye from `at_ms` for `block_ms`."""
    run_to(plc, at_ms)
    plc["%IW0"] = height_mm
    plc["%IX0.1"] = True
    plc.scan(n=block_ms // TICK_MS)
    plc["%IX0.1"] = False


def test_conveyor_counts_parts_per_size_class(conveyor):
    heights = [30, 75, 120, 49, 50, 99, 100, 10]
    for k, h in enumerate(heights):
        feed(conveyor, 1000 + 500 * k, h)
    scan_at(conveyor, 6000)
    assert [conveyor[a] for a in ("%MW0", "%MW1", "%MW2", "%MW3")] == [8, 3, 3, 2]
    assert conveyor["instance0.class_count"] == [3, 3, 2]
    assert conveyor["instance0.class_counter[2].CV"] == 3
    assert conveyor["instance0.part_class"] == "SMALL"


def test_conveyor_small_part_pushed_by_diverter_1_after_2s(conveyor):
    feed(conveyor, 1000, 30)
    rows = trace(conveyor, 6000, SMALL_PUSHER, MEDIUM_PUSHER)
    assert times_on([(t, s) for t, s, m in rows]) == list(range(3000, 3500, 20))
    assert times_on([(t, m) for t, s, m in rows]) == []


def test_conveyor_medium_part_pushed_by_diverter_2_after_4s(conveyor):
    feed(conveyor, 1000, 75)
    rows = trace(conveyor, 8000, SMALL_PUSHER, MEDIUM_PUSHER)
    assert times_on([(t, s) for t, s, m in rows]) == []
    assert times_on([(t, m) for t, s, m in rows]) == list(range(5000, 5500, 20))


def test_conveyor_large_part_runs_off_the_end(conveyor):
    feed(conveyor, 1000, 120)
    rows = trace(conveyor, 8000, SMALL_PUSHER, MEDIUM_PUSHER)
    assert all(not s and not m for _, s, m in rows)
    assert conveyor["%MW3"] == 1
    assert conveyor["%MW0"] == 1


def test_conveyor_tracks_several_parts_in_transit(conveyor):
    feed(conveyor, 1000, 20)  # small
    feed(conveyor, 1600, 80)  # medium
    feed(conveyor, 2200, 40)  # small
    scan_at(conveyor, 2500)
    assert conveyor["instance0.small_diverter.in_transit"] == 2
    assert conveyor["instance0.medium_diverter.in_transit"] == 1
    rows = trace(conveyor, 8000, SMALL_PUSHER, MEDIUM_PUSHER)
    assert times_on([(t, s) for t, s, m in rows]) == list(range(3000, 3500, 20)) + list(range(4200, 4700, 20))
    assert times_on([(t, m) for t, s, m in rows]) == list(range(5600, 6100, 20))
    assert conveyor["instance0.small_diverter.in_transit"] == 0
    assert conveyor["instance0.small_diverter.overflow"] is False


def test_conveyor_reset_clears_counts(conveyor):
    for k, h in enumerate([30, 75, 120]):
        feed(conveyor, 1000 + 500 * k, h)
    assert conveyor["%MW0"] == 3
    conveyor["%IX0.2"] = True
    conveyor.scan()
    conveyor["%IX0.2"] = False
    assert [conveyor[a] for a in ("%MW0", "%MW1", "%MW2", "%MW3")] == [0, 0, 0, 0]
    assert conveyor["instance0.class_count"] == [0, 0, 0]
    feed(conveyor, 4000, 75)
    conveyor.scan()
    assert [conveyor[a] for a in ("%MW0", "%MW1", "%MW2", "%MW3")] == [1, 0, 1, 0]


def test_conveyor_bin_full_lamp_when_class_reaches_bin_size(conveyor):
    assert conveyor["instance0.bin_size"] == 20
    conveyor["instance0.bin_size"] = 3
    feed(conveyor, 1000, 120)
    feed(conveyor, 2000, 120)
    feed(conveyor, 3000, 30)
    assert conveyor[BIN_FULL] is False
    feed(conveyor, 4000, 120)  # third large part
    assert conveyor[BIN_FULL] is True
    conveyor["%IX0.2"] = True  # bins emptied, counts reset
    conveyor.scan()
    assert conveyor[BIN_FULL] is False


def test_conveyor_jam_stops_belt_until_acknowledged(conveyor):
    run_to(conveyor, 1000)
    conveyor["%IW0"] = 120
    conveyor["%IX0.1"] = True  # a part gets stuck in the entry eye
    rows = trace(conveyor, 5000, MOTOR, JAM)
    assert changes([(t, (m, j)) for t, m, j in rows]) == [(1000, (True, False)), (4000, (False, True))]
    conveyor["%IX0.1"] = False  # operator frees the part
    conveyor.scan()
    assert (conveyor[MOTOR], conveyor[JAM]) == (False, True)
    conveyor["%IX0.3"] = True  # acknowledge
    conveyor.scan()
    assert (conveyor[MOTOR], conveyor[JAM]) == (True, False)
    assert conveyor["%MW0"] == 1  # the stuck part was counted once


def test_conveyor_stopping_the_belt_drops_tracked_parts(conveyor):
    feed(conveyor, 1000, 30)
    feed(conveyor, 1500, 75)
    run_to(conveyor, 2000)
    conveyor["%IX0.0"] = False
    scan_at(conveyor, 2000)
    assert conveyor[MOTOR] is False
    assert conveyor["instance0.small_diverter.in_transit"] == 0
    assert conveyor["instance0.medium_diverter.in_transit"] == 0
    run_to(conveyor, 2500)
    conveyor["%IX0.0"] = True
    rows = trace(conveyor, 8000, SMALL_PUSHER, MEDIUM_PUSHER)
    assert all(not s and not m for _, s, m in rows)
    assert [conveyor["%MW1"], conveyor["%MW2"]] == [1, 1]


def test_conveyor_ignores_parts_while_belt_stopped():
    plc = load("conveyor_sorter.st")
    feed(plc, 1000, 30)
    rows = trace(plc, 5000, MOTOR, SMALL_PUSHER)
    assert all(not m and not s for _, m, s in rows)
    assert plc["%MW0"] == 0
    assert plc["%MW1"] == 0
