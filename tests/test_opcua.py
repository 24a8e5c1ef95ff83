"""The OPC UA server with a real client (asyncua's): address space, types, values, subscriptions,
writes and their refusals, methods, users and security. One PLC runs in real time in a thread
while the server runs in its own process, as under `st run --opcua`."""

from __future__ import annotations

import asyncio
import re
import shutil
import threading
import time
from datetime import UTC, datetime
from pathlib import Path

import pytest
from asyncua import Client, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from cryptography.x509.oid import ExtendedKeyUsageOID

from st import PLC
from st.api import compile_text
from st.opcua import OpcUaServer
from st.opcua.users import add_user

pytestmark = pytest.mark.slow

SRC = """
TYPE Color : (Red, Green := 5, Blue); END_TYPE
TYPE Mode : (Idle, Run, Done); END_TYPE
PROGRAM main
VAR_INPUT
  setpoint : INT(0..100) := 5;  (* the set-point, % *)
END_VAR
VAR_OUTPUT
  counter : DINT;               (* one per scan *)
  twice : DINT;
  level : REAL := 1.5;
END_VAR
VAR
  color : Color := Blue;
  mode : Mode := Run;
  cycle : TIME := T#1s500ms;
  stamp : DT := DT#2024-01-02-03:04:05;
  table : ARRAY[1..3] OF INT := [1, 2, 3];
  grid : ARRAY[0..1, 0..2] OF LREAL := [0.5, 1.5, 2.5, 3.5, 4.5, 5.5];
  name : STRING[8] := 'cell';
  lamp AT %QX0.1 : BOOL;
END_VAR
counter := counter + 1;
twice := counter * 2;
lamp := NOT lamp;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC TASK t(INTERVAL := T#10ms); PROGRAM main WITH t : main; END_RESOURCE
END_CONFIGURATION
"""
MAP = """[symbols]
"main.*" = "read"
"main.setpoint" = "readwrite"
"main.color" = "readwrite"
"main.cycle" = "readwrite"
"main.stamp" = "readwrite"
"main.table" = "readwrite"
"main.name" = "readwrite"
"""


class Running:
    """A PLC in real time in a thread, its OPC UA server polled between jobs."""

    def __init__(self, tmp, **server):
        src = tmp / "cell.st"
        src.write_text(SRC)
        (tmp / "map.toml").write_text(MAP)
        self.users = tmp / "users"
        add_user(str(self.users), "op", "operate", "op-secret")
        add_user(str(self.users), "eng", "engineer", "eng-secret")
        add_user(str(self.users), "viewer", "read", "viewer-secret")
        self.plc = PLC.from_files(str(src))
        self.pki = tmp / "pki"
        opts = {"users": str(self.users), "pki": str(self.pki), "map_file": str(tmp / "map.toml"), **server}
        self.srv = OpcUaServer(self.plc, "127.0.0.1", 0, **opts)
        self.srv.start()
        self.stop = threading.Event()
        self.change = None  # a program to swap in at the next scan boundary (online change)
        self.changed = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        self.plc.run_realtime(duration="300s", on_idle=self._idle, stop=self.stop, gc_control=False)

    def _idle(self, plc):
        if self.change is not None:
            plc.online_change(self.change)
            self.change = None
            self.changed.set()
        self.srv.poll()

    def close(self):
        self.stop.set()
        self.thread.join(10)
        self.srv.stop()

    def log(self):
        return [m.text for m in self.plc.log.since(0)]


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    r = Running(tmp_path_factory.mktemp("opcua"), security=("none", "sign", "encrypt"), anonymous=True)
    yield r
    r.close()


def run(coro):
    return asyncio.run(coro)


async def connect(cell, user=None, password=None):
    c = Client(cell.srv.endpoint, timeout=10)
    if user:
        c.set_user(user)
        c.set_password(password)
    await c.connect()
    return c


def nid(path):
    return ua.NodeId(path, 2)


