"""A TwinCAT project's tasks (.TcTTO files) as the CONFIGURATION they mean.

A TwinCAT PLC project keeps each task in a .TcTTO file that its .plcproj compiles: the task's
name, its cycle time in microseconds, its priority and the programs it calls in order
(`<PouCall><Name>MAIN</Name></PouCall>`). `configuration` writes the equivalent IEC
configuration, so a project runs as TwinCAT runs it: only the programs a task calls, at its
cycle, each program the one instance its name stands for (`Prg.x` elsewhere is the same instance).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import PureWindowsPath

from .twincat import COMPILE_ITEM, find_ignoring_case

_TASK = re.compile(r"<Task\b[^>]*\bName\s*=\s*\"([^\"]+)\"[^>]*>(.*?)</Task>", re.S)
_CYCLE = re.compile(r"<CycleTime>\s*(\d+)\s*</CycleTime>")
_PRIORITY = re.compile(r"<Priority>\s*(\d+)\s*</Priority>")
_CALL = re.compile(r"<PouCall>\s*<Name>\s*([^<\s]+)\s*</Name>", re.S)
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class TwinCATTask:
    name: str
    cycle_us: int  # 0: no cycle given (the PLC's base cycle)
    priority: int
    calls: tuple[str, ...] = field(default_factory=tuple)  # the programs it calls, in order


def tasks(xml: str) -> list[TwinCATTask]:
    """The tasks one .TcTTO file declares (names that are no ST identifiers are left out)."""
    out = []
    for m in _TASK.finditer(xml):
        name, body = m.group(1), m.group(2)
        if not _IDENT.match(name):
            continue
        cycle = _CYCLE.search(body)
        prio = _PRIORITY.search(body)
        calls = tuple(c for c in _CALL.findall(body) if _IDENT.match(c.split(".")[-1]))
        out.append(TwinCATTask(name, int(cycle.group(1)) if cycle else 0, int(prio.group(1)) if prio else 0, calls))
    return out


def configuration(project: str, found: list[TwinCATTask]) -> str:
    """The CONFIGURATION of a project's tasks ('' when no task calls a program). A program two
    tasks call is one instance, run by the first (TwinCAT would run it in both; st runs each
    instance in one task)."""
    lines: list[str] = []
    seen: set[str] = set()
    for t in found:
        interval = f"INTERVAL := T#{t.cycle_us}us, " if t.cycle_us > 0 else ""
        lines.append(f"    TASK {t.name} ({interval}PRIORITY := {t.priority});")
        for prog in t.calls:
            name = prog.split(".")[-1]  # a library-qualified call: the program's own name
            if name.lower() in seen:
                continue
            seen.add(name.lower())
            lines.append(f"    PROGRAM {name} WITH {t.name} : {name};")
    if not seen:
        return ""
    ident = re.sub(r"\W", "_", project) or "Project"
    if not _IDENT.match(ident):
        ident = "_" + ident
    return (
        f"CONFIGURATION {ident}\n  RESOURCE PLC ON PLC\n" + "\n".join(lines) + "\n  END_RESOURCE\nEND_CONFIGURATION\n"
    )


def project_configuration(project_path: str, xml: str) -> str:
    """The CONFIGURATION of the tasks a .plcproj compiles (its .TcTTO items; '' if none calls a
    program). A task file that cannot be read is left out (its programs then run in no task)."""
    base = os.path.dirname(project_path)
    found: list[TwinCATTask] = []
    for m in COMPILE_ITEM.finditer(xml):
        rel = PureWindowsPath(m.group(1)).as_posix()
        if not rel.lower().endswith(".tctto"):
            continue
        exact = os.path.join(base, rel)
        path = exact if os.path.exists(exact) else find_ignoring_case(base, rel)
        try:
            with open(path or exact, encoding="utf-8-sig", errors="replace") as f:
                found += tasks(f.read())
        except OSError:
            continue
    name = re.search(r"<Name>\s*([^<]+?)\s*</Name>", xml)
    return configuration(name.group(1) if name else os.path.splitext(os.path.basename(project_path))[0], found)
