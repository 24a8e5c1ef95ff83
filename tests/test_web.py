"""The online mode's server and the PLC's side of it (st/web), driven as a page drives them: the
sign-in, the WebSocket's snapshots (values, the lines of the last scan, tasks, faults) and every
change a page can ask for. The PLC runs on virtual time here and the test calls the link between
two scans, as `st run`'s idle hook does; tests/test_web_browser.py drives the real page.
"""

from __future__ import annotations

import http.cookiejar
import json
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path

import pytest
from click.testing import CliRunner
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from st import PLC
from st.api import compile_paths, compile_text
from st.cli import main
from st.io.shm import MessageRing
from st.runtime.faults import PLCFaultError
from st.web.channel import Channel
from st.web.link import WebLink

LINE = Path(__file__).parent / "data" / "web" / "line.st"
TOKEN = "tok-0123456789"


@pytest.fixture
def web(tmp_path):
    compiled = compile_paths([str(LINE)], coverage=True)
    plc = PLC(compiled, retain=str(tmp_path / "line.db"))
    link = WebLink(plc, "line.st", "127.0.0.1", 0, token=TOKEN, password="s3cret", period=0.0).start()
    yield plc, link
    link.stop()
    plc.close()


def _base(link) -> str:
    return f"http://127.0.0.1:{link.port}"


def _opener():
    jar = http.cookiejar.CookieJar()
    return urllib.request.build_opener(urllib.request.HTTPCookieProcessor(jar)), jar


def _get(opener, url: str) -> tuple[int, str]:
    try:
        with opener.open(url) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


def _session(link) -> str:
    opener, jar = _opener()
    assert _get(opener, f"{_base(link)}/?token={TOKEN}")[0] == 200  # (the redirect, followed)
    return "; ".join(f"{c.name}={c.value}" for c in jar)


def _ws(link, cookie: str | None, origin: str | None = None):
    headers = {"Cookie": cookie} if cookie else {}
    headers["Origin"] = origin or _base(link)
    return connect(f"ws://127.0.0.1:{link.port}/ws", additional_headers=headers, open_timeout=5)


