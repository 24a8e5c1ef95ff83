"""The PLC: program instances of a configuration, tasks on a tick, the clock, variable access.

This is the runtime's first stage: tasks run cyclically in declaration order
on a base tick (the GCD of the task intervals), as OpenPLC v3 does, on virtual
time (`scan`, `advance`) or paced by the real clock (`run_realtime`). The PLC
clock that timers read is the scan's release time, so a run is deterministic
whether it is paced or not.
"""
from __future__ import annotations

import math
import re
import time as _time
from dataclasses import dataclass
from typing import Optional

from ..compiler import types as T
from ..compiler.driver import CompiledProgram
from .faults import FaultInfo, fault_from_exception
from .namespace import build_namespace
from .watchdog import Watchdog
from .values import ValueError_, from_python, parse_duration_arg, to_json, to_python

DEFAULT_CYCLE = 10_000_000
_PATH_TOKEN = re.compile(r"\s*(?:([A-Za-z_][A-Za-z0-9_]*)|\.([A-Za-z_][A-Za-z0-9_]*|[0-9]+)|\[([^\]]*)\])")
_ADDR = re.compile(r"%([IQM])([XBWDL]?)([0-9]+(?:\.[0-9]+)*)$", re.I)


class PLCFaultError(RuntimeError):
    """A scan ended in a PLC fault; `.fault` says where and why."""

    def __init__(self, fault: FaultInfo):
        super().__init__(str(fault))
        self.fault = fault


@dataclass
class Task:
    name: str
    interval: int               # ns (0: event task)
    priority: int
    instances: list             # [(name, object, InstanceModel)]
    single: str = ""
    prev_single: bool = False
    runs: int = 0
    calls: list = None          # [(name, object, copy-in fn, copy-out fn)]


