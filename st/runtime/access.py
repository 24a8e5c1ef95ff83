"""Reading, writing and forcing a running program's variables by path or %address, and dumps.

A write by path converts the value to the variable's type and keeps a located variable's
process-image cell in step (or the next latch would undo it). A %address reads or writes the
image itself, typed by the variable bound there. A forced variable holds its value whenever a
job starts and ends; forces are asked for by path and applied again after a reload.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..model import types as T
from . import refnames
from .helpers import _AttrRef, _ItemRef
from .paths import norm_addr, read, resolve, through_access_path, write
from .process_image import AddressError, from_raw, parse_address, to_raw
from .values import ValueError_, _nest, from_python, to_json, to_python
from .varref import VarRef

if TYPE_CHECKING:
    from .plc import PLC


def _writable(plc: PLC, path: str) -> str:
    """`path`, or the variable's a VAR_ACCESS name reaches; a READ_ONLY access path refused."""
    target, ap = through_access_path(plc, path)
    if ap is not None and ap.read_only:
        raise ValueError_(f"{path}: '{ap.name}' is a READ_ONLY access path")
    return target


def get(plc: PLC, path: str) -> Any:
    path = through_access_path(plc, path)[0]
    if path.strip().startswith("%"):
        return _image_read(plc, path)
    container, key, t = resolve(plc, path)
    return to_python(read(container, key), t, refnames.namer(plc))


def set_(plc: PLC, path: str, value: Any) -> None:
    path = _writable(plc, path)
    if path.strip().startswith("%"):
        _image_write(plc, path, value)
        return
    container, key, t = resolve(plc, path)
    v = from_python(value, t, path)
    write(container, key, v)
    b = plc._binding_of.get((id(container), key))
    if b is not None:  # keep the image in step, or the next latch would undo the write
        b.table[b.index] = to_raw(v, t, b.size)


def ref(plc: PLC, path: str) -> VarRef:
    container, key, t = resolve(plc, path)
    return VarRef(path, container, key, t, plc._binding_of.get((id(container), key)))


def force(plc: PLC, path: str, value: Any) -> None:
    _writable(plc, path)
    if through_access_path(plc, path)[0].strip().startswith("%"):
        path = through_access_path(plc, path)[0]
    if path.strip().startswith("%"):
        binds = plc.bindings.get(norm_addr(path))
        if not binds:
            raise KeyError(f"{path}: no located variable at this address")
        targets = [(b.container, b.key, b.type) for b in binds]
    else:
        targets = [resolve(plc, path)]
    plc._force_spec[path] = value
    for container, key, t in targets:
        v = from_python(value, t, path)
        write(container, key, v)
        plc._forced[(path.strip().lower(), id(container), key)] = (
            container,
            key,
            v,
            plc._binding_of.get((id(container), key)),
        )
    apply_forced(plc)


def unforce(plc: PLC, path: str | None = None) -> None:
    if path is None:
        plc._forced.clear()
        plc._force_spec.clear()
        return
    plc._force_spec.pop(path, None)
    p = path.strip().lower()
    for k in [k for k in plc._forced if k[0] == p]:
        del plc._forced[k]


def apply_forced(plc: PLC) -> None:
    """Every forced variable (and its image cell) to its forced value: when a job starts and ends."""
    for container, key, v, b in plc._forced.values():
        write(container, key, v)
        if b is not None:
            b.table[b.index] = b.conv_out(v)


def reapply_forces(plc: PLC) -> None:
    """After a reload: force the new program's variables again; a force whose variable is gone or
    changed its type is dropped."""
    if not plc._force_spec:
        return
    spec, plc._forced = dict(plc._force_spec), {}
    for path, value in spec.items():
        try:
            force(plc, path, value)
        except (KeyError, ValueError, TypeError):
            plc._force_spec.pop(path, None)


def _image_read(plc: PLC, addr: str) -> Any:
    """%I, %Q, %M read from the process image (what I/O and the HMI see), typed by the bound variable."""
    try:
        area, size, i = parse_address(addr)
    except AddressError as e:
        raise KeyError(str(e)) from None
    raw = plc.image.tables[(area, size)][i]
    binds = plc.bindings.get(norm_addr(addr))
    if binds:
        return to_python(from_raw(raw, binds[0].type, size), binds[0].type)
    return raw


def _image_write(plc: PLC, addr: str, value: Any) -> None:
    """Write an image cell; %Q and %M also write their variables (the program would overwrite them)."""
    try:
        area, size, i = parse_address(addr)
    except AddressError as e:
        raise KeyError(str(e)) from None
    binds = plc.bindings.get(norm_addr(addr), [])
    if binds:
        t = binds[0].type
        v = from_python(value, t, addr)
        raw = to_raw(v, t, size)
        if area in "QM":
            for b in binds:
                b.write_var(from_python(value, b.type, addr))
    else:
        if isinstance(value, bool) and size != "X" or not isinstance(value, (bool, int)):
            raise ValueError_(f"{addr}: expected {'a BOOL' if size == 'X' else 'an integer'}, got {value!r}")
        raw = value
    plc.image.set(addr, raw)


