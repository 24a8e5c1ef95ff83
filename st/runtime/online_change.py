"""Online change: a new build of the program swapped in at a scan boundary, its state carried over.

All or nothing: `prepare_change` refuses configuration or type changes, then builds the new
program (it may run in another thread while the old one scans); `apply_change` carries every
variable over by path and type, reading the old program only, then installs the new one.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..model import types as T
from ..model.compiled import CompiledProgram
from .access import store_python
from .build import Build, build, install
from .faults import PLCStartError, fault_from_exception
from .paths import Holder
from .relink import relink
from .values import to_python

if TYPE_CHECKING:
    from .plc import PLC


class OnlineChangeRefused(ValueError):
    """An online change that cannot be applied; the running program and its state are untouched."""

    def __init__(self, reasons: list[str]):
        super().__init__("online change refused, the old program keeps running:\n  " + "\n  ".join(reasons))
        self.reasons = list(reasons)


def prepare_change(plc: PLC, compiled: CompiledProgram) -> Build:
    problems = _change_problems(plc, compiled)
    if problems:
        raise OnlineChangeRefused(problems)
    try:
        return build(
            compiled, plc.image, cycle=plc.cycle, watchdog=plc.watchdog, policy=plc.policy_name, what="online change"
        )
    except PLCStartError as e:
        raise OnlineChangeRefused([f"the new program cannot start: {e}"]) from None


def apply_change(plc: PLC, b: Build) -> str:
    try:
        _carry_over(plc, b)
    except Exception as exc:  # noqa: BLE001 - whatever fails, the old program keeps running
        reason = exc.args[0] if isinstance(exc, (ValueError, KeyError)) and exc.args else str(fault_from_exception(exc))
        raise OnlineChangeRefused([f"the state cannot be carried over: {reason}"]) from None
    old_now = plc.ns.get("_now", 0)
    install(plc, b)
    plc.ns["_now"] = old_now
    for t in plc.tasks:
        for bd in t.outs:
            bd.publish()
    return f"online change: {len(b.instances)} instance(s) carried over"


def _carry_over(plc: PLC, b: Build) -> None:
    """Copy every variable whose path and type are unchanged from the running program into the
    built one, and re-aim interfaces and references at the new objects. Reads the old program only."""
    for key, (_name, obj, pou) in b.instances.items():
        old = plc.instances.get(key)
        if old is not None:
            store_python(Holder(obj), "v", pou, to_python(old[1], old[2]))
    old_globals = {g.pyname: g for g in plc.project.globals.values()}
    for g in b.project.globals.values():
        og = old_globals.get(g.pyname)
        if og is not None and str(og.type) == str(g.type):
            store_python(b.ns, g.pyname, g.type, to_python(plc.ns[og.pyname], og.type))
    # interface variables and references still point into the old objects: re-aim them
    relink(
        [
            (plc.instances[k][1], obj, plc.instances[k][2], pou)
            for k, (name, obj, pou) in b.instances.items()
            if k in plc.instances
        ],
        [
            (g.pyname, g.pyname, old_globals[g.pyname].type, g.type)
            for g in b.project.globals.values()
            if g.pyname in old_globals
        ],
        plc.ns,
        b.ns,
    )


def _change_problems(plc: PLC, compiled: CompiledProgram) -> list[str]:
    new_cfg = compiled.project.configs[0] if compiled.project.configs else None
    out: list[str] = []

    def shape(cfg: Any) -> tuple[set[tuple[Any, ...]], set[tuple[Any, ...]]]:
        if cfg is None:
            return set(), set()
        return (
            {(t.name.lower(), t.interval, t.priority, t.single) for t in cfg.tasks},
            {(i.name.lower(), i.type.name.lower(), i.task.lower()) for i in cfg.instances},
        )

    if shape(plc.config) != shape(new_cfg):
        out.append("the configuration's tasks or program instances changed (restart the PLC to apply it)")
    new_pous = {i.name.lower(): i.type for i in (new_cfg.instances if new_cfg else [])}
    for key, (name, _obj, pou) in plc.instances.items():
        if key in new_pous:
            _type_changes(pou, new_pous[key], name, out)
    new_globals = {g.pyname: g for g in compiled.project.globals.values()}
    for g in plc.project.globals.values():
        ng = new_globals.get(g.pyname)
        if ng is not None:
            _type_changes(g.type, ng.type, g.name, out)
    return out


def _type_changes(old: T.Type, new: T.Type, path: str, out: list[str]) -> None:
    """Variables that keep their name but change their type (their values cannot be carried over)."""
    uo, un = T.unalias(old), T.unalias(new)
    if (
        isinstance(uo, (T.POUType, T.StructType))
        and isinstance(un, (T.POUType, T.StructType))
        and type(uo) is type(un)
        and uo.name.lower() == un.name.lower()
    ):
        om = uo.members if isinstance(uo, T.StructType) else uo.vars
        nm = un.members if isinstance(un, T.StructType) else un.vars
        for k, m in om.items():
            if k in nm and getattr(m, "section", "") not in ("VAR_TEMP", "VAR_EXTERNAL", "VAR_IN_OUT"):
                _type_changes(m.type, nm[k].type, f"{path}.{m.name}", out)
        return
    if str(old) != str(new):
        out.append(f"{path} changed its type from {old} to {new}")