async def _browse(cell):
    c = await connect(cell)
    try:
        assert await c.get_namespace_index("urn:st:st") == 2
        programs = c.get_node(nid("Programs"))
        [main] = await programs.get_children()
        names = sorted([(await n.read_browse_name()).Name for n in await main.get_children()])
        level = c.get_node(nid("main.level"))
        desc = (await c.get_node(nid("main.setpoint")).read_description()).Text
        dtype = await c.get_node(nid("main.cycle")).read_data_type()
        grid = c.get_node(nid("main.grid"))
        dims = (await grid.read_value_rank(), await grid.read_array_dimensions())
        props = await c.get_node(nid("main.color")).get_properties()
        color_props = [(await p.read_browse_name()).Name for p in props]
        mode_strings = await c.get_node(ua.NodeId("main.mode.EnumStrings", 2)).read_value()
        children = await c.get_node(nid("Located")).get_children()
        located = [(await n.read_browse_name()).Name for n in children]
        access = await c.get_node(nid("main.counter")).get_access_level()
        return (
            names,
            await level.read_data_type_as_variant_type(),
            desc,
            dtype,
            dims,
            color_props,
            mode_strings,
            located,
            access,
        )
    finally:
        await c.disconnect()


def test_address_space(cell):
    names, level_type, desc, dtype, dims, color_props, mode_strings, located, access = run(_browse(cell))
    assert names == [
        "color", "counter", "cycle", "grid", "lamp", "level", "mode", "name", "setpoint", "stamp", "table", "twice"
    ]  # fmt: skip
    assert level_type == ua.VariantType.Float
    assert desc == "the set-point, %"
    assert dtype == ua.NodeId(ua.ObjectIds.Duration)
    assert dims == (2, [2, 3])
    assert color_props == ["EnumValues"]  # 0, 5, 6: not 0..n-1, so values with their names
    assert [t.Text for t in mode_strings] == ["Idle", "Run", "Done"]
    assert located == ["%QX0.1"]
    assert ua.AccessLevel.CurrentWrite not in access and ua.AccessLevel.CurrentRead in access


async def _values(cell):
    c = await connect(cell)
    try:
        out = {}
        for p in ("main.level", "main.cycle", "main.stamp", "main.table", "main.grid", "main.color", "main.name"):
            out[p] = await c.get_node(nid(p)).read_value()
        a = await c.get_node(nid("main.counter")).read_data_value()
        b = await c.get_node(nid("main.twice")).read_data_value()
        state = await c.get_node(nid("PLC.State")).read_value()
        jobs = await c.get_node(nid("PLC.Tasks.t.Jobs")).read_value()
        return out, a, b, state, jobs
    finally:
        await c.disconnect()


def test_values_and_source_timestamps(cell):
    time.sleep(1.2)  # no subscription: a sample a second
    out, a, b, state, jobs = run(_values(cell))
    assert out == {
        "main.level": 1.5,
        "main.cycle": 1500.0,  # TIME as a Duration, ms
        "main.stamp": datetime(2024, 1, 2, 3, 4, 5, tzinfo=UTC),
        "main.table": [1, 2, 3],
        "main.grid": [[0.5, 1.5, 2.5], [3.5, 4.5, 5.5]],  # two dimensions, row by row
        "main.color": 6,
        "main.name": "cell",
    }
    # counter and twice come from one scan: one PLC time, and twice is exactly 2 × counter
    assert b.Value.Value == 2 * a.Value.Value
    assert a.SourceTimestamp == b.SourceTimestamp
    assert abs((a.SourceTimestamp.replace(tzinfo=UTC) - datetime.now(UTC)).total_seconds()) < 5
    assert state == "RUN" and jobs > 0


async def _subscribe(cell):
    c = await connect(cell)
    got = []

    class Handler:
        def datachange_notification(self, node, val, data):
            got.append((val, data.monitored_item.Value.SourceTimestamp))

    try:
        sub = await c.create_subscription(100, Handler())
        await sub.subscribe_data_change(c.get_node(nid("main.counter")))
        await asyncio.sleep(1.55)
        await sub.delete()
        return got
    finally:
        await c.disconnect()


def test_subscription_samples_each_interval(cell):
    got = run(_subscribe(cell))
    assert 12 <= len(got) <= 18  # the initial value, then one per 100 ms
    values = [v for v, _ in got]
    stamps = [s for _, s in got]
    assert values == sorted(values) and len(set(values)) == len(values)
    gaps = [(b - a).total_seconds() for a, b in zip(stamps, stamps[1:], strict=False)]
    # PLC time between samples: at least the interval (10 ms scans: a sample lands on a scan)
    assert min(gaps) >= 0.099
    steps = [b - a for a, b in zip(values, values[1:], strict=False)]
    assert all(s >= 9 for s in steps)  # ≥ 9 scans of 10 ms between two samples


