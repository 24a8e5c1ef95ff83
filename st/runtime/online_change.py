"""Online change: a new build of the program swapped in at a scan boundary, its state carried over.

In two phases, so that the scan is never held in proportion to the data:

- `prepare_change` (beside the running scan, in another thread): refuses configuration or type
  changes, builds the new program (namespace, instances, FB_init; a large array a chunk at a time)
  and plans, from the types alone, how every variable is carried over (`Carry`);
- `apply_change` (at one scan boundary): runs the plan, which costs per variable, not per element:
  a variable of an elementary type is copied, an array of elementary values whose type is unchanged
  is moved (the running program's list becomes the new program's), structures and blocks are
  carried member by member; only an array of structures or blocks is carried element by element.
  References are re-aimed at the new objects (relink.py), the new program is installed, and what
  the old program leaves behind is released in the background, a chunk at a time.

All or nothing: whatever fails leaves the old program and its state as they were.
"""

from __future__ import annotations

import contextlib
import queue
import sys
import threading
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, NamedTuple

from ..model import types as T
from ..model.compiled import CompiledProgram
from .build import Build, build, install
from .faults import PLCStartError, fault_from_exception
from .relink import relink
from .values import from_python, to_python

if TYPE_CHECKING:
    from .plc import PLC

_SKIP = ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP", "VAR_STAT")
RELEASE_CHUNK = 1 << 15  # elements of a left-behind list freed at a time, in the background
YIELD_EVERY = 1 << 10  # objects visited in the background between two hand-overs to the scan
SWITCH_BESIDE_S = 0.0005  # the interpreter's switch interval while work runs beside the scan


_switch_lock = threading.Lock()
_switch_users = 0
_switch_saved = 0.005


@contextlib.contextmanager
def beside_the_scan() -> Iterator[None]:
    """Work in another thread beside the running scan (building a change, freeing what one left):
    the two share the interpreter, which then hands over every 0.5 ms rather than every 5 ms, so
    that a job waits at most that long for it."""
    global _switch_users, _switch_saved
    with _switch_lock:
        if _switch_users == 0:
            _switch_saved = sys.getswitchinterval()
            sys.setswitchinterval(min(_switch_saved, SWITCH_BESIDE_S))
        _switch_users += 1
    try:
        yield
    finally:
        with _switch_lock:
            _switch_users -= 1
            if _switch_users == 0:
                sys.setswitchinterval(_switch_saved)


class OnlineChangeRefused(ValueError):
    """An online change that cannot be applied; the running program and its state are untouched."""

    def __init__(self, reasons: list[str]):
        super().__init__("online change refused, the old program keeps running:\n  " + "\n  ".join(reasons))
        self.reasons = list(reasons)


STALE = "the running program changed while this change was built (it is built again)"


class Change:
    """An online change made ready beside the running program: the new build and its carry plan."""

    def __init__(self, b: Build, carry: Carry, base: Any = None):
        self.build = b
        self.carry = carry
        self.base = base  # the program it was planned against (a change to another is stale)


def prepare_change(plc: PLC, compiled: CompiledProgram) -> Change:
    problems = _change_problems(plc, compiled)
    if problems:
        raise OnlineChangeRefused(problems)
    try:
        b = build(
            compiled, plc.image, cycle=plc.cycle, watchdog=plc.watchdog, policy=plc.policy_name, what="online change"
        )
    except PLCStartError as e:
        raise OnlineChangeRefused([f"the new program cannot start: {e}"]) from None
    releaser()  # running before the swap, which only hands it work
    return Change(b, Carry(plc, b), plc.compiled)


