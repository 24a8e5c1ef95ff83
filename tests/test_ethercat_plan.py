"""EtherCAT segment timing (st.io.ethercat.plan) and the ESI reader (st.io.ethercat.esi).

Every expected number is worked out by hand in the comments. Frame rule: Ethernet header 14 +
EtherCAT header 2 + per datagram (10 + data + 2), padded to 60, + FCS 4; on the wire + 8 preamble/SFD
+ 12 inter-frame gap; 8 bits per byte at 100 Mbit/s = 0.08 µs per byte.
"""

from pathlib import Path

import pytest

from st.io.ethercat.esi import EsiError, load_esi, parse_esi, parse_number
from st.io.ethercat.pdo import CIA402_RX, CIA402_TX, PdoLayout
from st.io.ethercat.plan import DriveTiming, SegmentTiming, SlaveTiming, format_plan, frame_bytes, plan, wire_time_s

ESI = Path(__file__).parent / "data" / "esi"
US = 1e-6


def drives(n, **kw):
    """n CiA 402 drives with the default mapping: 11 bytes out, 12 bytes in."""
    return [SlaveTiming(f"axis{i + 1}", 11, 12, is_drive=True, **kw) for i in range(n)]


def approx(x):
    return pytest.approx(x, rel=1e-9, abs=1e-12)


# ---------------------------------------------------------------- frame_bytes


def test_frame_bytes_one_drive_with_dc():
    # LRW 23 + FRMW 8: 14 + 2 + (10+23+2) + (10+8+2) = 71 before the FCS; 71 + 4 + 8 + 12 = 95
    assert frame_bytes([23, 8]) == (71, 95)
    assert wire_time_s(95) == approx(7.6 * US)  # 95 * 8 / 100e6


def test_frame_bytes_pads_to_the_ethernet_minimum():
    # LRW 2: 14 + 2 + 14 = 30 → padded to 60; on the wire 60 + 4 + 8 + 12 = 84 (6.72 µs)
    assert frame_bytes([2]) == (60, 84)
    assert frame_bytes([]) == (60, 84)
    # LRW 32: 14 + 2 + 44 = 60 exactly; 31 is padded by one byte; 33 is past the minimum
    assert frame_bytes([32]) == (60, 84)
    assert frame_bytes([31]) == (60, 84)
    assert frame_bytes([33]) == (61, 85)


def test_frame_bytes_largest_frame():
    # 1498 bytes of datagrams at most: one LRW of 1486, or LRW 1466 + FRMW 8 (20 bytes)
    assert frame_bytes([1486]) == (1514, 1538)  # 14 + 2 + 1498; + 24
    assert frame_bytes([1466, 8]) == (1514, 1538)
    with pytest.raises(ValueError, match="1499"):
        frame_bytes([1487])
    with pytest.raises(ValueError):
        frame_bytes([1467, 8])
    with pytest.raises(ValueError):
        frame_bytes([-1])


# ---------------------------------------------------------------- plan: frames


def test_one_drive_with_dc():
    p = plan(SegmentTiming(drives(1), cycle_s=1e-3))
    assert (p.image_out_bytes, p.image_in_bytes, p.image_bytes) == (11, 12, 23)
    assert len(p.frames) == 1
    f = p.frames[0]
    assert [(d.cmd, d.data_bytes) for d in f.datagrams] == [("LRW", 23), ("FRMW", 8)]
    assert f.datagrams[0].logical == 0 and f.datagrams[1].register == 0x0910
    # 14 + 2 + (10+23+2) + (10+8+2) + 4 = 75 with the FCS; 95 on the wire; 7.6 µs
    assert (f.bytes_no_fcs, f.frame_bytes, f.wire_bytes) == (71, 75, 95)
    assert (p.frame_bytes, p.wire_bytes) == (75, 95)
    assert p.wire_s == approx(7.6 * US)
    s = p.slaves[0]
    assert (s.out_offset, s.in_offset, s.out_frames, s.in_frames) == (0, 11, (0,), (0,))


