"""The Modbus TCP slave, driven by clients that are not pymodbus: umodbus (PyPI), mbpoll (Debian)
and raw sockets for exact bytes. The PLC runs on virtual time in the test's thread; the server is
its own process."""

import os
import shutil
import socket
import struct
import subprocess
import textwrap
import threading
import time

import pytest
from umodbus import exceptions as uexc
from umodbus.client import tcp

from st import PLC
from st.io.modbus import MapError, ModbusSlave

PROGRAM = textwrap.dedent("""
    PROGRAM main
      VAR
        lamp AT %QX1.0 : BOOL;
        valve AT %QX0.3 : BOOL;
        flap AT %QX0.4 : BOOL;
        button AT %IX0.2 : BOOL;
        level AT %IW3 : INT;
        setpoint AT %QW0 : INT;
        speed AT %MW2 : UINT;
        total AT %MD1 : DINT;
        big AT %ML0 : LINT;
        temp : REAL := 21.5;
        name : STRING[10] := 'pump';
        count : DINT;
        echo : INT;
      END_VAR
      count := count + 1;
      lamp := button;
      echo := setpoint * 2;
    END_PROGRAM
""")

MAP = textwrap.dedent("""
    [[register]]
    path = "main.temp"
    table = "holding"
    address = 10000
    type = "REAL"

    [[register]]
    path = "main.name"
    table = "input"
    address = 2000

    [[register]]
    path = "main.count"
    table = "input"
    address = 2010
    word_order = "little"
""")


@pytest.fixture
def plc(tmp_path):
    src = tmp_path / "main.st"
    src.write_text(PROGRAM)
    return PLC.from_files(str(src))


@pytest.fixture
def slave(plc, tmp_path):
    m = tmp_path / "map.toml"
    m.write_text(MAP)
    with ModbusSlave(plc, port=0, map_file=str(m), idle_timeout=30) as s:
        yield s


def connect(slave, source: str = "127.0.0.1") -> socket.socket:
    """A client connection; `source` is its own address (any of 127.0.0.0/8 reaches the server)."""
    s = socket.create_connection(("127.0.0.1", slave.port), timeout=5, source_address=(source, 0))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def raw(sock, pdu: bytes, unit=1, tid=7) -> bytes:
    """Send one ADU, return the reply's PDU (after checking its MBAP header)."""
    sock.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu)
    head = _recv(sock, 7)
    rtid, pid, length, runit = struct.unpack(">HHHB", head)
    assert (rtid, pid, runit) == (tid, 0, unit)
    return _recv(sock, length - 1)


def _recv(sock, n) -> bytes:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed")
        data += chunk
    return data


def closed_by_peer(sock, timeout=5.0) -> bool:
    sock.settimeout(timeout)
    try:
        return sock.recv(100) == b""
    except (ConnectionResetError, BrokenPipeError):
        return True


# ---------------------------------------------------------------------------- OpenPLC's map


@pytest.mark.slow
def test_every_table_of_openplc_map_through_umodbus(plc, slave):
    plc["%IX0.2"] = True  # discrete input 2; the program copies it to %QX1.0 (coil 8)
    plc["%IW3"] = -7  # input register 3
    plc["main.setpoint"] = 1234  # holding 0
    plc["main.speed"] = 500  # %MW2 → holding 1026
    plc["main.total"] = 0x12345678  # %MD1 → holding 2050-2051, high word first
    plc["main.big"] = 0x0102030405060708  # %ML0 → holding 4096-4099
    plc.scan()
    s = connect(slave)
    assert tcp.send_message(tcp.read_coils(1, 8, 1), s) == [1]
    assert tcp.send_message(tcp.read_coils(1, 0, 16), s) == [0] * 8 + [1] + [0] * 7
    assert tcp.send_message(tcp.read_discrete_inputs(1, 0, 4), s) == [0, 0, 1, 0]
    assert tcp.send_message(tcp.read_input_registers(1, 3, 1), s) == [0xFFF9]
    assert tcp.send_message(tcp.read_holding_registers(1, 0, 1), s) == [1234]
    assert tcp.send_message(tcp.read_holding_registers(1, 1026, 1), s) == [500]
    assert tcp.send_message(tcp.read_holding_registers(1, 2050, 2), s) == [0x1234, 0x5678]
    assert tcp.send_message(tcp.read_holding_registers(1, 4096, 4), s) == [0x0102, 0x0304, 0x0506, 0x0708]
    # unused addresses read 0 and keep what is written (scratch memory, as OpenPLC)
    assert tcp.send_message(tcp.read_holding_registers(1, 7, 2), s) == [0, 0]
    tcp.send_message(tcp.write_multiple_registers(1, 7, [99, 98]), s)
    assert tcp.send_message(tcp.read_holding_registers(1, 7, 2), s) == [99, 98]
    tcp.send_message(tcp.write_single_coil(1, 100, 1), s)
    assert tcp.send_message(tcp.read_coils(1, 99, 3), s) == [0, 1, 0]
    s.close()