def _until(plc, link, ws, want, scans: int = 1, timeout: float = 20.0, results: list | None = None) -> dict:
    """Scan and serve until the page receives a snapshot for which `want(snapshot)` holds (the
    result messages that come meanwhile are added to `results`)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        link.poll()
        if plc.state == "RUN" and scans:
            try:
                plc.scan(scans)
            except PLCFaultError:
                pass
        link.poll()
        try:
            msg = json.loads(ws.recv(timeout=0.05))
        except TimeoutError:
            continue
        if msg["type"] == "result":
            if results is not None:
                results.append(msg)
            continue
        if want(msg):
            return msg
    raise AssertionError("no such snapshot came")


@pytest.mark.slow  # (the server process)
def test_everything_but_the_sign_in_page_needs_the_token_or_the_password(web):
    plc, link = web
    opener, jar = _opener()
    status, page = _get(opener, _base(link) + "/")
    assert status == 200 and 'data-testid="login-secret"' in page and "app.js" not in page
    assert _get(opener, _base(link) + "/api/program")[0] == 401
    assert _get(opener, f"{_base(link)}/?token=wrong")[0] == 401
    data = urllib.parse.urlencode({"secret": "s3cret"}).encode()
    with opener.open(urllib.request.Request(_base(link) + "/login", data=data)) as r:  # the password
        assert r.status == 200 and "static/app.js" in r.read().decode()
    assert [c.name for c in jar] == ["st_session"]
    assert _get(opener, _base(link) + "/api/program")[0] == 200
    for cookie, origin, code in ((None, None, 4401), (_session(link), "http://evil.example", 4403)):
        with _ws(link, cookie, origin) as ws, pytest.raises(ConnectionClosed) as e:
            ws.recv(timeout=5)
        assert e.value.rcvd is not None and e.value.rcvd.code == code


@pytest.mark.slow  # (the server process)
def test_the_program_description_has_the_instance_tree_and_the_source(web):
    plc, link = web
    opener, _ = _opener()
    _get(opener, f"{_base(link)}/?token={TOKEN}")
    status, text = _get(opener, _base(link) + "/api/program")
    doc = json.loads(text)
    assert status == 200 and doc["name"] == "line.st" and doc["read_only"] is False and doc["flow"] is True
    (inst,) = doc["instances"]
    assert (inst["path"], inst["pou"], inst["kind"]) == ("line", "line", "PROGRAM")
    assert [c["path"] for c in inst["children"]] == ["line.delay"]
    pou = doc["pous"]["line"]
    assert pou["first_line"] == 3 and pou["source"][0] == "PROGRAM line" and pou["source"][-1] == "END_PROGRAM"
    motor = next(v for v in pou["vars"] if v["name"] == "motor")
    assert motor == {
        "name": "motor",
        "type": "BOOL",
        "section": "VAR",
        "location": "%QX0.0",
        "output": True,
        "elementary": True,
    }
    assert doc["pous"]["TON"]["source"] == [] and doc["pous"]["TON"]["library"] is True


@pytest.mark.slow  # (the server process)
def test_a_page_gets_what_it_watches_and_the_lines_of_the_last_scan(web):
    plc, link = web
    with _ws(link, _session(link)) as ws:
        ws.send(json.dumps({"type": "view", "instance": "line"}))
        ws.send(json.dumps({"type": "watch", "paths": ["line.count", "line.nothing"]}))
        snap = _until(plc, link, ws, lambda m: m.get("lines") and "line.count" in m["values"])
        assert snap["state"] == "RUN" and snap["fault"] is None
        assert snap["lines"] == {"pou": "line", "hit": [17, 18, 19, 20, 21, 24]}  # not 22: the motor is off
        values = snap["values"]
        assert values["line.dwell"] == {"text": "T#200ms", "num": 200.0, "type": "TIME"}  # charted in ms
        assert values["line.delay.Q"] == {"text": "FALSE", "num": 0.0, "type": "BOOL"}  # for `delay.Q`
        assert values["line.speed"] == {"text": "1.5", "num": 1.5, "type": "REAL"}
        nothing = values["line.nothing"]  # the server's word for a path the program does not have
        assert nothing["text"] is None and nothing["error"] == "line.nothing: line has no variable 'nothing'"
        assert int(values["line.count"]["text"]) >= 1
        (task,) = snap["tasks"]
        assert task["jobs"] >= 1 and task["mk"]["met"] is True
        assert sum(task["hist"]["exec"]["counts"]) == task["jobs"] == snap["scans"]
        plc["line.run"] = True
        plc.advance("300ms")  # the timer runs out: the motor is on, line 22 runs
        snap = _until(plc, link, ws, lambda m: m["values"]["line.motor"]["text"] == "TRUE" and m["lines"])
        assert snap["lines"]["hit"] == [17, 18, 19, 20, 21, 22, 24]


@pytest.mark.slow  # (the server process)
def test_writes_forcing_and_stop_start_from_a_page_are_applied_and_logged(web):
    plc, link = web
    with _ws(link, _session(link)) as ws:
        ws.send(json.dumps({"type": "watch", "paths": ["line.count"]}))
        _until(plc, link, ws, lambda m: "line.count" in m["values"])
        ws.send(json.dumps({"type": "write", "path": "line.count", "value": "16#64", "id": 1}))
        ws.send(json.dumps({"type": "write", "path": "line.speed", "value": "fast", "id": 2}))
        ws.send(json.dumps({"type": "force", "path": "line.motor", "value": "TRUE", "id": 3}))
        got: list[dict] = []
        snap = _until(plc, link, ws, lambda m: len(got) >= 3, scans=0, results=got)
        results = {r["id"]: r for r in got}
        assert results[1] == {"type": "result", "id": 1, "ok": True}
        assert results[2] == {
            "type": "result",
            "id": 2,
            "ok": False,
            "error": "line.speed: not a literal of REAL: 'fast'",
        }
        assert results[3]["ok"] is True and snap["forced"] == ["line.motor"]
        assert plc["line.count"] == 100
        plc.scan(3)
        assert plc["line.motor"] is True and plc["line.count"] == 103  # forced against the program
        texts = [m["text"] for m in snap["log"]]
        assert any(t.startswith("web 127.0.0.1:") and t.endswith(": write line.count := 100") for t in texts)
        assert any(t.endswith(": force line.motor := TRUE") for t in texts)
        ws.send(json.dumps({"type": "unforce", "path": "line.motor", "id": 4}))
        ws.send(json.dumps({"type": "control", "action": "stop", "id": 5}))
        _until(plc, link, ws, lambda m: m["state"] == "STOP", scans=0)
        assert plc.forced == [] and plc.state == "STOP"
        ws.send(json.dumps({"type": "control", "action": "start", "id": 6}))
        _until(plc, link, ws, lambda m: m["state"] == "RUN", scans=0)


@pytest.mark.slow  # (the server process)
def test_a_fault_reaches_the_page_and_a_warm_or_cold_reset_clears_it(web):
    plc, link = web
    with _ws(link, _session(link)) as ws:
        ws.send(json.dumps({"type": "watch", "paths": ["line.kept", "line.divisor"]}))
        _until(plc, link, ws, lambda m: "line.kept" in m["values"])
        ws.send(json.dumps({"type": "write", "path": "line.divisor", "value": "0"}))
        snap = _until(plc, link, ws, lambda m: m["state"] == "FAULT")
        fault = snap["fault"]
        assert Path(fault.pop("file")).name == "line.st"
        assert fault == {"kind": "DIV0", "message": "division by zero", "line": 24, "pou": "line", "task": "main"}
        kept = plc["line.kept"]
        assert kept > 0
        ws.send(json.dumps({"type": "control", "action": "reset_warm"}))
        _until(plc, link, ws, lambda m: m["state"] == "RUN", scans=0)
        assert plc["line.divisor"] == 4 and plc["line.kept"] == kept  # RETAIN kept over a warm restart
        ws.send(json.dumps({"type": "control", "action": "reset_cold"}))
        _until(plc, link, ws, lambda m: m["state"] == "RUN" and m["values"]["line.kept"]["text"] == "0", scans=0)


@pytest.mark.slow  # (the server process)
def test_a_read_only_server_refuses_every_change():
    plc = PLC(compile_paths([str(LINE)]))
    link = WebLink(plc, "line.st", "127.0.0.1", 0, token=TOKEN, read_only=True, period=0.0).start()
    try:
        with _ws(link, _session(link)) as ws:
            ws.send(json.dumps({"type": "write", "path": "line.count", "value": "5", "id": 9}))
            reply = json.loads(ws.recv(timeout=5))
        assert reply == {
            "type": "result",
            "id": 9,
            "ok": False,
            "error": "the online mode is read-only (--web-read-only)",
        }
        assert plc["line.count"] == 0
    finally:
        link.stop()
        plc.close()


def test_the_channel_never_returns_a_torn_snapshot_and_a_full_ring_refuses():
    ch = Channel(create=True)
    try:
        other = Channel(ch.name)
        assert other.latest() is None
        ch.publish(b'{"a":1}')
        assert other.latest() == b'{"a":1}'
        ch.lock.begin_write()  # a writer in the middle of an update: the reader gives up, never tears
        assert other.lock.read(lambda: 1, retries=5) is None
        ch.lock.end_write()
        ring = MessageRing(memoryview(bytearray(32)), memoryview(bytearray(8)).cast("I"))
        assert ring.put(b"x" * 20) and not ring.put(b"y" * 20)
        assert ring.take() == [b"x" * 20] and ring.put(b"y" * 20) and ring.take() == [b"y" * 20]
        other.close()
    finally:
        ch.close(unlink=True)


def test_web_needs_a_real_time_run():
    r = CliRunner().invoke(main, ["run", str(LINE), "--web", "--virtual", "--scans", "3"])
    assert r.exit_code == 2
    assert "error: --web needs a run in real time (not --virtual)" in r.output


@pytest.mark.slow  # (the server process)
def test_an_online_change_sends_the_pages_the_new_program(web):
    plc, link = web
    with _ws(link, _session(link)) as ws:
        ws.send(json.dumps({"type": "watch", "paths": ["line.count"]}))
        _until(plc, link, ws, lambda m: "line.count" in m.get("values", {}))
        changed = LINE.read_text().replace("count := count + 1;", "count := count + 1000;")
        plc.online_change(compile_text(changed, str(LINE), coverage=True))
        note = _until(plc, link, ws, lambda m: m["type"] == "program")
        assert note["version"] == 2
        before = plc["line.count"]
        snap = _until(
            plc, link, ws, lambda m: m["type"] == "snapshot" and int(m["values"]["line.count"]["text"]) > before
        )
        assert int(snap["values"]["line.count"]["text"]) >= before + 1000  # the new body runs, the value kept


@pytest.mark.slow  # (a whole st run with its server process)
def test_a_web_run_exits_without_shared_memory_warnings():
    import subprocess
    import sys

    r = subprocess.run(
        [sys.executable, "-m", "st", "run", str(LINE), "--web", "127.0.0.1:0", "--duration", "1s", "--no-rt"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert "web: http://127.0.0.1:" in r.stderr
    assert "leaked" not in r.stderr and "resource_tracker" not in r.stderr
