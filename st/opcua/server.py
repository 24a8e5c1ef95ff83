"""The OPC UA server process (`python -m st.opcua`): asyncua serving the PLC's address space.

It builds the address space from the description the PLC wrote (symbols.py), copies each new
snapshot's changed values into the nodes (source timestamp: the PLC time of the scan they are
from), tells the PLC the fastest sampling interval its clients asked for, and turns the clients'
writes and method calls into requests the PLC applies at a scan boundary, answering each with
the status the PLC gave (or the check that refused it here: role, access, type, range).

Security: Basic256Sha256 Sign and SignAndEncrypt with a certificate made on the first start in
the PKI folder; a client's certificate must be in `trusted/` (an unknown one is saved to
`rejected/`, to be moved by whoever administers the PLC); users from the users file, anonymous
only when asked. This process never touches the PLC's objects: only the shared memory.
"""

from __future__ import annotations

import asyncio
import contextvars
import json
import logging
import marshal
import os
import socket
import sys
import time
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

from asyncua import Server, ua
from asyncua.common.utils import ServiceError
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import SimpleRoleRuleset, User, UserRole
from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
from asyncua.server.internal_session import InternalSession
from asyncua.server.monitored_item_service import MonitoredItemValues
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.x509.oid import ExtendedKeyUsageOID

from .channel import FAILED, SERVING, Channel
from .driver import ServerConfig
from .users import verify_password