def test_one_drive_without_dc_has_no_frmw():
    p = plan(SegmentTiming(drives(1), cycle_s=1e-3, dc=False))
    # 14 + 2 + (10+23+2) = 51 → padded to 60 → 64 with the FCS, 84 on the wire, 6.72 µs
    assert [d.cmd for d in p.frames[0].datagrams] == ["LRW"]
    assert (p.frame_bytes, p.wire_bytes) == (64, 84)
    assert p.wire_s == approx(6.72 * US)


def test_four_drives():
    p = plan(SegmentTiming(drives(4), cycle_s=1e-3))
    # image: 4*11 = 44 out, then 4*12 = 48 in → LRW 92
    # frame: 14 + 2 + (10+92+2) + 20 + 4 = 144; on the wire 164 → 13.12 µs
    assert p.frames[0].datagrams[0].data_bytes == 92
    assert (p.frame_bytes, p.wire_bytes) == (144, 164)
    assert p.wire_s == approx(13.12 * US)
    # outputs first, then inputs: drive k at out 11*(k-1), in 44 + 12*(k-1)
    assert [(s.out_offset, s.in_offset) for s in p.slaves] == [(0, 44), (11, 56), (22, 68), (33, 80)]
    # round trip: 13.12 + 2*4*0.005 (1 m of cable each) + 2*4*1.0 (forwarding both ways) = 21.16 µs
    assert p.propagation_s == approx(0.02 * US)
    assert p.forwarding_s == approx(4 * US)
    assert p.round_trip_s == approx(21.16 * US)


def test_63_drives_fit_one_frame_64_do_not():
    # with DC the first LRW holds at most 1486 - 20 = 1466 bytes; 63 * 23 = 1449 fits
    p63 = plan(SegmentTiming(drives(63), cycle_s=1e-3))
    assert len(p63.frames) == 1 and p63.frames[0].datagrams[0].data_bytes == 1449
    # 64 * 23 = 1472 > 1466: outputs 704, then 63 input blocks (756) → LRW 1460; the last
    # drive's 12 input bytes go alone: 14 + 2 + (10+12+2) = 40 → padded 60, 64 with FCS, 84 on the wire
    p64 = plan(SegmentTiming(drives(64), cycle_s=1e-3))
    assert [[(d.cmd, d.data_bytes) for d in f.datagrams] for f in p64.frames] == [
        [("LRW", 1460), ("FRMW", 8)],
        [("LRW", 12)],
    ]
    assert p64.frames[1].datagrams[0].logical == 1460
    assert (p64.frames[1].frame_bytes, p64.frames[1].wire_bytes) == (64, 84)
    assert p64.slaves[62].in_frames == (0,) and p64.slaves[63].in_frames == (1,)
    assert p64.slaves[63].out_frames == (0,)


def test_100_drives_spill_into_a_second_frame():
    p = plan(SegmentTiming(drives(100), cycle_s=1e-3))
    # image 1100 out + 1200 in = 2300 bytes > 1466. Frame 1: all 1100 output bytes, then whole
    # input blocks while they fit: (1466 - 1100) // 12 = 30 → LRW 1460 (+ FRMW).
    # Frame 1: 14 + 2 + (10+1460+2) + 20 + 4 = 1512, on the wire 1532
    # Frame 2: the other 70 drives' inputs, LRW 840: 14 + 2 + 852 + 4 = 872, on the wire 892
    assert p.image_bytes == 2300
    assert [[(d.cmd, d.data_bytes) for d in f.datagrams] for f in p.frames] == [
        [("LRW", 1460), ("FRMW", 8)],
        [("LRW", 840)],
    ]
    assert [(f.frame_bytes, f.wire_bytes) for f in p.frames] == [(1512, 1532), (872, 892)]
    assert p.wire_bytes == 2424
    assert p.wire_s == approx(193.92 * US)  # 2424 * 0.08
    assert p.frames[1].start_s == approx(122.56 * US)  # 1532 * 0.08
    # drive 30's inputs (offset 1100 + 29*12 = 1448) end frame 1; drive 31's open frame 2
    assert (p.slaves[29].in_offset, p.slaves[29].in_frames) == (1448, (0,))
    assert (p.slaves[30].in_offset, p.slaves[30].in_frames) == (1460, (1,))
    # round trip: 193.92 + 2*100*0.005 + 2*100*1.0 = 394.92 µs; budget 20 % of 1 ms = 200 µs
    assert p.round_trip_s == approx(394.92 * US)
    assert p.fits and p.slack_s == approx(405.08 * US)  # 1000 - 394.92 - 200
    assert p.utilisation_pct == approx(19.392)


