"""Online change for references: after the values of the old program are copied into the new one,
interface variables, REF_TO / POINTER TO / REFERENCE TO values still point into the OLD objects.
`relink` walks the old and the new variables side by side (by name and type, as the copy did),
pairs every old instance, structure and array with its new counterpart, and then points each
reference at the new object in the same place. What has no counterpart any more becomes NULL;
values made by __NEW (outside every variable) are kept as they are."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..model import types as T
from .helpers import _AttrRef, _ItemRef, _NegRef, _ObjRef

_SKIP = ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP", "VAR_STAT")


def _members(t: Any) -> dict[str, Any]:
    if isinstance(t, T.StructType):
        return {k: m for k, m in t.members.items()}
    return {k: s for k, s in t.vars.items() if s.section not in _SKIP}


def _walk(
    old: Any,
    new: Any,
    ot: Any,
    nt: Any,
    visit_leaf: Callable[[Any, Any, Any, Any], None],
    seen: set[int],
    pairs: dict[int, Any],
) -> None:
    """Visit (old, new) values of types (ot, nt); aggregates are paired in `pairs` and recursed. An
    array of elementary values is paired, not walked (nothing in it can point anywhere)."""
    ou: Any = T.unalias(ot)
    nu: Any = T.unalias(nt)
    if old is None or new is None or str(ou) != str(nu):
        return
    if isinstance(nu, T.ArrayType):
        if not isinstance(old, list) or not isinstance(new, list) or len(old) != len(new):
            return
        pairs[id(old)] = new
        if id(new) in seen or old is new or _plain(nu.element):
            return  # elementary values, or moved whole (an online change moves no array with links inside)
        seen.add(id(new))
        for i in range(len(new)):
            if _is_link(nu.element):
                visit_leaf(old, new, i, nu.element)
            else:
                _walk(old[i], new[i], ou.element, nu.element, visit_leaf, seen, pairs)
    elif isinstance(nu, T.StructType) or (isinstance(nu, T.POUType) and nu.pou_kind != "INTERFACE"):
        pairs[id(old)] = new
        if id(new) in seen:
            return
        seen.add(id(new))
        om = _members(ou)
        for k, m in _members(nu).items():
            o = om.get(k)
            if not hasattr(new, m.pyname):
                continue
            if o is None or str(T.unalias(o.type)) != str(T.unalias(m.type)) or not hasattr(old, o.pyname):
                if _is_link(m.type):  # a reference of the new program's own: may point at a replaced list
                    visit_leaf(None, _Attr(new, m.pyname), None, m.type)
                continue
            if _is_link(m.type):
                visit_leaf(_Attr(old, o.pyname), _Attr(new, m.pyname), None, m.type)
            else:
                _walk(getattr(old, o.pyname), getattr(new, m.pyname), o.type, m.type, visit_leaf, seen, pairs)


def _plain(t: Any) -> bool:
    u = T.unalias(t)
    if isinstance(u, T.ArrayType):
        return _plain(u.element)
    return not u.is_aggregate and not _is_link(u)


def _is_link(t: Any) -> bool:
    u = T.unalias(t)
    return isinstance(u, T.RefType) or (isinstance(u, T.POUType) and u.pou_kind == "INTERFACE")


class _Attr:
    """An attribute as an indexable slot, so that leaves of objects and lists are handled alike."""

    __slots__ = ("obj", "name")

    def __init__(self, obj: Any, name: str):
        self.obj, self.name = obj, name

    def get(self) -> Any:
        return getattr(self.obj, self.name)

    def put(self, v: Any) -> None:
        setattr(self.obj, self.name, v)


class _Item(_Attr):
    """A namespace entry (a global) as a slot."""

    __slots__ = ()

    def get(self) -> Any:
        return self.obj[self.name]

    def put(self, v: Any) -> None:
        self.obj[self.name] = v


def _read(container: Any, key: Any) -> Any:
    return container.get() if isinstance(container, _Attr) else container[key]


def _write(container: Any, key: Any, v: Any) -> None:
    if isinstance(container, _Attr):
        container.put(v)
    else:
        container[key] = v


def relink(
    instances: list[tuple[Any, Any, Any, Any]],
    globals_: list[tuple[str, str, Any, Any]],
    old_ns: dict[str, Any],
    new_ns: dict[str, Any],
    replaced: dict[int, Any] | None = None,
    kept: Callable[[Any], bool] | None = None,
    still_used: set[int] | None = None,
) -> int:
    """instances: (old object, new object, old type, new type) of every program instance;
    globals_: (old pyname, new pyname, old type, new type); replaced: the new build's objects that
    the online change replaced by the old ones, by id of the old one (a reference the new program
    made to one of them is aimed at the old one); kept: whether an old object the new program took
    over whole (an element of a moved array) is the target (the reference stays); still_used:
    filled with the ids of old objects a reference keeps pointing at (values of their own, made by
    __NEW), which must not be freed. Returns how many references now point at new objects."""
    pairs: dict[int, Any] = {id(old_ns): new_ns}
    leaves: list[tuple[Any, Any, Any, Any]] = []
    own: list[Any] = []  # references that only the new program has

    def collect(oc: Any, nc: Any, key: Any, t: Any) -> None:
        if oc is None:
            own.append(nc)
        else:
            leaves.append((oc, nc, key, t))

    seen: set[int] = set()
    for old, new, ot, nt in instances:
        _walk(old, new, ot, nt, collect, seen, pairs)
    for op, np_, ot, nt in globals_:
        if str(T.unalias(ot)) != str(T.unalias(nt)):
            continue
        if _is_link(nt):
            leaves.append((_Item(old_ns, op), _Item(new_ns, np_), None, nt))
        else:
            _walk(old_ns.get(op), new_ns.get(np_), ot, nt, collect, seen, pairs)
    moved = 0
    for oc, nc, key, _t in leaves:
        v = _read(oc, key)
        nv = _moved(v, pairs)
        if nv is None and v is not None and kept is not None and kept(getattr(v, "obj", v)):
            nv = v  # its target went into the new program as it is
        if nv is v and v is not None and still_used is not None:
            still_used.add(id(getattr(v, "obj", v)))
        if nv is not None:
            moved += 1
        _write(nc, key, nv)
    if replaced:
        back = {id(new): old for old_id, new in replaced.items() for old in (pairs.get(old_id),) if old is not None}
        for nc in own:
            v = _read(nc, None)
            nv = _moved(v, back) if v is not None and _points_into(v, back) else None
            if nv is not None:
                _write(nc, None, nv)
    return moved


def _points_into(v: Any, objects: dict[int, Any]) -> bool:
    obj = getattr(v, "obj", v)
    return id(obj) in objects


def _moved(v: Any, pairs: dict[int, Any]) -> Any:
    if v is None:
        return None
    if isinstance(v, _AttrRef):
        o = pairs.get(id(v.obj))
        return _AttrRef(o, v.name, v.spec) if o is not None else None
    if isinstance(v, _ItemRef):
        o = pairs.get(id(v.obj))
        if o is not None:
            return _ItemRef(o, v.key, v.spec)
        return v  # a value of its own (__NEW): nothing to point it at
    if isinstance(v, _ObjRef):
        o = pairs.get(id(v.obj))
        return _ObjRef(o) if o is not None else None
    if isinstance(v, _NegRef):
        return v
    return pairs.get(id(v))  # an interface variable: the instance itself
