"""Timing arithmetic of one EtherCAT segment: frame sizes, wire time, per-slave delays, cycle fit.

Pure functions, no I/O. `plan(SegmentTiming(...))` answers "how big is the cyclic frame, how long
is it on the wire, when does drive n see it, and does the whole exchange fit the cycle?";
`format_plan` prints the answer; `frame_bytes` is the frame-size rule on its own, for the emulator
to delay its frames by the same amounts.

Process-data frame (the SOEM convention, non-overlapping image)
    The logical image holds the outputs of every slave in bus order, then the inputs of every slave
    in bus order: size = sum(out) + sum(in). One LRW datagram covers the whole image. With
    distributed clocks on, the first frame also carries an FRMW of the reference clock's 8-byte
    system time (register 0x0910), as SOEM appends to its first process-data frame.

Frame size
    Ethernet header 14 + EtherCAT header 2 + per datagram (header 10 + data + WKC 2), padded to
    the 60-byte Ethernet minimum, + FCS 4. On the wire a frame also costs preamble+SFD 8 and the
    inter-frame gap 12. The datagrams of one frame may take at most 1498 bytes (a 1500-byte MTU
    less the EtherCAT header), so one LRW carries at most 1486 data bytes, 1466 in the first frame
    when the 20-byte FRMW rides along (SOEM's EC_MAXLRWDATA and EC_FIRSTDCDATAGRAM).

Splitting
    An image larger than that is cut into several frames of one LRW each, sent back to back. Cuts
    fall on slave boundaries (a slave's output or input block is not split across frames, so its
    SyncManager buffer is written by one frame), unless one block alone exceeds a frame.

Delays (thesis eq. 3.5-3.6 and 4.5-4.7)
    wire time        D_t = on-wire bytes * 8 / link_bps, summed over the frames.
    propagation      cable_m * 5 ns/m for the cable leading into each slave.
    forwarding       forwarding_delay_s per slave and per pass (the ESC's port-to-port delay).
    D_comm(n)        host_s + sum over k <= n of (forwarding_k + propagation_k): when the start of
                     the first frame reaches slave n (eq. 4.7's t_host + n*t_drive when all slaves
                     are alike).
    D_drive          R_MsgInt + C_MotorAct + R_MotorAct (eq. 4.5), or the slave's drive_delay_s.
    D(n)             D_comm(n) + D_drive (eq. 4.6), drives only. This is the frame-triggered model
                     of the thesis; with DC the drive acts on SYNC0 instead, so D(n) is then an
                     upper bound of how early the command could act, not when it does.
    round trip       the segment is a line closed into a ring by the last slave: the frames run out
                     through every slave and back through every slave to the master. Round trip =
                     wire time of all frames + 2 * sum(propagation) + 2 * sum(forwarding). Counting
                     the forwarding delay on the way back too (and at the last slave's loop-back as
                     its return pass) is deliberately conservative: a real ESC's return path skips
                     the processing unit and is somewhat faster.
    fit              host_s + round trip + master_budget_s <= cycle_s. host_s is counted once (the
                     master's send path); master_budget_s is the time the master needs to compute
                     between receiving inputs and sending the next outputs, by default 20 % of the
                     cycle. Utilisation = wire time / cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

# Frame arithmetic (bytes)
ETH_HEADER = 14  # destination, source, EtherType 0x88A4
ECAT_HEADER = 2  # 11-bit length, type 1
DATAGRAM_HEADER = 10  # cmd, idx, address, length/flags, irq
WKC = 2
DATAGRAM_OVERHEAD = DATAGRAM_HEADER + WKC
FCS = 4
MIN_FRAME_NO_FCS = 60  # 64-byte Ethernet minimum less the FCS
PREAMBLE_SFD = 8
INTER_FRAME_GAP = 12
MAX_ECAT_PAYLOAD = 1498  # datagrams of one frame: 1500-byte MTU less the EtherCAT header
MAX_LRW_DATA = MAX_ECAT_PAYLOAD - DATAGRAM_OVERHEAD  # 1486
DC_TIME_REGISTER = 0x0910  # the reference clock's 64-bit system time
DC_DATAGRAM_DATA = 8
DC_DATAGRAM_BYTES = DATAGRAM_OVERHEAD + DC_DATAGRAM_DATA  # 20

# Timing defaults
FORWARDING_DELAY_S = 1.0e-6  # an ESC with two 100BASE-TX PHYs, port to port (~1 us per slave)
PROPAGATION_S_PER_M = 5e-9  # twisted pair, about 2/3 of the speed of light
LINK_BPS = 100e6  # Fast Ethernet
MASTER_BUDGET_FRACTION = 0.2  # default compute share of the cycle for the master


@dataclass
class DriveTiming:
    """Drive-local command delay of eq. 4.5, D_drive = R_MsgInt + C_MotorAct + R_MotorAct.

    Defaults: the motor-action (control) task runs at 16 kHz, so its period C_MotorAct is 62.5 us;
    the worst-case response times of the PDO interrupt task (R_MsgInt) and of the motor-action task
    (R_MotorAct) are taken as a few microseconds, as for a drive MCU with a small RTOS.
    """

    r_msgint_s: float = 5e-6
    c_motoract_s: float = 62.5e-6
    r_motoract_s: float = 10e-6

    @property
    def total_s(self) -> float:
        return self.r_msgint_s + self.c_motoract_s + self.r_motoract_s


@dataclass
class SlaveTiming:
    """One slave in bus order. cable_m is the cable leading into this slave (from the master or the
    previous slave); forwarding_delay_s is its ESC's delay per pass of a frame."""

    name: str
    out_bytes: int
    in_bytes: int
    forwarding_delay_s: float = FORWARDING_DELAY_S
    cable_m: float = 1.0
    is_drive: bool = False
    drive_delay_s: float | None = None  # overrides drive_timing when given
    drive_timing: DriveTiming = field(default_factory=DriveTiming)

    @property
    def d_drive_s(self) -> float | None:
        if not self.is_drive:
            return None
        return self.drive_delay_s if self.drive_delay_s is not None else self.drive_timing.total_s