def test_100_drives_without_dc():
    p = plan(SegmentTiming(drives(100), cycle_s=1e-3, dc=False))
    # first LRW may take 1486: 1100 + 32*12 = 1484 (33 blocks would be 1496) → LRW 1484, LRW 816
    # 14 + 2 + 1496 + 4 = 1516 (1536 on the wire); 14 + 2 + 828 + 4 = 848 (868): 2404 → 192.32 µs
    assert [f.datagrams[0].data_bytes for f in p.frames] == [1484, 816]
    assert p.wire_bytes == 2404
    assert p.wire_s == approx(192.32 * US)


def test_a_block_larger_than_a_frame_is_cut():
    # one slave with 2000 output bytes: LRW 1466 (+FRMW) then 534 outputs + 4 inputs = 538
    p = plan(SegmentTiming([SlaveTiming("big", 2000, 4)], cycle_s=1e-3))
    assert [f.datagrams[0].data_bytes for f in p.frames] == [1466, 538]
    assert p.slaves[0].out_frames == (0, 1) and p.slaves[0].in_frames == (1,)


def test_no_process_data():
    # DC on: a frame with the FRMW alone, 14 + 2 + 20 = 36 → padded 60, 64, 84 on the wire
    p = plan(SegmentTiming([SlaveTiming("coupler", 0, 0)], cycle_s=1e-3))
    assert [[d.cmd for d in f.datagrams] for f in p.frames] == [["FRMW"]]
    assert p.wire_bytes == 84
    assert p.slaves[0].out_frames == () and p.slaves[0].in_frames == ()
    p = plan(SegmentTiming([], cycle_s=1e-3, dc=False))
    assert p.frames == [] and p.wire_s == 0 and p.round_trip_s == 0


# ---------------------------------------------------------------- plan: delays


def test_d_comm_is_host_plus_n_times_t_drive():
    # eq. 4.7: t_host = 5 µs, t_drive = 1 µs forwarding + 2 m * 5 ns/m = 1.01 µs
    seg = SegmentTiming(drives(3, cable_m=2.0), cycle_s=1e-3, host_s=5 * US)
    p = plan(seg)
    assert [s.d_comm_s for s in p.slaves] == [approx(6.01 * US), approx(7.02 * US), approx(8.03 * US)]
    for n, s in enumerate(p.slaves, 1):
        assert s.d_comm_s == approx(5 * US + n * 1.01 * US)
    # eq. 4.5 with the defaults: 5 + 62.5 (16 kHz motor task) + 10 = 77.5 µs; eq. 4.6: D = D_comm + D_drive
    assert DriveTiming().total_s == approx(77.5 * US)
    assert [s.d_s for s in p.slaves] == [approx(83.51 * US), approx(84.52 * US), approx(85.53 * US)]