def apply_change(plc: PLC, change: Change | Build) -> str:
    if isinstance(change, Build):  # built by a caller of its own: plan now
        change = Change(change, Carry(plc, change))
    b = change.build
    if change.base is not None and change.base is not plc.compiled:
        # another change (an edit, the native build) came in while this one was built: its carry
        # plan is for a program that no longer runs
        raise OnlineChangeRefused([STALE])
    try:
        moved = change.carry.run(plc, b)
        _relink(plc, b, moved)
    except Exception as exc:  # noqa: BLE001 - whatever fails, the old program keeps running
        reason = exc.args[0] if isinstance(exc, (ValueError, KeyError)) and exc.args else str(fault_from_exception(exc))
        raise OnlineChangeRefused([f"the state cannot be carried over: {reason}"]) from None
    # what the old program leaves (its instances, its globals, the new program's lists replaced by
    # the old ones) is kept here, so that nothing is freed at this boundary, and freed in the background
    left = [plc.instances, {g.pyname: plc.ns.get(g.pyname) for g in plc.project.globals.values()}, moved.replaced]
    kept = set(moved.replaced) | moved.still_used  # lists the new program took over or points at
    old_now = plc.ns.get("_now", 0)
    install(plc, b)
    plc.ns["_now"] = old_now
    for t in plc.tasks:
        for bd in t.outs:
            bd.publish()
    release_in_background(left, kept, moved.reclass)
    return f"online change: {len(b.instances)} instance(s) carried over"


# ---------------------------------------------------------------------------- the carry plan

# one step of an object's plan: (kind, old attribute, new attribute, detail)
#   "v"  the value itself (an elementary value, or an unchanged array of elementary values: moved)
#   "c"  an elementary value converted to a changed type (inside a structure of an array)
#   "o"  a structure or block, carried by its own plan
#   "a"  an array of structures or blocks, element by element by the element's plan
#   "m"  an array of structures whose type is unchanged: moved whole; its elements are given the
#        new program's classes in the background (the layout is the same, so either class serves)
#   "u"  a UNION: its bytes
Step = tuple[str, str, str, Any]


class Carry:
    """How every variable of the running program is carried into a new build, planned from the
    types (no value is read): program instances by name, globals by name, members by name, each
    only where its type is unchanged (a structure or block of the same name may have gained or lost
    members). `run` carries the values at the scan boundary."""

    def __init__(self, plc: PLC, b: Build):
        self._plans: dict[tuple[int, int], list[Step]] = {}
        self.new_ns = b.ns
        self.instances = [
            (key, self._object_plan(plc.instances[key][2], pou))
            for key, (_n, _o, pou) in b.instances.items()
            if key in plc.instances
        ]
        old_globals = {g.pyname: g for g in plc.project.globals.values()}
        self.globals: list[Step] = []
        for g in b.project.globals.values():
            og = old_globals.get(g.pyname)
            if og is not None:
                step = self._step(og.type, g.type, g.pyname, g.pyname, g.name)
                if step is not None:
                    self.globals.append(step)

    def run(self, plc: PLC, b: Build) -> Moved:
        """Carry the values; returns what was moved rather than copied."""
        moved = Moved()
        for key, plan in self.instances:
            _carry_object(plc.instances[key][1], b.instances[key][1], plan, moved)
        _carry_object(_Ns(plc.ns), _Ns(b.ns), self.globals, moved)
        return moved

    def _object_plan(self, ot: Any, nt: Any) -> list[Step]:
        ou, nu = T.unalias(ot), T.unalias(nt)
        key = (id(ou), id(nu))
        got = self._plans.get(key)
        if got is not None:
            return got
        plan: list[Step] = []
        self._plans[key] = plan  # a type inside itself was refused by the checker (E046)
        om, nm = _members(ou), _members(nu)
        for k, m in nm.items():
            o = om.get(k)
            if o is None:
                continue  # a new member keeps its initial value
            step = self._step(o.type, m.type, o.pyname, m.pyname, m.name)
            if step is not None:
                plan.append(step)
        return plan

    def _step(self, ot: Any, nt: Any, oname: str, nname: str, what: str) -> Step | None:
        ou, nu = T.unalias(ot), T.unalias(nt)
        if _is_link(ou) or _is_link(nu):
            return None  # references and interfaces: re-aimed by relink
        if isinstance(ou, T.ArrayType) and isinstance(nu, T.ArrayType):
            if str(ou) == str(nu) and _plain(nu):
                return ("v", oname, nname, None)  # moved whole
            if str(ou) == str(nu) and _movable(T.unalias(ou.element), T.unalias(nu.element)):
                return ("m", oname, nname, _reclass_plan(T.unalias(nu.element), self.new_ns))
            elements = self._elements(ou, nu)
            return ("a", oname, nname, elements) if elements is not None else None
        if _is_union(ou) and _is_union(nu):
            return ("u", oname, nname, None) if str(ou) == str(nu) and _same_members(ou, nu) else None
        if _is_object(ou) and _is_object(nu):
            if ou.name.lower() != nu.name.lower():
                return None
            return ("o", oname, nname, self._object_plan(ou, nu))
        if ou.is_aggregate or nu.is_aggregate:
            return None
        if str(ou) == str(nu):
            return ("v", oname, nname, None)
        return ("c", oname, nname, (ot, nt, what))

    def _elements(self, ou: T.ArrayType, nu: T.ArrayType) -> tuple[str, Any] | None:
        """How the elements of an array of structures or blocks (or of such arrays) are carried:
        ("obj", their plan) or ("arr", the inner array's); None where they cannot be."""
        if ou.dims != nu.dims:
            return None
        eu, en = T.unalias(ou.element), T.unalias(nu.element)
        if _is_object(eu) and _is_object(en) and eu.name.lower() == en.name.lower():
            return ("obj", self._object_plan(eu, en))
        if isinstance(eu, T.ArrayType) and isinstance(en, T.ArrayType):
            if str(eu) == str(en) and _plain(en):
                return ("arr", None)  # each inner array moved
            inner = self._elements(eu, en)
            return ("arr", inner) if inner is not None else None
        return None


