"""An emulated EtherCAT segment: a line of slave controllers a frame passes through and returns.

`Segment.exchange(frame, t)` takes a frame as the master sends it at time t (seconds on the
segment's clock), lets every datagram pass every slave in order with the addressing and
working-counter rules of each command, and returns the frame as it arrives back at the master
(source address marked as processed), or None when it is lost. Slave n (0-based) sees the frame
at t + host_delay + (n + 1)·(forwarding delay + cable propagation): the D_comm(n) of the thesis's
eq. 4.7, applied to the device's physics, DC receive-time latches and system time.

Faults for tests: `drop_frames(n)` loses the next n frames, `break_after(k)` cuts the cable after
slave k (the frame returns from there, so the slaves beyond stop answering: working-counter errors).
"""

from __future__ import annotations

from . import wire
from .esc import SlaveController
from .wire import APRD, APRW, APWR, ARMW, BRD, BRW, BWR, FPRD, FPRW, FPWR, FRMW, LRD, LRW, LWR, FrameError

_READ_OR_RW = {APRD, FPRD, BRD, APRW, FPRW, BRW}
_WRITE_OR_RW = {APWR, FPWR, BWR, APRW, FPRW, BRW}
_AUTO = {APRD, APWR, APRW, ARMW}
_FIXED = {FPRD, FPWR, FPRW, FRMW}
_BCAST = {BRD, BWR, BRW}


