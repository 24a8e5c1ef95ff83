"""Variable paths ("main.fb.arr[1, 2].x", "g_count", "main.w.3") resolved to where the value lives.

A resolved variable is a (container, key, type) triple: the key is an attribute name, a dict key
(globals live in the namespace dict) or a list index. A program instance itself and a bit of an
integer have no such slot, so they are reached through a small holder object with one attribute
`v`. `read` and `write` are raw: no conversion, no process-image update.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any, Protocol

from ..model import types as T
from ..model.addresses import canonical
from .helpers import _setbit

_PATH_TOKEN = re.compile(r"\s*(?:([A-Za-z_][A-Za-z0-9_]*)|\.([A-Za-z_][A-Za-z0-9_]*|[0-9]+)|\[([^\]]*)\])")


class Program(Protocol):
    """What resolution needs of a program: the running PLC or a build being prepared."""

    instances: dict[str, tuple[str, Any, Any]]
    project: Any
    ns: dict[str, Any]


def read(container: Any, key: Any) -> Any:
    if isinstance(key, str):
        if isinstance(container, dict):
            return container[key]
        return getattr(container, key)
    return container[key]


def write(container: Any, key: Any, value: Any) -> None:
    if isinstance(key, str):
        if isinstance(container, dict):
            container[key] = value
        else:
            setattr(container, key, value)
    else:
        container[key] = value


class Holder:
    """A slot for a value that is not stored in a container (a program instance as a whole)."""

    def __init__(self, v: Any):
        self.v = v


class BitHolder:
    """One bit of an integer variable (`main.w.3`), read and written as a BOOL."""

    def __init__(self, container: Any, key: Any, bit: int, t: Any):
        self.container, self.key, self.bit, self.t = container, key, bit, t

    @property
    def v(self) -> bool:
        return bool(read(self.container, self.key) >> self.bit & 1)

    @v.setter
    def v(self, value: Any) -> None:
        write(
            self.container,
            self.key,
            _setbit(read(self.container, self.key), self.bit, value, self.t.bits, self.t.signed),
        )


def through_access_path(src: Program, path: str) -> tuple[str, Any]:
    """A path that starts with a VAR_ACCESS name, as the path of the variable it reaches (what
    follows the name kept: `counter.field`), and its AccessPath; other paths as they are, None."""
    aps = getattr(src.project, "access_paths", None)
    if not aps:
        return path, None
    m = re.match(r"\s*([A-Za-z_][A-Za-z0-9_]*)", path)
    ap = aps.get(m.group(1).lower()) if m else None
    if (
        ap is None
        or m is None
        or m.group(1).lower() in src.instances
        or src.project.global_names.get(m.group(1).lower())
    ):
        return path, None
    return ap.target + path[m.end() :], ap


def resolve(src: Program, path: str) -> tuple[Any, Any, Any]:
    """path → (container, key, type) in `src`; KeyError saying what is wrong with the path."""
    path = through_access_path(src, path)[0]
    toks = list(tokens(path))
    if not toks:
        raise KeyError(f"empty variable path {path!r}")
    kind, first = toks[0]
    if kind != "name":
        raise KeyError(f"{path}: a path starts with a program instance or global name")
    key = first.lower()
    container: Any
    attr: Any
    t: Any
    if key in src.instances:
        name, obj, pou = src.instances[key]
        if len(toks) == 1:
            return Holder(obj), "v", pou
        container, attr, t = obj, None, pou
        rest = toks[1:]
    else:
        g = src.project.global_names.get(key)
        if not g:
            raise KeyError(f"{path}: no program instance or global variable named '{first}'")
        container, attr, t = src.ns, g[0].pyname, g[0].type
        rest = toks[1:]
    cur = container if attr is None else read(container, attr)
    for kind, val in rest:
        ut = T.unalias(t)
        if kind == "name":
            if isinstance(ut, T.POUType):
                sym = ut.vars.get(val.lower())
                if sym is None or sym.section in ("VAR_EXTERNAL", "VAR_TEMP"):
                    if sym is not None and sym.global_ref is not None:
                        container, attr, t = src.ns, sym.global_ref.pyname, sym.global_ref.type
                        cur = read(container, attr)
                        continue
                    raise KeyError(f"{path}: {ut.name} has no variable '{val}'")
                container, attr, t = cur, sym.pyname, sym.type
            elif isinstance(ut, T.StructType):
                m = ut.members.get(val.lower())
                if m is None:
                    raise KeyError(f"{path}: {ut.name} has no field '{val}'")
                container, attr, t = cur, m.pyname, m.type
            elif isinstance(T.base_of(ut), T.ElemType) and val.isdigit() and T.base_of(ut).is_intlike:
                return BitHolder(container, attr, int(val), T.base_of(ut)), "v", T.BOOL
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
        cur = read(container, attr)
    return container, attr, t


def tokens(path: str) -> Iterator[tuple[str, str]]:
    """("name", text) and ("index", "1,2") tokens of a path."""
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


def norm_addr(addr: str) -> str:
    """'%qx0.1' → '%QX0.1', '%I0.0' → '%IX0.0', '%QX1' → '%QX1.0': the key of the bindings table
    (the compiler's spelling of a cell, st.model.addresses.canonical)."""
    return canonical(addr)