@pytest.mark.slow
def test_writes_are_applied_at_the_start_of_the_next_scan(plc, slave):
    plc.scan()
    s = connect(slave)
    tcp.send_message(tcp.write_single_register(1, 0, 0xFFFD), s)  # %QW0 := -3
    tcp.send_message(tcp.write_single_coil(1, 3, 1), s)  # %QX0.3
    tcp.send_message(tcp.write_multiple_coils(1, 4, [1]), s)  # %QX0.4 only, not the byte
    tcp.send_message(tcp.write_multiple_registers(1, 2050, [0xFFFF, 0xFFFE]), s)  # %MD1 := -2
    assert (plc["main.setpoint"], plc["main.valve"]) == (0, False)  # nothing happens between scans
    plc.scan()
    assert (plc["main.setpoint"], plc["main.echo"], plc["main.valve"], plc["main.flap"], plc["main.total"]) == (
        -3,
        -6,
        True,
        True,
        -2,
    )
    assert tcp.send_message(tcp.read_coils(1, 0, 8), s) == [0, 0, 0, 1, 1, 0, 0, 0]
    # one register of a %MD changes only its half; the last writer wins
    tcp.send_message(tcp.write_single_register(1, 2051, 5), s)
    tcp.send_message(tcp.write_single_register(1, 1026, 1), s)
    tcp.send_message(tcp.write_single_register(1, 1026, 2), s)
    plc.scan()
    assert (plc["main.total"], plc["main.speed"]) == (-65536 + 5, 2)
    assert tcp.send_message(tcp.read_holding_registers(1, 2050, 2), s) == [0xFFFF, 5]
    # read/write multiple (FC23, which umodbus lacks): the reply already shows the write
    assert raw(s, bytes([23, 0, 0, 0, 2, 0, 0, 0, 1, 2, 0, 40])) == bytes([23, 4, 0, 40, 0, 0])
    plc.scan()
    assert plc["main.echo"] == 80
    s.close()


@pytest.mark.slow
def test_map_file_real_string_and_word_order(plc, slave):
    plc["main.count"] = 0x00010002
    plc.scan()
    s = connect(slave)
    assert tcp.send_message(tcp.read_holding_registers(1, 10000, 2), s) == [0x41AC, 0x0000]  # 21.5
    assert tcp.send_message(tcp.read_input_registers(1, 2000, 5), s) == [0x7075, 0x6D70, 0, 0, 0]  # 'pump'
    assert tcp.send_message(tcp.read_input_registers(1, 2010, 2), s) == [0x0003, 0x0001]  # little (the scan added 1)
    pi = struct.unpack(">HH", struct.pack(">f", 3.14159))
    tcp.send_message(tcp.write_multiple_registers(1, 10000, list(pi)), s)
    plc.scan()
    assert plc["main.temp"] == pytest.approx(3.14159, rel=1e-7)
    assert tcp.send_message(tcp.read_holding_registers(1, 10000, 2), s) == list(pi)
    with pytest.raises(uexc.IllegalDataAddressError):  # input registers are read-only
        tcp.send_message(tcp.write_single_register(1, 10002, 1), s)  # and 10002 is outside the map
    s.close()


def test_map_file_errors_name_file_line_and_column(plc, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[register]]\npath = "main.nope"\naddress = 5\n')
    with pytest.raises(MapError) as info:
        ModbusSlave(plc, port=0, map_file=str(bad))
    assert str(info.value).startswith(f"{bad}:2:8: error: no variable 'main.nope' in the program")
    bad.write_text('[[register]]\npath = "main.temp"\ntable = "coil"\naddress = 1\n')
    with pytest.raises(MapError) as info:
        ModbusSlave(plc, port=0, map_file=str(bad))
    assert str(info.value) == f"{bad}:2:8: error: 'main.temp' is REAL: only BOOL variables go into the coils"
    bad.write_text('[[register]]\npath = "main.temp"\naddress = 10\n[[register]]\npath = "main.count"\naddress = 11\n')
    with pytest.raises(MapError) as info:
        ModbusSlave(plc, port=0, map_file=str(bad))
    assert "'main.count' at holding registers 11 overlaps 'main.temp' (10..11)" in str(info.value)


