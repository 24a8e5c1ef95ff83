"""The PLC's side of the online mode: the server process, the snapshots it reads, the requests
it sends.

Everything here runs between two jobs (`poll`, from `st run`'s idle hook), never inside one:
requests (subscriptions, writes, forcing, RUN/STOP/reset) take effect at a scan boundary, and
a snapshot is built only while a page is connected, only when the slack before the next
release is larger than the last snapshot took, and at most every `period` seconds.
"""

from __future__ import annotations

import json
import marshal
import os
import subprocess
import time
from itertools import islice
from typing import Any

from ..io import server_process
from ..model import types as T
from ..runtime.lifecycle import FAULT, RUN, STOP
from ..runtime.values import from_st_text, to_st_literal
from .channel import FAILED, SERVING, STARTING, Channel
from .describe import describe, type_text

_PLAIN = (bool, int, float, str)  # what marshal takes as it is (bool before int: a bool is an int)
SAMPLES_KEPT = 5000  # a task's latencies and execution times handed over per snapshot, at most
RESULTS_KEPT = 64  # change results kept in the snapshot (the server forwards each once)
LOG_KEPT = 200


class WebConfig:
    """What the server process needs (pickled to it on stdin)."""

    def __init__(
        self,
        host: str,
        port: int,
        token: str,
        password: str,
        read_only: bool,
        channel: str,
        pid: int,
        names: tuple[str, ...] = (),
        cert: str = "",
        key: str = "",
    ):
        self.host, self.port, self.token, self.password = host, port, token, password
        self.read_only, self.channel, self.pid = read_only, channel, pid
        self.names = names  # --web-host: the names the server answers to besides its address
        self.cert, self.key = cert, key  # --web-cert / --web-key: HTTPS

    @property
    def scheme(self) -> str:
        return "https" if self.cert else "http"