class Segment:
    def __init__(
        self,
        devices,
        host_delay: float = 5e-6,
        forwarding_delay: float = 1e-6,
        cable_m: float = 1.0,
        propagation_per_m: float = 5e-9,
        clock_spread_ns: int = 1_000_003,
    ):
        self.slaves = [SlaveController(d, clock_base_ns=(i + 1) * clock_spread_ns) for i, d in enumerate(devices)]
        self.host_delay = host_delay
        self.propagation = cable_m * propagation_per_m
        for sl in self.slaves:
            sl.forwarding_delay = forwarding_delay
        self.t = 0.0
        self.capture: wire.PcapWriter | None = None
        self._drop = 0
        self._cut = None  # index of the last reachable slave, or None
        self.frames = 0
        self._relink()

    def _relink(self) -> None:
        last = len(self.slaves) - 1 if self._cut is None else self._cut
        for i, s in enumerate(self.slaves):
            s.set_links(i < last)

    # ------------------------------------------------------------------ faults
    def drop_frames(self, n: int) -> None:
        self._drop += n

    def break_after(self, k) -> None:
        """Cut the line after slave k (0-based); None restores it."""
        self._cut = k
        self._relink()

    def d_comm(self, n: int) -> float:
        """When slave n (0-based) sees a frame, after it was sent (s): t_host + Σ (forwarding + cable)."""
        return self.host_delay + sum(s.forwarding_delay + self.propagation for s in self.slaves[: n + 1])

    def _arrivals(self, t: float, n: int) -> list:
        out = []
        acc = t + self.host_delay
        for s in self.slaves[:n]:
            acc += s.forwarding_delay + self.propagation
            out.append(acc)
        return out

    # ------------------------------------------------------------------ time
    def advance(self, t: float) -> None:
        """Advance every device to time t (no frame: the drives keep running on their own)."""
        self.t = max(self.t, t)
        for s in self.slaves:
            s.advance(t)

    def open_capture(self, path: str) -> None:
        self.capture = wire.PcapWriter(path)

    def close(self) -> None:
        if self.capture is not None:
            self.capture.close()
            self.capture = None

    # ------------------------------------------------------------------ frames
    def exchange(self, frame: bytes, t: float | None = None):
        t = self.t if t is None else t
        self.t = max(self.t, t)
        if self.capture is not None:
            self.capture.write(frame, t)
        if self._drop:
            self._drop -= 1
            return None
        try:
            _dst, _src, dgs = wire.decode_frame(frame)
        except FrameError:
            return None
        self.frames += 1
        reach = self.slaves if self._cut is None else self.slaves[: self._cut + 1]
        n_reach = len(reach)
        arrive = self._arrivals(t, n_reach)
        for dg in dgs:
            self._datagram(dg, reach, arrive)
        out = self._answer(frame, dgs)
        if self.capture is not None:
            self.capture.write(out, (2 * arrive[-1] - t) if arrive else t)
        return out

    @staticmethod
    def _answer(frame: bytes, dgs: list) -> bytes:
        """The frame as it returns: the source address marked as processed (bit 1), the datagrams
        after the EtherCAT header at byte 16 (a VLAN tag is not sent back), then what followed
        them in the frame (padding)."""
        out = bytearray(frame)
        try:
            wire.encode_datagrams_into(out, 16, dgs)
        except FrameError:  # longer than they came (a read past the end of an ESC's memory)
            out = out[:16] + wire.encode_datagrams(dgs)
        out[6] |= 0x02
        return bytes(out)

    def _datagram(self, dg, reach, arrive) -> None:
        c = dg.cmd
        if c == LRW or c == LRD or c == LWR:
            addr = dg.logical
            rd, wr = c != LWR, c != LRD
            data = dg.data
            wkc = dg.wkc
            for s, t in zip(reach, arrive):
                wkc += s.logical(rd, wr, addr, data, t)
            dg.wkc = wkc
            return
        if c in _BCAST:
            for i, s in enumerate(reach):
                self._access(s, dg, c, arrive[i], i, len(reach), bcast=True)
                dg.adp = (dg.adp + 1) & 0xFFFF
            return
        if c == FRMW or c == ARMW:
            self._read_multiple_write(dg, reach, arrive, auto=c == ARMW)
            return
        if c in _AUTO or c in _FIXED:
            auto = c in _AUTO
            for i, s in enumerate(reach):
                if dg.adp == 0 if auto else s.station == dg.adp:
                    self._access(s, dg, c, arrive[i], i, len(reach))
                if auto:
                    dg.adp = (dg.adp + 1) & 0xFFFF
            return
        # NOP and unknown commands pass untouched

    @staticmethod
    def _read_multiple_write(dg, reach, arrive, auto: bool) -> None:
        """ARMW/FRMW (the DC time): the addressed slave reads, every other slave writes what the
        datagram carries when it passes."""
        n = len(dg.data)
        carried = None  # bytes(dg.data), made again after a read
        for s, t in zip(reach, arrive):
            if dg.adp == 0 if auto else s.station == dg.adp:
                got = s.read(dg.ado, n, t)
                if got is not None:
                    dg.data[:] = got
                    dg.wkc += 1
                    carried = None
            else:
                if carried is None:
                    carried = bytes(dg.data)
                if s.write(dg.ado, carried, t):
                    dg.wkc += 1
            if auto:
                dg.adp = (dg.adp + 1) & 0xFFFF

    def _access(self, s: SlaveController, dg, c: int, t: float, i: int, n_reach: int, bcast: bool = False) -> None:
        """A register read and/or write at one slave; a write stores the data as it arrives there."""
        n = len(dg.data)
        inc = 0
        original = bytes(dg.data)
        if c in _READ_OR_RW:
            got = s.read(dg.ado, n, t)
            if got is not None:
                if bcast:
                    dg.data[:] = bytes(a | b for a, b in zip(dg.data, got))
                else:
                    dg.data[:] = got
                inc += 1
        if c in _WRITE_OR_RW:
            if s.write(dg.ado, original, t):
                inc += 2 if c in _READ_OR_RW else 1
                if dg.ado <= wire_dc_latch < dg.ado + n:
                    downstream = self.slaves[i + 1 : n_reach]
                    back = t + 2 * sum(x.forwarding_delay + self.propagation for x in downstream)
                    s.receive_times(t, back)
        dg.wkc += inc


wire_dc_latch = 0x0900
