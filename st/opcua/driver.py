"""The PLC side of the OPC UA server: starts the server process, samples the published variables,
applies the clients' writes and commands.

An I/O driver (st/runtime/iodriver.py), like the Modbus slave: the clients' writes are applied at
the start of a job, and the published variables are sampled after one, all in one go, when the
fastest subscription's publishing interval has passed in PLC time (so every value of one
sample is from the same scan, stamped with that scan's PLC time). Under `st run` the sample is
taken by `poll()`, between two jobs when there is slack, so it never lengthens a job; without
`poll()` (the API on virtual time) at the end of the job. A write is answered after the job
that applied it, with the written variable's value, without waiting for the next sample.
Commands (Start, Stop, Reset) are applied by `poll()`. Nothing here raises into the scan: a
failure is logged once in the PLC's log.
"""

from __future__ import annotations

import json
import marshal
import operator
import os
import subprocess
import time
from typing import Any

from ..io import server_process
from ..runtime.iodriver import IODriverBase
from ..runtime.lifecycle import FAULT, RUN, STOP
from ..runtime.paths import resolve
from ..runtime.scheduler import Task
from ..runtime.values import to_st_literal
from .channel import FAILED, SERVING, STARTING, Channel
from .symbols import READWRITE, describe, load_map
from .users import load_users

IDLE_SAMPLING_NS = 1_000_000_000  # while no client subscribes: what a Read gets is at most this old
RESULTS_KEPT = 256


class ServerConfig:
    """What the server process needs (pickled to it on stdin)."""

    def __init__(self, **kw: Any):
        self.host: str = kw.get("host", "127.0.0.1")
        self.port: int = kw.get("port", 4840)
        self.channel: str = kw.get("channel", "")
        self.pid: int = kw.get("pid", 0)
        self.name: str = kw.get("name", "st")
        self.anonymous: bool = kw.get("anonymous", False)
        self.users: dict[str, tuple[str, str]] = kw.get("users", {})  # name → (role, password hash)
        self.security: tuple[str, ...] = kw.get("security", ("sign", "encrypt"))
        self.pki: str = kw.get("pki", "")
        self.write_timeout: float = kw.get("write_timeout", 2.0)