def test_d_comm_with_unequal_slaves_and_drive_delays():
    slaves = [
        SlaveTiming("coupler", 0, 0, forwarding_delay_s=0.5 * US, cable_m=10),  # 0.5 + 0.05
        SlaveTiming("dio", 1, 1, forwarding_delay_s=0.3 * US, cable_m=0.2),  # 0.3 + 0.001
        SlaveTiming("axis", 11, 12, is_drive=True, drive_delay_s=100 * US, cable_m=4),  # 1 + 0.02
        SlaveTiming(
            "axis2",
            11,
            12,
            is_drive=True,
            drive_timing=DriveTiming(r_msgint_s=2 * US, c_motoract_s=31.25 * US, r_motoract_s=4 * US),
        ),
    ]
    p = plan(SegmentTiming(slaves, cycle_s=1e-3, host_s=2 * US))
    # 2 + 0.55 = 2.55; + 0.301 = 2.851; + 1.02 = 3.871; + 1.005 = 4.876 µs
    assert [s.d_comm_s for s in p.slaves] == [
        approx(2.55 * US),
        approx(2.851 * US),
        approx(3.871 * US),
        approx(4.876 * US),
    ]
    assert p.slaves[0].d_s is None and p.slaves[1].d_drive_s is None
    assert p.slaves[2].d_drive_s == approx(100 * US) and p.slaves[2].d_s == approx(103.871 * US)
    # 2 + 31.25 + 4 = 37.25 µs (a 32 kHz motor task)
    assert p.slaves[3].d_s == approx((4.876 + 37.25) * US)
    # one way: propagation 0.05 + 0.001 + 0.02 + 0.005 = 0.076 µs, forwarding 0.5 + 0.3 + 1 + 1 = 2.8 µs
    assert p.propagation_s == approx(0.076 * US) and p.forwarding_s == approx(2.8 * US)


# ---------------------------------------------------------------- plan: does it fit


def test_fits_at_1ms_and_at_50us():
    # one drive: round trip 7.6 + 2*0.005 + 2*1 = 9.61 µs
    p = plan(SegmentTiming(drives(1), cycle_s=1e-3))
    assert p.round_trip_s == approx(9.61 * US)
    assert p.master_budget_s == approx(200 * US)  # 20 % of 1 ms
    assert p.fits and p.slack_s == approx(790.39 * US)  # 1000 - 9.61 - 200
    assert p.utilisation_pct == approx(0.76)  # 7.6 / 1000
    p = plan(SegmentTiming(drives(1), cycle_s=50 * US))
    # budget 10 µs: 9.61 + 10 = 19.61 ≤ 50
    assert p.fits and p.slack_s == approx(30.39 * US)
    assert p.utilisation_pct == approx(15.2)


def test_does_not_fit_at_50us():
    # 4 drives and a 20 µs host path: 20 + 21.16 + 10 = 51.16 µs > 50 µs
    p = plan(SegmentTiming(drives(4), cycle_s=50 * US, host_s=20 * US))
    assert p.used_s == approx(51.16 * US)
    assert not p.fits and p.slack_s == approx(-1.16 * US)
    # the same segment at 1 ms: 20 + 21.16 + 200 = 241.16 → slack 758.84 µs
    p = plan(SegmentTiming(drives(4), cycle_s=1e-3, host_s=20 * US))
    assert p.fits and p.slack_s == approx(758.84 * US)
    # 100 drives never fit 50 µs: the wire alone takes 193.92 µs
    assert not plan(SegmentTiming(drives(100), cycle_s=50 * US)).fits


def test_explicit_master_budget():
    # 100 drives, no compute budget: 394.92 µs of round trip in a 400 µs cycle leaves 5.08 µs
    p = plan(SegmentTiming(drives(100), cycle_s=400 * US, master_budget_s=0.0))
    assert p.fits and p.slack_s == approx(5.08 * US)
    p = plan(SegmentTiming(drives(100), cycle_s=400 * US, master_budget_s=6 * US))
    assert not p.fits and p.slack_s == approx(-0.92 * US)


def test_link_speed_and_propagation_parameters():
    # at 1 Gbit/s the 95-byte frame takes 0.76 µs; 4 ns/m over 50 m is 0.2 µs each way
    p = plan(SegmentTiming(drives(1, cable_m=50), cycle_s=1e-3, link_bps=1e9, propagation_s_per_m=4e-9))
    assert p.wire_s == approx(0.76 * US)
    assert p.round_trip_s == approx((0.76 + 0.4 + 2) * US)


def test_invalid_segments():
    with pytest.raises(ValueError):
        plan(SegmentTiming(drives(1), cycle_s=0))
    with pytest.raises(ValueError):
        plan(SegmentTiming([SlaveTiming("x", -1, 0)], cycle_s=1e-3))


# ---------------------------------------------------------------- format_plan


