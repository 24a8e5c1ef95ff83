"""Shared memory between the PLC process and a server process (Modbus, the web page), lock-free.

Three pieces, used by st.io.modbus.exchange and st.web.channel:

- `SharedBlock`: one named block and the views cut from it (the PLC's side creates, clears and
  finally unlinks it; the server's side attaches by name).
- `SeqLock`: a counter that is odd while the writer (the PLC) updates a region; a reader copies
  the region and retries when the counter moved, so it never sees a torn value and the writer
  never waits. `Document`: one variable-length document in a region under a seqlock.
- `MessageRing`: a single-producer single-consumer ring of length-prefixed messages (the server
  produces, the PLC drains at a scan boundary). A full ring refuses a message instead of
  blocking the producer.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from multiprocessing import resource_tracker, shared_memory
from typing import TypeVar

T = TypeVar("T")

_LEN = struct.Struct("<I")


class SharedBlock:
    """`size` bytes of shared memory: created (and zeroed) when `create`, else attached by `name`."""

    def __init__(self, size: int, name: str | None = None, create: bool = False):
        self.shm = shared_memory.SharedMemory(name=name, create=create, size=size if create else 0)
        if not create:
            # the creator owns and unlinks it: an attaching process's resource tracker must not
            # (Python < 3.13 registers every attach; at exit it would unlink the block and warn
            # "leaked shared_memory")
            try:
                resource_tracker.unregister(self.shm._name, "shared_memory")  # type: ignore[attr-defined]
            except Exception:  # noqa: BLE001 - best effort: at worst the warning comes back
                pass
        buf = self.shm.buf
        assert buf is not None  # None only once closed
        if create:
            buf[:size] = bytes(size)
        self.name = self.shm.name
        self._buf = buf
        self._views: list[memoryview] = []

    def view(self, start: int, end: int, fmt: str = "") -> memoryview:
        """Bytes start..end of the block (cast to `fmt`: "Q", "I", "H"), released by close()."""
        mv = self._buf[start:end]
        if fmt:
            mv = mv.cast(fmt)  # type: ignore[call-overload]  # (a format chosen by the caller)
        self._views.append(mv)
        return mv

    def close(self, unlink: bool = False) -> None:
        for mv in self._views:
            mv.release()
        self._views.clear()
        self.shm.close()
        if unlink:
            try:
                self.shm.unlink()
            except FileNotFoundError:
                pass


class SeqLock:
    """Over one u64 (`seq`, a memoryview cast to "Q")."""

    def __init__(self, seq: memoryview):
        self.seq = seq

    def begin_write(self) -> None:
        self.seq[0] += 1

    def end_write(self) -> None:
        self.seq[0] += 1

    def read(self, copy: Callable[[], T], retries: int = 1000) -> T | None:
        """`copy()` of a consistent state, or None if the writer never settled."""
        seq = self.seq
        for _ in range(retries):
            s1 = seq[0]
            if s1 & 1:
                continue
            value = copy()
            if seq[0] == s1:
                return value
        return None


class Document:
    """A document of up to len(`region`) bytes; its length is `words[index]` (and, with
    `version`, words[version] counts its writes). The writer replaces it, a reader copies it whole."""

    def __init__(self, lock: SeqLock, region: memoryview, words: memoryview, index: int, version: int = -1):
        self.lock, self.region, self.words, self.index, self.version = lock, region, words, index, version

    def write(self, doc: bytes) -> bool:
        """False (nothing written) when `doc` is larger than the region."""
        if len(doc) > len(self.region):
            return False
        self.lock.begin_write()
        try:
            self.region[: len(doc)] = doc
            self.words[self.index] = len(doc)
            if self.version >= 0:
                self.words[self.version] += 1
        finally:
            self.lock.end_write()
        return True

    def read(self) -> bytes | None:
        """A consistent copy (b"" before the first write), None if the writer never settled."""
        return self.lock.read(lambda: bytes(self.region[: self.words[self.index]]))


class MessageRing:
    """Over `ring` (bytes) with `ctl[0]` the head (producer) and `ctl[1]` the tail (consumer),
    both free-running u32 byte counters (a memoryview cast to "I")."""

    def __init__(self, ring: memoryview, ctl: memoryview):
        self.ring, self.ctl, self.size = ring, ctl, len(ring)

    def put(self, payload: bytes) -> bool:
        """Producer: queue one message; False when the ring has no room for it."""
        msg = _LEN.pack(len(payload)) + payload
        head, tail = self.ctl[0], self.ctl[1]
        if self.size - ((head - tail) & 0xFFFFFFFF) < len(msg):
            return False
        self._copy_in(head % self.size, msg)
        self.ctl[0] = (head + len(msg)) & 0xFFFFFFFF  # published after the bytes are in place
        return True

    def pending(self) -> bool:
        return self.ctl[0] != self.ctl[1]

    def take(self) -> list[bytes]:
        """Consumer: every queued message, oldest first."""
        out = []
        head, tail = self.ctl[0], self.ctl[1]
        while tail != head:
            (n,) = _LEN.unpack(self._copy_out(tail % self.size, _LEN.size))
            out.append(self._copy_out((tail + _LEN.size) % self.size, n))
            tail = (tail + _LEN.size + n) & 0xFFFFFFFF
        self.ctl[1] = tail
        return out

    def _copy_in(self, pos: int, data: bytes) -> None:
        first = min(len(data), self.size - pos)
        self.ring[pos : pos + first] = data[:first]
        if first < len(data):
            self.ring[0 : len(data) - first] = data[first:]

    def _copy_out(self, pos: int, n: int) -> bytes:
        first = min(n, self.size - pos)
        data = bytes(self.ring[pos : pos + first])
        if first < n:
            data += bytes(self.ring[0 : n - first])
        return data