POLL_S = 0.005
YIELD_EVERY = 200  # nodes written between two chances for the clients' requests
_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)
_VTYPE = {
    "Boolean": ua.VariantType.Boolean,
    "SByte": ua.VariantType.SByte,
    "Byte": ua.VariantType.Byte,
    "Int16": ua.VariantType.Int16,
    "UInt16": ua.VariantType.UInt16,
    "Int32": ua.VariantType.Int32,
    "UInt32": ua.VariantType.UInt32,
    "Int64": ua.VariantType.Int64,
    "UInt64": ua.VariantType.UInt64,
    "Float": ua.VariantType.Float,
    "Double": ua.VariantType.Double,
    "String": ua.VariantType.String,
    "Duration": ua.VariantType.Double,
    "DateTime": ua.VariantType.DateTime,
}
_INTS = {"SByte", "Byte", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64"}
_SESSION: contextvars.ContextVar[Any] = contextvars.ContextVar("st_opcua_session", default=None)
ROLE_WRITE = ("operate", "engineer")
_ADMIN = User(role=UserRole.Admin)  # asyncua's default for a write without a session


def _remember_session(method: Any) -> Any:
    """InternalSession's write/call, with the calling session kept for the handlers (asyncua gives
    a write handler the user but not the session, and a method handler neither)."""

    async def wrapped(self: Any, params: Any) -> Any:
        token = _SESSION.set(self)
        try:
            return await method(self, params)
        finally:
            _SESSION.reset(token)

    return wrapped


InternalSession.write = _remember_session(InternalSession.write)  # type: ignore[method-assign]

# asyncua deep-copies every value it hands to a monitored item (a guard against a caller that
# changes the value afterwards): a few hundred µs per node when a thousand change in one sample.
# The values this bridge writes are made for the write and never changed, so they are kept as
# they are; every other write still gets its copy.
_OWN_VALUE: contextvars.ContextVar[bool] = contextvars.ContextVar("st_opcua_own_value", default=False)
_copying_set = MonitoredItemValues.set_current_datavalue


def _set_current_datavalue(self: Any, cur_val: ua.DataValue) -> None:
    if _OWN_VALUE.get():
        self.old_dvalue = self.current_dvalue
        self.current_dvalue = cur_val
    else:
        _copying_set(self, cur_val)


MonitoredItemValues.set_current_datavalue = _set_current_datavalue  # type: ignore[method-assign]
InternalSession.call = _remember_session(InternalSession.call)  # type: ignore[method-assign]


class Users:
    """asyncua's user manager over the users file: every user is asyncua's `User` role (st's role,
    read/operate/engineer, is looked up by name), refused sign-ins are told to the PLC's log."""

    def __init__(self, cfg: ServerConfig, note: Any):
        self.cfg, self.note = cfg, note

    def get_user(self, iserver: Any, username: str | None = None, password: str | None = None, certificate: Any = None):
        if not username:
            return User(role=UserRole.User, name=None) if self.cfg.anonymous else None
        entry = self.cfg.users.get(username)
        if entry is None or not verify_password(password or "", entry[1]):
            self.note(f"sign-in refused for user {username!r}")
            return None
        return User(role=UserRole.User, name=username)

    def role(self, user: Any) -> str:
        name = getattr(user, "name", None)
        if not name:
            return "read" if self.cfg.anonymous else ""
        entry = self.cfg.users.get(name)
        return entry[0] if entry else ""


class TrustList:
    """Client certificates: trusted when a copy of the very certificate is in `trusted/`; an unknown
    one is written to `rejected/` (moving it to `trusted/` trusts it, no restart needed)."""

    def __init__(self, pki: Path, note: Any):
        self.trusted, self.rejected, self.note = pki / "trusted", pki / "rejected", note
        self.trusted.mkdir(parents=True, exist_ok=True)
        self.rejected.mkdir(parents=True, exist_ok=True)
        self.basic = CertificateValidator(
            CertificateValidatorOptions.TIME_RANGE | CertificateValidatorOptions.PEER_CLIENT
        )

    def _known(self) -> set[bytes]:
        out = set()
        for p in self.trusted.iterdir():
            try:
                data = p.read_bytes()
                cert = (
                    x509.load_pem_x509_certificate(data)
                    if data.startswith(b"-----")
                    else x509.load_der_x509_certificate(data)
                )
                out.add(cert.fingerprint(hashes.SHA256()))
            except (OSError, ValueError):
                continue
        return out

    async def __call__(self, cert: x509.Certificate, app: ua.ApplicationDescription) -> None:
        await self.basic.validate(cert, app)
        fp = cert.fingerprint(hashes.SHA256())
        if fp in self._known():
            return
        name = "".join(c if c.isalnum() or c in "-_." else "_" for c in (app.ApplicationName.Text or "client"))
        path = self.rejected / f"{name}-{fp.hex()[:16]}.der"
        if not path.exists():
            path.write_bytes(cert.public_bytes(serialization.Encoding.DER))
            self.note(f"client certificate of {app.ApplicationName.Text!r} refused (untrusted), saved to {path}")
        raise ServiceError(ua.StatusCodes.BadCertificateUntrusted)


class Bridge:
    """The address space and its traffic with the PLC."""

    def __init__(self, cfg: ServerConfig, ch: Channel):
        self.cfg, self.ch = cfg, ch
        self.server: Server | None = None
        self.idx = 2
        self.users = Users(cfg, self.note)
        self.vars: list[dict] = []
        self.node_ids: list[ua.NodeId] = []
        self.by_node: dict[ua.NodeId, dict] = {}
        self.last: list[Any] = []
        self.version = -1
        self.number = 0  # the last document read
        self.sample = 0  # the last sample applied
        self.results_seen = 0
        self.waiting: dict[int, asyncio.Future] = {}
        self.next_id = 0
        self.nodes: dict[str, dict] = {}  # the description's nodes by id, as built
        self.made: dict[str, Any] = {}  # … and their asyncua nodes
        self.status: dict[str, Any] = {}
        self.task_nodes: dict[str, dict[str, Any]] = {}
        self.tasks_folder: Any = None

    def note(self, text: str) -> None:
        self.ch.requests.put(json.dumps({"type": "note", "text": text}).encode())

    # ------------------------------------------------------------------ start-up
    async def start(self) -> None:
        cfg = self.cfg
        server = self.server = Server(user_manager=self.users)  # type: ignore[arg-type]
        await server.init()
        host = cfg.host or "0.0.0.0"
        server.set_endpoint(f"opc.tcp://{'[' + host + ']' if ':' in host else host}:{cfg.port}/st/")
        server.set_server_name(f"st soft PLC ({cfg.name})")
        uri = f"urn:st:plc:{socket.gethostname()}"
        await server.set_application_uri(uri)
        policies = []
        if "none" in cfg.security:
            policies.append(ua.SecurityPolicyType.NoSecurity)
        if "sign" in cfg.security:
            policies.append(ua.SecurityPolicyType.Basic256Sha256_Sign)
        if "encrypt" in cfg.security:
            policies.append(ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt)
        server.set_security_policy(policies, permission_ruleset=SimpleRoleRuleset())
        server.set_identity_tokens([ua.UserNameIdentityToken] + ([ua.AnonymousIdentityToken] if cfg.anonymous else []))
        pki = Path(cfg.pki)
        own = pki / "own"
        own.mkdir(parents=True, exist_ok=True)
        key, cert = own / "key.pem", own / "cert.der"
        await setup_self_signed_certificate(
            key,
            cert,
            uri,
            socket.gethostname(),
            [ExtendedKeyUsageOID.CLIENT_AUTH, ExtendedKeyUsageOID.SERVER_AUTH],
            {"countryName": "XX", "organizationName": "st", "commonName": f"st PLC {cfg.name}"},
        )
        os.chmod(key, 0o600)
        await server.load_certificate(str(cert))
        await server.load_private_key(str(key))
        server.set_certificate_validator(TrustList(pki, self.note))  # type: ignore[arg-type]
        self.idx = await server.register_namespace(f"urn:st:{cfg.name}")
        service = server.iserver.attribute_service
        original = service.write

        async def write(params: ua.WriteParameters, user: User = _ADMIN) -> list[ua.StatusCode]:
            return await self.write(params, user, original)

        service.write = write  # type: ignore[method-assign]
        await self._plc_object()
        await self._build()
        await server.start()

    async def _plc_object(self) -> None:
        assert self.server is not None
        objects = self.server.nodes.objects
        idx = self.idx
        plc = await objects.add_object(ua.NodeId("PLC", idx), ua.QualifiedName("PLC", idx))
        for name, vt, value in (
            ("State", ua.VariantType.String, ""),
            ("Fault", ua.VariantType.String, ""),
            ("Scans", ua.VariantType.UInt64, 0),
            ("PlcTime", ua.VariantType.Double, 0.0),
        ):
            node = await plc.add_variable(
                ua.NodeId(f"PLC.{name}", idx), ua.QualifiedName(name, idx), ua.Variant(value, vt)
            )
            self.status[name] = node
        await self._describe(self.status["PlcTime"], "the PLC time of the latest values, ms since the run started")
        self.tasks_folder = await plc.add_folder(ua.NodeId("PLC.Tasks", idx), ua.QualifiedName("Tasks", idx))
        for action, what in (
            ("Start", "RUN from STOP, or from FAULT (the fault reset)"),
            ("Stop", "STOP: no task runs, outputs at their safe values"),
            ("Reset", "a warm restart: fresh instances, retained values kept"),
        ):
            method = await plc.add_method(
                ua.NodeId(f"PLC.{action}", idx), ua.QualifiedName(action, idx), self._method(action.lower()), [], []
            )
            await self._describe(method, what)

    def _method(self, action: str) -> Any:
        async def call(parent: ua.NodeId) -> ua.StatusCode:
            session = _SESSION.get()
            user = getattr(session, "user", None)
            if self.users.role(user) != "engineer":
                return ua.StatusCode(ua.StatusCodes.BadUserAccessDenied)
            return await self._request({"type": "control", "action": action}, session)

        return call

    @staticmethod
    async def _describe(node: Any, text: str) -> None:
        if text:
            await node.write_attribute(ua.AttributeIds.Description, ua.DataValue(ua.Variant(ua.LocalizedText(text))))

    # ------------------------------------------------------------------ the address space
    async def _build(self) -> None:
        """Bring the program's nodes in line with the PLC's description: after an online change only
        the nodes that changed are removed and made again, so the clients' monitored items on the
        others carry on."""
        assert self.server is not None
        raw = self.ch.description()
        if not raw:
            return
        self.version = self.ch.description_version
        doc = json.loads(raw)
        new = {n["id"]: n for n in doc["nodes"]}
        changed = {i for i, n in self.nodes.items() if new.get(i) != n}
        # a changed object takes its descendants with it
        for n in doc["nodes"]:
            if n["parent"] in changed and n["id"] in self.nodes:
                changed.add(n["id"])
        gone = [self.made[i] for i in reversed(list(self.nodes)) if i in changed]
        if gone:
            await self.server.delete_nodes(gone)
        for i in changed:
            self.made.pop(i, None)
        last = {n["id"]: v for n, v in zip(self.vars, self.last, strict=True)}
        idx = self.idx
        objects = self.server.nodes.objects
        self.vars, self.node_ids, self.by_node, self.last = [], [], {}, []
        for n in doc["nodes"]:
            nid = ua.NodeId(n["id"], idx)
            if n["id"] not in self.made:
                parent = self.made.get(n["parent"], objects)
                qn = ua.QualifiedName(n["name"], idx)
                if n["kind"] == "folder":
                    node = await parent.add_folder(nid, qn)
                elif n["kind"] == "object":
                    node = await parent.add_object(nid, qn)
                else:
                    node = await self._variable(parent, nid, qn, n)
                self.made[n["id"]] = node
                await self._describe(node, n.get("desc", ""))
            if n["kind"] == "var":
                self.vars.append(n)
                self.node_ids.append(nid)
                self.by_node[nid] = n
                self.last.append(last.get(n["id"]))
        self.nodes = new

    async def _variable(self, parent: Any, nid: ua.NodeId, qn: ua.QualifiedName, n: dict) -> Any:
        vt = _VTYPE[n["ua"]]
        dims = n.get("dims")
        initial: Any = _zero(n)
        if dims:
            total = 1
            for d in dims:
                total *= d
            initial = [initial] * total
        datatype = ua.NodeId(ua.ObjectIds.Duration) if n["ua"] == "Duration" else None
        node = await parent.add_variable(
            nid, qn, ua.Variant(initial, vt, Dimensions=dims if dims and len(dims) > 1 else None), vt, datatype
        )
        if dims:
            await node.write_attribute(
                ua.AttributeIds.ValueRank, ua.DataValue(ua.Variant(len(dims), ua.VariantType.Int32))
            )
            await node.write_attribute(
                ua.AttributeIds.ArrayDimensions, ua.DataValue(ua.Variant(list(dims), ua.VariantType.UInt32))
            )
        # no value before the PLC's first sample of it (a new variable after an online change, every
        # variable at start): a client reading it meanwhile gets this status, never a made-up zero
        await node.write_attribute(
            ua.AttributeIds.Value,
            ua.DataValue(
                ua.Variant(initial, vt, Dimensions=dims if dims and len(dims) > 1 else None),
                StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData),
            ),
        )
        if n["access"] == "readwrite":
            await node.set_writable()
        if n.get("enum"):
            values = n["enum"]
            if [v for v, _ in values] == list(range(len(values))):
                await node.add_property(
                    ua.NodeId(n["id"] + ".EnumStrings", self.idx),
                    ua.QualifiedName("EnumStrings", 0),
                    ua.Variant([ua.LocalizedText(name) for _, name in values], ua.VariantType.LocalizedText),
                )
            else:
                await node.add_property(
                    ua.NodeId(n["id"] + ".EnumValues", self.idx),
                    ua.QualifiedName("EnumValues", 0),
                    ua.Variant(
                        [ua.EnumValueType(Value=v, DisplayName=ua.LocalizedText(name)) for v, name in values],
                        ua.VariantType.ExtensionObject,
                    ),
                )
        return node

    # ------------------------------------------------------------------ values from the PLC
    async def pump(self) -> None:
        """Copy each new snapshot into the nodes; tell the PLC the sampling interval wanted."""
        assert self.server is not None
        if self.ch.description_version != self.version:
            await self._build()
        self.ch.sampling_us = self._sampling_us()
        raw = self.ch.latest()
        if not raw:
            return
        doc = marshal.loads(raw)
        if doc["n"] == self.number:
            return
        self.number = doc["n"]
        if doc["v"] == self.version:
            token = _OWN_VALUE.set(True)
            try:
                if doc["s"] != self.sample:
                    self.sample = doc["s"]
                    await self._values(enumerate(doc["values"]), doc["epoch"] + doc["t"])
                await self._values(doc["written"], doc["epoch"] + doc["tw"])
            finally:
                _OWN_VALUE.reset(token)
        await self._status(doc)
        for seq, rid, status, text in doc["results"]:
            if seq <= self.results_seen:
                continue
            self.results_seen = seq
            fut = self.waiting.pop(rid, None)
            if fut is not None and not fut.done():
                fut.set_result((status, text))

    async def _values(self, values: Any, wall_ns: int) -> None:
        """The values that changed into their nodes, stamped with the PLC time of their scan; the
        loop lets requests in every YIELD_EVERY nodes."""
        assert self.server is not None
        source = datetime.fromtimestamp(wall_ns / 1e9, UTC)
        now = datetime.now(UTC)
        last, nodes, ids, write = self.last, self.vars, self.node_ids, self.server.write_attribute_value
        done = 0
        for k, value in values:
            old = last[k]
            if value == old and type(value) is type(old):
                continue
            last[k] = value
            await write(ids[k], ua.DataValue(_variant(nodes[k], value), SourceTimestamp=source, ServerTimestamp=now))
            done += 1
            if done % YIELD_EVERY == 0:
                await asyncio.sleep(0)

    async def _status(self, doc: dict) -> None:
        assert self.server is not None
        for name, value, vt in (
            ("State", doc["state"], ua.VariantType.String),
            ("Fault", doc["fault"], ua.VariantType.String),
            ("Scans", doc["scans"], ua.VariantType.UInt64),
            ("PlcTime", doc["t"] / 1e6, ua.VariantType.Double),
        ):
            await self.server.write_attribute_value(self.status[name].nodeid, ua.DataValue(ua.Variant(value, vt)))
        for t in doc["tasks"]:
            nodes = self.task_nodes.get(t["name"])
            if nodes is None:
                nodes = self.task_nodes[t["name"]] = await self._task_nodes(t)
            for key, node in nodes.items():
                vt = ua.VariantType.UInt64 if key in ("jobs", "overruns") else ua.VariantType.Double
                await self.server.write_attribute_value(node.nodeid, ua.DataValue(ua.Variant(t[key], vt)))

    async def _task_nodes(self, t: dict) -> dict[str, Any]:
        idx = self.idx
        name = t["name"]
        obj = await self.tasks_folder.add_object(ua.NodeId(f"PLC.Tasks.{name}", idx), ua.QualifiedName(name, idx))
        out = {}
        for key, label in (
            ("jobs", "Jobs"),
            ("overruns", "Overruns"),
            ("latency_max_us", "LatencyMaxUs"),
            ("exec_mean_us", "ExecMeanUs"),
            ("exec_max_us", "ExecMaxUs"),
        ):
            vt = ua.VariantType.UInt64 if key in ("jobs", "overruns") else ua.VariantType.Double
            out[key] = await obj.add_variable(
                ua.NodeId(f"PLC.Tasks.{name}.{label}", idx), ua.QualifiedName(label, idx), ua.Variant(t[key], vt)
            )
        return out

    def _sampling_us(self) -> int:
        assert self.server is not None
        subs = self.server.iserver.subscription_service.subscriptions.values()
        intervals = [s.data.RevisedPublishingInterval for s in subs if s.data.RevisedPublishingInterval]
        return int(min(intervals) * 1000) if intervals else 0

    # ------------------------------------------------------------------ writes and commands
    async def write(self, params: ua.WriteParameters, user: User, original: Any) -> list[ua.StatusCode]:
        out: list[ua.StatusCode] = []
        session = _SESSION.get()
        external = getattr(session, "external", False)  # (the server's own writes are not a client's)
        for wv in params.NodesToWrite:
            n = self.by_node.get(wv.NodeId) if external else None
            if n is None:
                out.extend(await original(ua.WriteParameters(NodesToWrite=[wv]), user=user))
                continue
            out.append(await self._write_one(n, wv, user, session))
        return out

    async def _write_one(self, n: dict, wv: ua.WriteValue, user: User, session: Any) -> ua.StatusCode:
        if wv.AttributeId != ua.AttributeIds.Value:
            return ua.StatusCode(ua.StatusCodes.BadUserAccessDenied)
        if self.users.role(user) not in ROLE_WRITE:
            return ua.StatusCode(ua.StatusCodes.BadUserAccessDenied)
        if n["access"] != "readwrite":
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        if wv.IndexRange:
            return ua.StatusCode(ua.StatusCodes.BadWriteNotSupported)
        variant = wv.Value.Value if wv.Value is not None else None
        if variant is None or variant.VariantType != _VTYPE[n["ua"]]:
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        try:
            value = _from_ua(n, variant.Value)
        except TypeError:
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        except ValueError:
            return ua.StatusCode(ua.StatusCodes.BadOutOfRange)
        return await self._request({"type": "write", "path": n["path"], "value": value}, session)

    async def _request(self, msg: dict, session: Any) -> ua.StatusCode:
        self.next_id += 1
        rid = self.next_id
        user = getattr(getattr(session, "user", None), "name", None)
        sid = getattr(session, "session_id", None)
        shown = sid.to_string() if isinstance(sid, ua.NodeId) else "?"
        peer = getattr(session, "name", None)  # asyncua names a session after its peer's address
        if isinstance(peer, tuple) and len(peer) >= 2:
            shown += f" from {peer[0]}:{peer[1]}"
        elif peer:
            shown += f" {peer}"
        msg.update(id=rid, user=user or "anonymous", session=shown)
        fut = asyncio.get_running_loop().create_future()
        self.waiting[rid] = fut
        if not self.ch.requests.put(json.dumps(msg).encode()):
            self.waiting.pop(rid, None)
            return ua.StatusCode(ua.StatusCodes.BadResourceUnavailable)
        try:
            status, _text = await asyncio.wait_for(fut, self.cfg.write_timeout)
        except TimeoutError:
            self.waiting.pop(rid, None)
            return ua.StatusCode(ua.StatusCodes.BadTimeout)
        return ua.StatusCode(getattr(ua.StatusCodes, status, ua.StatusCodes.BadUnexpectedError))