def test_format_plan_one_drive():
    text = format_plan(plan(SegmentTiming(drives(1), cycle_s=1e-3)))
    for key in (
        "axis1",
        "LRW 23 B + FRMW 8 B",
        "75 B",
        "95 B on the wire",
        "7.600 µs",
        "round trip: 9.610 µs",
        "1.005",  # D_comm(1) = 1 + 0.005 µs
        "78.505",  # D(1) = 1.005 + 77.5 µs
        "fits: yes",
        "slack 790.390 µs",
        "0.76 %",
        "1000.000 µs",
        "1.000 ms",
        "200.000 µs",
    ):
        assert key in text, key
    row = next(line for line in text.splitlines() if line.lstrip().startswith("1 "))
    assert row.split() == ["1", "axis1", "11", "12", "0", "11", "1", "1.005", "78.505"]


def test_format_plan_two_frames_and_a_miss():
    text = format_plan(plan(SegmentTiming(drives(100), cycle_s=250 * US)))
    # 394.92 + 50 = 444.92 µs used of 250 µs → slack -194.92 µs; utilisation 193.92 / 250 = 77.57 %
    for key in (
        "frame 1: LRW 1460 B + FRMW 8 B",
        "frame 2: LRW 840 B",
        "frames: 2, 2384 B, 2424 B",
        "193.920 µs",
        "394.920 µs",
        "fits: NO",
        "slack -194.920 µs",
        "77.57 %",
    ):
        assert key in text, key
    row = next(line for line in text.splitlines() if line.split()[:2] == ["31", "axis31"])
    assert row.split()[6] == "1-2"  # outputs in frame 1, inputs in frame 2


# ---------------------------------------------------------------- ESI


def test_parse_number():
    assert parse_number("#x029C") == 0x29C
    assert parse_number("#x0000029C") == 668
    assert parse_number(" 668 ") == 668
    assert parse_number("0x29c") == 668
    with pytest.raises(ValueError):
        parse_number("#xZZ")


def test_esi_drive_identity_and_mailbox():
    devs = load_esi(ESI / "example_drive.xml")
    assert len(devs) == 2
    d = devs[0]
    assert (d.vendor_id, d.product_code, d.revision) == (0xABC, 0x00D20001, 0x00010000)
    assert d.name == "XD-200 servo drive"  # the LcId 1033 name, not the first
    assert d.type_name == "XD-200" and d.group == "ServoDrives" and d.vendor_name == "Example Motion Ltd"
    assert d.mailbox and d.coe and d.coe_complete_access
    assert d.mailbox_protocols == ("CoE", "FoE")
    assert devs[1].revision == 0x00020000 and devs[1].coe and not devs[1].coe_complete_access


def test_esi_drive_pdos():
    d = load_esi(ESI / "example_drive.xml", product_code=0xD20001, revision=0x10000)[0]
    assert [(p.index, p.sm, p.assigned, p.fixed, p.mandatory) for p in d.rx_pdos] == [
        (0x1600, 2, True, True, True),
        (0x1601, None, False, False, False),
    ]
    assert [p.index for p in d.assigned_rx] == [0x1600] and [p.index for p in d.assigned_tx] == [0x1A00]
    assert d.rx_pdos[0].excludes == [0x1601] and d.pdo(0x1601).excludes == [0x1600]
    assert d.pdo(0x1A00).sm == 3
    # the alternative PDO: "#x00" subindex, an INT and 8 bits of padding (Index 0, no type or name)
    assert [e.as_tuple() for e in d.pdo(0x1601).entries] == [
        (0x6040, 0, 16, "UINT", "Controlword"),
        (0x6071, 0, 16, "INT", "Target torque"),
        (0, 0, 8, "PAD", ""),
    ]
    assert d.pdo(0x1601).bits == 40
    # the assigned PDOs are exactly the CiA 402 default mapping (names aside)
    assert [e[:4] for e in d.rx_entries()] == [e[:4] for e in CIA402_RX]
    assert [e[:4] for e in d.tx_entries()] == [e[:4] for e in CIA402_TX]
    assert d.rx_entries()[1] == (0x607A, 0, 32, "DINT", "Target position")
    rx, tx = PdoLayout(d.rx_entries()), PdoLayout(d.tx_entries())
    assert (rx.size, tx.size) == (11, 12)
    assert rx.unpack(rx.pack([0x000F, -1000, 250, 8])) == [0x000F, -1000, 250, 8]