class OpcUaServer(IODriverBase):
    """`st run --opcua`: an OPC UA server for `plc` in its own process (asyncua).

    host/port: where to listen (port 0 picks a free one: see `.port`); map_file: the symbol map
    (symbols.py); anonymous: let clients in without a user (role read); users: a users file
    (users.py; `st opcua user` writes one); security: of "none", "sign", "encrypt"
    (Basic256Sha256); pki: the folder of the server's certificate (made on first start) and its
    trust list; name: the application's name in the address space."""

    name = "opcua"

    def __init__(
        self,
        plc: Any,
        host: str = "127.0.0.1",
        port: int = 4840,
        *,
        map_file: str | None = None,
        anonymous: bool = False,
        users: str | None = None,
        security: tuple[str, ...] = ("sign", "encrypt"),
        pki: str | None = None,
        name: str = "st",
        log_path: str | None = None,
    ):
        self.plc = plc
        self.rules = load_map(map_file) if map_file else []
        bad = [s for s in security if s not in ("none", "sign", "encrypt")]
        if bad or not security:
            raise ValueError(f"OPC UA security {','.join(security)!r}: expected none, sign and/or encrypt")
        user_table = load_users(users) if users else {}
        if not anonymous and not user_table:
            raise ValueError(
                "no client could sign in: give --opcua-users FILE (st opcua user adds one) or --opcua-anonymous"
            )
        self.cfg = ServerConfig(
            host=host,
            port=port,
            pid=os.getpid(),
            name=name,
            anonymous=anonymous,
            users=user_table,
            security=tuple(security),
            pki=pki or default_pki(),
        )
        self.log_path = log_path
        self.ch: Channel | None = None
        self.proc: subprocess.Popen[bytes] | None = None
        self.epoch = 0  # wall-clock ns at PLC time 0 (source timestamps)
        self.writes_applied = 0
        self._vars: list[dict] = []
        self._sample: Any = None  # () → the published variables' values, in the description's order
        self._by_path: dict[str, int] = {}  # lower path → index in _vars
        self._number = 0  # documents published
        self._samples = 0  # samples taken (a document that only answers writes repeats the last)
        self._values: list[Any] = []
        self._sample_time = 0
        self._last_sample: int | None = None
        self._scan_time = 0  # the PLC time of the last job
        self._due = False  # a job ran since the last sample
        self._polled = False  # poll() is called between jobs: it samples
        self._cost = 0.0  # the last sample's cost (s)
        self._written: dict[int, Any] = {}  # variables written in this job: index → value
        self._next_wall = 0.0
        self._results: list[tuple[int, int, str, str]] = []  # (seq, request id, status name, text)
        self._seq = 0
        self._commands: list[dict] = []
        self._state_seen = ""
        self._failed = False

    # ------------------------------------------------------------------ life cycle
    def start(self, timeout: float = 30.0) -> OpcUaServer:
        ch = self.ch = Channel(create=True)
        self.cfg.channel = ch.name
        self.epoch = time.time_ns() - self.plc.time
        self.rebind()
        proc = self.proc = server_process.spawn("st.opcua", self.cfg, self.log_path)
        deadline = time.monotonic() + timeout
        while ch.state == STARTING and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        if ch.state != SERVING:
            why = "address in use?" if ch.state == FAILED else "the server did not start"
            self.stop()
            raise OSError(f"the OPC UA server could not listen on {self.cfg.host}:{self.cfg.port} ({why})")
        self.plc.io.append(self)
        self._publish(sample=True)
        return self

    @property
    def port(self) -> int:
        return self.ch.port if self.ch is not None else 0

    @property
    def endpoint(self) -> str:
        host = f"[{self.cfg.host}]" if ":" in self.cfg.host else self.cfg.host
        return f"opc.tcp://{host}:{self.port}/st/"

    def stop(self) -> None:
        if self in self.plc.io:
            self.plc.io.remove(self)
        server_process.stop(self.proc)
        self.proc = None
        if self.ch is not None:
            self.ch.close(unlink=True)
            self.ch = None

    def __enter__(self) -> OpcUaServer:
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def rebind(self) -> None:
        """Describe the running program again (after start, a warm restart or an online change)."""
        if self.ch is None:
            return
        doc = describe(self.plc, self.cfg.name, self.rules)
        self._vars = [n for n in doc["nodes"] if n["kind"] == "var"]
        self._by_path = {n["path"].lower(): k for k, n in enumerate(self._vars)}
        self._sample = _sampler(self.plc, self._vars)
        self.ch.describe(json.dumps(doc, separators=(",", ":")).encode())
        self._last_sample = None
        self._due = True

    # ------------------------------------------------------------------ the job boundary
    def before_job(self, task: Task | None = None) -> None:
        """Apply the clients' writes, oldest first (commands wait for `poll`, between two jobs)."""
        ch = self.ch
        if ch is None or not ch.requests.pending():
            return
        self._drain()

    def after_job(self, task: Task | None = None) -> None:
        """Answer the writes of this job; sample here unless poll() samples between jobs."""
        if self.ch is None:
            return
        self._scan_time = self.plc.time
        self._due = True
        if self._pending_results():
            self._publish(sample=False)
        if not self._polled and self._sample_due():
            self._publish(sample=True)

    def poll(self) -> None:
        """Between two jobs: writes and commands, and the sample when it is due and the next
        release is far enough (at most a second late)."""
        self._polled = True
        try:
            if self.ch is None:
                return
            if self.ch.requests.pending():
                self._drain()
            commands, self._commands = self._commands, []
            for msg in commands:
                self._command(msg)
            now = time.monotonic()
            plc = self.plc
            if commands or plc.state != self._state_seen or (plc.state != RUN and now >= self._next_wall):
                self._scan_time = plc.time
                self._publish(sample=True)
                self._next_wall = now + self._interval() / 1e9
            elif self._pending_results():
                self._publish(sample=False)
            elif self._due and self._sample_due():
                if plc.clock.real and plc.idle_slack < 1.5 * self._cost * 1e9 and now < self._next_wall + 1.0:
                    return  # not now: the next release is too close
                self._publish(sample=True)
                self._next_wall = now + self._interval() / 1e9
        except Exception as e:  # noqa: BLE001 - the server's trouble is never the PLC's end
            self._fail(e)

    def _sample_due(self) -> bool:
        return self._last_sample is None or self._scan_time - self._last_sample >= self._interval()

    def _interval(self) -> int:
        """The fastest publishing interval asked for (asyncua samples a monitored item at its
        subscription's publishing interval, and sends each change: a faster sample would be a second
        notification), or IDLE_SAMPLING_NS while nobody subscribes."""
        us = self.ch.sampling_us if self.ch is not None else 0
        return us * 1000 if us else IDLE_SAMPLING_NS

    def _pending_results(self) -> bool:
        return bool(self._results) and self._results[-1][0] > self._published_seq

    _published_seq = 0

    # ------------------------------------------------------------------ requests
    def _drain(self) -> None:
        assert self.ch is not None
        for raw in self.ch.requests.take():
            try:
                msg = json.loads(raw)
            except ValueError:
                continue
            kind = msg.get("type")
            if kind == "write":
                self._write(msg)
            elif kind == "control":
                self._commands.append(msg)
            elif kind == "note":
                self.plc.log.add(self.plc.time, 0x02, "opcua: " + str(msg.get("text", ""))[:300])

    def _who(self, msg: dict) -> str:
        return f"{msg.get('user') or 'anonymous'} (session {msg.get('session', '?')})"

    def _write(self, msg: dict) -> None:
        path = str(msg.get("path", ""))
        index = self._by_path.get(path.lower())
        if index is None:
            return self._result(msg, "BadNodeIdUnknown", f"{path} is not published")
        node = self._vars[index]
        if node["access"] != READWRITE:
            return self._result(msg, "BadNotWritable", f"{path} is published read-only")
        value = msg.get("value")
        plc = self.plc
        try:
            if node["dims"]:
                items = list(value or ())
                for k, index in enumerate(_flat_indices(node)):
                    plc[f"{path}[{', '.join(map(str, index))}]"] = items[k]
                shown = f"[{len(items)} elements]"
            else:
                plc[path] = value
                shown = to_st_literal(plc.ref(path).get(), plc.ref(path).type)
        except KeyError as e:
            return self._result(msg, "BadNodeIdUnknown", str(e.args[0] if e.args else e))
        except (ValueError, OverflowError) as e:
            text = str(e.args[0] if e.args else e)
            return self._result(msg, "BadOutOfRange" if "outside" in text else "BadTypeMismatch", text)
        except TypeError as e:
            return self._result(msg, "BadTypeMismatch", str(e))
        self.writes_applied += 1
        self._written[index] = _plain(plc.ref(path).get())
        plc.log.add(plc.time, 0x01, f"opcua {self._who(msg)}: write {path} := {shown}")
        self._result(msg, "Good", "")

    def _command(self, msg: dict) -> None:
        plc = self.plc
        action = msg.get("action")
        try:
            if action == "stop":
                if plc.state != STOP:
                    plc.stop()
            elif action == "start":
                if plc.state == FAULT:
                    plc.reset_fault()
                elif plc.state == STOP:
                    plc.start()
            elif action == "reset":
                plc.restart()
            elif action == "reset_cold":
                plc.restart(cold=True)
            else:
                return self._result(msg, "BadMethodInvalid", f"unknown command {action!r}")
        except Exception as e:  # noqa: BLE001 - a refused command is the client's answer
            return self._result(msg, "BadInvalidState", str(e.args[0] if e.args else e))
        plc.log.add(plc.time, 0x01, f"opcua {self._who(msg)}: {action} (now {plc.state})")
        self._result(msg, "Good", "")

    def _result(self, msg: dict, status: str, text: str) -> None:
        self._seq += 1
        self._results.append((self._seq, int(msg.get("id", 0)), status, text))
        del self._results[:-RESULTS_KEPT]

    # ------------------------------------------------------------------ the snapshot
    def _publish(self, sample: bool) -> None:
        """A document for the server: a new sample of every published variable (`sample`), or the
        last sample again with the values written since and the writes' answers."""
        ch = self.ch
        if ch is None:
            return
        plc = self.plc
        t0 = time.perf_counter()
        if sample:
            try:
                self._values = self._sample()
            except Exception as e:  # noqa: BLE001 - a path gone with a reload: describe again
                self._fail(e)
                self.rebind()
                return
            self._samples += 1
            self._sample_time = self._scan_time
            self._written.clear()
        self._number += 1
        fault = plc.fault if plc.state == FAULT else None
        doc = {
            "n": self._number,
            "s": self._samples,
            "v": ch.description_version,
            "t": self._sample_time,
            "tw": self._scan_time,
            "epoch": self.epoch,
            "state": plc.state,
            "fault": str(fault) if fault is not None else "",
            "scans": sum(t.runs for t in plc.tasks),
            "tasks": [_task(t) for t in plc.tasks],
            "values": self._values,
            "written": list(self._written.items()),
            "results": list(self._results),
        }
        try:
            data = marshal.dumps(doc)
        except ValueError:  # a value of an unusual Python type: as plain values
            doc["values"] = self._values = [_plain(v) for v in self._values]
            data = marshal.dumps(doc)
        if not ch.publish(data):
            self._fail(ValueError("the values of one scan do not fit the shared snapshot"))
            return
        self._state_seen = plc.state
        self._published_seq = self._seq
        if sample:
            self._last_sample = self._sample_time
            self._due = False
            self._cost = time.perf_counter() - t0

    def _fail(self, e: Exception) -> None:
        if not self._failed:
            self._failed = True
            self.plc.log.add(self.plc.time, 0x04, f"opcua: {type(e).__name__}: {e} (values may be stale)")


