"""The program as the page shows it: the instance tree, each POU's source lines and variables.

Built once per program (again after an online change) in the PLC process and handed to the
server, which serves it as `api/program`.
"""

from __future__ import annotations

import re
from typing import Any

from ..model import types as T

_END = re.compile(r"^\s*END_(PROGRAM|FUNCTION_BLOCK|FUNCTION)\b", re.IGNORECASE)
_SECTIONS = ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP", "VAR_EXTERNAL", "VAR_STAT")
MAX_CHILDREN = 200  # block instances listed under one instance (an ARRAY OF blocks is cut here)


def describe(plc: Any, name: str, read_only: bool) -> dict:
    """The JSON of `api/program` for the PLC's running program."""
    from ..stdlib.plcopen import registry

    compiled = plc.compiled
    pous: dict[str, dict] = {}
    instances = []
    task_of = {inst.lower(): t.name for t in plc.tasks for inst, *_ in t.calls} if plc.tasks else {}
    for key, (display, _obj, pou) in plc.instances.items():
        instances.append(_instance(display, pou, pous, compiled, task_of.get(key)))
    reg = registry(plc)
    # the configured axes and those already in use (an axis registers when a block first uses it)
    axes = sorted(set(reg.configs) | {getattr(a, "axis_no", 0) for a in reg.axes.values()}) if reg is not None else []
    return {
        "name": name,
        "read_only": read_only,
        "tasks": [{"name": t.name, "interval_ns": t.interval, "priority": t.priority} for t in plc.tasks],
        "instances": instances,
        "pous": pous,
        "axes": axes,
        "ethercat": any(d.name == "ethercat" for d in plc.io),
        "modbus": any(d.name == "modbus" for d in plc.io),
        "flow": compiled.coverage_hits is not None,
    }


def _instance(path: str, pou: T.POUType, pous: dict, compiled: Any, task: str | None, depth: int = 0) -> dict:
    if pou.name not in pous:
        pous[pou.name] = _pou(pou, compiled)
    children: list[dict] = []
    if depth < 16:
        for v in pou.vars.values():
            t = T.unalias(v.type)
            if v.section in ("VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_STAT") and isinstance(t, T.POUType):
                if t.pou_kind == "FUNCTION_BLOCK" and len(children) < MAX_CHILDREN:
                    children.append(_instance(f"{path}.{v.name}", t, pous, compiled, None, depth + 1))
    return {"path": path, "pou": pou.name, "kind": pou.pou_kind, "task": task, "children": children}


def _pou(pou: T.POUType, compiled: Any) -> dict:
    out: dict[str, Any] = {"file": None, "first_line": 0, "source": [], "vars": [], "library": bool(pou.library)}
    span = getattr(pou.decl, "span", None)
    src = compiled.sources.get(span.file) if span is not None and not pou.library else None
    if src is not None and span is not None:
        lines = src.text.splitlines()
        first = span.line
        while first > 1 and not re.search(r"\b(PROGRAM|FUNCTION_BLOCK|FUNCTION)\b", lines[first - 1], re.I):
            first -= 1  # the keyword may stand on a line above the name
        last = next((i + 1 for i in range(span.line - 1, len(lines)) if _END.match(lines[i])), len(lines))
        last = max(last, _members_after(pou, span.file, last, lines))
        out.update(file=span.file, first_line=first, source=lines[first - 1 : last])
    for v in pou.vars.values():
        if v.section not in _SECTIONS:
            continue
        t = T.unalias(v.type)
        out["vars"].append(
            {
                "name": v.name,
                "type": type_text(v.type),
                "section": v.section,
                "location": v.location or None,
                "output": (v.location or "").upper().startswith("%Q"),
                "elementary": not (t.is_aggregate or isinstance(t, (T.POUType, T.RefType))),
            }
        )
    return out


_MEMBER_END = re.compile(r"^\s*END_(METHOD|PROPERTY|ACTION)\b", re.IGNORECASE)


def _members_after(pou: T.POUType, file: str, last: int, lines: list[str]) -> int:
    """The last line of the block's METHODs, PROPERTYs and ACTIONs written after its END_FUNCTION_BLOCK
    (as TwinCAT and CODESYS text exports place them), or `last` when there are none."""
    starts = []
    for m in [*pou.methods.values(), *pou.actions.values()]:
        span = getattr(getattr(m, "decl", m), "span", None)
        if getattr(m, "owner_fb", pou) is pou and span is not None and span.file == file and span.line > last:
            starts.append(span.line)
    for ps in pou.properties.values():
        if ps.owner is pou and ps.span is not None and ps.span.file == file and ps.span.line > last:
            starts.append(ps.span.line)
    end = last
    for start in starts:
        end = max(end, next((i + 1 for i in range(start - 1, len(lines)) if _MEMBER_END.match(lines[i])), start))
    return end


def type_text(t: T.Type) -> str:
    """A type as the page names it: INT, TrafficPhase, STRING(80), ARRAY[1..5] OF INT, POINTER TO X."""
    if isinstance(t, T.StringType):
        return str(t)
    name = getattr(t, "name", None)
    if name:
        return str(name)
    ut = T.unalias(t)
    if isinstance(ut, T.ArrayType):
        dims = ", ".join(f"{lo}..{hi}" for lo, hi in ut.dims)
        return f"ARRAY[{dims}] OF {type_text(ut.element)}"
    if isinstance(ut, T.RefType):
        return str(ut)
    return type(ut).__name__