async def _write(cell, user, password, path, variant):
    c = await connect(cell, user, password)
    try:
        await c.get_node(nid(path)).write_value(variant)
        return "Good"
    except ua.UaStatusCodeError as e:
        return type(e).__name__
    finally:
        await c.disconnect()


def _wait_for(cell, path, value, timeout=3.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cell.plc[path] == value:
            return True
        time.sleep(0.02)
    return False


def test_writes_applied_and_logged(cell):
    w = lambda path, variant: run(_write(cell, "op", "op-secret", path, variant))  # noqa: E731
    assert w("main.setpoint", ua.Variant(42, ua.VariantType.Int16)) == "Good"
    assert cell.plc["main.setpoint"] == 42  # the answer came after the PLC applied it
    assert w("main.cycle", ua.Variant(250.0, ua.VariantType.Double)) == "Good"
    assert cell.plc["main.cycle"] == 250_000_000
    assert w("main.stamp", ua.Variant(datetime(2025, 6, 7, 8, 9, 10, tzinfo=UTC), ua.VariantType.DateTime)) == "Good"
    assert cell.plc["main.stamp"] == 1749283750_000_000_000
    assert w("main.table", ua.Variant([7, 8, 9], ua.VariantType.Int16)) == "Good"
    assert cell.plc["main.table"] == [7, 8, 9]
    assert w("main.color", ua.Variant(5, ua.VariantType.Int32)) == "Good"
    assert cell.plc["main.color"] == "Green"
    assert w("main.name", ua.Variant("line 2", ua.VariantType.String)) == "Good"
    log = cell.log()
    assert any(
        re.fullmatch(r"opcua op \(session i=\d+ from 127\.0\.0\.1:\d+\): write main\.setpoint := 42", t) for t in log
    )
    for shown in ("main.cycle := T#250ms", "main.stamp := DT#2025-06-07-08:09:10", "main.color := Color#Green"):
        assert any(t.endswith("write " + shown) for t in log)


def test_writes_refused_with_status_codes(cell):
    w = lambda user, pw, path, variant: run(_write(cell, user, pw, path, variant))  # noqa: E731
    op = ("op", "op-secret")
    assert w(*op, "main.setpoint", ua.Variant(101, ua.VariantType.Int16)) == "BadOutOfRange"  # INT(0..100)
    assert w(*op, "main.setpoint", ua.Variant(7, ua.VariantType.Int32)) == "BadTypeMismatch"
    assert w(*op, "main.color", ua.Variant(3, ua.VariantType.Int32)) == "BadOutOfRange"  # not a member
    assert w(*op, "main.name", ua.Variant("much too long", ua.VariantType.String)) == "BadOutOfRange"
    assert w(*op, "main.table", ua.Variant([1, 2], ua.VariantType.Int16)) == "BadTypeMismatch"
    assert w(*op, "main.counter", ua.Variant(1, ua.VariantType.Int32)) == "BadNotWritable"
    assert w("viewer", "viewer-secret", "main.setpoint", ua.Variant(9, ua.VariantType.Int16)) == "BadUserAccessDenied"
    assert w(None, None, "main.setpoint", ua.Variant(9, ua.VariantType.Int16)) == "BadUserAccessDenied"
    assert cell.plc["main.setpoint"] != 9 and cell.plc["main.setpoint"] <= 100


async def _call(cell, user, password, action):
    c = await connect(cell, user, password)
    try:
        await c.get_node(nid("PLC")).call_method(nid(f"PLC.{action}"))
        return "Good"
    except ua.UaStatusCodeError as e:
        return type(e).__name__
    finally:
        await c.disconnect()


def test_methods_need_the_engineer_role(cell):
    assert run(_call(cell, "op", "op-secret", "Stop")) == "BadUserAccessDenied"
    assert cell.plc.state == "RUN"
    assert run(_call(cell, "eng", "eng-secret", "Stop")) == "Good"
    assert cell.plc.state == "STOP"
    assert run(_call(cell, "eng", "eng-secret", "Start")) == "Good"
    assert cell.plc.state == "RUN"
    assert any(t.startswith("opcua eng (session ") and t.endswith("stop (now STOP)") for t in cell.log())


def test_wrong_password_is_refused_and_logged(cell):
    async def attempt():
        c = Client(cell.srv.endpoint, timeout=10)
        c.set_user("op")
        c.set_password("guess")
        try:
            await c.connect()
        except ua.UaStatusCodeError as e:
            return type(e).__name__
        await c.disconnect()
        return "Good"

    assert run(attempt()) == "BadUserAccessDenied"
    end = time.monotonic() + 3
    while time.monotonic() < end and not any("sign-in refused for user 'op'" in t for t in cell.log()):
        time.sleep(0.05)
    assert "opcua: sign-in refused for user 'op'" in cell.log()


@pytest.fixture(scope="module")
def secure(tmp_path_factory):
    r = Running(tmp_path_factory.mktemp("opcua_secure"))  # the defaults: sign, encrypt; no anonymous
    yield r
    r.close()


async def _endpoints(url):
    c = Client(url, timeout=10)
    return sorted(
        (e.SecurityMode.name, e.SecurityPolicyUri.rsplit("#", 1)[-1])
        for e in await c.connect_and_get_server_endpoints()
    )


async def _secure_session(cell, cert, key, user, password):
    c = Client(cell.srv.endpoint, timeout=10)
    c.application_uri = "urn:st:test:client"
    await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key), mode=ua.MessageSecurityMode.SignAndEncrypt)
    if user:
        c.set_user(user)
        c.set_password(password)
    try:
        await c.connect()
    except (TimeoutError, ua.UaStatusCodeError, ConnectionError, OSError) as e:
        return type(e).__name__
    try:
        return await c.get_node(nid("main.level")).read_value()
    finally:
        await c.disconnect()