@pytest.mark.slow
def test_st_modbus_map_prints_the_effective_map(tmp_path):
    (tmp_path / "main.st").write_text(PROGRAM)
    (tmp_path / "map.toml").write_text(MAP)
    out = subprocess.run(
        ["st", "modbus", "map", str(tmp_path / "main.st"), "--modbus-map", str(tmp_path / "map.toml")],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    lines = [ln.split() for ln in out.stdout.splitlines()[1:-1]]
    assert [ln[:4] if ln[0] != "coils" else ln[:3] for ln in lines][:3] == [
        ["coils", "3", "%QX0.3"],
        ["coils", "4", "%QX0.4"],
        ["coils", "8", "%QX1.0"],
    ]
    assert ["holding", "registers", "2050-2051", "%MD1", "main.total", "DINT"] == lines[-3][:6]
    assert ["holding", "registers", "10000-10001", "-", "main.temp", "REAL"] == lines[-1][:6]


# ---------------------------------------------------------------------------- protocol


@pytest.mark.slow
def test_exception_codes_exact_bytes(plc, slave):
    plc.scan()
    s = connect(slave)
    assert raw(s, bytes([0x11])) == bytes([0x91, 0x01])  # unsupported function
    assert raw(s, bytes([0x08, 0, 0, 0x12, 0x34])) == bytes([0x88, 0x01])
    assert raw(s, bytes([0x03, 0x23, 0x28, 0, 1])) == bytes([0x83, 0x02])  # holding 9000: outside
    assert raw(s, bytes([0x04, 0x04, 0x00, 0, 1])) == bytes([0x84, 0x02])  # input register 1024
    assert raw(s, bytes([0x03, 0x1F, 0xFF, 0, 2])) == bytes([0x83, 0x02])  # 8191..8192 crosses the end
    assert raw(s, bytes([0x03, 0, 0, 0, 126])) == bytes([0x83, 0x03])  # > 125 registers
    assert raw(s, bytes([0x03, 0, 0, 0, 0])) == bytes([0x83, 0x03])
    assert raw(s, bytes([0x01, 0, 0, 0x07, 0xD1])) == bytes([0x81, 0x03])  # > 2000 bits
    assert raw(s, bytes([0x02, 0, 0, 0x07, 0xD0]))[:2] == bytes([0x02, 250])  # 2000 bits is fine
    assert raw(s, bytes([0x05, 0, 3, 0x12, 0x34])) == bytes([0x85, 0x03])  # FC5 value not 0/FF00
    assert raw(s, bytes([0x10, 0, 0, 0, 2, 3, 0, 1, 0])) == bytes([0x90, 0x03])  # byte count 3 for 2 regs
    assert raw(s, bytes([0x10, 0, 0, 0, 1, 2, 0])) == bytes([0x90, 0x03])  # frame shorter than count
    assert raw(s, bytes([0x0F, 0, 0, 0, 9, 1, 0xFF])) == bytes([0x8F, 0x03])  # 9 coils need 2 bytes
    assert raw(s, bytes([0x06, 0x23, 0x28, 0, 1])) == bytes([0x86, 0x02])  # write outside
    assert raw(s, bytes([0x2B, 0x0D, 1, 0])) == bytes([0xAB, 0x01])  # MEI type 13: unsupported
    assert raw(s, bytes([0x2B, 0x0E, 9, 0])) == bytes([0xAB, 0x03])  # read code 9
    assert raw(s, bytes([0x05, 0, 3, 0xFF, 0x00])) == bytes([0x05, 0, 3, 0xFF, 0x00])  # and it still works
    s.close()


@pytest.mark.slow
def test_device_identification(plc, slave):
    s = connect(slave)
    reply = raw(s, bytes([0x2B, 0x0E, 1, 0]))  # basic: objects 0, 1, 2
    assert reply[:7] == bytes([0x2B, 0x0E, 1, 0x83, 0, 0, 3])
    objs, pos = {}, 7
    while pos < len(reply):
        oid, n = reply[pos], reply[pos + 1]
        objs[oid] = reply[pos + 2 : pos + 2 + n].decode()
        pos += 2 + n
    assert objs == {0: "st", 1: "st-plc", 2: "0.1"}
    assert raw(s, bytes([0x2B, 0x0E, 4, 4]))[6:] == bytes([1, 4, 11]) + b"st soft PLC"
    assert raw(s, bytes([0x2B, 0x0E, 4, 0x55])) == bytes([0xAB, 0x02])  # no such object
    s.close()


@pytest.mark.slow
def test_several_requests_in_one_segment_are_all_answered_in_order(plc, slave):
    plc["main.setpoint"] = 11
    plc.scan()
    s = connect(slave)
    frames = b"".join(struct.pack(">HHHB", tid, 0, 6, 1) + bytes([3, 0, 0, 0, 1]) for tid in (1, 2, 3))
    frames += struct.pack(">HHHB", 4, 0, 2, 1) + bytes([0x11])
    s.sendall(frames)
    replies = _recv(s, 3 * 11 + 9)
    assert [struct.unpack_from(">H", replies, off)[0] for off in (0, 11, 22, 33)] == [1, 2, 3, 4]
    assert replies[9:11] == b"\x00\x0b" and replies[-2:] == b"\x91\x01"
    s.close()


@pytest.mark.slow
def test_unit_id_policy(plc):
    with ModbusSlave(plc, port=0, unit_ids=[1, 255]) as slave:
        s = connect(slave)
        assert raw(s, bytes([3, 0, 0, 0, 1]), unit=255) == bytes([3, 2, 0, 0])
        assert raw(s, bytes([3, 0, 0, 0, 1]), unit=5) == bytes([0x83, 0x0B])
        s.close()


@pytest.mark.slow
def test_read_only_and_writable_ranges(plc):
    with ModbusSlave(plc, port=0, read_only=True) as slave:
        s = connect(slave)
        assert raw(s, bytes([6, 0, 0, 0, 1])) == bytes([0x86, 0x01])  # read-only: illegal function
        assert raw(s, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])
        s.close()
    with ModbusSlave(plc, port=0, writable="holding:0-9,coil:3-3") as slave:
        s = connect(slave)
        assert raw(s, bytes([6, 0, 9, 0, 1])) == bytes([6, 0, 9, 0, 1])
        assert raw(s, bytes([0x10, 0, 9, 0, 2, 4, 0, 1, 0, 2])) == bytes([0x90, 0x02])  # 9..10 leaves the range
        assert raw(s, bytes([5, 0, 3, 0xFF, 0])) == bytes([5, 0, 3, 0xFF, 0])
        assert raw(s, bytes([5, 0, 4, 0xFF, 0])) == bytes([0x85, 0x02])
        s.close()
        plc.scan()
    assert (plc["main.valve"], plc["main.flap"]) == (True, False)


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("mbpoll") is None, reason="mbpoll (Debian package mbpoll) is not installed")
def test_mbpoll_reads_and_writes(plc, slave):
    plc["main.setpoint"] = -2
    plc.scan()
    base = ["mbpoll", "-m", "tcp", "-p", str(slave.port), "-a", "1", "-0", "-1"]

    def poll(*args):
        out = subprocess.run(base + list(args) + ["127.0.0.1"], capture_output=True, text=True, timeout=20)
        return out.returncode, [ln.split(":", 1)[1].strip() for ln in out.stdout.splitlines() if ln.startswith("[")]

    assert poll("-t", "4", "-r", "0", "-c", "1") == (0, ["65534 (-2)"])
    assert poll("-t", "4:float", "-B", "-r", "10000", "-c", "1") == (0, ["21.5"])
    assert poll("-t", "0", "-r", "8", "-c", "1") == (0, ["0"])
    assert subprocess.run(base + ["-t", "4", "-r", "1026", "127.0.0.1", "321"], capture_output=True).returncode == 0
    plc.scan()
    assert plc["main.speed"] == 321
    assert poll("-t", "4", "-r", "9000", "-c", "1")[0] == 1  # exception 02 → exit 1