class _Ns:
    """A namespace's globals as attributes, so that they are carried like members."""

    __slots__ = ("d",)

    def __init__(self, d: dict[str, Any]):
        self.d = d

    def get(self, name: str) -> Any:
        return self.d[name]

    def put(self, name: str, v: Any) -> None:
        self.d[name] = v


def _get(obj: Any, name: str) -> Any:
    return obj.get(name) if isinstance(obj, _Ns) else getattr(obj, name)


def _put(obj: Any, name: str, v: Any) -> None:
    if isinstance(obj, _Ns):
        obj.put(name, v)
    else:
        setattr(obj, name, v)


class Moved:
    """What the carry moved rather than copied: `replaced` (id of a running program's list that the
    new one took over → the new build's own list, freed in the background), `reclass` (arrays of
    structures moved whole, with the plan that gives their elements the new program's classes)."""

    def __init__(self) -> None:
        self.replaced: dict[int, Any] = {}
        self.reclass: list[tuple[list[Any], Any]] = []
        self.still_used: set[int] = set()  # old objects a reference of the new program points at
        self._elements: set[int] | None = None

    def holds(self, obj: Any) -> bool:
        """Is `obj` an element of an array moved whole (a reference to it stays as it is)?"""
        if self._elements is None:  # built when a reference first asks: most programs never do
            self._elements = {id(e) for arr, _plan in self.reclass for e in _objects_in(arr, _plan)}
        return id(obj) in self._elements


def _carry_object(old: Any, new: Any, plan: list[Step], moved: Moved) -> None:
    for kind, oname, nname, detail in plan:
        v = _get(old, oname)
        if kind == "v":
            if isinstance(v, list):  # an array moved whole: the new build's list goes
                moved.replaced[id(v)] = _get(new, nname)
            _put(new, nname, v)
        elif kind == "o":
            _carry_object(v, _get(new, nname), detail, moved)
        elif kind == "a":
            _put(new, nname, _carry_array(v, _get(new, nname), detail, moved))
        elif kind == "m":
            moved.replaced[id(v)] = _get(new, nname)
            moved.reclass.append((v, detail))
            _put(new, nname, v)
        elif kind == "u":
            _get(new, nname)._b[:] = v._b
        else:  # "c": converted, range-checked as a write of the new type would be
            ot, nt, what = detail
            _put(new, nname, from_python(to_python(v, ot), nt, what))