def _zero(n: dict) -> Any:
    ua_name = n["ua"]
    if ua_name == "Boolean":
        return False
    if ua_name in ("Float", "Double", "Duration"):
        return 0.0
    if ua_name == "String":
        return ""
    if ua_name == "DateTime":
        return _EPOCH
    return 0


def _variant(n: dict, value: Any) -> ua.Variant:
    vt = _VTYPE[n["ua"]]
    conv = _to_ua(n)
    dims = n.get("dims")
    if dims:
        return ua.Variant([conv(x) for x in value], vt, Dimensions=dims if len(dims) > 1 else None)
    return ua.Variant(conv(value), vt)


def _to_ua(n: dict) -> Any:
    if n["ua"] == "Duration":
        return lambda ns: ns / 1e6
    if n["ua"] == "DateTime":
        return lambda ns: datetime.fromtimestamp(ns / 1e9, UTC)
    return lambda v: v


def _from_ua(n: dict, value: Any) -> Any:
    """A client's value as the PLC's (TIME ns, DT ns since 1970, …); ValueError when out of range,
    TypeError when the shape is wrong."""
    dims = n.get("dims")
    if dims:
        if not isinstance(value, list):
            raise TypeError("an array expected")
        total = 1
        for d in dims:
            total *= d
        if len(value) != total:
            raise TypeError(f"{total} elements expected")
        return [_one(n, v) for v in value]
    return _one(n, value)