def _sampler(plc: Any, nodes: list[dict]) -> Any:
    """() → the values of `nodes` in their order: one attrgetter/itemgetter per run of variables
    that live in the same container (a program's or block's object, the globals), so a sample of a
    thousand variables is a few dozen C calls."""
    groups: list[tuple[Any, Any, int]] = []  # (container, getter, how many)
    run: list[Any] = []
    where: Any = None
    kind = ""

    def close() -> None:
        if run:
            getter = (operator.attrgetter if kind == "attr" else operator.itemgetter)(*run)
            groups.append((where, getter, len(run)))

    for n in nodes:
        container, key, _t = resolve(plc, n["path"])
        k = "attr" if isinstance(key, str) and not isinstance(container, dict) else "item"
        if container is not where or k != kind:
            close()
            run, where, kind = [], container, k
        run.append(key)
    close()

    arrays = [k for k, n in enumerate(nodes) if n["dims"]]

    def sample() -> list[Any]:
        out: list[Any] = []
        for container, getter, count in groups:
            got = getter(container)
            if count == 1:
                out.append(got)
            else:
                out.extend(got)
        for k in arrays:  # a copy: the program goes on changing its array
            out[k] = list(out[k])
        return out

    return sample


def _plain(v: Any) -> Any:
    """A value as a plain bool, int, float, str or list of them (what marshal takes)."""
    for t in (bool, int, float, str):
        if isinstance(v, t):
            return t(v)
    if isinstance(v, (list, tuple)) or hasattr(v, "__iter__"):
        return [_plain(x) for x in v]
    return v