@dataclass
class SegmentTiming:
    """A segment: its slaves in bus order and the cycle it should run at.

    host_s is t_host: the master stack and NIC latency until the frame leaves towards the first
    slave. master_budget_s None means MASTER_BUDGET_FRACTION of the cycle."""

    slaves: list
    cycle_s: float
    host_s: float = 0.0
    dc: bool = True
    link_bps: float = LINK_BPS
    propagation_s_per_m: float = PROPAGATION_S_PER_M
    master_budget_s: float | None = None

    @property
    def budget_s(self) -> float:
        return self.cycle_s * MASTER_BUDGET_FRACTION if self.master_budget_s is None else self.master_budget_s


@dataclass
class DatagramPlan:
    cmd: str  # "LRW" or "FRMW"
    data_bytes: int
    logical: int | None = None  # LRW: logical address (offset into the image)
    register: int | None = None  # FRMW: register offset (0x0910)


@dataclass
class FramePlan:
    index: int  # 0-based, in sending order
    datagrams: list
    bytes_no_fcs: int  # Ethernet header .. last WKC, padded to 60
    frame_bytes: int  # with the FCS (what a capture with FCS shows)
    wire_bytes: int  # with preamble, SFD and inter-frame gap
    wire_s: float
    start_s: float  # when its first bit leaves, relative to the first frame's


@dataclass
class SlavePlan:
    position: int  # 1-based, bus order
    name: str
    out_bytes: int
    in_bytes: int
    out_offset: int  # logical offset of its outputs in the image
    in_offset: int  # logical offset of its inputs in the image
    out_frames: tuple  # indexes of the frames carrying its outputs (empty: none)
    in_frames: tuple
    propagation_s: float  # of the cable into this slave
    forwarding_s: float
    d_comm_s: float  # D_comm(n)
    d_drive_s: float | None  # D_drive, drives only
    d_s: float | None  # D(n) = D_comm(n) + D_drive, drives only
    is_drive: bool = False


@dataclass
class Plan:
    segment: SegmentTiming
    slaves: list  # [SlavePlan]
    frames: list  # [FramePlan]
    image_out_bytes: int
    image_in_bytes: int
    image_bytes: int
    frame_bytes: int  # all frames, with FCS
    wire_bytes: int  # all frames on the wire
    wire_s: float  # D_t of all frames
    propagation_s: float  # one way, all cables
    forwarding_s: float  # one way, all slaves
    round_trip_s: float
    master_budget_s: float
    used_s: float  # host + round trip + master budget
    slack_s: float  # cycle - used (negative: does not fit)
    fits: bool
    utilisation_pct: float  # wire time / cycle