def test_esi_drive_dc_opmodes():
    d = load_esi(ESI / "example_drive.xml")[0]
    dc, free = d.dc_opmodes
    assert (dc.name, dc.assign_activate, dc.cycle_time_sync0, dc.cycle_time_sync0_factor, dc.shift_time_sync0) == (
        "DC",
        0x0300,
        0,
        1,
        0,
    )
    assert (free.name, free.assign_activate, free.cycle_time_sync0) == ("FreeRun", 0, None)
    assert load_esi(ESI / "example_drive.xml")[1].dc_opmodes == []


def test_esi_feeds_the_plan():
    d = load_esi(ESI / "example_drive.xml", product_code=0xD20001, revision=0x10000)[0]
    s = SlaveTiming(d.name, PdoLayout(d.rx_entries()).size, PdoLayout(d.tx_entries()).size, is_drive=True)
    assert plan(SegmentTiming([s], cycle_s=1e-3)).frame_bytes == 75


def test_esi_revision_filter():
    (d,) = load_esi(ESI / "example_drive.xml", revision=0x00020000)
    assert d.name == "XD-200 servo drive (rev 2)"
    assert d.rx_entries() == [(0x6040, 0, 16, "UINT", "Controlword")]
    assert len(load_esi(ESI / "example_drive.xml", product_code=0x00D20001)) == 2


def test_esi_digital_terminal_with_namespace_and_bits():
    (d,) = load_esi(ESI / "example_digital_io.xml")
    # decimal Vendor/Id 2748 = 0xABC, decimal RevisionNo; tags in a default namespace
    assert (d.vendor_id, d.product_code, d.revision) == (0xABC, 0x0DA40404, 1)
    assert d.name == "DIO-44 4 in / 4 out, 24 V DC" and d.group == "DigitalIO"
    assert not d.mailbox and not d.coe and d.dc_opmodes == []
    # no mailbox: process data on SM0 (outputs, one PDO per channel) and SM1 (inputs)
    assert [(p.index, p.sm) for p in d.assigned_rx] == [(0x1600, 0), (0x1601, 0), (0x1602, 0), (0x1603, 0)]
    assert d.rx_entries() == [
        (0x7000, 1, 1, "BOOL", "Output 1"),
        (0x7010, 1, 1, "BOOL", "Output 2"),
        (0x7020, 1, 1, "BOOL", "Output 3"),
        (0x7030, 1, 1, "BOOL", "Output 4"),
    ]
    # BIT → BOOL; "#x0" padding of 4 bits fills the byte
    assert d.tx_entries() == [
        (0x6000, 1, 1, "BOOL", "Input 1"),
        (0x6000, 2, 1, "BOOL", "Input 2"),
        (0x6000, 3, 1, "BOOL", "Input 3"),
        (0x6000, 4, 1, "BOOL", "Input 4"),
        (0, 0, 4, "PAD", ""),
    ]
    assert d.pdo(0x1A00).entries[0].esi_type == "BIT"
    rx, tx = PdoLayout(d.rx_entries()), PdoLayout(d.tx_entries())
    assert (rx.size, tx.size) == (1, 1)
    assert rx.pack([1, 0, 1, 1]) == bytes([0b1101])
    assert tx.unpack(bytes([0b0101])) == [True, False, True, False]


def test_esi_bit_widths_and_aliases():
    entry = (
        "<Entry><Index>{}</Index><SubIndex>{}</SubIndex><BitLen>{}</BitLen>"
        "<Name>{}</Name><DataType>{}</DataType></Entry>"
    )
    entries = "".join(
        entry.format(*e)
        for e in [
            ("#x6000", 1, 2, "a", "BIT2"),
            ("#x6000", 2, 6, "b", "BIT6"),
            ("#x6001", 0, 16, "c", "WORD"),
            ("#x6002", 0, 32, "d", "REAL"),
        ]
    )
    xml = f"""<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>
      <Type ProductCode="2" RevisionNo="3">T</Type>
      <TxPdo Sm="3"><Index>#x1A00</Index>{entries}</TxPdo></Device></Devices></Descriptions></EtherCATInfo>"""
    (d,) = parse_esi(xml)
    assert [e[3] for e in d.tx_entries()] == ["USINT", "USINT", "UINT", "REAL"]
    assert d.revision == 3 and d.name == "T"
    tx = PdoLayout(d.tx_entries())
    assert tx.size == 7
    assert tx.unpack(tx.pack([3, 0x2A, 0xBEEF, 1.5])) == [3, 0x2A, 0xBEEF, 1.5]