# ---------------------------------------------------------------------------- robustness and limits


@pytest.mark.slow
def test_malformed_headers_close_only_that_connection(plc, tmp_path):
    log = tmp_path / "modbus.log"
    slave = ModbusSlave(plc, port=0, log_path=str(log)).start()
    plc.scan()
    good = connect(slave)
    assert raw(good, bytes([3, 0, 0, 0, 1]), tid=0xBEEF) == bytes([3, 2, 0, 0])
    for frame in (
        struct.pack(">HHHB", 1, 7, 6, 1) + bytes([3, 0, 0, 0, 1]),  # protocol id 7
        struct.pack(">HHHB", 1, 0, 1, 1),  # length 1: no function code
        struct.pack(">HHHB", 1, 0, 300, 1) + bytes(299),  # longer than any ADU
        os.urandom(1) + b"\xa5" * 40,
    ):  # garbage
        bad = connect(slave)
        bad.sendall(frame)
        assert closed_by_peer(bad)
        bad.close()
    assert raw(good, bytes([3, 0, 0, 0, 1]), tid=0xBEEF) == bytes([3, 2, 0, 0])
    good.close()
    slave.stop()
    err = log.read_text()
    assert "malformed MBAP header (protocol id 7, length 6)" in err
    assert "be ef" not in err and "beef" not in err  # never another client's frame


@pytest.mark.slow
def test_truncated_frames_and_slow_senders_time_out_while_others_are_served(plc):
    with ModbusSlave(plc, port=0, idle_timeout=1.0) as slave:
        slow = [connect(slave) for _ in range(3)]
        for i, s in enumerate(slow):
            s.sendall(struct.pack(">HHHB", 1, 0, 6, 1)[: 3 + i])  # a frame that never ends
        good = connect(slave)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 2.5:
            assert raw(good, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])
            time.sleep(0.1)
        assert all(closed_by_peer(s, 3.0) for s in slow)  # idle timeout (1 s)
        assert raw(good, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])  # active: kept
        good.close()


@pytest.mark.slow
def test_a_thousand_connections_do_not_lock_out_a_polling_client(plc):
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < 1200:
        resource.setrlimit(resource.RLIMIT_NOFILE, (min(hard, 4096), hard))
    with ModbusSlave(plc, port=0, max_connections=16) as slave:
        good = connect(slave)
        crowd = []
        for i in range(1000):
            crowd.append(socket.create_connection(("127.0.0.1", slave.port), timeout=5))
            if i % 50 == 0:
                assert raw(good, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])
        assert raw(good, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])
        deadline = time.monotonic() + 10
        while True:  # the server accepts the backlog and evicts as it goes
            still_open = [c for c in crowd if not (_readable(c) and closed_by_peer(c, 0.01))]
            if len(still_open) <= 15 or time.monotonic() > deadline:
                break
            time.sleep(0.2)
        assert len(still_open) == 15  # 16 with the polling client
        assert raw(good, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])
        for c in crowd:
            c.close()
        good.close()