class PLC:
    """A running PLC for one compiled program (its first CONFIGURATION)."""

    def __init__(self, compiled: CompiledProgram, cycle=None, *, watchdog=None):
        self.compiled = compiled
        self.project = compiled.project
        def install(ns):
            self._wd = Watchdog(ns)
        ns = self.ns = build_namespace(compiled, install)
        self.state = "RUN"
        self.fault: Optional[FaultInfo] = None
        self._time = 0
        self.scans = 0
        cfg = self.project.configs[0] if self.project.configs else None
        self.config = cfg
        self.instances: dict = {}           # lower name → (display name, object, POUType)
        self.tasks: list[Task] = []
        cyc = parse_duration_arg(cycle) if cycle is not None else None
        if cfg is not None:
            for tm in cfg.tasks:
                interval = tm.interval
                if cfg.implicit or (interval == 0 and not tm.single):
                    interval = cyc or DEFAULT_CYCLE
                self.tasks.append(Task(tm.name, interval, tm.priority, [], tm.single))
            by_task = {t.name.lower(): t for t in self.tasks}
            for im in cfg.instances:
                obj = ns[im.type.pyname]()
                self.instances[im.name.lower()] = (im.name, obj, im.type)
                task = by_task.get(im.task.lower()) if im.task else None
                if task is None:
                    if not self.tasks:
                        self.tasks.append(Task("main", cyc or DEFAULT_CYCLE, 0, []))
                    task = self.tasks[0]
                task.instances.append((im.name, obj, im))
            self._apply_var_config(cfg)
        for t in self.tasks:
            t.calls = [(name, obj, ns.get("_cfg_in_" + name.lower()), ns.get("_cfg_out_" + name.lower()))
                       for name, obj, im in t.instances]
        intervals = [t.interval for t in self.tasks if t.interval > 0]
        self.tick = math.gcd(*intervals) if intervals else (cyc or DEFAULT_CYCLE)
        self.watchdog = parse_duration_arg(watchdog) if watchdog is not None else None
        self._located = self._collect_located()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_source(cls, text: str, cycle=None, *, name: str = "<source>.st", **kw) -> "PLC":
        from ..api import compile_text
        return cls(compile_text(text, name, **_compile_kw(kw)), cycle, **kw)

    @classmethod
    def from_files(cls, *paths: str, cycle=None, **kw) -> "PLC":
        from ..api import compile_paths
        return cls(compile_paths(list(paths), **_compile_kw(kw)), cycle, **kw)

    def _apply_var_config(self, cfg) -> None:
        """VAR_CONFIG initial values (literals) for variables inside program instances."""
        for path, location, init, ty, span in cfg.var_config:
            if init is None or not path or not hasattr(init, "value"):
                continue
            try:
                self[".".join(path)] = init.value
            except (KeyError, ValueError_) as e:
                raise ValueError(f"{span.file}:{span.line}: VAR_CONFIG {'.'.join(path)}: {e}") from None

    def _collect_located(self) -> dict:
        """address → [(container, attribute, type)] for every located variable of every instance."""
        out: dict = {}
        for lname, (name, obj, pou) in self.instances.items():
            for sym in pou.vars.values():
                if sym.location and "*" not in sym.location:
                    out.setdefault(_norm_addr(sym.location), []).append((obj, sym.pyname, sym.type))
        for g in self.project.globals.values():
            if g.location and "*" not in g.location:
                out.setdefault(_norm_addr(g.location), []).append((self.ns, g.pyname, g.type))
        for addr, (pyname, t) in self.project.direct_vars.items():
            out.setdefault(_norm_addr(addr), []).append((self.ns, pyname, t))
        if self.config is not None:
            for path, location, init, ty, span in self.config.var_config:
                if location and "*" not in location:
                    try:
                        container, key, t = self._resolve(".".join(path))
                        out.setdefault(_norm_addr(location), []).append((container, key, t))
                    except KeyError:
                        pass
        return out

    # ------------------------------------------------------------------ time
    @property
    def time(self) -> int:
        """The PLC time (ns) at which the next scan runs."""
        return self._time

    def scan(self, n: int = 1) -> None:
        """Run n base ticks on virtual time; each due task runs its program instances once."""
        for _ in range(n):
            self._tick()

    def advance(self, duration) -> None:
        """Run scans on virtual time until `duration` more PLC time has passed."""
        d = parse_duration_arg(duration)
        end = self._time + d
        while self._time < end:
            self._tick()

    def _tick(self) -> None:
        if self.state == "FAULT":
            raise PLCFaultError(self.fault)
        now = self._time
        ns = self.ns
        ns["_now"] = now
        for task in self.tasks:
            due = False
            if task.single:
                cur = bool(ns.get(task.single, False))
                due = cur and not task.prev_single
                task.prev_single = cur
            elif task.interval > 0 and now % task.interval == 0:
                due = True
            if not due:
                continue
            budget = self.watchdog or max(10 * task.interval, 1_000_000_000)
            self._wd.start(budget)
            try:
                for name, obj, cin, cout in task.calls:
                    if cin is not None:
                        cin(obj)
                    obj._body()
                    if cout is not None:
                        cout(obj)
            except Exception as exc:  # noqa: BLE001 - every fault of user code lands here
                self._wd.stop()
                info = fault_from_exception(exc, task.name)
                self.state = "FAULT"
                self.fault = info
                raise PLCFaultError(info) from None
            self._wd.stop()
            task.runs += 1
        self.scans += 1
        self._time = now + self.tick

    def run_realtime(self, scans: Optional[int] = None, duration=None, on_scan=None) -> None:
        """Pace scans by CLOCK_MONOTONIC with absolute deadlines (no drift)."""
        end_scans = self.scans + scans if scans is not None else None
        stop_at = self._time + parse_duration_arg(duration) if duration is not None else None
        t0 = _time.monotonic_ns() - self._time
        while True:
            if end_scans is not None and self.scans >= end_scans:
                break
            if stop_at is not None and self._time >= stop_at:
                break
            deadline = t0 + self._time
            delay = deadline - _time.monotonic_ns()
            if delay > 0:
                _time.sleep(delay / 1e9)
            self._tick()
            if on_scan is not None:
                on_scan(self)

    def reset_fault(self) -> None:
        self.state = "RUN"
        self.fault = None

    # ------------------------------------------------------------------ variables
    def __getitem__(self, path: str):
        if path.strip().startswith("%"):
            binds = self._located.get(_norm_addr(path))
            if not binds:
                raise KeyError(f"no variable is located at {path}")
            c, k, t = binds[0]
            return to_python(_get(c, k), t)
        container, key, t = self._resolve(path)
        return to_python(_get(container, key), t)

    def __setitem__(self, path: str, value) -> None:
        if path.strip().startswith("%"):
            binds = self._located.get(_norm_addr(path))
            if not binds:
                raise KeyError(f"no variable is located at {path}")
            for c, k, t in binds:
                _set(c, k, from_python(value, t, path))
            return
        container, key, t = self._resolve(path)
        _set(container, key, from_python(value, t, path))

    def _resolve(self, path: str):
        """path → (container, key, type): key is an attribute name or a list index."""
        toks = list(_tokens(path))
        if not toks:
            raise KeyError(f"empty variable path {path!r}")
        kind, first = toks[0]
        if kind != "name":
            raise KeyError(f"{path}: a path starts with a program instance or global name")
        key = first.lower()
        if key in self.instances:
            name, obj, pou = self.instances[key]
            if len(toks) == 1:
                return _Holder(obj), "v", pou
            container, attr, t = obj, None, pou
            rest = toks[1:]
        else:
            g = self.project.global_names.get(key)
            if not g:
                raise KeyError(f"{path}: no program instance or global variable named '{first}'")
            container, attr, t = self.ns, g[0].pyname, g[0].type
            rest = toks[1:]
        cur = container if attr is None else _get(container, attr)
        for kind, val in rest:
            ut = T.unalias(t)
            if kind == "name":
                if isinstance(ut, T.POUType):
                    sym = ut.vars.get(val.lower())
                    if sym is None or sym.section in ("VAR_EXTERNAL", "VAR_TEMP"):
                        if sym is not None and sym.global_ref is not None:
                            container, attr, t = self.ns, sym.global_ref.pyname, sym.global_ref.type
                            cur = _get(container, attr)
                            continue
                        raise KeyError(f"{path}: {ut.name} has no variable '{val}'")
                    container, attr, t = cur, sym.pyname, sym.type
                elif isinstance(ut, T.StructType):
                    m = ut.members.get(val.lower())
                    if m is None:
                        raise KeyError(f"{path}: {ut.name} has no field '{val}'")
                    container, attr, t = cur, m.pyname, m.type
                elif isinstance(T.base_of(ut), T.ElemType) and val.isdigit() and T.base_of(ut).is_intlike:
                    return _BitHolder(container, attr, int(val), T.base_of(ut)), "v", T.BOOL
                else:
                    raise KeyError(f"{path}: '{val}' cannot be read from a {t}")
            else:  # index
                if not isinstance(ut, T.ArrayType):
                    raise KeyError(f"{path}: {t} is not an array")
                idx = [int(x) for x in val.split(",")]
                if len(idx) != len(ut.dims):
                    raise KeyError(f"{path}: the array has {len(ut.dims)} dimension(s)")
                flat = 0
                for i, (lo, hi) in zip(idx, ut.dims):
                    if not lo <= i <= hi:
                        raise KeyError(f"{path}: index {i} is outside {lo}..{hi}")
                    flat = flat * (hi - lo + 1) + (i - lo)
                container, attr, t = cur, flat, ut.element
            cur = _get(container, attr)
        return container, attr, t

    def variables(self) -> dict:
        """Every variable of every program instance, as JSON values keyed "instance.var"."""
        out = {}
        for lname, (name, obj, pou) in self.instances.items():
            for sym in pou.vars.values():
                if sym.section == "VAR_TEMP":
                    continue
                if sym.section == "VAR_EXTERNAL":
                    if sym.global_ref is not None:
                        out[f"{name}.{sym.name}"] = to_json(self.ns[sym.global_ref.pyname], sym.global_ref.type)
                    continue
                out[f"{name}.{sym.name}"] = to_json(getattr(obj, sym.pyname), sym.type)
        return out

    def globals(self) -> dict:
        return {g.name: to_json(self.ns[g.pyname], g.type) for g in self.project.globals.values()}