def _carry_array(old: list[Any], new: list[Any], elements: tuple[str, Any], moved: Moved) -> list[Any]:
    """An array of structures or blocks, element by element; returns the array the new program keeps."""
    kind, detail = elements
    if kind == "obj":
        for o, n in zip(old, new):
            _carry_object(o, n, detail, moved)
        return new
    for i, (o, n) in enumerate(zip(old, new)):  # the elements are arrays
        if detail is None:  # of elementary values: each moved whole
            moved.replaced[id(o)] = n
            new[i] = o
        else:
            new[i] = _carry_array(o, n, detail, moved)
    return new


def _movable(eu: Any, en: Any) -> bool:
    """A structure (or UNION) type unchanged in every member, with no reference or block inside: its
    values can stay the objects they are, the new program's class differing only by its identity."""
    if not (isinstance(eu, T.StructType) and isinstance(en, T.StructType)):
        return False
    if eu.name.lower() != en.name.lower() or eu.kind != en.kind or not _same_members(eu, en):
        return False
    for m in en.members.values():
        mu = T.unalias(m.type)
        while isinstance(mu, T.ArrayType):
            mu = T.unalias(mu.element)
        if _is_link(mu) or isinstance(mu, T.POUType):
            return False
        if isinstance(mu, T.StructType) and not _movable(mu, mu):
            return False
    return True


def _reclass_plan(st: Any, ns: dict[str, Any]) -> tuple[Any, list[tuple[str, Any]]]:
    """(the new program's class of structure `st`, [(member, its plan)] for members holding structures)."""
    inner = []
    for m in st.members.values():
        mu = T.unalias(m.type)
        while isinstance(mu, T.ArrayType):
            mu = T.unalias(mu.element)
        if isinstance(mu, T.StructType):
            inner.append((m.pyname, _reclass_plan(mu, ns)))
    return ns[st.pyname], inner


def _objects_in(arr: list[Any], plan: tuple[Any, list[tuple[str, Any]]]) -> list[Any]:
    """The structure objects of a moved array, those nested in them included."""
    out = []
    stack: list[tuple[Any, Any]] = [(e, plan) for e in arr]
    while stack:
        x, (_cls, inner) = stack.pop()
        if isinstance(x, list):
            stack.extend((e, (_cls, inner)) for e in x)
            continue
        out.append(x)
        for name, sub in inner:
            stack.append((getattr(x, name), sub))
    return out


def _reclass(arr: list[Any], plan: tuple[Any, list[tuple[str, Any]]]) -> None:
    """Give the elements of a moved array (and the structures inside them) the new program's class,
    a chunk at a time: the same layout, so the program reads them alike before and after."""
    stack: list[tuple[Any, Any]] = [(arr, plan)]
    n = 0
    while stack:
        x, (cls, inner) = stack.pop()
        if isinstance(x, list):
            stack.extend((e, (cls, inner)) for e in x)
            continue
        if type(x) is not cls:
            try:
                x.__class__ = cls
            except TypeError:  # a layout Python will not swap: the old class serves as well, by name
                pass
        for name, sub in inner:
            stack.append((getattr(x, name), sub))
        n += 1
        if n % YIELD_EVERY == 0:
            time.sleep(0)


def _members(t: Any) -> dict[str, Any]:
    if isinstance(t, T.StructType):
        return dict(t.members)
    return {k: s for k, s in t.vars.items() if s.section not in _SKIP}


def _is_link(u: Any) -> bool:
    return isinstance(u, T.RefType) or (isinstance(u, T.POUType) and u.pou_kind == "INTERFACE")


def _is_union(u: Any) -> bool:
    return isinstance(u, T.StructType) and u.kind == "union"


def _is_object(u: Any) -> bool:
    return (isinstance(u, T.StructType) and u.kind != "union") or (
        isinstance(u, T.POUType) and u.pou_kind in ("FUNCTION_BLOCK", "PROGRAM")
    )


def _plain(u: Any) -> bool:
    """Elementary values, or arrays of them (at any depth): moved whole when the type is unchanged."""
    u = T.unalias(u)
    if isinstance(u, T.ArrayType):
        return _plain(u.element)
    return not u.is_aggregate and not _is_link(u)


