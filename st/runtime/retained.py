"""Which variables are retained (RETAIN/PERSISTENT), their values as a snapshot, and restoring one.

The snapshot maps a variable's path to (its type as text, its value in to_python form); a value
is restored only where the path still names a variable of the same type. retain.py keeps the
snapshots in SQLite.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from ..model import types as T
from .access import store_python
from .values import to_python

if TYPE_CHECKING:
    from .plc import PLC


def retained_paths(plc: PLC) -> Iterator[tuple[str, Any, Any, Any]]:
    """(path, container, key, type) of every RETAIN/PERSISTENT variable of the instances and globals."""
    for _lname, (name, obj, pou) in plc.instances.items():
        yield from _retained_in(name, obj, pou)
    for g in plc.project.globals.values():
        if g.retain or g.persistent:
            yield g.name, plc.ns, g.pyname, g.type
        else:
            yield from _retained_inside(g.name, plc.ns[g.pyname], g.type)


def retained_values(plc: PLC) -> dict[str, tuple[str, Any]]:
    out = {}
    for path, c, k, t in retained_paths(plc):
        out[path] = (str(t), to_python(c[k] if isinstance(c, dict) else getattr(c, k), t))
    return out


def commit_retained(plc: PLC) -> None:
    if plc.retain_store is not None:
        plc.retain_store.save(retained_values(plc), plc._time)


def restore_retained(plc: PLC, saved: dict[str, tuple[str, Any]]) -> int:
    """Restore a snapshot; returns how many values were restored."""
    n = 0
    for path, c, k, t in retained_paths(plc):
        got = saved.get(path)
        if got is None or got[0] != str(t):
            continue
        try:
            store_python(c, k, t, got[1])
            n += 1
        except (ValueError, KeyError, TypeError, IndexError):
            continue
    return n


def _retained_in(path: str, obj: Any, pou: T.POUType) -> Iterator[tuple[str, Any, Any, Any]]:
    """(path, container, key, type) of the RETAIN/PERSISTENT variables of one program or block
    instance, and of the block instances inside it (a RETAIN in a block is kept wherever the
    block is instantiated, as in CODESYS)."""
    for sym in pou.vars.values():
        if sym.section in ("VAR_EXTERNAL", "VAR_TEMP", "VAR_IN_OUT", "VAR_STAT"):
            continue
        if sym.retain or sym.persistent:
            yield f"{path}.{sym.name}", obj, sym.pyname, sym.type
        else:
            yield from _retained_inside(f"{path}.{sym.name}", getattr(obj, sym.pyname), sym.type)


def _retained_inside(path: str, value: Any, t: T.Type) -> Iterator[tuple[str, Any, Any, Any]]:
    """The retained variables inside a value that is not retained as a whole: block instances and
    arrays of them."""
    ut = T.unalias(t)
    if isinstance(ut, T.POUType) and ut.pou_kind == "FUNCTION_BLOCK" and value is not None:
        yield from _retained_in(path, value, ut)
    elif isinstance(ut, T.ArrayType) and isinstance(T.unalias(ut.element), (T.POUType, T.ArrayType)):
        for i, index in enumerate(_array_indices(ut.dims)):
            yield from _retained_inside(f"{path}[{index}]", value[i], ut.element)


def _array_indices(dims: list[tuple[int, int]]) -> list[str]:
    """'1', '2', … or '0,1', … : the ST indices of a flat array's elements, in storage order."""
    out = [""]
    for lo, hi in dims:
        out = [f"{a},{i}" if a else str(i) for a in out for i in range(lo, hi + 1)]
    return out