@pytest.mark.slow
def test_a_burst_of_short_connections_never_evicts_a_polling_hmi(plc):
    # The failure seen in the field: an HMI polls once a second on one long-lived connection; another
    # client opens short connections in a loop (each one request, some never closed). Between two of
    # the HMI's polls every burst connection is fresher than the HMI, so "the longest idle goes"
    # closed the HMI. Here the HMI polls every 0.2 s (idle timeout 2 s) and the burst opens at least 200
    # connections, one after the other, going on until the HMI has polled twice meanwhile.
    plc["main.setpoint"] = 1234
    plc["%IW3"] = -7
    plc.scan()
    hmi_reply = bytes([3, 4, 0x04, 0xD2, 0, 0])  # holding 0-1: 1234, 0
    with ModbusSlave(plc, port=0, max_connections=4, idle_timeout=2.0) as slave:
        hmi = connect(slave)
        polls, errors, stop = [], [], threading.Event()

        def poll():
            tid = 0
            try:
                while not stop.is_set():
                    tid += 1
                    polls.append(raw(hmi, bytes([3, 0, 0, 0, 2]), tid=tid))
                    stop.wait(0.2)
            except Exception as e:  # noqa: BLE001 - reported below
                errors.append(f"poll {tid}: {e!r}")

        def wait_polls(n):
            deadline = time.monotonic() + 10
            while len(polls) < n and poller.is_alive() and time.monotonic() < deadline:
                time.sleep(0.02)

        poller = threading.Thread(target=poll, daemon=True)
        poller.start()
        wait_polls(2)  # the HMI is established, then the burst starts
        kept, burst_replies, sent = [], [], 0
        during = len(polls) + 2
        i = -1
        while i < 199 or (len(polls) < during and poller.is_alive()):  # 200, and over two HMI polls
            i += 1
            c = connect(slave)
            if len(kept) > 100:  # long evicted by the server: only file
                kept.pop(0).close()  # descriptors here
            if i % 5 == 4:  # connects, never sends anything, never closes
                kept.append(c)
                continue
            sent += 1
            burst_replies.append(raw(c, bytes([4, 0, 3, 0, 1]), tid=i & 0xFFFF))
            if i % 3 == 0:
                kept.append(c)  # one request, then left open
            else:
                c.close()
        wait_polls(len(polls) + 2)  # and the HMI goes on polling after it
        stop.set()
        poller.join(5)
        assert errors == []
        assert len(polls) >= 6 and polls == [hmi_reply] * len(polls)  # 2 before, 2 during, 2 after
        assert raw(hmi, bytes([3, 0, 0, 0, 2]), tid=9999) == hmi_reply  # the same connection, still open
        assert sent >= 160 and burst_replies == [bytes([4, 2, 0xFF, 0xF9])] * sent  # the burst was served too
        for c in kept:
            c.close()
        hmi.close()


def _readable(sock) -> bool:
    import select

    return bool(select.select([sock], [], [], 0)[0])


@pytest.mark.slow
def test_connection_limit_evicts_never_active_then_the_busiest_peer_newest_first(plc):
    # all clients on this host; their source addresses (127.0.0.x) are the peers the policy counts
    plc["main.setpoint"] = 42
    plc.scan()
    ok = bytes([3, 2, 0, 42])

    def served(*socks):
        return all(raw(s, bytes([3, 0, 0, 0, 1])) == ok for s in socks)

    with ModbusSlave(plc, port=0, max_connections=4) as slave:
        s1 = connect(slave, "127.0.0.1")  # s1, s2, s3 never send a request
        s2, s3 = connect(slave, "127.0.0.2"), connect(slave, "127.0.0.2")
        b1 = connect(slave, "127.0.0.2")
        assert served(b1)
        a = connect(slave, "127.0.0.1")  # never-active first; .2 holds the most (3): its oldest, s2
        assert closed_by_peer(s2, 2.0)  # (s1 is older, but .1 holds 2 with a)
        assert not _readable(s1) and not _readable(s3) and served(a, b1)
        b2 = connect(slave, "127.0.0.2")  # never-active s1 (.1: 2) and s3 (.2: 3 with b1, b2): s3
        assert closed_by_peer(s3, 2.0)
        assert not _readable(s1) and served(b2, a, b1)
        c1 = connect(slave, "127.0.0.3")  # the last never-active one, whatever its peer
        assert closed_by_peer(s1, 2.0)
        assert served(c1, a, b1, b2)
        b3 = connect(slave, "127.0.0.2")  # all active: .2 would hold 3, its newest goes (b2),
        assert closed_by_peer(b2, 2.0)  # not c1, the newest of all
        assert served(b3, a, b1, c1)
        c2 = connect(slave, "127.0.0.3")  # .2 and .3 would hold 2 each: the newest of
        assert closed_by_peer(b3, 2.0)  # theirs goes (b3, newer than c1 and b1)
        assert served(c2, a, b1, c1)
        d1 = connect(slave, "127.0.0.1")  # .1 and .3 would hold 2 each: the newest (c2)
        assert closed_by_peer(c2, 2.0)
        assert served(d1, a, b1, c1)
        for s in (a, b1, c1, d1, s1, s2, s3, b2, b3, c2):
            s.close()


