"""The online mode's defences (st/web/guard.py): the Host a request names, the Origin of a sign-in
post and of the WebSocket, one rate limiter for every presented secret, and `st run --web`'s
refusal to serve beyond this machine without a password."""

from __future__ import annotations

import asyncio
import http.client
import shutil
import socket
import ssl
import subprocess
import urllib.parse
from pathlib import Path

import pytest
from click.testing import CliRunner

from st import PLC
from st.api import compile_paths
from st.cli import main
from st.web.guard import Limiter, Site, split_host
from st.web.link import WebLink

LINE = Path(__file__).parent / "data" / "web" / "line.st"
TOKEN = "tok-0123456789"


# ---------------------------------------------------------------- Host and Origin


@pytest.mark.parametrize(
    ("header", "parts"),
    [("127.0.0.1:8080", ("127.0.0.1", 8080)), ("[::1]:80", ("::1", 80)), ("Plc1.Local", ("plc1.local", None))],
)
def test_a_host_header_is_split_into_name_and_port(header, parts):
    assert split_host(header) == parts


def test_a_loopback_server_answers_only_to_loopback_names_at_its_port():
    site = Site("127.0.0.1", 8080)
    assert [site.host_ok(h) for h in ("127.0.0.1:8080", "localhost:8080", "[::1]:8080")] == [True, True, True]
    # DNS rebinding: another name pointed at 127.0.0.1; another port; no Host at all
    assert [site.host_ok(h) for h in ("evil.example:8080", "127.0.0.1:9090", None, "")] == [False] * 4


def test_a_server_on_every_interface_answers_to_addresses_and_to_its_given_names():
    site = Site("0.0.0.0", 8443, "https", ("plc1.plant.local",))
    assert site.host_ok("192.168.1.20:8443") and site.host_ok("PLC1.plant.local:8443")
    assert not site.host_ok("evil.example:8443") and not site.host_ok("192.168.1.20:8080")
    assert Site("0.0.0.0", 443, "https").host_ok("10.0.0.5")  # (the scheme's default port)


def test_an_origin_must_match_scheme_host_and_port():
    site = Site("127.0.0.1", 8080)
    host = "127.0.0.1:8080"
    assert site.origin_ok("http://127.0.0.1:8080", host)
    assert site.origin_ok(None, host)  # no browser
    refused = ("https://127.0.0.1:8080", "http://127.0.0.1:9999", "http://evil.example", "null")
    assert [site.origin_ok(o, host) for o in refused] == [False] * 4
    assert Site("0.0.0.0", 443, "https").origin_ok("https://10.0.0.5", "10.0.0.5:443")


# ---------------------------------------------------------------- the limiter


class Clock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_wrong_secrets_back_off_exponentially_per_client_and_a_right_one_resets():
    clock, lines = Clock(), []
    lim = Limiter(base=0.5, cap=4.0, log=lines.append, clock=clock)

    async def tries():
        out = []
        for _ in range(5):
            out.append(await lim.check("10.0.0.9", lambda: False, "token"))
            out.append(lim.delay("10.0.0.9"))
            clock.now += lim.delay("10.0.0.9")  # (the next attempt comes when it may)
        return out

    got = asyncio.run(tries())
    assert got == [False, 0.5, False, 1.0, False, 2.0, False, 4.0, False, 4.0]  # capped
    assert lines[2] == "web: wrong token from 10.0.0.9 (3 in a row; the next is looked at in 2 s)"
    assert lim.delay("10.0.0.7") == 0.0  # another client is not slowed
    assert asyncio.run(lim.check("10.0.0.9", lambda: True, "token")) is True
    assert lim.delay("10.0.0.9") == 0.0


def test_an_early_attempt_waits_for_its_back_off_before_it_is_looked_at():
    lim = Limiter(base=0.2, cap=1.0)
    looked_at = []

    async def two():
        await lim.check("c", lambda: False, "password")
        loop = asyncio.get_running_loop()
        t0 = loop.time()
        await lim.check("c", lambda: looked_at.append(loop.time() - t0) or False, "password")

    asyncio.run(two())
    assert looked_at and looked_at[0] >= 0.19


