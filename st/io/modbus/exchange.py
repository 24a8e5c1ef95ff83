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

from ..shm import Document, MessageRing, SeqLock, SharedBlock

N = 65536
COILS, DISCRETE, INPUT, HOLDING = 0, 1, 2, 3
TABLE_NAMES = {COILS: "coils", DISCRETE: "discrete inputs", INPUT: "input registers", HOLDING: "holding registers"}

# seq u64 @0, ring head u32 @8, ring tail u32 @12, port u32 @16, state u32 @20, status length
# u32 @24, status seq u64 @32
_HDR = 64
_OFF = {COILS: _HDR, DISCRETE: _HDR + N, INPUT: _HDR + 2 * N, HOLDING: _HDR + 4 * N}
_RING = _HDR + 6 * N
RING_SIZE = 1 << 16
_STATUS = _RING + RING_SIZE
STATUS_SIZE = 1 << 14  # the server's status (its connected clients, JSON), written once a second
SIZE = _STATUS + STATUS_SIZE

_MSG = struct.Struct("<BHH")  # table, address, count; then the values (one ring message)


class Exchange(SharedBlock):
    """Both sides' view of the block; `create=True` on the PLC side (which owns and unlinks it)."""

    def __init__(self, name: str | None = None, create: bool = False):
        super().__init__(SIZE, name, create)
        self.seq = self.view(0, 8, "Q")
        self.ctl = self.view(8, 28, "I")  # head, tail, port, state, status length
        self.status_seq = self.view(32, 40, "Q")
        self.status_buf = self.view(_STATUS, _STATUS + STATUS_SIZE)
        self._status = Document(SeqLock(self.status_seq), self.status_buf, self.ctl, 4)
        self.bits = {
            COILS: self.view(_OFF[COILS], _OFF[COILS] + N),
            DISCRETE: self.view(_OFF[DISCRETE], _OFF[DISCRETE] + N),
        }
        self.regs = {
            INPUT: self.view(_OFF[INPUT], _OFF[INPUT] + 2 * N, "H"),
            HOLDING: self.view(_OFF[HOLDING], _OFF[HOLDING] + 2 * N, "H"),
        }
        self.ring = self.view(_RING, _RING + RING_SIZE)
        self.lock = SeqLock(self.seq)
        self.writes = MessageRing(self.ring, self.view(8, 16, "I"))

    # ---------------------------------------------------------------- snapshot (seqlock)
    def begin_write(self) -> None:
        self.lock.begin_write()

    def end_write(self) -> None:
        self.lock.end_write()

    def read(self, table: int, address: int, count: int, retries: int = 1000):
        """A consistent copy of `count` entries (list of ints), or None if the writer never settled."""
        src = self.bits[table] if table in (COILS, DISCRETE) else self.regs[table]
        return self.lock.read(lambda: src[address : address + count].tolist(), retries)

    # ---------------------------------------------------------------- the write ring
    def put_write(self, table: int, address: int, values: list) -> bool:
        """Producer (server): queue one write; False when the ring is full."""
        payload = bytes(values) if table in (COILS, DISCRETE) else struct.pack(f"<{len(values)}H", *values)
        return self.writes.put(_MSG.pack(table, address, len(values)) + payload)

    def pending(self) -> bool:
        return self.writes.pending()

    def take_writes(self) -> list:
        """Consumer (PLC): every queued write as (table, address, values)."""
        out = []
        for msg in self.writes.take():
            table, address, count = _MSG.unpack_from(msg)
            body = msg[_MSG.size :]
            values = list(body) if table in (COILS, DISCRETE) else list(struct.unpack(f"<{count}H", body))
            out.append((table, address, values))
        return out

    # ---------------------------------------------------------------- the server's status
    def set_status(self, doc: bytes) -> None:
        """Server: its status document (cut to the block's size)."""
        self._status.write(doc[:STATUS_SIZE])

    def status(self) -> bytes:
        """PLC: the server's latest status document (b"" before the first, or if it never settled)."""
        return self._status.read() or b""

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