def test_secure_by_default(secure, tmp_path):
    modes = run(_endpoints(secure.srv.endpoint))
    assert modes == [("Sign", "Basic256Sha256"), ("SignAndEncrypt", "Basic256Sha256")]  # no None unless asked
    key, cert = tmp_path / "client.pem", tmp_path / "client.der"
    run(
        setup_self_signed_certificate(
            key, cert, "urn:st:test:client", "localhost", [ExtendedKeyUsageOID.CLIENT_AUTH], {"commonName": "test"}
        )
    )
    # an unknown client certificate is refused and kept in rejected/ for the administrator
    assert run(_secure_session(secure, cert, key, "op", "op-secret")) != 1.5
    rejected = list((secure.pki / "rejected").iterdir())
    assert len(rejected) == 1
    shutil.move(str(rejected[0]), str(secure.pki / "trusted" / rejected[0].name))
    assert run(_secure_session(secure, cert, key, "op", "op-secret")) == 1.5  # trusted now, no restart
    assert run(_secure_session(secure, cert, key, None, None)) != 1.5  # anonymous is off by default
    assert (secure.pki / "own" / "cert.der").exists()
    assert (secure.pki / "own" / "key.pem").stat().st_mode & 0o777 == 0o600


async def _across_a_change(cell):
    c = await connect(cell)
    got = []

    class Handler:
        def datachange_notification(self, node, val, data):
            got.append(val)

    try:
        sub = await c.create_subscription(50, Handler())
        await sub.subscribe_data_change(c.get_node(nid("main.counter")))
        await asyncio.sleep(0.5)
        before = len(got)
        # a new output and a comment: the running program changes at a scan boundary
        text = SRC.replace("  level : REAL := 1.5;", "  level : REAL := 1.5;\n  extra : INT := 7;  (* added online *)")
        cell.change = compile_text(text, "cell.st")
        await asyncio.get_running_loop().run_in_executor(None, cell.changed.wait, 5)
        extra = None
        for _ in range(100):
            try:
                extra = await c.get_node(nid("main.extra")).read_value()
                break
            except ua.UaStatusCodeError:
                await asyncio.sleep(0.05)
        desc = (await c.get_node(nid("main.extra")).read_description()).Text
        after = len(got)
        await asyncio.sleep(0.5)
        return before, after, len(got), extra, desc, got
    finally:
        await c.disconnect()


def test_online_change_keeps_subscriptions(cell):
    before, after, end, extra, desc, got = run(_across_a_change(cell))
    assert (extra, desc) == (7, "added online")
    assert before >= 5 and end >= after + 5  # the monitored item lives on across the change
    assert got == sorted(got)  # the counter carried over: it never went back


