"""Loading a program: from a compiled program to a running one, in two steps.

`build` executes the generated modules into a new namespace, creates the program instances
(declared values, FB_init), applies VAR_CONFIG and checks every located address, all under
the watchdog and without touching the running PLC; any failure raises PLCStartError.
`install` then makes it the PLC's running program, and cannot fail for reasons of the
program. Start-up, warm restart and online change all go this way, so a change is all or
nothing.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from ..model.addresses import is_special
from ..model.compiled import CompiledProgram
from .access import reapply_forces
from .faults import PLCStartError, fault_from_exception
from .namespace import build_namespace
from .paths import norm_addr, resolve, write
from .process_image import AddressError, Binding, ProcessImage
from .scheduler import Policy, Task, make_policy, reset_releases
from .special_registers import SpecialRegisters
from .stats import TaskStats
from .values import ValueError_, from_python
from .watchdog import Watchdog

if TYPE_CHECKING:
    from .plc import PLC

DEFAULT_CYCLE = 10_000_000

# start-up, warm restart and online change run initial values and FB_init under the watchdog too,
# with the task budget (--watchdog) but at least this much
STARTUP_BUDGET = 1_000_000_000


class Build:
    """A program made ready to run (namespace, instances, tasks, image bindings) but not running yet.
    Its attribute names are the PLC's, so path resolution works on either."""

    def __init__(self, compiled: CompiledProgram):
        self.compiled = compiled
        self.project = compiled.project
        self.ns: dict[str, Any] = {}
        self.wd: Watchdog | None = None
        self.config: Any = None
        self.instances: dict[str, tuple[str, Any, Any]] = {}  # lower name → (display name, object, POUType)
        self.tasks: list[Task] = []
        self.tick = DEFAULT_CYCLE
        self.policy: Policy = None  # type: ignore[assignment]      # set by build()
        self.bindings: dict[str, list[Binding]] = {}  # normalised address → [Binding]
        self.binding_of: dict[tuple[int, Any], Binding] = {}  # (id(container), key) → Binding


def build(
    compiled: CompiledProgram,
    image: ProcessImage,
    *,
    cycle: int | None,
    watchdog: int | None,
    policy: str,
    what: str = "start-up",
) -> Build:
    """The program ready to run, bound to `image`; PLCStartError says why it cannot start."""
    b = Build(compiled)
    budget = max(watchdog or 0, STARTUP_BUDGET)

    def install_watchdog(ns: dict[str, Any]) -> None:
        b.wd = Watchdog(ns)
        b.wd.start(budget, f"the {what} (initial values, FB_init)")

    try:
        b.ns = build_namespace(compiled, install_watchdog)
        cfg = b.config = b.project.configs[0] if b.project.configs else None
        cyc = cycle
        if cfg is not None:
            for tm in cfg.tasks:
                interval = tm.interval
                if cfg.implicit or (interval == 0 and not tm.single):
                    interval = cyc or DEFAULT_CYCLE
                b.tasks.append(Task(tm.name, interval, tm.priority, [], tm.single, index=len(b.tasks)))
            by_task = {t.name.lower(): t for t in b.tasks}
            for im in cfg.instances:
                obj = b.ns[im.singleton] if im.singleton else b.ns[im.type.pyname]()
                b.instances[im.name.lower()] = (im.name, obj, im.type)
                task = by_task.get(im.task.lower()) if im.task else None
                if task is None:
                    if not b.tasks:
                        b.tasks.append(Task("main", cyc or DEFAULT_CYCLE, 0, []))
                    task = b.tasks[0]
                task.instances.append((im.name, obj, im))
            _apply_var_config(cfg, b)
        for t in b.tasks:
            t.calls = [
                (name, obj, b.ns.get("_cfg_in_" + name.lower()), b.ns.get("_cfg_out_" + name.lower()))
                for name, obj, im in t.instances
            ]
        intervals = [t.interval for t in b.tasks if t.interval > 0]
        b.tick = math.gcd(*intervals) if intervals else (cyc or DEFAULT_CYCLE)
        b.policy = make_policy(policy, b.tasks, b.tick)
        _bind_image(b, image)
    except PLCStartError:
        raise
    except (AddressError, KeyError, ValueError_, ValueError) as e:
        raise PLCStartError(str(e)) from None
    except Exception as exc:  # noqa: BLE001 - a fault of ST code (FB_init, an initial value) or a limit
        info = fault_from_exception(exc)
        raise PLCStartError(str(info), info) from None
    finally:
        if b.wd is not None:
            b.wd.stop()
    return b