class _Holder:
    def __init__(self, v):
        self.v = v


class _BitHolder:
    def __init__(self, container, key, bit, t):
        self.container, self.key, self.bit, self.t = container, key, bit, t

    @property
    def v(self):
        return bool(_get(self.container, self.key) >> self.bit & 1)

    @v.setter
    def v(self, value):
        from .helpers import _setbit
        _set(self.container, self.key, _setbit(_get(self.container, self.key), self.bit, value, self.t.bits,
                                               self.t.signed))


def _get(container, key):
    if isinstance(key, str):
        if isinstance(container, dict):
            return container[key]
        return getattr(container, key)
    return container[key]


def _set(container, key, value):
    if isinstance(key, str):
        if isinstance(container, dict):
            container[key] = value
        else:
            setattr(container, key, value)
    else:
        container[key] = value


def _tokens(path: str):
    pos = 0
    path = path.strip()
    while pos < len(path):
        m = _PATH_TOKEN.match(path, pos)
        if not m or m.end() == pos:
            raise KeyError(f"malformed variable path {path!r}")
        if m.group(1) is not None:
            if pos != 0:
                raise KeyError(f"malformed variable path {path!r}")
            yield "name", m.group(1)
        elif m.group(2) is not None:
            yield "name", m.group(2)
        else:
            yield "index", m.group(3).replace(" ", "")
        pos = m.end()


def _norm_addr(addr: str) -> str:
    a = addr.strip().upper()
    m = _ADDR.match(a)
    if not m:
        return a
    size = m.group(2) or "X"
    return f"%{m.group(1)}{size}{m.group(3)}"


def _compile_kw(kw: dict) -> dict:
    out = {}
    for k in ("f_trig_first_scan", "time_unit", "use_cache", "coverage"):
        if k in kw:
            out[k] = kw.pop(k)
    return out
