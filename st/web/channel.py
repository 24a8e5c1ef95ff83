"""The shared memory between the PLC process and the web server process.

The web server runs in its own process for the reason the Modbus server does (a server thread
in the scan's process makes the scan wait for the interpreter lock). They exchange through one
`multiprocessing.shared_memory` block and never wait for each other (st/io/shm.py):

- **Snapshot** (PLC → server): the latest state as one JSON document, written by the PLC
  between two jobs under a seqlock; the server copies it and retries if it moved.
- **Request ring** (server → PLC): the pages' subscriptions and changes (JSON messages),
  drained by the PLC between two jobs.
- **Control words**: the server's port and state, and how many pages are connected (the PLC
  builds no snapshot while none is).
"""

from __future__ import annotations

import struct

from ..io.shm import Document, MessageRing, SeqLock, SharedBlock

SNAPSHOT_SIZE = 8 << 20  # the largest snapshot (values of a few thousand variables fit easily)
DESCRIPTION_SIZE = 16 << 20  # the program's description (its sources included)
RING_SIZE = 1 << 18
# seq u64 @0; ring head, tail u32 @8; port @16, state @20, pages @24, snapshot length @28,
# description length @32, description version @36, the number of the last snapshot read @40
_HDR = 64
_DESC = _HDR + SNAPSHOT_SIZE
SIZE = _DESC + DESCRIPTION_SIZE + RING_SIZE
STARTING, SERVING, FAILED = 0, 1, 2
_LEN = struct.Struct("<I")


class Channel(SharedBlock):
    """Both sides' view of the block; `create=True` on the PLC side (which owns and unlinks it)."""

    def __init__(self, name: str | None = None, create: bool = False):
        super().__init__(SIZE, name, create)
        self._seq = self.view(0, 8, "Q")
        self._ctl = self.view(8, 44, "I")  # head, tail, port, state, pages, lengths, version, read
        self._snap = self.view(_HDR, _HDR + SNAPSHOT_SIZE)
        self._desc = self.view(_DESC, _DESC + DESCRIPTION_SIZE)
        self._ring = self.view(_DESC + DESCRIPTION_SIZE, SIZE)
        self.lock = SeqLock(self._seq)
        self.requests = MessageRing(self._ring, self.view(8, 16, "I"))
        self._snapshot = Document(self.lock, self._snap, self._ctl, 5)
        self._description = Document(self.lock, self._desc, self._ctl, 6, version=7)

    # ---------------------------------------------------------------- PLC side
    def publish(self, doc: bytes) -> bool:
        """The latest snapshot; False (nothing written) when it is larger than the block."""
        return self._snapshot.write(doc)

    def describe(self, doc: bytes) -> None:
        """The program's description (again after an online change: its version counts up)."""
        if not self._description.write(doc):
            raise ValueError(f"the program's description takes {len(doc)} bytes, more than {DESCRIPTION_SIZE}")

    # ---------------------------------------------------------------- server side
    def latest(self) -> bytes | None:
        """A consistent copy of the latest snapshot (None before the first, or if it never settled)."""
        return self._snapshot.read() or None

    @property
    def description_version(self) -> int:
        return self._ctl[7]

    def description(self) -> tuple[int, bytes] | None:
        """(version, a consistent copy of the description), None if it never settled."""
        return self.lock.read(lambda: (self._ctl[7], bytes(self._desc[: self._ctl[6]])))

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
    def pages(self) -> int:
        """Pages connected (set by the server)."""
        return self._ctl[4]

    @pages.setter
    def pages(self, value: int) -> None:
        self._ctl[4] = value

    @property
    def consumed(self) -> int:
        """The number of the last snapshot the server read (set by the server)."""
        return self._ctl[8]

    @consumed.setter
    def consumed(self, value: int) -> None:
        self._ctl[8] = value & 0xFFFFFFFF