@pytest.mark.slow
def test_regular_clients_are_never_evicted_and_new_connections_are_refused_instead(plc, tmp_path):
    log = tmp_path / "modbus.log"
    ok = bytes([3, 2, 0, 0])
    slave = ModbusSlave(plc, port=0, max_connections=3, log_path=str(log)).start()
    try:
        once = connect(slave)
        assert raw(once, bytes([3, 0, 0, 0, 1])) == ok  # one request, then nothing: not regular
        h1, h2 = connect(slave), connect(slave)
        assert raw(h1, bytes([3, 0, 0, 0, 1])) == ok and raw(h2, bytes([3, 0, 0, 0, 1])) == ok
        time.sleep(1.1)
        assert raw(h1, bytes([3, 0, 0, 0, 1])) == ok and raw(h2, bytes([3, 0, 0, 0, 1])) == ok  # regular now
        n = connect(slave)  # h2 is the newest, but regular: `once` goes
        assert closed_by_peer(once, 2.0)
        assert raw(n, bytes([3, 0, 0, 0, 1])) == ok
        m = connect(slave)  # n is the only one that is not regular
        assert closed_by_peer(n, 2.0)
        assert raw(m, bytes([3, 0, 0, 0, 1])) == ok
        time.sleep(1.1)
        assert raw(m, bytes([3, 0, 0, 0, 1])) == ok  # m is regular too: every slot is
        refused = []
        for _ in range(5):
            r = connect(slave)
            assert closed_by_peer(r, 2.0)
            refused.append(f"127.0.0.1:{r.getsockname()[1]}")
            r.close()
        for s in (h1, h2, m):
            assert raw(s, bytes([3, 0, 0, 0, 1])) == ok
            s.close()
    finally:
        slave.stop()
    lines = [ln for ln in log.read_text().splitlines() if "refused" in ln]
    head = "st modbus: WARNING connection limit 3: every connection is a regular client; refused"
    assert lines == [
        f"{head} 1 new connection(s), the last from {refused[0]}",  # at once
        f"{head} 4 new connection(s), the last from {refused[4]}",
    ]  # the rest: once, at the stop


@pytest.mark.slow
def test_request_rate_is_bounded_per_connection(plc):
    with ModbusSlave(plc, port=0, max_rate=50) as slave:
        s = connect(slave)
        frames = b"".join(struct.pack(">HHHB", t, 0, 6, 1) + bytes([3, 0, 0, 0, 1]) for t in range(100))
        t0 = time.monotonic()
        s.sendall(frames)
        replies = _recv(s, 100 * 11)
        elapsed = time.monotonic() - t0
        assert [struct.unpack_from(">H", replies, 11 * i)[0] for i in range(100)] == list(range(100))
        assert elapsed >= 0.9  # a burst of 50, then 50 per second
        s.close()


@pytest.mark.slow
def test_a_client_that_never_reads_replies_is_throttled_and_memory_stays_bounded(plc):
    with ModbusSlave(plc, port=0, max_rate=0) as slave:
        rss0 = _rss(slave.proc.pid)
        hog = connect(slave)
        hog.setblocking(False)
        frame = struct.pack(">HHHB", 1, 0, 6, 1) + bytes([3, 0, 0, 0, 125])  # 259-byte replies
        sent = 0
        t0 = time.monotonic()
        while time.monotonic() - t0 < 3.0:
            try:
                sent += hog.send(frame * 100)
            except BlockingIOError:
                time.sleep(0.01)
        good = connect(slave)
        assert raw(good, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 0])
        grew = _rss(slave.proc.pid) - rss0
        assert sent < 50_000_000 and grew < 20_000_000, (sent, grew)  # the hog was stopped
        good.close()
        hog.close()


def _rss(pid) -> int:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


