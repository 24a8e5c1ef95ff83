"""The web server process: the page, its program description and a WebSocket per page.

Runs as `python -m st.web` (st/web/link.py starts it), apart from the PLC: it reads the PLC's
snapshots from the shared memory (channel.py) 10 times a second, sends each page what it
watches, and queues the pages' requests for the PLC.

Security: the server listens on loopback unless told otherwise. A browser gets in with the
token printed at start (`/?token=…`, as Jupyter does) or the configured password; it then
holds a random session cookie (HttpOnly, SameSite=Strict, Secure over HTTPS). Everything but
the login page and the static files needs that session. Every request must name this server in
its Host header, the login post and the WebSocket must come from one of its pages (Origin), and
every secret goes through one rate limiter (guard.py). The changes travel only over the
WebSocket; each carries its origin (the client's address) into the PLC's log.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import json
import marshal
import math
import os
import secrets
from bisect import bisect_right
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, PlainTextResponse, RedirectResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from ..model import types as T
from ..runtime.values import to_st_literal
from .channel import FAILED, SERVING, Channel
from .guard import Limiter, Site
from .link import WebConfig

STATIC = Path(__file__).with_name("static")
COOKIE = "st_session"
PERIOD = 0.1  # s between two updates of a page (10 Hz)
_CHANGES = ("write", "force", "unforce", "control")

LOGIN = """<!doctype html><html><head><meta charset="utf-8"><title>st online — sign in</title>
<style>body{{font:15px system-ui,sans-serif;margin:15vh auto;max-width:26em;color:#222}}
input{{font:inherit;padding:.4em;width:100%;box-sizing:border-box;margin:.5em 0}}
button{{font:inherit;padding:.4em 1.2em}} .err{{color:#b00}}</style></head><body>
<h2>st online mode</h2><p>Enter the token printed by <code>st run --web</code>{password}.</p>
<form method="post" action="login"><input name="secret" type="password" autofocus data-testid="login-secret">
<button type="submit" data-testid="login-submit">Sign in</button></form>{error}</body></html>"""


class Client:
    """One connected page: what it watches and views, what it has been sent."""

    def __init__(self, ws: WebSocket, number: int):
        self.ws, self.number = ws, number
        peer = ws.client
        self.origin = f"{peer.host}:{peer.port}" if peer else "?"
        self.paths: list[str] = []
        self.view: str | None = None  # an instance path
        self.view_paths: list[str] = []
        self.view_pou: str | None = None
        self.result_seq = 0
        self.log_total: int | None = None
        self.pending: list[dict] = []  # messages for this page, sent before its next snapshot


class Hub:
    """The server's state: the channel, the sessions, the pages."""

    def __init__(self, cfg: WebConfig):
        self.cfg = cfg
        self.ch = Channel(cfg.channel)
        self.sessions: set[str] = set()
        self.clients: dict[int, Client] = {}
        self._numbers = 0
        self.description: dict = {}
        self.description_text = b"{}"
        self.description_version = -1
        self.subscribed: tuple[list[str], list[str]] | None = None
        self.last_doc: bytes | None = None
        self.hist: dict[str, dict] = {}  # task → the histograms of its latencies and execution times
        self.site = Site(cfg.host, cfg.port, cfg.scheme, tuple(cfg.names))  # port: the bound one, once bound
        self.limiter = Limiter(log=self.note)

    def note(self, text: str) -> None:
        """A line for the PLC's log (and so the pages' and st run's): the limiter's reports."""
        self.ch.requests.put(json.dumps({"type": "note", "text": text}).encode())

    # ------------------------------------------------------------------ sessions
    def check_secret(self, secret: str) -> bool:
        ok = bool(secret) and hmac.compare_digest(secret.encode(), self.cfg.token.encode())
        if self.cfg.password and secret:
            ok = ok or hmac.compare_digest(secret.encode(), self.cfg.password.encode())
        return ok

    def new_session(self) -> str:
        sid = secrets.token_urlsafe(32)
        self.sessions.add(sid)
        return sid

    def authed(self, cookies: dict) -> bool:
        sid = cookies.get(COOKIE, "").encode()  # (bytes: a cookie may hold any character)
        return bool(sid) and any(hmac.compare_digest(sid, s.encode()) for s in self.sessions)

    # ------------------------------------------------------------------ the program
    def refresh_description(self) -> None:
        if self.ch.description_version == self.description_version:
            return
        got = self.ch.description()
        if got is None:
            return
        version, text = got
        changed = self.description_version >= 0  # not the first: an online change
        self.description_version, self.description_text = version, text
        self.description = json.loads(text) if text else {}
        for c in self.clients.values():
            self.set_view(c, c.view)
        self.subscribe()
        if changed:  # the pages load the new program
            for c in list(self.clients.values()):
                c.pending.append({"type": "program", "version": version})

    def set_view(self, c: Client, instance: str | None) -> None:
        """The paths of the viewed instance's variables, and those of the blocks inside it."""
        c.view, c.view_paths, c.view_pou = instance, [], None
        if not instance:
            return
        node = _find(self.description.get("instances", []), instance)
        if node is None:
            return
        pous = self.description.get("pous", {})
        c.view_pou = node["pou"]
        kids = {ch["path"].rsplit(".", 1)[-1].lower(): ch for ch in node.get("children", [])}
        for v in pous.get(node["pou"], {}).get("vars", []):
            path = f"{instance}.{v['name']}"
            if v["elementary"]:
                c.view_paths.append(path)
            elif v["name"].lower() in kids:
                child = kids[v["name"].lower()]
                c.view_paths += [
                    f"{path}.{m['name']}" for m in pous.get(child["pou"], {}).get("vars", []) if m["elementary"]
                ]

    def subscribe(self) -> None:
        """The union of every page's paths and views, to the PLC when it changed."""
        paths = sorted({p for c in self.clients.values() for p in (*c.paths, *c.view_paths)})
        pous = sorted({c.view_pou for c in self.clients.values() if c.view_pou})
        if (paths, pous) != self.subscribed:
            if self.ch.requests.put(json.dumps({"type": "subscribe", "paths": paths, "pous": pous}).encode()):
                self.subscribed = (paths, pous)

    # ------------------------------------------------------------------ pages
    async def handle(self, c: Client, msg: dict) -> None:
        kind = msg.get("type")
        if kind == "view":
            self.refresh_description()
            self.set_view(c, str(msg.get("instance") or "") or None)
            self.subscribe()
        elif kind == "watch":
            c.paths = [str(p) for p in msg.get("paths", []) if isinstance(p, str)][:2000]
            self.subscribe()
        elif kind in _CHANGES:
            if self.cfg.read_only:
                await self.reply(c, msg, False, "the online mode is read-only (--web-read-only)")
                return
            req = {k: msg.get(k) for k in ("type", "path", "value", "action", "id")}
            req.update(client=c.number, origin=c.origin)
            if not self.ch.requests.put(json.dumps(req).encode()):
                await self.reply(c, msg, False, "the PLC is busy: too many requests queued")
        else:
            await self.reply(c, msg, False, f"unknown request {kind!r}")

    async def reply(self, c: Client, msg: dict, ok: bool, error: str = "") -> None:
        out = {"type": "result", "id": msg.get("id"), "ok": ok}
        if error:
            out["error"] = error
        with contextlib.suppress(Exception):
            await c.ws.send_text(json.dumps(out))

    async def pump(self) -> None:
        """Every PERIOD: the latest snapshot to every page, tailored."""
        while True:
            await asyncio.sleep(PERIOD)
            self.ch.pages = len(self.clients)
            if not self.clients:
                continue
            self.refresh_description()
            doc = self.ch.latest()
            if doc is None or doc == self.last_doc:
                continue
            self.last_doc = doc
            snap = marshal.loads(doc)
            self.ch.consumed = snap["number"]  # the PLC's next samples start after this one's
            for t in snap["tasks"]:
                empty = [0] * (len(EDGES) - 1)
                h = self.hist.setdefault(t["name"], {"latency": list(empty), "exec": list(empty), "jobs": 0})
                fresh = max(t["jobs"] - h["jobs"], 0)  # (samples binned already may come again)
                h["jobs"] = t["jobs"]
                for key in ("latency", "exec"):
                    counts = h[key]
                    for v in t.pop("new_" + key)[:fresh]:
                        counts[_bin(v)] += 1
            for c in list(self.clients.values()):
                out = self.for_client(c, snap)
                with contextlib.suppress(Exception):
                    for note in c.pending:
                        await c.ws.send_text(json.dumps(note))
                    c.pending.clear()
                    for result in out.pop("results"):  # the answers to this page's changes first
                        await c.ws.send_text(json.dumps(result))
                    await c.ws.send_text(json.dumps(out, allow_nan=False))

    def task_view(self, t: dict) -> dict:
        """A task's statistics with its histograms and the p99 they give."""
        h = self.hist.get(t["name"])
        if h is None:
            return t
        t = dict(t)
        t["latency_ns"] = {**t["latency_ns"], "p99": _pct(h["latency"], 0.99)}
        t["exec_ns"] = {**t["exec_ns"], "p99": _pct(h["exec"], 0.99)}
        t["hist"] = {"exec": _hist(h["exec"]), "latency": _hist(h["latency"])}
        return t

    def for_client(self, c: Client, snap: dict) -> dict:
        """The snapshot a page gets: its values formatted, its lines, its results, its new log."""
        index = snap.setdefault("_index", {p: i for i, p in enumerate(snap["paths"])})
        skip = ("paths", "types", "type_names", "values", "lines", "results", "log", "log_total", "_index", "number")
        out = {k: v for k, v in snap.items() if k not in skip}
        out["type"] = "snapshot"
        out["tasks"] = [self.task_view(t) for t in snap["tasks"]]
        types, raw, names = snap["types"], snap["values"], snap.get("type_names", {})
        out["values"] = {
            p: {**format_value(types[index[p]], raw[index[p]]), "type": names.get(p)}
            for p in (*c.paths, *c.view_paths)
            if p in index
        }
        lines = snap.get("lines")
        out["lines"] = (
            {"pou": c.view_pou, "hit": lines.get(c.view_pou, [])} if lines is not None and c.view_pou else None
        )
        total = snap.get("log_total", 0)
        log = snap.get("log", [])
        new = len(log) if c.log_total is None else max(0, min(len(log), total - c.log_total))
        out["log"] = [{"time_ns": t, "kind": k, "text": x} for t, k, x in log[len(log) - new :]] if new else []
        c.log_total = total
        results = [r for r in snap.get("results", []) if r["seq"] > c.result_seq]
        if results:
            c.result_seq = results[-1]["seq"]
        out["results"] = [
            {"type": "result", "id": r["id"], "ok": r["ok"], **({"error": r["error"]} if r["error"] else {})}
            for r in results
            if r["client"] == c.number
        ]
        return out


# histogram bins: 1 µs to ~17 s, four per octave (ns edges)
EDGES = [0] + [int(1000 * 2 ** (i / 4)) for i in range(0, 4 * 24 + 1)]


def _bin(v: float) -> int:
    return min(max(bisect_right(EDGES, v) - 1, 0), len(EDGES) - 2)


def _pct(counts: list[int], q: float) -> float:
    """The upper edge of the bin holding quantile q (ns)."""
    total = sum(counts)
    if not total:
        return 0
    acc = 0
    for i, c in enumerate(counts):
        acc += c
        if acc >= q * total:
            return EDGES[i + 1]
    return EDGES[-1]


def _hist(counts: list[int]) -> dict:
    """The bins from the first to the last used one."""
    used = [i for i, c in enumerate(counts) if c]
    if not used:
        return {"edges_ns": [], "counts": []}
    a, b = used[0], used[-1] + 1
    return {"edges_ns": EDGES[a : b + 1], "counts": counts[a:b]}


_MS = ("TIME", "LTIME", "TIME_OF_DAY", "TOD", "LTIME_OF_DAY", "LTOD")  # charted in ms (their values are ns)


def format_value(kind: str, v: Any) -> dict:
    """A value as the page shows it: its IEC literal and a number for charts (see link._value):
    TIME-like values in ms, an enumeration value as its ordinal (the literal names it)."""
    if kind == "!":
        return {"text": None, "num": None, "error": v}
    if kind == "=":
        return {"text": v, "num": None}
    if kind == "#":
        ordinal, text = v
        return {"text": text, "num": ordinal}
    num = float(v) if isinstance(v, (bool, int, float)) else None
    if num is not None and (math.isnan(num) or math.isinf(num)):
        num = None
    if num is not None and kind in _MS:
        num /= 1e6
    return {"text": to_st_literal(v, T.ELEMENTARY[kind]), "num": num}


def _find(nodes: list, path: str) -> dict | None:
    for n in nodes:
        if n["path"].lower() == path.lower():
            return n
        found = _find(n.get("children", []), path)
        if found is not None:
            return found
    return None


def _peer(conn: Request | WebSocket) -> str:
    return conn.client.host if conn.client else "?"


class HostGuard:
    """ASGI middleware: a request whose Host header does not name this server gets 421, and such a
    WebSocket is refused at its handshake (403), before any route sees it."""

    def __init__(self, app: Any, hub: Hub):
        self.app, self.hub = app, hub

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] in ("http", "websocket"):
            host = next((v.decode("latin-1") for k, v in scope.get("headers", []) if k == b"host"), None)
            if not self.hub.site.host_ok(host):
                if scope["type"] == "http":
                    await PlainTextResponse("misdirected request: this server is not that host", 421)(
                        scope, receive, send
                    )
                else:
                    await receive()  # websocket.connect
                    await send({"type": "websocket.close", "code": 4403})
                return
        await self.app(scope, receive, send)


def make_app(hub: Hub) -> Any:
    def login_page(error: str = "", status: int = 200) -> HTMLResponse:
        password = " or the password" if hub.cfg.password else ""
        err = f'<p class="err" data-testid="login-error">{error}</p>' if error else ""
        return HTMLResponse(LOGIN.format(password=password, error=err), status_code=status)

    def signed_in(location: str = "./") -> Response:
        r = RedirectResponse(location, status_code=303)
        secure = hub.site.scheme == "https"
        r.set_cookie(COOKIE, hub.new_session(), httponly=True, samesite="strict", path="/", secure=secure)
        return r

    async def try_secret(request: Request, secret: str, what: str) -> Response:
        """The one way a token or password is looked at (guard.Limiter)."""
        ok = await hub.limiter.check(_peer(request), lambda: hub.check_secret(secret), what)
        if ok:
            return signed_in("./")
        if ok is None:
            return login_page("Too many wrong secrets lately: try again in a minute.", 429)
        return login_page("Wrong token or password." if what == "password" else "That token is not this server's.", 401)

    async def index(request: Request) -> Response:
        token = request.query_params.get("token")
        if token is not None:
            return await try_secret(request, token, "token")
        if not hub.authed(request.cookies):
            return login_page()
        return HTMLResponse((STATIC / "index.html").read_text(encoding="utf-8"), headers={"Cache-Control": "no-store"})

    async def login(request: Request) -> Response:
        if not hub.site.origin_ok(request.headers.get("origin"), request.headers.get("host")):
            return PlainTextResponse("a sign-in from another site's page is refused", 403)
        body = (await request.body())[:4096].decode("utf-8", "replace")  # a urlencoded form of one field
        secret = parse_qs(body).get("secret", [""])[0]
        return await try_secret(request, secret, "password")

    async def program(request: Request) -> Response:
        if not hub.authed(request.cookies):
            return JSONResponse({"error": "sign in first"}, status_code=401)
        hub.refresh_description()
        return Response(hub.description_text, media_type="application/json", headers={"Cache-Control": "no-store"})

    async def ws_endpoint(ws: WebSocket) -> None:
        await ws.accept()
        same_origin = hub.site.origin_ok(ws.headers.get("origin"), ws.headers.get("host"))
        if not hub.authed(ws.cookies) or not same_origin:  # closed before anything is sent
            await ws.close(code=4401 if not hub.authed(ws.cookies) else 4403)
            return
        hub._numbers += 1
        c = hub.clients[hub._numbers] = Client(ws, hub._numbers)
        hub.ch.pages = len(hub.clients)
        try:
            while True:
                text = await ws.receive_text()
                try:
                    msg = json.loads(text)
                except ValueError:
                    continue
                if isinstance(msg, dict):
                    await hub.handle(c, msg)
        except WebSocketDisconnect:
            pass
        finally:
            hub.clients.pop(c.number, None)
            hub.ch.pages = len(hub.clients)
            hub.subscribe()

    routes = [
        Route("/", index),
        Route("/login", login, methods=["POST"]),
        Route("/api/program", program),
        WebSocketRoute("/ws", ws_endpoint),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    return HostGuard(Starlette(routes=routes), hub)


async def _watch_parent(pid: int, server: uvicorn.Server) -> None:
    """Ends the server when the PLC process is gone."""
    while True:
        await asyncio.sleep(1.0)
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            server.should_exit = True
            return


async def _serve(cfg: WebConfig) -> None:
    hub = Hub(cfg)
    config = uvicorn.Config(
        make_app(hub),
        host=cfg.host,
        port=cfg.port,
        log_level="warning",
        ws_max_size=1 << 20,
        ssl_certfile=cfg.cert or None,
        ssl_keyfile=cfg.key or None,
    )
    server = uvicorn.Server(config)
    task = asyncio.create_task(server.serve())
    while not server.started and not task.done():
        await asyncio.sleep(0.01)
    if not server.started:
        hub.ch.state = FAILED
        with contextlib.suppress(BaseException):
            await task
        return
    sock = server.servers[0].sockets[0]
    hub.ch.port = hub.site.port = sock.getsockname()[1]
    hub.ch.state = SERVING
    pump = asyncio.create_task(hub.pump())
    parent = asyncio.create_task(_watch_parent(cfg.pid, server))
    try:
        await task
    finally:
        pump.cancel()
        parent.cancel()
        hub.ch.close()


def serve(cfg: WebConfig) -> None:
    try:
        asyncio.run(_serve(cfg))
    except SystemExit:  # uvicorn could not bind
        with contextlib.suppress(Exception):
            ch = Channel(cfg.channel)
            ch.state = FAILED
            ch.close()