def frame_bytes(datagram_data_sizes) -> tuple:
    """Data sizes of the datagrams of one frame → (frame bytes without FCS, padded to 60; bytes on
    the wire with FCS, preamble+SFD and inter-frame gap). ValueError if they exceed one frame."""
    sizes = list(datagram_data_sizes)
    if any(s < 0 for s in sizes):
        raise ValueError(f"negative datagram size in {sizes}")
    payload = sum(s + DATAGRAM_OVERHEAD for s in sizes)
    if payload > MAX_ECAT_PAYLOAD:
        raise ValueError(f"datagrams of {payload} bytes exceed one EtherCAT frame ({MAX_ECAT_PAYLOAD} bytes)")
    no_fcs = max(ETH_HEADER + ECAT_HEADER + payload, MIN_FRAME_NO_FCS)
    return no_fcs, no_fcs + FCS + PREAMBLE_SFD + INTER_FRAME_GAP


def wire_time_s(on_wire_bytes: int, link_bps: float = LINK_BPS) -> float:
    """Eq. 3.5: the time to put on_wire_bytes on the link."""
    return on_wire_bytes * 8 / link_bps


def _split_image(blocks, first_cap: int, cap: int) -> list:
    """Block sizes in image order → LRW data sizes, cutting at block boundaries where possible."""
    chunks = []
    cur, room = 0, first_cap
    for b in blocks:
        if b == 0:
            continue
        if cur and cur + b > room and b <= cap:  # move the whole block to the next frame
            chunks.append(cur)
            cur, room = 0, cap
        while cur + b > room:  # a block larger than a frame: cut it
            take = room - cur
            chunks.append(cur + take)
            b -= take
            cur, room = 0, cap
        cur += b
    if cur:
        chunks.append(cur)
    return chunks


def plan(seg: SegmentTiming) -> Plan:
    if seg.cycle_s <= 0:
        raise ValueError(f"cycle_s must be positive, not {seg.cycle_s}")
    if seg.link_bps <= 0:
        raise ValueError(f"link_bps must be positive, not {seg.link_bps}")
    for s in seg.slaves:
        if s.out_bytes < 0 or s.in_bytes < 0:
            raise ValueError(f"slave {s.name!r}: negative process data size")

    outs = [s.out_bytes for s in seg.slaves]
    ins = [s.in_bytes for s in seg.slaves]
    total_out, total_in = sum(outs), sum(ins)
    image = total_out + total_in

    # LRW chunks over the image, then the frames around them
    first_cap = MAX_LRW_DATA - (DC_DATAGRAM_BYTES if seg.dc else 0)
    chunks = _split_image(outs + ins, first_cap, MAX_LRW_DATA)
    frames = []
    t = 0.0
    addr = 0
    ranges = []  # (start, end) of each frame's LRW
    for i in range(max(len(chunks), 1 if seg.dc else 0)):
        dgs = []
        if i < len(chunks):
            dgs.append(DatagramPlan("LRW", chunks[i], logical=addr))
            ranges.append((addr, addr + chunks[i]))
            addr += chunks[i]
        if i == 0 and seg.dc:
            dgs.append(DatagramPlan("FRMW", DC_DATAGRAM_DATA, register=DC_TIME_REGISTER))
        no_fcs, wire = frame_bytes([d.data_bytes for d in dgs])
        ws = wire_time_s(wire, seg.link_bps)
        frames.append(FramePlan(i, dgs, no_fcs, no_fcs + FCS, wire, ws, t))
        t += ws

    def frames_of(start, size):
        return tuple(i for i, (a, b) in enumerate(ranges) if size and a < start + size and start < b)

    slaves = []
    d_comm = seg.host_s
    out_off, in_off = 0, total_out
    for n, s in enumerate(seg.slaves, 1):
        prop = s.cable_m * seg.propagation_s_per_m
        d_comm += s.forwarding_delay_s + prop
        dd = s.d_drive_s
        slaves.append(
            SlavePlan(
                n,
                s.name,
                s.out_bytes,
                s.in_bytes,
                out_off,
                in_off,
                frames_of(out_off, s.out_bytes),
                frames_of(in_off, s.in_bytes),
                prop,
                s.forwarding_delay_s,
                d_comm,
                dd,
                None if dd is None else d_comm + dd,
                s.is_drive,
            )
        )
        out_off += s.out_bytes
        in_off += s.in_bytes

    wire_s = sum(f.wire_s for f in frames)
    prop_s = sum(p.propagation_s for p in slaves)
    fwd_s = sum(p.forwarding_s for p in slaves)
    round_trip = wire_s + 2 * prop_s + 2 * fwd_s
    budget = seg.budget_s
    used = seg.host_s + round_trip + budget
    slack = seg.cycle_s - used
    return Plan(
        seg,
        slaves,
        frames,
        total_out,
        total_in,
        image,
        sum(f.frame_bytes for f in frames),
        sum(f.wire_bytes for f in frames),
        wire_s,
        prop_s,
        fwd_s,
        round_trip,
        budget,
        used,
        slack,
        slack >= -1e-12,
        100.0 * wire_s / seg.cycle_s,
    )