def test_too_many_wrong_secrets_from_anyone_refuse_every_secret_for_the_window():
    clock, lines = Clock(), []
    lim = Limiter(base=0.0, window=60.0, global_max=3, log=lines.append, clock=clock)

    async def run():
        got = [await lim.check(f"10.0.0.{i}", lambda: False, "token") for i in range(3)]
        got.append(await lim.check("10.0.0.99", lambda: True, "token"))  # right, but not looked at
        clock.now += 61
        got.append(await lim.check("10.0.0.99", lambda: True, "token"))
        return got

    assert asyncio.run(run()) == [False, False, False, None, True]
    assert lines[3] == "web: token from 10.0.0.99 refused: 3 wrong secrets in 60 s"


# ---------------------------------------------------------------- a real server


@pytest.fixture
def web(tmp_path):
    plc = PLC(compile_paths([str(LINE)]), retain=str(tmp_path / "line.db"))
    link = WebLink(plc, "line.st", "127.0.0.1", 0, token=TOKEN, password="s3cret", period=0.0).start()
    yield plc, link
    link.stop()
    plc.close()


def _request(link, method: str, path: str, headers: dict, body: bytes | None = None) -> tuple[int, str]:
    conn = http.client.HTTPConnection("127.0.0.1", link.port, timeout=10)
    conn.putrequest(method, path, skip_host=True)
    for k, v in headers.items():
        conn.putheader(k, v)
    if body is not None:
        conn.putheader("Content-Length", str(len(body)))
    conn.endheaders(body)
    r = conn.getresponse()
    out = r.status, r.read().decode()
    conn.close()
    return out


@pytest.mark.slow  # (the server process)
def test_a_request_naming_another_host_is_refused_even_with_the_token(web):
    _plc, link = web
    here = f"127.0.0.1:{link.port}"
    assert _request(link, "GET", "/", {"Host": here})[0] == 200
    assert _request(link, "GET", "/", {"Host": f"localhost:{link.port}"})[0] == 200
    for host in (f"evil.example:{link.port}", "127.0.0.1:1", ""):
        status, text = _request(link, "GET", f"/?token={TOKEN}", {"Host": host})
        assert (status, text) == (421, "misdirected request: this server is not that host")


@pytest.mark.slow  # (the server process)
def test_a_sign_in_posted_from_another_sites_page_is_refused(web):
    _plc, link = web
    here = f"127.0.0.1:{link.port}"
    body = urllib.parse.urlencode({"secret": "s3cret"}).encode()
    form = {"Host": here, "Content-Type": "application/x-www-form-urlencoded"}
    for origin in ("http://evil.example", f"https://{here}"):
        status, text = _request(link, "POST", "/login", {**form, "Origin": origin}, body)
        assert (status, text) == (403, "a sign-in from another site's page is refused")
    assert _request(link, "POST", "/login", {**form, "Origin": f"http://{here}"}, body)[0] == 303


@pytest.mark.slow  # (the server process)
def test_wrong_tokens_and_passwords_share_one_back_off_and_are_logged(web):
    plc, link = web
    here = {"Host": f"127.0.0.1:{link.port}"}
    assert _request(link, "GET", "/?token=guess1", here)[0] == 401
    body = urllib.parse.urlencode({"secret": "guess2"}).encode()
    headers = {**here, "Content-Type": "application/x-www-form-urlencoded"}
    assert _request(link, "POST", "/login", headers, body)[0] == 401
    assert _request(link, "GET", f"/?token={TOKEN}", here)[0] == 303  # after its 1 s wait, the right one
    link.poll()
    lines = [m.text for m in plc.log.entries if m.text.startswith("web: ")]
    assert lines == [
        "web: wrong token from 127.0.0.1 (1 in a row; the next is looked at in 0.5 s)",
        "web: wrong password from 127.0.0.1 (2 in a row; the next is looked at in 1 s)",
    ]