def _task(t: Any) -> dict:
    s = t.stats
    jobs = s.jobs
    return {
        "name": t.name,
        "jobs": jobs,
        "overruns": s.overruns,
        "latency_max_us": s.lat_max / 1000 if jobs else 0.0,
        "exec_mean_us": s.exec_sum / jobs / 1000 if jobs else 0.0,
        "exec_max_us": s.exec_max / 1000 if jobs else 0.0,
    }


def _flat_indices(node: dict):
    """The ST indices of an array's elements in the order of its flat value (row-major)."""
    los = node.get("lo") or [0] * len(node["dims"])
    idx = [0] * len(node["dims"])
    total = 1
    for d in node["dims"]:
        total *= d
    for _ in range(total):
        yield tuple(lo + i for lo, i in zip(los, idx, strict=True))
        for k in range(len(idx) - 1, -1, -1):
            idx[k] += 1
            if idx[k] < node["dims"][k]:
                break
            idx[k] = 0


def default_pki() -> str:
    """Where the server keeps its certificate and trust list: `$XDG_DATA_HOME/st/opcua`."""
    base = os.environ.get("XDG_DATA_HOME", "")
    root = base if base and os.path.isabs(base) else os.path.join(os.path.expanduser("~"), ".local", "share")
    return os.path.join(root, "st", "opcua")


__all__ = ["OpcUaServer", "ServerConfig", "SERVING"]