def _same_members(a: Any, b: Any) -> bool:
    return [(k, str(m.type)) for k, m in a.members.items()] == [(k, str(m.type)) for k, m in b.members.items()]


def _relink(plc: PLC, b: Build, moved: Moved) -> None:
    """Interface variables and references still point into the old objects: re-aim them."""
    old_globals = {g.pyname: g for g in plc.project.globals.values()}
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
        moved.replaced,
        moved.holds,
        moved.still_used,
    )


# ---------------------------------------------------------------------------- releasing what is left


class _Hold(NamedTuple):
    reached: threading.Event  # the releaser waits at the hold
    go: threading.Event  # and goes on when this is set


class _Releaser:
    """One background thread per process that frees what online changes leave behind (started
    beside the scan, when a change is prepared: starting a thread at the swap would make the scan
    wait for it to run)."""

    def __init__(self) -> None:
        self.queue: queue.SimpleQueue[tuple[list[Any], set[int], list[tuple[list[Any], Any]]]] = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._loop, name="st-online-change-release", daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        while True:
            job = self.queue.get()
            if isinstance(job, threading.Event):
                job.set()
                continue
            if isinstance(job, _Hold):
                job.reached.set()
                job.go.wait()
                continue
            try:
                with beside_the_scan():
                    _release(*job)
            except Exception:  # noqa: BLE001 - what is left is then freed the ordinary way; the thread goes on
                continue

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Nothing handed over while the block runs is released before it ends (tests: what an
        online change leaves to the background, seen before the background does it)."""
        hold = _Hold(threading.Event(), threading.Event())
        self.queue.put(hold)  # type: ignore[arg-type]
        hold.reached.wait(30.0)
        try:
            yield
        finally:
            hold.go.set()

    def flush(self, timeout: float = 30.0) -> bool:
        """Wait until what was handed over so far is released (tests, an orderly exit)."""
        done = threading.Event()
        self.queue.put(done)  # type: ignore[arg-type]
        return done.wait(timeout)


_releaser: _Releaser | None = None
_releaser_lock = threading.Lock()


def releaser() -> _Releaser:
    global _releaser
    with _releaser_lock:
        if _releaser is None:
            _releaser = _Releaser()
        return _releaser


def release_in_background(left: list[Any], kept: set[int], reclass: list[tuple[list[Any], Any]] | None = None) -> None:
    """After a swap, in the background: give the elements of moved arrays of structures the new
    program's classes, then free what the old program leaves behind without holding the scan (its
    large lists emptied a chunk at a time, then the rest dropped). `kept`: ids of lists the new
    program took over, which are left alone."""
    releaser().queue.put((left, kept, reclass or []))


def _release(left: list[Any], kept: set[int], reclass: list[tuple[list[Any], Any]]) -> None:
    for arr, plan in reclass:
        _reclass(arr, plan)
    for big in _large_lists(left, kept):
        while big:
            del big[-RELEASE_CHUNK:]
            time.sleep(0)  # hand over between chunks
    while left:  # the rest, a root at a time
        left.pop()
        time.sleep(0)
    reclass.clear()


def _large_lists(roots: list[Any], kept: set[int]) -> list[list[Any]]:
    """The lists of more than RELEASE_CHUNK elements reachable from `roots` through instances,
    structures, dicts and lists (not through references), except `kept`."""
    found: list[list[Any]] = []
    seen: set[int] = set()
    stack: list[Any] = list(roots)
    while stack:
        x = stack.pop()
        if id(x) in seen or id(x) in kept:
            continue
        seen.add(id(x))
        if len(seen) % YIELD_EVERY == 0:
            time.sleep(0)
        if isinstance(x, list):
            if len(x) > RELEASE_CHUNK:
                found.append(x)
            if x and not isinstance(x[0], (int, float, str, bool, bytes)):
                stack.extend(x)
        elif isinstance(x, dict):
            stack.extend(x.values())
        elif isinstance(x, tuple):
            stack.extend(x)
        else:
            for name in getattr(type(x), "__slots__", ()):
                if not name.startswith("_e_"):
                    stack.append(getattr(x, name, None))
    return found


# ---------------------------------------------------------------------------- what cannot change


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
