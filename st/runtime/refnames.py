"""Names for references in reads and dumps: a REF_TO / POINTER TO / REFERENCE TO value is shown as
`REF(path)` of the variable it designates (`REF(main.arr[1])`, `REF(main.fb.x)`, `REF(g_count)`),
`REF(__NEW)` for a value made by __NEW. The index from objects to paths is built once per
dump, only when a reference is met."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..model import types as T
from .helpers import _AttrRef, _ItemRef, _ObjRef
from .paths import Program
from .pointers import ByteView

_SKIP = ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP", "VAR_STAT")


def _index(plc: Program) -> dict[int, tuple[str, Any]]:
    """id(container) → (path, type) for every instance, structure and array of the PLC."""
    out: dict[int, tuple[str, Any]] = {}

    def walk(v: Any, t: Any, path: str) -> None:
        u = T.unalias(t)
        if v is None or id(v) in out:
            return
        if isinstance(u, T.ArrayType):
            out[id(v)] = (path, u)
            for i, x in enumerate(v):
                walk(x, u.element, path + _subscript(u, i))
        elif isinstance(u, T.StructType):
            out[id(v)] = (path, u)
            for m in u.members.values():
                walk(getattr(v, m.pyname, None), m.type, f"{path}.{m.name}")
        elif isinstance(u, T.POUType) and u.pou_kind != "INTERFACE":
            out[id(v)] = (path, u)
            for s in u.vars.values():
                if s.section not in _SKIP:
                    walk(getattr(v, s.pyname, None), s.type, f"{path}.{s.name}")

    for name, obj, pou in plc.instances.values():
        walk(obj, pou, name)
    for g in plc.project.globals.values():
        walk(plc.ns.get(g.pyname), g.type, g.name)
    return out


def _subscript(at: T.ArrayType, flat: int) -> str:
    idx = []
    for lo, hi in reversed(at.dims):
        n = hi - lo + 1
        idx.append(lo + flat % n)
        flat //= n
    return "[" + ", ".join(str(i) for i in reversed(idx)) + "]"


def _member(t: Any, pyname: str) -> str:
    members = t.members.values() if isinstance(t, T.StructType) else t.vars.values()
    for m in members:
        if m.pyname == pyname:
            name: str = m.name
            return name
    return pyname


def namer(plc: Program) -> Callable[[Any], str]:
    """A function giving the display text of a reference value (for to_python / to_json)."""
    cache: dict[str, dict[int, tuple[str, Any]]] = {}

    def name(ref: Any) -> str:
        if "index" not in cache:
            cache["index"] = _index(plc)
        index = cache["index"]
        if isinstance(ref, _AttrRef) and id(ref.obj) in index:
            path, t = index[id(ref.obj)]
            return f"REF({path}.{_member(t, ref.name)})"
        if isinstance(ref, _ItemRef):
            if ref.obj is plc.ns:
                for g in plc.project.globals.values():
                    if g.pyname == ref.key:
                        return f"REF({g.name})"
            elif id(ref.obj) in index:
                path, t = index[id(ref.obj)]
                return f"REF({path}{_subscript(t, ref.key)})"
            elif isinstance(ref.obj, list) and len(ref.obj) == 1:
                return "REF(__NEW)"  # a value of its own, made by __NEW
        if isinstance(ref, _ObjRef) and id(ref.obj) in index:
            return f"REF({index[id(ref.obj)][0]})"
        if isinstance(ref, ByteView):  # a pointer over the bytes of another variable
            whole = name(ref.ref)
            return whole if not ref.offset else f"{whole} + {ref.offset} byte(s)"
        return "REF(?)"

    return name