def store_python(container: Any, key: Any, t: T.Type, value: Any) -> None:
    """Write a to_python-form value back into a variable, aggregates element by element (retained
    data, online change); references are left alone (relink re-aims them)."""
    ut = T.unalias(t)
    if isinstance(ut, T.ArrayType):
        arr = read(container, key)
        flat = _flatten(value, len(ut.dims))
        if len(flat) != len(arr):
            raise ValueError("array size changed")
        for i, v in enumerate(flat):
            store_python(arr, i, ut.element, v)
    elif isinstance(ut, T.RefType) or (isinstance(ut, T.POUType) and ut.pou_kind == "INTERFACE"):
        return  # references: re-aimed by relink()
    elif isinstance(ut, (T.StructType, T.POUType)):
        obj = read(container, key)
        members = ut.members if isinstance(ut, T.StructType) else ut.vars
        for m in members.values():
            if m.name in value and getattr(m, "section", "") not in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP"):
                store_python(obj, m.pyname, m.type, value[m.name])
    else:
        write(container, key, from_python(value, t, ""))


def _flatten(v: Any, depth: int) -> list[Any]:
    if depth <= 1:
        return list(v)
    return [x for row in v for x in _flatten(row, depth - 1)]


def variables(plc: PLC, all: bool = False) -> dict[str, Any]:
    """Every variable of every program instance, as JSON values keyed "instance.var". A function
    block instance shows its interface only (VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT), not the state a
    block keeps inside (a TON's START_TIME); all=True shows every variable of every instance."""
    out = {}
    ref = refnames.namer(plc)
    dump = to_json if all else _public_json
    for _lname, (name, obj, pou) in plc.instances.items():
        for sym in pou.vars.values():
            if sym.section == "VAR_TEMP":
                continue
            if sym.section == "VAR_EXTERNAL":
                if sym.global_ref is not None:
                    out[f"{name}.{sym.name}"] = dump(plc.ns[sym.global_ref.pyname], sym.global_ref.type, ref)
                continue
            out[f"{name}.{sym.name}"] = dump(getattr(obj, sym.pyname), sym.type, ref)
    return out


_INTERFACE = ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")


def _public_json(v: Any, t: T.Type, ref: Any) -> Any:
    """to_json, with every function block instance inside `v` shown by its interface only."""
    ut = T.unalias(t)
    if not _holds_blocks(ut):
        return to_json(v, t, ref)
    if v is None:
        return None
    if isinstance(ut, T.POUType):
        out = {}
        for s in ut.vars.values():
            if s.section in _INTERFACE:
                x = getattr(v, s.pyname, None)
                if s.section == "VAR_IN_OUT" and isinstance(x, (_AttrRef, _ItemRef)):
                    x = x.get()  # an in-out whose address is taken holds the caller's reference
                out[s.name] = None if x is None else _public_json(x, s.type, ref)
        return out
    if isinstance(ut, T.ArrayType):
        return _nest([_public_json(x, ut.element, ref) for x in v], ut.dims)
    assert isinstance(ut, T.StructType)
    return {m.name: _public_json(getattr(v, m.pyname), m.type, ref) for m in ut.members.values()}


def _holds_blocks(t: Any, seen: frozenset[int] = frozenset()) -> bool:
    """True when values of the (unaliased) type t are or contain function block instances."""
    if isinstance(t, T.POUType):
        return t.pou_kind == "FUNCTION_BLOCK"
    if id(t) in seen:
        return False
    if isinstance(t, T.ArrayType):
        return _holds_blocks(T.unalias(t.element), seen | {id(t)})
    if isinstance(t, T.StructType):
        return any(_holds_blocks(T.unalias(m.type), seen | {id(t)}) for m in t.members.values())
    return False


def globals_(plc: PLC) -> dict[str, Any]:
    """Global variables, and static ones (VAR_STAT) as 'POU.name' or 'FB.Method.name'."""

    def name(g: Any) -> str:
        if g.section != "VAR_STAT" or g.owner is None:
            return str(g.name)
        fb = getattr(g.owner, "owner_fb", None)
        return f"{fb.name + '.' if fb is not None else ''}{g.owner.name}.{g.name}"

    ref = refnames.namer(plc)
    lib_files = {path for lib in plc.project.libraries for path, _ in lib.sources}

    def own(g: Any) -> bool:  # a library's globals (ADSLOG_MSGTYPE_…, its VAR_STATs) are not the program's
        return getattr(g.span, "file", None) not in lib_files

    return {name(g): to_json(plc.ns[g.pyname], g.type, ref) for g in plc.project.globals.values() if own(g)}
