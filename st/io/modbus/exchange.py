"""The shared memory between the PLC process and the Modbus server process.

The server runs in its own process (a server thread in the scan's process makes the scan wait
for the interpreter lock under load: ../shared/notes/realtime.md). The two exchange through one
`multiprocessing.shared_memory` block and never wait for each other:

- **Snapshot** (PLC → server): the four Modbus tables, 65,536 entries each (coils and discrete
  inputs one byte per bit, registers native 16-bit words). At the end of every job the PLC
  writes the cells it owns inside a seqlock (the counter is odd while writing); the server
  copies the range a request reads and retries if the counter moved, so a multi-register value
  is never torn and the scan never takes a lock. Cells the PLC does not own are the server's
  scratch memory (OpenPLC: unused addresses accept writes and read them back).
- **Write ring** (server → PLC): a single-producer single-consumer byte ring. The server appends
  one message per write request to PLC-owned cells; the PLC drains the ring at the start of the
  next job. A full ring makes the server answer exception 06 (busy) instead of blocking.
"""

from __future__ import annotations

import struct
from multiprocessing import shared_memory

N = 65536
COILS, DISCRETE, INPUT, HOLDING = 0, 1, 2, 3
TABLE_NAMES = {COILS: "coils", DISCRETE: "discrete inputs", INPUT: "input registers", HOLDING: "holding registers"}

_HDR = 64  # seq u64 @0, ring head u32 @8, ring tail u32 @12, port u32 @16, state u32 @20
_OFF = {COILS: _HDR, DISCRETE: _HDR + N, INPUT: _HDR + 2 * N, HOLDING: _HDR + 4 * N}
_RING = _HDR + 6 * N
RING_SIZE = 1 << 16
SIZE = _RING + RING_SIZE

_MSG = struct.Struct("<HBHH")  # total length, table, address, count; then the values


class Exchange:
    """Both sides' view of the block; `create=True` on the PLC side (which owns and unlinks it)."""

    def __init__(self, name: str | None = None, create: bool = False):
        self.shm = shared_memory.SharedMemory(name=name, create=create, size=SIZE if create else 0)
        buf = self.shm.buf
        assert buf is not None  # None only once closed
        if create:
            buf[:SIZE] = bytes(SIZE)
        self.name = self.shm.name
        self.seq = buf[0:8].cast("Q")
        self.ctl = buf[8:24].cast("I")  # head, tail, port, state
        self.bits = {COILS: buf[_OFF[COILS] : _OFF[COILS] + N], DISCRETE: buf[_OFF[DISCRETE] : _OFF[DISCRETE] + N]}
        self.regs = {
            INPUT: buf[_OFF[INPUT] : _OFF[INPUT] + 2 * N].cast("H"),
            HOLDING: buf[_OFF[HOLDING] : _OFF[HOLDING] + 2 * N].cast("H"),
        }
        self.ring = buf[_RING : _RING + RING_SIZE]

    # ---------------------------------------------------------------- snapshot (seqlock)
    def begin_write(self) -> None:
        self.seq[0] += 1

    def end_write(self) -> None:
        self.seq[0] += 1

    def read(self, table: int, address: int, count: int, retries: int = 1000):
        """A consistent copy of `count` entries (list of ints), or None if the writer never settled."""
        seq = self.seq
        src = self.bits[table] if table in (COILS, DISCRETE) else self.regs[table]
        for _ in range(retries):
            s1 = seq[0]
            if s1 & 1:
                continue
            values = src[address : address + count].tolist()
            if seq[0] == s1:
                return values
        return None

    # ---------------------------------------------------------------- the write ring
    def put_write(self, table: int, address: int, values: list) -> bool:
        """Producer (server): queue one write; False when the ring is full."""
        payload = bytes(values) if table in (COILS, DISCRETE) else struct.pack(f"<{len(values)}H", *values)
        msg = _MSG.pack(_MSG.size + len(payload), table, address, len(values)) + payload
        head, tail = self.ctl[0], self.ctl[1]
        if RING_SIZE - ((head - tail) & 0xFFFFFFFF) < len(msg):
            return False
        self._copy_in(head % RING_SIZE, msg)
        self.ctl[0] = (head + len(msg)) & 0xFFFFFFFF  # publish after the bytes are in place
        return True

    def pending(self) -> bool:
        return self.ctl[0] != self.ctl[1]

    def take_writes(self) -> list:
        """Consumer (PLC): every queued write as (table, address, values)."""
        out = []
        head, tail = self.ctl[0], self.ctl[1]
        while tail != head:
            hdr = self._copy_out(tail % RING_SIZE, _MSG.size)
            total, table, address, count = _MSG.unpack(hdr)
            body = self._copy_out((tail + _MSG.size) % RING_SIZE, total - _MSG.size)
            values = list(body) if table in (COILS, DISCRETE) else list(struct.unpack(f"<{count}H", body))
            out.append((table, address, values))
            tail = (tail + total) & 0xFFFFFFFF
        self.ctl[1] = tail
        return out

    def _copy_in(self, pos: int, data: bytes) -> None:
        first = min(len(data), RING_SIZE - pos)
        self.ring[pos : pos + first] = data[:first]
        if first < len(data):
            self.ring[0 : len(data) - first] = data[first:]

    def _copy_out(self, pos: int, n: int) -> bytes:
        first = min(n, RING_SIZE - pos)
        data = bytes(self.ring[pos : pos + first])
        if first < n:
            data += bytes(self.ring[0 : n - first])
        return data

    # ---------------------------------------------------------------- server state
    @property
    def port(self) -> int:
        return self.ctl[2]

    def set_port(self, port: int) -> None:
        self.ctl[2] = port

    @property
    def state(self) -> int:
        """0 starting, 1 serving, 2 failed to bind."""
        return self.ctl[3]

    def set_state(self, s: int) -> None:
        self.ctl[3] = s

    def close(self, unlink: bool = False) -> None:
        for mv in (self.seq, self.ctl, *self.bits.values(), *self.regs.values(), self.ring):
            mv.release()
        self.shm.close()
        if unlink:
            try:
                self.shm.unlink()
            except FileNotFoundError:
                pass