async def _gantry(endpoint):
    c = Client(endpoint, timeout=10)
    c.set_user("op")
    c.set_password("op-secret")
    got = []

    class Handler:
        def datachange_notification(self, node, val, data):
            got.append(val)

    async with c:
        [gantry] = await c.get_node(nid("Programs")).get_children()
        names = {(await n.read_browse_name()).Name for n in await gantry.get_children()}
        sub = await c.create_subscription(100, Handler())
        await sub.subscribe_data_change(c.get_node(nid("gantry.strokes")))
        for _ in range(100):  # the beam's first strokes (250 mm/s over 200 mm: about one a second)
            if got and got[-1] >= 2:
                break
            await asyncio.sleep(0.1)
        await c.get_node(nid("gantry.auto")).write_value(ua.Variant(False, ua.VariantType.Boolean))
        await asyncio.sleep(2.5)  # the stroke under way ends; no new one starts without the button
        held = await c.get_node(nid("gantry.strokes")).read_value()
        await asyncio.sleep(1.5)
        later = await c.get_node(nid("gantry.strokes")).read_value()
        moving = await c.get_node(nid("%QX0.0")).read_value()
        return names, got, held, later, moving


def test_st_run_gantry_with_opcua(tmp_path):
    """`st run programs/gantry.st --opcua`: browsed, subscribed and written, as the issue asks."""
    import socket
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    users = tmp_path / "users"
    add_user(str(users), "op", "operate", "op-secret")
    (tmp_path / "map.toml").write_text('[symbols]\n"gantry.*" = "read"\n"gantry.auto" = "readwrite"\n')
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen(
        [sys.executable, "-m", "st.cli", "run", str(root / "programs" / "gantry.st"), "--duration", "60s",
         "--opcua", f"127.0.0.1:{port}", "--opcua-users", str(users), "--opcua-map", str(tmp_path / "map.toml"),
         "--opcua-security", "none,sign,encrypt", "--opcua-pki", str(tmp_path / "pki"), "--python", "-q"],
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        endpoint = f"opc.tcp://127.0.0.1:{port}/st/"
        deadline = time.monotonic() + 30
        while True:
            try:
                run(_endpoints(endpoint))
                break
            except (OSError, TimeoutError):
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise
                time.sleep(0.2)
        names, got, held, later, moving = run(_gantry(endpoint))
    finally:
        proc.terminate()
        _out, err = proc.communicate(timeout=20)
    assert {"auto", "strokes", "step", "offset", "move1", "power1", "x1"} <= names
    assert got == sorted(got) and got[0] <= 1 and got[-1] >= 2  # one notification per new stroke count
    assert held == later  # auto off: the strokes stopped at a scan boundary and stay
    assert moving is False
    assert "write gantry.auto := FALSE" in err


def test_api_plc_with_opcua_on_virtual_time(tmp_path):
    """`PLC(..., opcua={...})`: served while it lives; writes and commands taken between scans."""
    users = tmp_path / "users"
    add_user(str(users), "eng", "engineer", "eng-secret")
    (tmp_path / "map.toml").write_text(MAP)
    opts = {"endpoint": "127.0.0.1:0", "users": str(users), "map_file": str(tmp_path / "map.toml")}
    plc = PLC.from_source(SRC, opcua={**opts, "security": ("none",), "pki": str(tmp_path / "pki")})
    results = {}

    async def client():
        c = Client(plc.opcua.endpoint, timeout=10)
        c.set_user("eng")
        c.set_password("eng-secret")
        async with c:
            await c.get_node(nid("main.setpoint")).write_value(ua.Variant(77, ua.VariantType.Int16))
            results["scans at the write"] = await c.get_node(nid("PLC.Scans")).read_value()
            await c.get_node(nid("PLC")).call_method(nid("PLC.Stop"))

    t = threading.Thread(target=lambda: run(client()))
    t.start()
    try:
        end = time.monotonic() + 20
        while t.is_alive() and time.monotonic() < end:
            plc.scan(10)  # virtual time: 100 ms of PLC time per call, polled after each
            time.sleep(0.005)
        t.join(1)
        assert plc["main.setpoint"] == 77
        assert plc.state == "STOP"
        assert results["scans at the write"] > 0
    finally:
        plc.close()
    assert plc.opcua is None