# ---------------------------------------------------------------- ESI errors


def test_esi_missing_file(tmp_path):
    path = tmp_path / "nope.xml"
    with pytest.raises(EsiError, match="nope.xml: cannot read"):
        load_esi(path)


@pytest.mark.parametrize(
    "text, line, column, cause",
    [
        # line 5 is "  </Devices>": expat points at the name after "</" (0-based column 4 → 5)
        (
            '<?xml version="1.0"?>\n<EtherCATInfo>\n  <Vendor><Id>1</Id></Vendor>\n  <Descriptions>\n'
            "  </Devices>\n</EtherCATInfo>\n",
            5,
            5,
            "mismatched tag",
        ),
        ("<EtherCATInfo>\n<Vendor>&bogus;</Vendor></EtherCATInfo>", 2, 9, "undefined entity"),
        ("<EtherCATInfo><Vendor><Id>#x1</Id></Vendor", 1, 35, "unclosed token"),
    ],
)
def test_esi_malformed_xml_has_line_and_column(tmp_path, text, line, column, cause):
    path = tmp_path / "broken.xml"
    path.write_text(text)
    with pytest.raises(EsiError) as ei:
        load_esi(path)
    e = ei.value
    assert (e.line, e.column) == (line, column)
    assert str(e) == f"{path}:{line}:{column}: malformed XML: {cause}"


def test_esi_no_matching_product(tmp_path):
    with pytest.raises(
        EsiError,
        match=r"example_drive.xml: no device with product code 0x00001234 "
        r"\(the file has: 0x00d20001 rev 0x00010000, 0x00d20001 rev 0x00020000\)",
    ):
        load_esi(ESI / "example_drive.xml", product_code=0x1234)
    with pytest.raises(EsiError, match="product code 0x00d20001 revision 0x00000005"):
        load_esi(ESI / "example_drive.xml", product_code=0xD20001, revision=5)


@pytest.mark.parametrize(
    "text, message",
    [
        ("<html/>", "root element is <html>"),
        ("<EtherCATInfo><Descriptions/></EtherCATInfo>", "no Vendor/Id"),
        (
            "<EtherCATInfo><Vendor><Id>#x1</Id></Vendor><Descriptions><Devices/></Descriptions></EtherCATInfo>",
            "no Descriptions/Devices/Device",
        ),
        ("<EtherCATInfo><Vendor><Id>#xG1</Id></Vendor></EtherCATInfo>", "Vendor/Id: '#xG1' is not a number"),
        (
            "<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>"
            "<Type ProductCode='#xZZ'>X</Type></Device></Devices></Descriptions></EtherCATInfo>",
            r"device 1 \(X\): ProductCode: '#xZZ' is not a number",
        ),
        (
            "<EtherCATInfo><Vendor><Id>1</Id></Vendor><Descriptions><Devices><Device>"
            "<Type ProductCode='1'>X</Type><RxPdo Sm='2'><Index>#x1600</Index>"
            "<Entry><Index>#x6040</Index><BitLen>sixteen</BitLen></Entry></RxPdo>"
            "</Device></Devices></Descriptions></EtherCATInfo>",
            r"RxPdo 0x1600: Entry 1: BitLen: 'sixteen'",
        ),
    ],
)
def test_esi_content_errors(tmp_path, text, message):
    path = tmp_path / "bad.xml"
    path.write_text(text)
    with pytest.raises(EsiError, match=message) as ei:
        load_esi(path)
    assert str(ei.value).startswith(f"{path}: ")