class WebLink:
    def __init__(
        self,
        plc: Any,
        name: str,
        host: str = "127.0.0.1",
        port: int = 8080,
        token: str = "",
        password: str = "",
        read_only: bool = False,
        period: float = 0.1,
        log_path: str | None = None,
        names: tuple[str, ...] = (),
        cert: str = "",
        key: str = "",
    ):
        self.plc, self.name, self.read_only, self.period = plc, name, read_only, period
        self.cfg = WebConfig(host, port, token, password, read_only, "", os.getpid(), names, cert, key)
        self.log_path = log_path
        self.ch: Channel | None = None
        self.proc: subprocess.Popen[bytes] | None = None
        self.paths: list[str] = []  # what the pages watch or view
        self.views: list[str] = []  # POUs whose lines are marked
        self._refs: dict[str, Any] = {}
        self.type_names: dict[str, str] = {}  # path → its type's name (ARRAY element rows have no other)
        self._compiled: Any = None
        self._next = 0.0
        self._cost = 0.0  # the last snapshot's cost (s)
        self._armed_runs: int | None = None  # the jobs counted when the line probes were cleared
        self._results: list[dict] = []
        self._seq = 0
        self._number = 0  # snapshots published
        self._failed = False  # a poll failed (reported once in the PLC's log)
        self._jobs_at: dict[int, dict[str, int]] = {}  # snapshot number → each task's jobs then
        self._last_lines: dict | None = None
        self._instances: Any = None

    # ------------------------------------------------------------------ life cycle
    def start(self, timeout: float = 10.0) -> WebLink:
        ch = self.ch = Channel(create=True)
        self.cfg.channel = ch.name
        for t in self.plc.tasks:  # execution times for the histograms, from now on
            keep = getattr(t.stats, "keep_execs", None)
            if keep is not None:
                keep()
        self._describe()
        proc = self.proc = server_process.spawn("st.web", self.cfg, self.log_path)
        deadline = time.monotonic() + timeout
        while ch.state == STARTING and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        if ch.state != SERVING:
            why = "address in use?" if ch.state == FAILED else "the server did not start"
            self.stop()
            raise OSError(f"the web server could not listen on {self.cfg.host}:{self.cfg.port} ({why})")
        return self

    @property
    def port(self) -> int:
        return self.ch.port if self.ch is not None else 0

    def stop(self) -> None:
        server_process.stop(self.proc)
        self.proc = None
        if self.ch is not None:
            self.ch.close(unlink=True)
            self.ch = None

    # ------------------------------------------------------------------ between two jobs
    def poll(self, force: bool = False) -> None:
        """Apply the pages' requests; publish a snapshot when one is due and there is time. Never
        raises: whatever goes wrong here is the page's problem, not the PLC's (the log says it)."""
        try:
            self._poll(force)
        except Exception as e:  # noqa: BLE001 - the online mode must never stop the scan
            if not self._failed:
                self._failed = True
                self.plc.log.add(self.plc.time, 0x04, f"web: {type(e).__name__}: {e} (snapshots may be missing)")

    def _poll(self, force: bool) -> None:
        ch = self.ch
        if ch is None:
            return
        changed = False
        if ch.requests.pending():
            for raw in ch.requests.take():
                changed |= self._request(raw)
        if self.plc.compiled is not self._compiled:  # an online change: a new program to show
            self._describe()
        if not ch.pages and not force:
            self._armed_runs = None
            return
        now = time.monotonic()
        if now < self._next and not changed and not force:
            return
        if self.plc.clock.real and self.plc.state == RUN and not force:
            if self.plc.idle_slack < 1.5 * self._cost * 1e9 and now < self._next + 1.0:
                return  # not now: the next release is too close (at most a second late)
        hits = self.plc.compiled.coverage_hits
        measured = False
        if hits is not None and self.plc.state == RUN and not force and not changed:
            # the lines of the last scan: clear the probes, publish after the next job
            runs = sum(t.runs for t in self.plc.tasks)
            if self._armed_runs is None:
                hits[:] = bytes(len(hits))
                self._armed_runs = runs
                return
            if runs == self._armed_runs:
                return
            measured = True
        t0 = time.perf_counter()
        if measured:
            self._last_lines = self._lines()
        self._number += 1
        doc = self._snapshot()
        ch.publish(marshal.dumps(doc))
        self._jobs_at[self._number] = {t["name"]: t["jobs"] for t in doc["tasks"]}
        for old in [n for n in self._jobs_at if n < ch.consumed or n <= self._number - 100]:
            del self._jobs_at[old]  # read already (only the newest read one is needed), or long ago
        self._armed_runs = None
        self._cost = time.perf_counter() - t0
        self._next = max(self._next + self.period, now - self.period)  # 10 Hz on average, not drifting

    # ------------------------------------------------------------------ requests
    def _request(self, raw: bytes) -> bool:
        try:
            msg = json.loads(raw)
        except ValueError:
            return False
        kind = msg.get("type")
        if kind == "subscribe":  # the server's union of every page's watch list and view
            self.paths = [str(p) for p in msg.get("paths", [])][:5000]
            self.views = [str(p) for p in msg.get("pous", [])][:64]
            return True
        if kind == "note":  # the server's word for the PLC's log (wrong secrets, refusals)
            self.plc.log.add(self.plc.time, 0x02, str(msg.get("text", ""))[:300])
            return True
        if kind in ("write", "force", "unforce", "control"):
            ok, error = self._change(msg)
            self._seq += 1
            self._results.append(
                {"seq": self._seq, "client": msg.get("client"), "id": msg.get("id"), "ok": ok, "error": error}
            )
            del self._results[:-RESULTS_KEPT]
            return True
        return False

    def _change(self, msg: dict) -> tuple[bool, str]:
        plc = self.plc
        origin = msg.get("origin", "?")
        kind = msg["type"]
        if self.read_only:
            return False, "the online mode is read-only (--web-read-only)"
        try:
            if kind == "control":
                action = msg.get("action")
                if action == "stop":
                    if plc.state != STOP:
                        plc.stop()
                elif action == "start":
                    if plc.state == FAULT:
                        plc.reset_fault()
                    elif plc.state == STOP:
                        plc.start()
                elif action == "reset_warm":
                    plc.restart()
                elif action == "reset_cold":  # retained values too start from their initial values
                    plc.restart(cold=True)
                else:
                    return False, f"unknown action {action!r}"
                what = f"{action} (now {plc.state})"
            else:
                path = str(msg.get("path") or "")
                if kind == "unforce":
                    plc.unforce(path or None)
                    what = f"unforce {path or 'all'}"
                else:
                    ref = plc.ref(path)
                    value = from_st_text(str(msg.get("value", "")), ref.type, path)
                    if kind == "write":
                        plc[path] = value
                    else:
                        plc.force(path, value)
                    what = f"{kind} {path} := {to_st_literal(value, ref.type)}"
        except Exception as e:  # noqa: BLE001 - any refusal is the page's answer, never the PLC's end
            return False, str(e.args[0]) if e.args else type(e).__name__
        plc.log.add(plc.time, 0x01, f"web {origin}: {what}")
        return True, ""

    # ------------------------------------------------------------------ the snapshot
    def _describe(self) -> None:
        self._compiled = self.plc.compiled
        self._refs.clear()
        assert self.ch is not None
        doc = describe(self.plc, self.name, self.read_only)
        self._pou_files = {
            name: (p["file"], p["first_line"], p["first_line"] + len(p["source"]) - 1)
            for name, p in doc["pous"].items()
        }
        self.ch.describe(json.dumps(doc, separators=(",", ":"), default=str).encode())

    def _snapshot(self) -> dict:
        """The state as plain values (marshal): raw variable values, formatted by the server."""
        plc = self.plc
        if plc.instances is not self._instances:  # a restart or an online change: new objects
            self._refs.clear()
            self._instances = plc.instances
        types, values = [], []
        for path in self.paths:
            t, v = self._value(path)
            types.append(t)
            values.append(v)
        type_names = {p: self.type_names[p] for p in self.paths if p in self.type_names}
        fault = plc.fault if plc.state == FAULT else None
        io = io_status(plc)
        log = [(m.time, m.kind, m.text) for m in plc.log.since(max(plc.log.total - LOG_KEPT, 0))]
        return {
            "number": self._number,
            "time_ns": plc.time,
            "state": plc.state,
            "fault": None
            if fault is None
            else {k: getattr(fault, k) for k in ("kind", "message", "file", "line", "pou", "task")},
            "scans": sum(t.runs for t in plc.tasks),
            "tasks": [self._task(t) for t in plc.tasks],
            "paths": list(self.paths),
            "types": types,
            "type_names": type_names,  # each path's declared type, as the page shows it
            "values": values,
            "forced": plc.forced,
            "lines": self._last_lines,  # (measured after one job; the last measure otherwise)
            "axes": io["motion"]["axes"] if "motion" in io else None,
            "ethercat": io.get("ethercat"),
            "modbus": io.get("modbus"),
            "log": log,
            "log_total": plc.log.total,
            "results": list(self._results),
        }

    def _value(self, path: str) -> tuple[str, Any]:
        """(how the server formats it, the value): an elementary type's name and the raw value;
        "#" and (its ordinal, its literal) for an enumeration value; "=" and the text for anything
        else (formatted here); "!" and why for a path that fails."""
        entry = self._refs.get(path)
        try:
            if entry is None:
                ref = self.plc.ref(path)
                bt = T.base_of(ref.type)
                name = getattr(bt, "name", "")
                enum = isinstance(T.unalias(ref.type), T.EnumType)
                elementary = T.ELEMENTARY.get(name) is bt and not enum
                entry = self._refs[path] = (ref, name if elementary else "#" if enum else "=")
                self.type_names[path] = type_text(ref.type)
            ref, kind = entry
            v = ref.get()
        except Exception as e:  # noqa: BLE001 - a path the program does not have (any more)
            self._refs.pop(path, None)
            return "!", str(e.args[0] if e.args else e)
        if kind == "#":
            if isinstance(v, int):
                return kind, (int(v), to_st_literal(v, ref.type))
            return "=", to_st_literal(v, ref.type)
        if kind != "=" and type(v) in _PLAIN:
            return kind, v
        if kind != "=" and isinstance(v, _PLAIN):  # an int subclass (an IntEnum), …: its plain value
            base: Any = next(p for p in _PLAIN if isinstance(v, p))
            return kind, base(v)
        return "=", to_st_literal(v, ref.type)

    def _lines(self) -> dict | None:
        c = self.plc.compiled
        if c.coverage_hits is None or not self.views:
            return None
        hits, points = c.coverage_hits, c.coverage_points
        out: dict[str, list[int]] = {}
        for pou in self.views:
            where = self._pou_files.get(pou)
            if where is None or where[0] is None:
                continue
            file, first, last = where
            out[pou] = sorted(
                {p[1] for k, p in enumerate(points) if hits[k] and p[0] == file and first <= p[1] <= last}
            )
        return out

    def _task(self, t: Any) -> dict:
        """A task's statistics, with its jobs' latencies and execution times since the last
        snapshot the server read (newest first, at most SAMPLES_KEPT; the server bins them)."""
        s = t.stats
        keep = getattr(s, "keep_execs", None)  # (a stand-in for TaskStats may keep none)
        execs = keep() if keep is not None else ()
        read = self._jobs_at.get(self.ch.consumed if self.ch is not None else 0, {})
        new = min(s.jobs - read.get(t.name, 0), len(s.latencies), SAMPLES_KEPT)
        jobs = s.jobs
        return {
            "name": t.name,
            "jobs": jobs,
            "overruns": s.overruns,
            "skipped": s.skipped,
            "latency_ns": {
                "min": s.lat_min if jobs else 0,
                "mean": s.lat_sum / jobs if jobs else 0,
                "max": s.lat_max,
                "last": s.latencies[-1] if s.latencies else 0,
            },
            "exec_ns": {
                "min": s.exec_min if jobs else 0,
                "mean": s.exec_sum / jobs if jobs else 0,
                "max": s.exec_max,
                "last": s.last_exec,
            },
            "mk": {"m": s.m, "k": s.k, "met": s.utility >= s.m / s.k, "utility": round(s.utility, 4)},
            "new_latency": list(islice(reversed(s.latencies), new)),
            "new_exec": list(islice(reversed(execs), min(new, len(execs)))),
        }


def io_status(plc: Any) -> dict[str, dict]:
    """Each named I/O driver's `status()` by its name (the first driver of a name; a driver with
    nothing to show is left out): "motion" (the axes), "ethercat", "modbus", …"""
    out: dict[str, dict] = {}
    for d in plc.io:
        if d.name and d.name not in out:
            s = d.status()
            if s is not None:
                out[d.name] = s
    return out