def _one(n: dict, value: Any) -> Any:
    kind = n["ua"]
    if kind == "Duration":
        if value != value:
            raise ValueError("NaN")
        out = round(value * 1e6)
        if not -(1 << 63) <= out < 1 << 63:
            raise ValueError("outside TIME")
        return out
    if kind == "DateTime":
        if value.tzinfo is None:
            value = value.replace(tzinfo=UTC)
        return (value - _EPOCH) // timedelta(microseconds=1) * 1000
    if kind == "String" and len(value) > n.get("length", 1 << 30):
        raise ValueError("longer than the STRING")
    if n.get("enum") is not None and value not in {v for v, _ in n["enum"]}:
        raise ValueError("not a value of the enumeration")
    if kind in _INTS and "range" in n:
        lo, hi = n["range"]
        if not lo <= value <= hi:
            raise ValueError("outside the type's range")
    return value


async def _watch_parent(pid: int) -> None:
    while True:
        await asyncio.sleep(0.5)
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            os._exit(0)
        except PermissionError:
            pass


async def _main(cfg: ServerConfig) -> None:
    ch = Channel(cfg.channel)
    bridge = Bridge(cfg, ch)
    try:
        await bridge.start()
    except OSError as e:
        print(f"st opcua: cannot listen on {cfg.host}:{cfg.port}: {e}", file=sys.stderr)
        ch.state = FAILED
        ch.close()
        return
    assert bridge.server is not None and bridge.server.bserver is not None
    ch.port = bridge.server.bserver.port
    ch.state = SERVING
    asyncio.get_running_loop().create_task(_watch_parent(cfg.pid))
    while True:
        t0 = time.monotonic()
        try:
            await bridge.pump()
        except Exception as e:  # noqa: BLE001 - the server goes on; the PLC's log says it once
            logging.getLogger("st.opcua").exception("pump")
            bridge.note(f"server: {type(e).__name__}: {e}")
        await asyncio.sleep(max(0.0, POLL_S - (time.monotonic() - t0)))


def serve(cfg: ServerConfig) -> None:
    logging.basicConfig(level=logging.WARNING, format="st opcua: %(message)s")
    for name in ("asyncua", "asyncua.server.address_space", "asyncua.server.uaprocessor"):
        logging.getLogger(name).setLevel(logging.ERROR)
    try:
        asyncio.run(_main(cfg))
    except KeyboardInterrupt:
        pass
