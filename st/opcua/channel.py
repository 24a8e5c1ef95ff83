"""The shared memory between the PLC process and the OPC UA server process.

The same shape as the online mode's (st/web/channel.py, st/io/shm.py): neither side ever waits
for the other.

- **Description** (PLC → server): the address space as JSON (symbols.py), written again after
  an online change (its version counts up).
- **Snapshot** (PLC → server): the published variables' values of one scan, the PLC time of that
  scan, the PLC's state and its tasks' figures, and the results of the writes and commands
  applied since the last (marshal), under a seqlock.
- **Request ring** (server → PLC): writes and commands (JSON), applied by the PLC at a scan boundary.
- **Control words**: the server's state and port, and the sampling interval the clients asked
  for (the PLC samples no more often than that).
"""

from __future__ import annotations

from ..io.shm import Document, MessageRing, SeqLock, SharedBlock

SNAPSHOT_SIZE = 8 << 20
DESCRIPTION_SIZE = 8 << 20
RING_SIZE = 1 << 18
# seq u64 @0; ring head, tail u32 @8; port @16, state @20, sampling µs @24, snapshot length @28,
# description length @32, description version @36
_HDR = 64
SIZE = _HDR + SNAPSHOT_SIZE + DESCRIPTION_SIZE + RING_SIZE
STARTING, SERVING, FAILED = 0, 1, 2


class Channel(SharedBlock):
    """Both sides' view of the block; `create=True` on the PLC side (which owns and unlinks it)."""

    def __init__(self, name: str | None = None, create: bool = False):
        super().__init__(SIZE, name, create)
        self._seq = self.view(0, 8, "Q")
        self._ctl = self.view(8, 40, "I")  # head, tail, port, state, sampling, lengths, version
        snap = _HDR
        desc = snap + SNAPSHOT_SIZE
        ring = desc + DESCRIPTION_SIZE
        self.lock = SeqLock(self._seq)
        self.requests = MessageRing(self.view(ring, SIZE), self.view(8, 16, "I"))
        self._snapshot = Document(self.lock, self.view(snap, desc), self._ctl, 5)
        self._description = Document(self.lock, self.view(desc, ring), self._ctl, 6, version=7)

    # ---------------------------------------------------------------- PLC side
    def publish(self, doc: bytes) -> bool:
        return self._snapshot.write(doc)

    def describe(self, doc: bytes) -> None:
        if not self._description.write(doc):
            raise ValueError(f"the OPC UA address space takes {len(doc)} bytes, more than {DESCRIPTION_SIZE}")

    # ---------------------------------------------------------------- server side
    def latest(self) -> bytes | None:
        return self._snapshot.read() or None

    @property
    def description_version(self) -> int:
        return self._ctl[7]

    def description(self) -> bytes | None:
        return self._description.read()

    # ---------------------------------------------------------------- control words
    @property
    def port(self) -> int:
        return self._ctl[2]

    @port.setter
    def port(self, value: int) -> None:
        self._ctl[2] = value

    @property
    def state(self) -> int:
        return self._ctl[3]

    @state.setter
    def state(self, value: int) -> None:
        self._ctl[3] = value

    @property
    def sampling_us(self) -> int:
        """The fastest sampling interval a client asked for, µs (0: none asked; set by the server)."""
        return self._ctl[4]

    @sampling_us.setter
    def sampling_us(self, value: int) -> None:
        self._ctl[4] = max(0, min(int(value), 0xFFFFFFFF))
