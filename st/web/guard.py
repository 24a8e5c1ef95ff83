"""What the web server checks before it trusts a request: the Host it was sent to, the Origin of a
page that posts or opens the WebSocket, and how fast anyone may try secrets.

- **Host.** A request must name this server: the address it is bound to, a loopback name when it
  is bound to loopback, an IP address when it listens on every interface, or a name given with
  `--web-host`; with the bound port. A page on another name that resolves here (DNS rebinding:
  `evil.example` pointed at 127.0.0.1) is refused, cookie or not.
- **Origin.** A form post (/login) and the WebSocket must come from a page of this server: same
  scheme, host and port. A request without Origin is no browser's and passes (browsers always
  send it on these).
- **Secrets.** Every check of a token or password goes through one `Limiter`: after the n-th
  wrong secret in a row a client waits `base · 2^(n-1)` seconds (at most `cap`) before its next
  one is even looked at, and when more than `global_max` wrong secrets came in the last `window`
  seconds from anyone, every secret is refused until the window has room again. Each wrong
  secret and each refusal is reported through `log`.
"""

from __future__ import annotations

import asyncio
import ipaddress
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from urllib.parse import urlsplit

LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")


def split_host(value: str) -> tuple[str, int | None]:
    """'name:port' / '[v6]:port' / 'name' → (lower-case host, port or None)."""
    value = value.strip().lower()
    if value.startswith("["):
        host, _, rest = value[1:].partition("]")
        port = rest[1:] if rest.startswith(":") else ""
    else:
        host, _, port = value.rpartition(":") if value.count(":") == 1 else (value, "", "")
    try:
        return host, int(port) if port else None
    except ValueError:
        return host, -1


def _is_ip(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        return False


def _loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass
class Site:
    """Where the server is reached: the address it is bound to, its port, its scheme, and the extra
    names (--web-host) it answers to."""

    bound: str
    port: int
    scheme: str = "http"
    names: tuple[str, ...] = ()

    def host_ok(self, header: str | None) -> bool:
        """Does a request's Host header name this server?"""
        if not header:
            return False
        host, port = split_host(header)
        default = 443 if self.scheme == "https" else 80
        if (port if port is not None else default) != self.port:
            return False
        if host in (n.lower() for n in self.names):
            return True
        bound = self.bound.lower()
        if bound in ("0.0.0.0", "::", ""):
            return _is_ip(host) or host == "localhost"  # any of this machine's addresses, no other name
        if _loopback(bound):
            return _loopback(host)
        return host == bound

    def origin_ok(self, origin: str | None, host_header: str | None) -> bool:
        """Is `origin` a page of this server, as the (checked) Host header names it?"""
        if origin is None:
            return True  # not a browser
        if origin == "null" or not host_header:
            return False
        o = urlsplit(origin)
        if o.scheme != self.scheme:
            return False
        return split_host(o.netloc) == _with_port(split_host(host_header), self.scheme)


def _with_port(hp: tuple[str, int | None], scheme: str) -> tuple[str, int | None]:
    host, port = hp
    default = 443 if scheme == "https" else 80
    return host, None if port == default else port


@dataclass
class _Client:
    failures: int = 0
    not_before: float = 0.0
    lock: asyncio.Lock = field(default_factory=asyncio.Lock)


class Limiter:
    """One gate for every presented secret (see the module doc)."""

    def __init__(
        self,
        base: float = 0.5,
        cap: float = 60.0,
        window: float = 60.0,
        global_max: int = 30,
        log: Callable[[str], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.base, self.cap, self.window, self.global_max = base, cap, window, global_max
        self.log = log or (lambda _text: None)
        self.clock = clock
        self.clients: dict[str, _Client] = {}
        self.recent: deque[float] = deque()  # times of the wrong secrets in the window

    def _room(self) -> bool:
        now = self.clock()
        while self.recent and self.recent[0] <= now - self.window:
            self.recent.popleft()
        return len(self.recent) < self.global_max

    def delay(self, client: str) -> float:
        """How long `client` must wait before its next secret is looked at."""
        c = self.clients.get(client)
        return max(0.0, c.not_before - self.clock()) if c is not None else 0.0

    async def check(self, client: str, secret_ok: Callable[[], bool], what: str) -> bool | None:
        """True / False: the secret is right / wrong; None: not looked at (too many wrong secrets
        from anyone lately). A client with wrong secrets behind it waits its back-off first."""
        if not self._room():
            self.log(f"web: {what} from {client} refused: {self.global_max} wrong secrets in {self.window:g} s")
            return None
        c = self.clients.setdefault(client, _Client())
        async with c.lock:  # one attempt of a client at a time: parallel guesses queue behind the back-off
            wait = c.not_before - self.clock()
            if wait > 0:
                await asyncio.sleep(wait)
            if not self._room():
                return None
            if secret_ok():
                self.clients.pop(client, None)
                return True
            c.failures += 1
            back_off = min(self.base * 2 ** (c.failures - 1), self.cap)
            c.not_before = self.clock() + back_off
            self.recent.append(self.clock())
            self.log(
                f"web: wrong {what} from {client} ({c.failures} in a row; the next is looked at in {back_off:g} s)"
            )
            return False