def install(plc: PLC, b: Build, first: bool = False) -> None:
    """Make a built program the PLC's running one (at a scan boundary); `first` at start-up."""
    assert b.wd is not None  # a finished build has its watchdog
    plc.compiled, plc.project, plc.ns, plc._wd = b.compiled, b.project, b.ns, b.wd
    plc.config, plc.instances, plc.tasks = b.config, b.instances, b.tasks
    plc.tick, plc.policy = b.tick, b.policy
    plc.job_lock = plc.image_lock if b.policy.name == "frame" else None  # the thesis's semaphore
    plc.bindings, plc._binding_of = b.bindings, b.binding_of
    # one message log per PLC: what the build itself logged (FB_init, initial values) joins it
    own = b.ns.get("_plc_log")
    if own is not None and own is not plc.log:
        for m in own.entries:
            plc.log.add(m.time, m.mask, m.text)
    b.ns["_plc_log"] = plc.log
    # drivers that live in the namespace (the motion kernel) follow it; the old ones hand over
    old_drivers = {type(d): d for d in plc.io if d.per_namespace}
    plc.io = [d for d in plc.io if not d.per_namespace]
    for d in b.ns.get("_io_drivers", []):
        prev = old_drivers.get(type(d))
        if prev is not None and not first:
            d.adopt(prev)
        d.join(plc)
    # OpenPLC's special function registers (%ML1024 and up), when the program binds one
    plc.io = [d for d in plc.io if not isinstance(d, SpecialRegisters)]
    if any(is_special(bd.area, bd.size, bd.index) for binds in plc.bindings.values() for bd in binds):
        plc.io.append(SpecialRegisters(plc))
    for t in plc.tasks:
        old = plc._stats.get(t.name)
        t.stats = old if old is not None and old.period == t.interval else TaskStats(t.name, t.interval)
        plc._stats[t.name] = t.stats
    for binds in plc.bindings.values():
        for bd in binds:
            bd.publish() if bd.area in "QM" else bd.latch_in()
    plc._event_tasks = [t for t in plc.tasks if t.single]
    plc._next_tick = reset_releases(plc.tasks, plc.tick, plc._time)
    reapply_forces(plc)
    for d in plc.io:
        d.rebind()


def _apply_var_config(cfg: Any, b: Build) -> None:
    """VAR_CONFIG initial values (literals) for variables inside program instances."""
    for path, _location, init, _ty, span in cfg.var_config:
        if init is None or not path or not hasattr(init, "value"):
            continue
        try:
            container, key, t = resolve(b, ".".join(path))
            write(container, key, from_python(init.value, t, ".".join(path)))
        except (KeyError, ValueError_) as e:
            raise PLCStartError(f"{span.file}:{span.line}: VAR_CONFIG {'.'.join(path)}: {e}") from None


def _located(b: Build) -> Iterator[tuple[str, Any, Any, Any, str | None, str]]:
    """(address, container, key, type, owning instance name or None, where it is declared as
    'file:line:col: ' or '') of every located variable."""
    for lname, (_name, obj, pou) in b.instances.items():
        for sym in pou.vars.values():
            if sym.location and "*" not in sym.location:
                yield sym.location, obj, sym.pyname, sym.type, lname, _where(sym.span)
    for g in b.project.globals.values():
        if g.location and "*" not in g.location:
            yield g.location, b.ns, g.pyname, g.type, None, _where(g.span)
    for addr, (pyname, t) in b.project.direct_vars.items():
        yield addr, b.ns, pyname, t, None, ""
    if b.config is not None:
        for path, location, _init, _ty, span in b.config.var_config:
            if location and "*" not in location:
                try:
                    container, key, t = resolve(b, ".".join(path))
                except KeyError:
                    continue
                yield location, container, key, t, path[0].lower(), _where(span)


def _where(span: Any) -> str:
    """'file:line:col: ' of a declaration, for a start error that names it ('' if unknown)."""
    return f"{span.file}:{span.line}:{span.col}: " if span is not None and span.line else ""


def _bind_image(b: Build, image: ProcessImage) -> None:
    """Each task latches the inputs of its own instances (and located globals) and publishes its outputs."""
    owner_task = {}
    for t in b.tasks:
        t.ins, t.outs = [], []
        for name, _obj, _im in t.instances:
            owner_task[name.lower()] = t
    for addr, container, key, t, inst, where in _located(b):
        try:
            bd = Binding(addr, container, key, t, image)
        except AddressError as e:
            raise PLCStartError(f"{where}{e}") from None
        b.bindings.setdefault(norm_addr(addr), []).append(bd)
        b.binding_of[(id(container), key)] = bd
        targets = [owner_task[inst]] if inst in owner_task else b.tasks
        for task in targets:
            if bd.area in "IM":
                task.ins.append(bd)
            if bd.area in "QM":
                task.outs.append(bd)