def _us(s: float) -> str:
    return f"{s * 1e6:.3f} µs"


def _frames(ix: tuple) -> str:
    if not ix:
        return "-"
    return str(ix[0] + 1) if len(ix) == 1 else f"{ix[0] + 1}-{ix[-1] + 1}"


def format_plan(p: Plan) -> str:
    """A readable report: the slave table, the frames, the totals and the verdict."""
    seg = p.segment
    lines = [
        f"EtherCAT segment: {len(p.slaves)} slave(s), cycle {_us(seg.cycle_s)} "
        f"({seg.cycle_s * 1e3:.3f} ms), DC {'on' if seg.dc else 'off'}, "
        f"link {seg.link_bps / 1e6:g} Mbit/s, t_host {_us(seg.host_s)}",
        "",
    ]
    head = ("#", "slave", "out B", "in B", "out @", "in @", "frame", "D_comm(n) µs", "D(n) µs")
    rows = [
        (
            str(s.position),
            s.name,
            str(s.out_bytes),
            str(s.in_bytes),
            str(s.out_offset),
            str(s.in_offset),
            _frames(tuple(sorted(set(s.out_frames + s.in_frames)))),
            f"{s.d_comm_s * 1e6:.3f}",
            "-" if s.d_s is None else f"{s.d_s * 1e6:.3f}",
        )
        for s in p.slaves
    ]
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    left = {1}

    def fmt_row(r):
        return "  ".join(c.ljust(w) if i in left else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths))).rstrip()

    lines.append(fmt_row(head))
    lines.append("  ".join("-" * w for w in widths))
    lines += [fmt_row(r) for r in rows]
    drives = [s for s in p.slaves if s.d_drive_s is not None]
    if drives:
        dd = sorted({s.d_drive_s for s in drives})
        lines.append("D_drive (R_MsgInt + C_MotorAct + R_MotorAct): " + ", ".join(_us(x) for x in dd))
    lines.append("")
    lines.append(f"image: {p.image_out_bytes} B out + {p.image_in_bytes} B in = {p.image_bytes} B")
    for f in p.frames:
        dgs = " + ".join(f"{d.cmd} {d.data_bytes} B" for d in f.datagrams)
        lines.append(
            f"frame {f.index + 1}: {dgs}: {f.frame_bytes} B frame, {f.wire_bytes} B on the wire, {_us(f.wire_s)}"
        )
    lines.append(f"frames: {len(p.frames)}, {p.frame_bytes} B, {p.wire_bytes} B on the wire, wire time {_us(p.wire_s)}")
    lines.append(f"propagation {_us(p.propagation_s)} + forwarding {_us(p.forwarding_s)} each way")
    lines.append(f"round trip: {_us(p.round_trip_s)}")
    lines.append(f"master budget: {_us(p.master_budget_s)}")
    lines.append(f"used: {_us(p.used_s)} of {_us(seg.cycle_s)} (t_host + round trip + master budget)")
    verdict = "yes" if p.fits else "NO"
    lines.append(f"fits: {verdict}, slack {p.slack_s * 1e6:.3f} µs; bus utilisation {p.utilisation_pct:.2f} %")
    return "\n".join(lines)