# ---------------------------------------------------------------- st run --web


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--web", "0.0.0.0:0"], "error: --web 0.0.0.0:0 serves the PLC beyond this machine: give it a --web-password"),
        (["--web", "127.0.0.1:0", "--web-cert", "c.pem"], "error: --web-cert and --web-key go together"),
    ],
)
def test_st_run_refuses_an_unprotected_or_half_configured_web_server(args, message):
    r = CliRunner().invoke(main, ["run", str(LINE), "--duration", "1s", *args])
    assert r.exit_code != 0
    assert message in r.output


def test_every_web_option_needs_web():
    r = CliRunner().invoke(main, ["run", str(LINE), "--virtual", "--scans", "1", "--web-insecure"])
    assert r.exit_code == 2 and "--web-insecure" in r.output and "--web" in r.output


@pytest.mark.slow  # (the server process)
@pytest.mark.skipif(shutil.which("openssl") is None, reason="openssl is not installed (to make a test certificate)")
def test_web_cert_and_key_serve_https_with_a_secure_cookie(tmp_path):
    cert, key = tmp_path / "plc.crt", tmp_path / "plc.key"
    subprocess.run(
        [
            "openssl",
            "req",
            "-x509",
            "-newkey",
            "rsa:2048",
            "-sha256",
            "-days",
            "2",
            "-nodes",
            "-keyout",
            str(key),
            "-out",
            str(cert),
            "-subj",
            "/CN=127.0.0.1",
            "-addext",
            "subjectAltName=IP:127.0.0.1",
        ],
        check=True,
        capture_output=True,
    )
    plc = PLC(compile_paths([str(LINE)]), retain=str(tmp_path / "line.db"))
    link = WebLink(plc, "line.st", "127.0.0.1", 0, token=TOKEN, cert=str(cert), key=str(key)).start()
    try:
        ctx = ssl.create_default_context(cafile=str(cert))
        conn = http.client.HTTPSConnection("127.0.0.1", link.port, timeout=10, context=ctx)
        conn.request("GET", f"/?token={TOKEN}")
        r = conn.getresponse()
        cookie = r.getheader("set-cookie") or ""
        assert r.status == 303
        assert "st_session=" in cookie and "Secure" in cookie and "HttpOnly" in cookie and "SameSite=strict" in cookie
        conn.close()
        with pytest.raises(http.client.RemoteDisconnected):  # no plain HTTP on that port
            plain = http.client.HTTPConnection("127.0.0.1", link.port, timeout=10)
            plain.request("GET", "/")
            plain.getresponse()
    finally:
        link.stop()
        plc.close()


@pytest.mark.slow  # (the server process)
def test_the_websocket_refuses_a_rebound_host_and_a_foreign_scheme_even_with_a_session(web):
    """DNS rebinding's shape: Host and Origin both evil.example (they agree), with a valid cookie."""
    from websockets.exceptions import ConnectionClosed, InvalidStatus
    from websockets.sync.client import connect

    _plc, link = web
    conn = http.client.HTTPConnection("127.0.0.1", link.port, timeout=10)
    conn.request("GET", f"/?token={TOKEN}", headers={"Host": f"127.0.0.1:{link.port}"})
    cookie = (conn.getresponse().getheader("set-cookie") or "").split(";")[0]
    conn.close()
    evil = f"evil.example:{link.port}"
    for host, origin in ((evil, f"http://{evil}"), (f"127.0.0.1:{link.port}", f"https://127.0.0.1:{link.port}")):
        sock = socket.create_connection(("127.0.0.1", link.port), timeout=5)  # the name resolves here
        headers = {"Cookie": cookie, "Origin": origin}
        try:
            with connect(f"ws://{host}/ws", sock=sock, additional_headers=headers, open_timeout=5) as ws:
                with pytest.raises(ConnectionClosed) as e:
                    ws.recv(timeout=5)
                assert e.value.rcvd is not None and e.value.rcvd.code == 4403, host  # (the foreign scheme)
        except InvalidStatus as refused:  # the rebound Host: refused before the upgrade
            assert refused.response.status_code == 403 and host == evil