@pytest.mark.slow
def test_st_run_with_modbus_serves_and_stops_cleanly(tmp_path):
    (tmp_path / "main.st").write_text(PROGRAM)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    child = subprocess.Popen(
        [
            "st",
            "run",
            str(tmp_path / "main.st"),
            "--no-rt",
            "--duration",
            "20s",
            "--modbus",
            f"127.0.0.1:{port}",
            "--dump-json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 15
    while True:
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=1)
            break
        except OSError:
            assert time.monotonic() < deadline and child.poll() is None
            time.sleep(0.1)
    tcp.send_message(tcp.write_single_register(1, 0, 21), s)
    # the write reaches the image at the start of the next scan: read until a scan has run (a fixed
    # sleep was too short on a loaded machine), the value exact
    deadline = time.monotonic() + 15
    while (got := tcp.send_message(tcp.read_holding_registers(1, 0, 1), s)) != [21] and time.monotonic() < deadline:
        time.sleep(0.05)
    assert got == [21]
    s.close()
    child.terminate()
    out, err = child.communicate(timeout=20)
    assert child.returncode == 0, err
    assert f"modbus: serving on 127.0.0.1:{port}" in err
    import json

    assert json.loads(out.splitlines()[-1])["main.echo"] == 42
    with pytest.raises(OSError):  # the server process is gone
        socket.create_connection(("127.0.0.1", port), timeout=1)


@pytest.mark.slow
def test_forced_values_win_over_hmi_writes_and_the_program(plc, slave):
    plc.force("main.setpoint", 5)  # a %QW0 variable the HMI writes
    plc.force("%QX1.0", True)  # lamp, which the program sets from button
    s = connect(slave)
    tcp.send_message(tcp.write_single_register(1, 0, 77), s)
    plc.scan()
    assert (plc["main.setpoint"], plc["main.echo"], plc["main.lamp"]) == (5, 10, True)
    assert tcp.send_message(tcp.read_holding_registers(1, 0, 1), s) == [5]
    assert tcp.send_message(tcp.read_coils(1, 8, 1), s) == [1]
    assert plc.forced == ["%qx1.0", "main.setpoint"]
    plc.unforce("main.setpoint")
    tcp.send_message(tcp.write_single_register(1, 0, 77), s)
    plc.scan()
    assert (plc["main.setpoint"], plc["main.echo"], plc["main.lamp"]) == (77, 154, True)
    plc.unforce()
    plc.scan()
    assert plc["main.lamp"] is False
    s.close()


@pytest.mark.slow
def test_online_change_rebinds_the_served_cells(plc, slave, tmp_path):
    from st.api import compile_text

    plc["main.setpoint"] = 3
    plc.scan()
    src = PROGRAM.replace("echo : INT;", "echo : INT;\n    extra AT %QW5 : INT;").replace(
        "echo := setpoint * 2;", "echo := setpoint * 2; extra := extra + 1;"
    )
    assert (
        plc.online_change(compile_text(src, str(tmp_path / "main.st"))) == "online change: 1 instance(s) carried over"
    )
    s = connect(slave)
    tcp.send_message(tcp.write_single_register(1, 5, 100), s)
    plc.scan()
    assert (plc["main.extra"], plc["main.setpoint"]) == (101, 3)
    assert tcp.send_message(tcp.read_holding_registers(1, 0, 6), s) == [3, 0, 0, 0, 0, 101]
    s.close()


def test_the_slave_reports_its_connected_clients(plc, slave):
    s = connect(slave)
    raw(s, bytes([0x03, 0, 0, 0, 1]))  # one request: read a holding register
    raw(s, bytes([0x03, 0, 0, 0, 1]))
    peer = f"127.0.0.1:{s.getsockname()[1]}"
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and slave.clients() != [{"peer": peer, "requests": 2, "regular": False}]:
        time.sleep(0.05)  # (the request counts come once a second)
    assert slave.clients() == [{"peer": peer, "requests": 2, "regular": False}]
    s.close()
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and slave.clients():
        time.sleep(0.05)
    assert slave.clients() == []


# ---------------------------------------------------------------------------- read-only, the warning, the map's names


@pytest.mark.slow
def test_a_read_only_server_answers_every_write_function_with_illegal_function(plc):
    plc["main.setpoint"] = 7
    plc.scan()
    with ModbusSlave(plc, port=0, read_only=True) as slave:
        s = connect(slave)
        writes = [
            bytes([5, 0, 3, 0xFF, 0]),  # FC 5: coil 3 (main.valve) on
            bytes([6, 0, 0, 0, 9]),  # FC 6: holding 0 (main.setpoint)
            bytes([15, 0, 3, 0, 2, 1, 3]),  # FC 15: coils 3-4
            bytes([16, 0, 0, 0, 1, 2, 0, 9]),  # FC 16: holding 0
            bytes([23, 0, 0, 0, 1, 0, 0, 0, 1, 2, 0, 9]),  # FC 23: read and write holding 0
            bytes([6, 0x23, 0x28, 0, 1]),  # a write outside the map: 01 too, the function comes first
            bytes([16, 0, 0, 0, 200, 2, 0, 9]),  # a malformed quantity: 01 too
        ]
        for pdu in writes:
            assert raw(s, pdu) == bytes([pdu[0] | 0x80, 0x01]), pdu
        assert raw(s, bytes([3, 0, 0, 0, 1])) == bytes([3, 2, 0, 7])  # reads are served
        assert raw(s, bytes([1, 0, 3, 0, 2])) == bytes([1, 1, 0])
        assert raw(s, bytes([4, 0, 3, 0, 1])) == bytes([4, 2, 0, 0])
        assert raw(s, bytes([0x2B, 0x0E, 4, 0]))[6:] == bytes([1, 0, 2]) + b"st"
        s.close()
        plc.scan()
    assert (plc["main.setpoint"], plc["main.valve"], plc["main.flap"]) == (7, False, False)


def _serve_on_all_interfaces(tmp_path, *extra):
    """`st run --modbus 0.0.0.0:0` for a moment: its stderr."""
    (tmp_path / "main.st").write_text(PROGRAM)
    out = subprocess.run(
        ["st", "run", str(tmp_path / "main.st"), "--no-rt", "--duration", "300ms", "--modbus", "0.0.0.0:0", *extra],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    return out.stderr


@pytest.mark.slow
def test_a_server_beyond_loopback_is_announced_with_a_warning(tmp_path):
    err = _serve_on_all_interfaces(tmp_path, "-q")  # printed even with -q (after the compiler's warnings)
    port = err.split("0.0.0.0:")[1].split(" ")[0]
    assert err.split("0 error(s), 2 warning(s)\n")[1] == (
        f"warning: the Modbus server on 0.0.0.0:{port} is reachable from other machines, without authentication, "
        "and accepts writes to the PLC (--modbus-read-only refuses them)\n"
    )
    err = _serve_on_all_interfaces(tmp_path, "--modbus-read-only")
    port = err.split("serving on 0.0.0.0:")[1].split(" ")[0]
    assert (
        f"modbus: serving on 0.0.0.0:{port} (OpenPLC map, read-only)\n"
        f"warning: the Modbus server on 0.0.0.0:{port} is reachable from other machines, without authentication "
        "(read-only: writes are refused)\n"
    ) in err


def test_loopback_addresses_get_no_warning():
    from st.app.params import is_loopback
    from st.app.session import modbus_warning

    assert all(is_loopback(h) for h in ("127.0.0.1", "127.0.0.2", "::1", "[::1]", "localhost"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "::", "192.168.1.5", "plc.example.com"))
    assert modbus_warning("::", 502, False).startswith("warning: the Modbus server on [::]:502 is reachable")


MAP_LINES = [
    "table              addresses    location  variable       type    encoding                        access",
    "coils              3            %QX0.3    main.valve     BOOL    bit                             read/write",
    "coils              4            %QX0.4    main.flap      BOOL    bit                             read/write",
    "coils              8            %QX1.0    main.lamp      BOOL    bit                             read/write",
    "discrete inputs    2            %IX0.2    main.button    BOOL    bit                             read",
    "input registers    3            %IW3      main.level     INT     16-bit                          read",
    "input registers    2000-2004    -         main.name      STRING  5 registers, 2 characters each  read",
    "input registers    2010-2011    -         main.count     DINT    2 registers, little word order  read",
    "holding registers  0            %QW0      main.setpoint  INT     16-bit                          read/write",
    "holding registers  1026         %MW2      main.speed     UINT    16-bit                          read/write",
    "holding registers  2050-2051    %MD1      main.total     DINT    32-bit, high word first         read/write",
    "holding registers  4096-4099    %ML0      main.big       LINT    64-bit, high word first         read/write",
    "holding registers  10000-10001  -         main.temp      REAL    2 registers, big word order     read/write",
    "other addresses in OpenPLC's ranges (coils and discrete inputs 0-8191, input registers 0-1023, holding "
    "registers 0-8191) read 0 and keep what is written; beyond them: exception 02",
]


def test_st_modbus_map_names_each_located_variable_by_path_and_type(tmp_path):
    from click.testing import CliRunner

    from st.cli import main

    (tmp_path / "main.st").write_text(PROGRAM)
    (tmp_path / "map.toml").write_text(MAP)
    r = CliRunner().invoke(
        main, ["modbus", "map", str(tmp_path / "main.st"), "--modbus-map", str(tmp_path / "map.toml")]
    )
    assert r.exit_code == 0, r.output
    assert r.stdout.splitlines() == MAP_LINES
    # the old name still works, with a deprecation warning
    r = CliRunner().invoke(main, ["modbus", "map", str(tmp_path / "main.st"), "--map", str(tmp_path / "map.toml")])
    assert r.exit_code == 0, r.output
    assert r.stdout.splitlines() == MAP_LINES
    assert r.stderr.startswith("warning: --map is deprecated, use --modbus-map\n")
    assert "--map" not in CliRunner().invoke(main, ["modbus", "map", "--help"]).stdout.replace("--modbus-map", "")


SHARED = textwrap.dedent("""
    PROGRAM P
      VAR out AT %QX0.0 : BOOL; END_VAR
      out := NOT out;
    END_PROGRAM
    CONFIGURATION c
      VAR_GLOBAL alarm AT %QX0.1 : BOOL; level AT %IW0 : INT; END_VAR
      RESOURCE r ON PLC
        TASK t (INTERVAL := T#10ms);
        PROGRAM p1 WITH t : P;
        PROGRAM p2 WITH t : P;
      END_RESOURCE
    END_CONFIGURATION
""")


def test_st_modbus_map_names_globals_and_every_instance_at_one_address(tmp_path):
    from click.testing import CliRunner

    from st.cli import main

    (tmp_path / "c.st").write_text(SHARED)
    r = CliRunner().invoke(main, ["modbus", "map", str(tmp_path / "c.st")])
    assert r.exit_code == 0, r.output
    assert r.stdout.splitlines()[:4] == [
        "table            addresses  location  variable        type  encoding  access",
        "coils            0          %QX0.0    p1.out, p2.out  BOOL  bit       read/write",
        "coils            1          %QX0.1    alarm           BOOL  bit       read/write",
        "input registers  0          %IW0      level           INT   16-bit    read",
    ]
