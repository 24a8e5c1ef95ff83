"""The PLC side of the Modbus TCP slave: starts the server process and exchanges data at job boundaries.

At the end of every job the cells the PLC owns (located variables in OpenPLC's map, and the map
file's variables) are published into the shared snapshot; at the start of the next job the
writes the server queued are applied (in arrival order, so the last writer wins). Nothing here
blocks: publishing is a few memory stores per cell inside a seqlock, taking writes is one
comparison when there are none.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from typing import Any

from ...runtime.iodriver import IODriverBase
from ...runtime.scheduler import Task
from ...runtime.values import from_python
from .. import server_process
from .addressmap import OPENPLC_LIMIT, TABLES, Encoding, effective_map, load_map, located_cells
from .exchange import COILS, DISCRETE, HOLDING, INPUT, Exchange
from .server import ServerConfig

DEFAULT_IDENTITY = {
    0: "st",
    1: "st-plc",
    2: "0.1",
    3: "https://example.invalid/st",
    4: "st soft PLC",
    5: "st Modbus TCP slave",
    6: "",
}


def parse_endpoint(text: str, default_host: str = "127.0.0.1"):
    """'[HOST:]PORT' → (host, port); an IPv6 host may be written in brackets ('[::1]:5020')."""
    host, sep, port = str(text).rpartition(":")
    if not sep:
        host = default_host
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    try:
        p = int(port)
    except ValueError:
        raise ValueError(f"--modbus {text!r}: expected [HOST:]PORT, e.g. 127.0.0.1:5020") from None
    if not 0 <= p <= 65535:
        raise ValueError(f"--modbus {text!r}: port {p} is not 0..65535")
    return host or default_host, p


def parse_ranges(text: str) -> dict:
    """'holding:0-99,coil:0-15' → {HOLDING: [(0, 100)], COILS: [(0, 16)]}."""
    out: dict = {}
    for part in filter(None, (p.strip() for p in str(text).split(","))):
        name, _, span = part.partition(":")
        table = TABLES.get(name.strip().lower())
        lo, _, hi = span.partition("-")
        try:
            first, last = int(lo), int(hi or lo)
        except ValueError:
            table = None
        if table is None or not 0 <= first <= last <= 65535:
            raise ValueError(f"writable range {part!r}: expected TABLE:FIRST-LAST, e.g. holding:0-99")
        out.setdefault(table, []).append((first, last + 1))
    return {t: _merge(r) for t, r in out.items()}


def _merge(ranges) -> list:
    out: list[tuple[int, int]] = []
    for lo, hi in sorted(ranges):
        if out and lo <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out


class ModbusSlave(IODriverBase):
    """`st run --modbus`: a Modbus TCP slave for `plc` in its own process.

    host/port: where to listen (port 0 picks a free one: see `.port`); map_file: a TOML map of
    non-located variables; read_only: every write function (5, 6, 15, 16, 23) answers exception 01
    (illegal function), reads are served; writable: '{table: [(first, end)]}' or 'holding:0-99,…';
    max_connections, idle_timeout (s), max_rate (requests/s per connection, 0 = unbounded);
    unit_ids: the unit ids answered (None = all; others get exception 0x0B); log_path: append the
    server's log there instead of to stderr."""

    name = "modbus"

    def __init__(
        self,
        plc,
        host: str = "127.0.0.1",
        port: int = 5020,
        map_file: str | None = None,
        read_only: bool = False,
        writable=None,
        max_connections: int = 16,
        idle_timeout: float = 60.0,
        max_rate: float = 1000.0,
        unit_ids=None,
        identity: dict | None = None,
        log_path: str | None = None,
    ):
        self.plc = plc
        self.log_path = log_path
        self.entries = load_map(map_file, plc) if map_file else []
        if isinstance(writable, str):
            writable = parse_ranges(writable)
        self.cfg = ServerConfig(
            host,
            port,
            writable=writable,
            read_only=read_only,
            max_connections=max_connections,
            idle_timeout=idle_timeout,
            max_rate=max_rate,
            unit_ids=set(unit_ids) if unit_ids is not None else None,
            identity={**DEFAULT_IDENTITY, **(identity or {})},
        )
        self.ex: Exchange | None = None
        self.proc: subprocess.Popen[bytes] | None = None
        self.writes_applied = 0
        self._bits: list = []
        self._words: list = []
        self._vars: list = []
        self._route: dict = {}

    # ------------------------------------------------------------------ life cycle
    def start(self, timeout: float = 10.0) -> ModbusSlave:
        ex = self.ex = Exchange(create=True)
        self.rebind()
        self._set_ranges()
        proc = self.proc = server_process.spawn("st.io.modbus", (self.cfg, ex.name, os.getpid()), self.log_path)
        deadline = time.monotonic() + timeout
        while ex.state == 0 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        if ex.state != 1:
            self.stop()
            raise OSError(
                f"the Modbus server could not listen on {self.cfg.host}:{self.cfg.port}"
                + (" (ports below 1024 need root)" if 0 < self.cfg.port < 1024 else " (address in use?)")
            )
        self.plc.io.append(self)
        self.after_job()
        return self

    @property
    def port(self) -> int:
        return self.ex.port if self.ex is not None else 0

    def stop(self) -> None:
        if self in self.plc.io:
            self.plc.io.remove(self)
        server_process.stop(self.proc)
        self.proc = None
        if self.ex is not None:
            self.ex.close(unlink=True)
            self.ex = None

    def clients(self) -> list[dict]:
        """The connected clients as the server last reported them (within a second):
        [{"peer": "host:port", "requests": n, "regular": bool}]."""
        if self.ex is None:
            return []
        doc = self.ex.status()
        return json.loads(doc).get("clients", []) if doc else []

    def status(self) -> dict[str, Any]:
        """The online mode's view: {"clients": clients()}."""
        return {"clients": self.clients()}

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()

    def map_rows(self) -> list:
        return effective_map(self.plc, self.entries)

    # ------------------------------------------------------------------ what the PLC owns
    def _set_ranges(self) -> None:
        owned: dict = {}
        valid: dict = {t: [(0, OPENPLC_LIMIT[t])] for t in (COILS, DISCRETE, INPUT, HOLDING)}
        for table, address in self._route:
            owned.setdefault(table, []).append((address, address + 1))
        for e in self.entries:
            valid[e.table].append((e.address, e.end))
        self.cfg.owned = {t: _merge(r) for t, r in owned.items()}
        self.cfg.valid = {t: _merge(r) for t, r in valid.items()}

    def rebind(self) -> None:
        """(Re)build the published cells and the write routes from the PLC's current bindings
        (after start, a warm restart or an online change)."""
        if self.ex is None:
            return
        plc = self.plc
        bits, words, route, varcells = [], [], {}, []
        for binds, table, first, n in located_cells(plc, self.entries):
            b = binds[0]
            if n == 1 and b.size == "X":
                bits.append((b.table, b.index, self.ex.bits[table], first))
            else:
                words.append((b.table, b.index, self.ex.regs[table], first, n))
            for k in range(n):
                route[(table, first + k)] = ("cell", binds, k, n)
        for e in self.entries:
            ref = plc.ref(e.path)
            dst = self.ex.bits[e.table] if e.table in (COILS, DISCRETE) else self.ex.regs[e.table]
            cell = [ref, e.encoding, dst, e.address]
            varcells.append(cell)
            for k in range(e.count):
                route[(e.table, e.address + k)] = ("var", cell, k, e.count)
        self._bits, self._words, self._vars, self._route = bits, words, varcells, route

    # ------------------------------------------------------------------ the job boundary
    def after_job(self, task: Task | None = None) -> None:
        """Publish every owned cell into the snapshot (seqlock: readers retry while it moves)."""
        ex = self.ex
        if ex is None:
            return
        ex.begin_write()
        try:
            for table, i, dst, a in self._bits:
                dst[a] = 1 if table[i] else 0
            for table, i, dst, a, n in self._words:
                raw = table[i]
                if n == 1:
                    dst[a] = raw & 0xFFFF
                else:
                    for k in range(n):
                        dst[a + k] = (raw >> (16 * (n - 1 - k))) & 0xFFFF
            for ref, enc, dst, a in self._vars:
                v = ref.get()
                if enc.registers == 0:
                    dst[a] = 1 if v else 0
                else:
                    for k, w in enumerate(enc.to_words(v)):
                        dst[a + k] = w
        finally:
            ex.end_write()

    def before_job(self, task: Task | None = None) -> None:
        """Apply the queued HMI writes, oldest first."""
        ex = self.ex
        if ex is None or not ex.pending():
            return
        for table, address, values in ex.take_writes():
            for k, v in enumerate(values):
                r = self._route.get((table, address + k))
                if r is None:
                    continue
                if r[0] == "cell":
                    self._write_cell(r[1], r[2], r[3], v)
                else:
                    self._write_var(r[1], r[2], r[3], v)
            self.writes_applied += 1

    def _write_cell(self, binds, k: int, n: int, word: int) -> None:
        b = binds[0]
        if b.size == "X":
            raw = bool(word)
        else:
            shift = 16 * (n - 1 - k)
            raw = (b.table[b.index] & ~(0xFFFF << shift)) | ((word & 0xFFFF) << shift)
        b.table[b.index] = raw
        for x in binds:
            x.write_var(x.conv_in(raw))

    def _write_var(self, cell, k: int, n: int, word: int) -> None:
        ref, enc, dst, a = cell
        if enc.registers == 0:
            value = bool(word)
        else:
            words = enc.to_words(ref.get())
            words[k] = word & 0xFFFF
            value = enc.from_words(words)
        try:
            v = from_python(value, ref.type, ref.path)
        except (ValueError, TypeError, OverflowError):
            return  # e.g. a REAL pattern that is NaN for an integer
        ref.set(v)
        b = ref.binding
        if b is not None:
            b.table[b.index] = b.conv_out(v)


__all__ = ["ModbusSlave", "parse_endpoint", "parse_ranges", "Encoding"]
