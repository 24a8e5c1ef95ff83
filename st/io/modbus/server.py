"""The Modbus TCP server: its own process, asyncio, pymodbus PDUs, our framing and limits.

pymodbus 3.x decodes the request PDUs and encodes the responses. Its TCP server falls short of
what a PLC's HMI port needs (measured, ../shared/notes/modbus.md: only the first of several
requests in one segment is answered, over-limit quantities get the wrong exception, the function
code is lost from an 01 exception, FC5 takes any value as ON, there is no connection limit or idle
timeout, a malformed frame logs other clients' frames), so the transport, the MBAP framing, the
request validation and the access rules live here, around pymodbus's PDU classes:

- every complete frame in the buffer is answered, in order; a frame with a protocol id other than
  0 or a length outside 2..254 closes that connection (the stream cannot be resynchronised);
- exceptions: 01 unsupported function (echoed + 0x80), and every write function (5, 6, 15, 16,
  23) of a read-only server, before its request is looked at; 02 address outside the map or
  outside the writable ranges, 03 illegal quantity / byte count / FC5 value, 06 busy (the PLC has
  not taken the queued writes), 0x0B for a unit id the policy does not serve;
- at most `max_connections`, an idle timeout, a per-connection request rate (excess requests wait:
  reading pauses), and flow control: a client that does not read its replies stops being read.

The connection limit protects clients that poll. A connection is *regular* once it has completed
requests at least REGULAR_AFTER seconds apart (two polls of an HMI, however slow, as long as it
polls within the idle timeout); a regular connection is never evicted. When a new connection
finds every slot taken, one that is not regular makes room for it, ranked by: no completed
request before any, then the peer address holding the most non-regular connections (the new one
counts for its address), then the oldest of those without a request, the newest of the others.
So a client opening short connections in a loop churns through its own connections and leaves
older clients alone. When every other connection is regular the new one is refused (closed);
refusals are logged at most once per REFUSAL_LOG_INTERVAL, with their count.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import signal
import struct
import time
from collections import Counter

from .exchange import COILS, DISCRETE, HOLDING, INPUT, Exchange

log = logging.getLogger("st.modbus")

MAX_BITS_READ, MAX_REGS_READ = 2000, 125
MAX_BITS_WRITE, MAX_REGS_WRITE, MAX_REGS_RW_WRITE = 1968, 123, 121
ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, SERVER_FAILURE, BUSY, GATEWAY_NO_RESPONSE = 1, 2, 3, 4, 6, 0x0B
READ_TABLE = {1: COILS, 2: DISCRETE, 3: HOLDING, 4: INPUT}
WRITE_FUNCTIONS = frozenset((5, 6, 15, 16, 23))  # a read-only server answers these with 01
REGULAR_AFTER = 1.0  # s between a connection's first and latest request: it polls, never evicted
REFUSAL_LOG_INTERVAL = 10.0  # s: refused connections are logged at most this often, with their count


class ServerConfig:
    """Everything the server process needs (picklable)."""

    def __init__(
        self,
        host="127.0.0.1",
        port=5020,
        valid=None,
        owned=None,
        writable=None,
        read_only=False,
        max_connections=16,
        idle_timeout=60.0,
        max_rate=1000.0,
        unit_ids=None,
        identity=None,
    ):
        self.host, self.port = host, port
        self.valid = valid or {}  # table → sorted [(first, end)] addresses that exist
        self.owned = owned or {}  # table → [(first, end)] cells the PLC owns (writes queued)
        self.writable = writable  # None (everything writable) or table → [(first, end)]
        self.read_only = read_only  # every write function answers 01 (illegal function)
        self.max_connections = max_connections
        self.idle_timeout = idle_timeout
        self.max_rate = max_rate
        self.unit_ids = unit_ids  # None: every unit id; else a set
        self.identity = identity or {}


def _covers(ranges, first: int, end: int) -> bool:
    """True when [first, end) lies inside the union of the sorted, merged ranges."""
    for lo, hi in ranges:
        if lo <= first < hi:
            if end <= hi:
                return True
            first = hi
        elif lo > first:
            return False
    return False


def _overlaps(ranges, first: int, end: int) -> bool:
    return any(lo < end and first < hi for lo, hi in ranges)


class Handler:
    """Request PDU → response PDU bytes, against the shared tables."""

    def __init__(self, cfg: ServerConfig, ex: Exchange):
        from pymodbus.pdu import DecodePDU

        self.cfg, self.ex = cfg, ex
        self.decoder = DecodePDU(is_server=True)

    def handle(self, unit: int, pdu: bytes) -> bytes:
        fc = pdu[0]
        if self.cfg.unit_ids is not None and unit not in self.cfg.unit_ids:
            return bytes((fc | 0x80, GATEWAY_NO_RESPONSE))
        try:
            return self._dispatch(fc, pdu)
        except _Exc as e:
            return bytes(((fc & 0x7F) | 0x80, e.code))
        except Exception as e:  # noqa: BLE001 - a request must never take the server down
            log.error("function %d: %s: %s", fc, type(e).__name__, e)
            return bytes(((fc & 0x7F) | 0x80, SERVER_FAILURE))

    def _dispatch(self, fc: int, pdu: bytes) -> bytes:
        from pymodbus.pdu import bit_message as B
        from pymodbus.pdu import register_message as R

        n = len(pdu)
        if self.cfg.read_only and fc in WRITE_FUNCTIONS:
            # the function itself is not allowed on this server, whatever its address or values:
            # 01, as the Modbus application protocol says for a function the server does not take
            raise _Exc(ILLEGAL_FUNCTION)
        if fc in (1, 2, 3, 4):
            if n != 5:
                raise _Exc(ILLEGAL_VALUE)
            address, count = struct.unpack(">HH", pdu[1:5])
            limit = MAX_BITS_READ if fc in (1, 2) else MAX_REGS_READ
            if not 1 <= count <= limit:
                raise _Exc(ILLEGAL_VALUE)
            values = self._read(READ_TABLE[fc], address, count)
            cls = {
                1: B.ReadCoilsResponse,
                2: B.ReadDiscreteInputsResponse,
                3: R.ReadHoldingRegistersResponse,
                4: R.ReadInputRegistersResponse,
            }[fc]
            resp = cls(bits=[bool(v) for v in values]) if fc in (1, 2) else cls(registers=values)
            return bytes((fc,)) + resp.encode()
        if fc == 5:
            if n != 5:
                raise _Exc(ILLEGAL_VALUE)
            address, value = struct.unpack(">HH", pdu[1:5])
            if value not in (0x0000, 0xFF00):
                raise _Exc(ILLEGAL_VALUE)
            self._write(COILS, address, [1 if value else 0])
            return pdu
        if fc == 6:
            if n != 5:
                raise _Exc(ILLEGAL_VALUE)
            address, value = struct.unpack(">HH", pdu[1:5])
            self._write(HOLDING, address, [value])
            return pdu
        if fc == 15:
            if n < 6:
                raise _Exc(ILLEGAL_VALUE)
            address, count, nbytes = struct.unpack(">HHB", pdu[1:6])
            if not 1 <= count <= MAX_BITS_WRITE or nbytes != (count + 7) // 8 or n != 6 + nbytes:
                raise _Exc(ILLEGAL_VALUE)
            req = self.decoder.decode(pdu)
            assert isinstance(req, B.WriteMultipleCoilsRequest)  # the lengths were checked above
            self._write(COILS, address, [1 if b else 0 for b in list(req.bits)[:count]])
            return bytes((fc,)) + B.WriteMultipleCoilsResponse(address=address, count=count).encode()
        if fc == 16:
            if n < 6:
                raise _Exc(ILLEGAL_VALUE)
            address, count, nbytes = struct.unpack(">HHB", pdu[1:6])
            if not 1 <= count <= MAX_REGS_WRITE or nbytes != 2 * count or n != 6 + nbytes:
                raise _Exc(ILLEGAL_VALUE)
            req = self.decoder.decode(pdu)
            assert isinstance(req, R.WriteMultipleRegistersRequest)  # the lengths were checked above
            self._write(HOLDING, address, list(req.registers))
            return bytes((fc,)) + R.WriteMultipleRegistersResponse(address=address, count=count).encode()
        if fc == 23:
            if n < 10:
                raise _Exc(ILLEGAL_VALUE)
            raddr, rcount, waddr, wcount, nbytes = struct.unpack(">HHHHB", pdu[1:10])
            if (
                not 1 <= rcount <= MAX_REGS_READ
                or not 1 <= wcount <= MAX_REGS_RW_WRITE
                or nbytes != 2 * wcount
                or n != 10 + nbytes
            ):
                raise _Exc(ILLEGAL_VALUE)
            req = self.decoder.decode(pdu)
            assert isinstance(req, R.ReadWriteMultipleRegistersRequest)  # the lengths were checked above
            written = list(req.write_registers)
            self._check(HOLDING, raddr, rcount, write=False)
            self._write(HOLDING, waddr, written)  # the write happens before the read
            values = self._read(HOLDING, raddr, rcount)
            for i in range(rcount):  # a queued write shows in this reply already
                a = raddr + i
                if waddr <= a < waddr + wcount:
                    values[i] = written[a - waddr]
            return bytes((fc,)) + R.ReadWriteMultipleRegistersResponse(registers=values).encode()
        if fc == 43:
            return self._device_identification(pdu)
        raise _Exc(ILLEGAL_FUNCTION)

    # ------------------------------------------------------------------ tables
    def _check(self, table: int, address: int, count: int, write: bool) -> None:
        end = address + count
        if end > 65536 or not _covers(self.cfg.valid.get(table, ()), address, end):
            raise _Exc(ILLEGAL_ADDRESS)
        if write:
            if self.cfg.read_only:  # (refused with 01 before: a write never gets here)
                raise _Exc(ILLEGAL_FUNCTION)
            w = self.cfg.writable
            if w is not None and not _covers(w.get(table, ()), address, end):
                raise _Exc(ILLEGAL_ADDRESS)

    def _read(self, table: int, address: int, count: int) -> list:
        self._check(table, address, count, write=False)
        values = self.ex.read(table, address, count)
        if values is None:
            raise _Exc(BUSY)
        return values

    def _write(self, table: int, address: int, values: list) -> None:
        self._check(table, address, len(values), write=True)
        # every write goes to the PLC, which applies what its current bindings own (they can
        # change with an online change); scratch memory (cells no variable owns) takes the values
        # here at once, owned cells show the PLC's value after its next publish
        if not self.ex.put_write(table, address, values):
            raise _Exc(BUSY)
        owned = self.cfg.owned.get(table, ())
        dst = self.ex.bits[table] if table in (COILS, DISCRETE) else self.ex.regs[table]
        for i, v in enumerate(values):
            a = address + i
            if not _overlaps(owned, a, a + 1):
                dst[a] = v

    def _device_identification(self, pdu: bytes) -> bytes:
        from pymodbus.pdu.mei_message import ReadDeviceInformationResponse

        if len(pdu) != 4 or pdu[1] != 0x0E:
            raise _Exc(ILLEGAL_FUNCTION if len(pdu) >= 2 and pdu[1] != 0x0E else ILLEGAL_VALUE)
        read_code, object_id = pdu[2], pdu[3]
        ident = {int(k): v.encode("latin-1", "replace") for k, v in self.cfg.identity.items()}
        if read_code not in (1, 2, 3, 4):
            raise _Exc(ILLEGAL_VALUE)
        if read_code == 4:
            if object_id not in ident:
                raise _Exc(ILLEGAL_ADDRESS)
            info = {object_id: ident[object_id]}
        else:
            top = {1: 0x02, 2: 0x06, 3: 0xFF}[read_code]
            start = object_id if object_id in ident and object_id <= top else 0
            info = {k: v for k, v in sorted(ident.items()) if start <= k <= top}
        resp = ReadDeviceInformationResponse(read_code=read_code, information=info)
        resp.conformity = 0x83
        return bytes((43,)) + resp.encode()


class _Exc(Exception):
    def __init__(self, code: int):
        self.code = code


class Server:
    def __init__(self, cfg: ServerConfig, ex: Exchange):
        self.cfg = cfg
        self.ex = ex
        self.handler = Handler(cfg, ex)
        self.conns: set = set()
        self.served = 0
        self.accepted = 0  # connections seen: their sequence numbers (newest = highest)
        self.refused = 0  # refused since the last report
        self.refused_last = "?"
        self.refused_reported = float("-inf")

    def admit(self, new: Connection) -> bool:
        """Make room for `new` under the connection limit: evict one connection that is not regular,
        or refuse `new` (close it, False) when every other connection is regular. O(connections)."""
        others = [c for c in self.conns if c is not new]
        if len(others) < self.cfg.max_connections:
            return True
        now = time.monotonic()
        candidates = [c for c in others if not c.regular]
        if not candidates:
            new.close()
            self.refused += 1
            self.refused_last = new.peer
            self.report_refusals(now)
            return False
        held = Counter(c.host for c in candidates)
        held[new.host] += 1
        # never active first (the oldest: it had the longest chance to send a request), then the peer
        # address holding the most evictable slots, then the newest
        victim = min(candidates, key=lambda c: (c.requests > 0, -held[c.host], -c.seq if c.requests else c.seq))
        log.info(
            "connection limit %d: closing %s (%d request(s), idle %.1f s) for %s",
            self.cfg.max_connections,
            victim.peer,
            victim.requests,
            now - victim.last_activity,
            new.peer,
        )
        victim.close()
        return True

    def report_refusals(self, now: float, final: bool = False) -> None:
        if self.refused and (final or now - self.refused_reported >= REFUSAL_LOG_INTERVAL):
            log.warning(
                "connection limit %d: every connection is a regular client; refused %d new "
                "connection(s), the last from %s",
                self.cfg.max_connections,
                self.refused,
                self.refused_last,
            )
            self.refused = 0
            self.refused_reported = now

    async def reaper(self) -> None:
        while True:
            await asyncio.sleep(min(1.0, self.cfg.idle_timeout / 2))
            now = time.monotonic()
            for c in list(self.conns):
                if now - c.last_activity > self.cfg.idle_timeout:
                    log.info("%s idle for %.1f s: closing", c.peer, now - c.last_activity)
                    c.close()
            self.report_refusals(now)
            self.publish_status()

    def publish_status(self) -> None:
        """The connected clients, for the PLC's side (`ModbusSlave.clients`, the web page): when
        one comes or goes, and once a second for their request counts."""
        clients = [
            {"peer": c.peer, "requests": c.requests, "regular": c.regular}
            for c in sorted(self.conns, key=lambda c: c.seq)[:100]
        ]
        self.ex.set_status(json.dumps({"clients": clients, "served": self.served}).encode())


class Connection(asyncio.Protocol):
    def __init__(self, server: Server):
        self.server = server
        self.buf = bytearray()
        self.transport: asyncio.Transport | None = None  # set by connection_made, before any data
        self.peer = self.host = "?"
        server.accepted += 1
        self.seq = server.accepted
        self.last_activity = time.monotonic()  # the latest complete request (or the connect)
        self.requests = 0
        self.first_request = 0.0
        self.regular = False  # requests REGULAR_AFTER s apart: never evicted
        self.write_paused = False
        self.rate_paused = False
        self.tokens = server.cfg.max_rate
        self.t_tokens = time.monotonic()

    def connection_made(self, transport) -> None:
        self.transport = transport
        p = transport.get_extra_info("peername")
        if p:
            self.host, self.peer = str(p[0]), f"{p[0]}:{p[1]}"
        transport.set_write_buffer_limits(high=64 * 1024)
        self.server.conns.add(self)
        self.server.admit(self)
        self.server.publish_status()

    def connection_lost(self, exc) -> None:
        self.server.conns.discard(self)
        self.buf.clear()
        self.server.publish_status()

    def close(self) -> None:
        self.server.conns.discard(self)  # at once: connection_lost comes a loop turn later
        if self.transport is not None:
            self.transport.abort()

    def data_received(self, data: bytes) -> None:
        self.buf += data
        self.process()

    def pause_writing(self) -> None:  # the client does not read its replies: stop reading it
        self.write_paused = True
        assert self.transport is not None
        self.transport.pause_reading()

    def resume_writing(self) -> None:
        self.write_paused = False
        assert self.transport is not None
        if not self.rate_paused:
            self.transport.resume_reading()
        self.process()

    def _resume_rate(self) -> None:
        self.rate_paused = False
        assert self.transport is not None
        if not self.write_paused and not self.transport.is_closing():
            self.transport.resume_reading()
            self.process()

    def process(self) -> None:
        buf = self.buf
        out: list[bytes] = []
        while len(buf) >= 7 and not self.write_paused and not self.rate_paused:
            tid, pid, length = struct.unpack_from(">HHH", buf)
            if pid != 0 or not 2 <= length <= 254:
                log.warning(
                    "%s: malformed MBAP header (protocol id %d, length %d): %s…; closing",
                    self.peer,
                    pid,
                    length,
                    bytes(buf[:12]).hex(" "),
                )
                self._flush(out)
                self.close()
                return
            if len(buf) < 6 + length:
                break
            if not self._take_token():
                break
            unit = buf[6]
            pdu = bytes(buf[7 : 6 + length])
            del buf[: 6 + length]
            now = time.monotonic()
            if not self.requests:
                self.first_request = now
            elif now - self.first_request >= REGULAR_AFTER:
                self.regular = True
            self.requests += 1
            self.last_activity = now
            reply = self.server.handler.handle(unit, pdu)
            out.append(struct.pack(">HHHB", tid, 0, len(reply) + 1, unit) + reply)
        self._flush(out)

    def _flush(self, out: list) -> None:
        assert self.transport is not None
        if out and not self.transport.is_closing():
            self.transport.write(b"".join(out))
            self.server.served += len(out)

    def _take_token(self) -> bool:
        rate = self.server.cfg.max_rate
        if not rate:
            return True
        now = time.monotonic()
        self.tokens = min(rate, self.tokens + (now - self.t_tokens) * rate)
        self.t_tokens = now
        if self.tokens >= 1:
            self.tokens -= 1
            return True
        self.rate_paused = True
        assert self.transport is not None
        self.transport.pause_reading()
        asyncio.get_running_loop().call_later((1 - self.tokens) / rate, self._resume_rate)
        return False


def serve(cfg: ServerConfig, shm_name: str, parent_pid: int) -> None:
    """Entry point of the server process."""
    logging.basicConfig(level=os.environ.get("ST_MODBUS_LOG", "WARNING"), format="st modbus: %(levelname)s %(message)s")
    ex = Exchange(shm_name)  # (attached: the PLC owns and unlinks it, st/io/shm.py)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C goes to the PLC, which stops us
    try:
        asyncio.run(_main(cfg, ex, parent_pid))
    finally:
        ex.close()


async def _main(cfg: ServerConfig, ex: Exchange, parent_pid: int) -> None:
    server = Server(cfg, ex)
    loop = asyncio.get_running_loop()
    stop = loop.create_future()

    def on_sigterm() -> None:
        if not stop.done():
            stop.set_result(None)

    loop.add_signal_handler(signal.SIGTERM, on_sigterm)
    try:
        srv = await loop.create_server(lambda: Connection(server), cfg.host, cfg.port, reuse_address=True, backlog=1024)
    except OSError as e:
        log.error("cannot listen on %s:%s: %s", cfg.host, cfg.port, e.strerror)
        ex.set_state(2)
        return
    ex.set_port(srv.sockets[0].getsockname()[1])
    ex.set_state(1)
    reaper = loop.create_task(server.reaper())

    async def orphan_watch():
        while os.getppid() == parent_pid:
            await asyncio.sleep(0.5)
        stop.done() or stop.set_result(None)

    watch = loop.create_task(orphan_watch())
    await stop
    reaper.cancel()
    server.report_refusals(time.monotonic(), final=True)
    watch.cancel()
    srv.close()
    for c in list(server.conns):
        c.close()
