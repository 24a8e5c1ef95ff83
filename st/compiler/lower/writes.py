"""Who else may write an instance's variables while one of its bodies runs.

Two choices of code generation rest on it: an instance's variables are kept in Python locals
during its body (codegen/pous.py, "cached"), and a FOR whose body does not write its counter runs
as a Python `for` (loops.py, "range"). Both are right only if nothing but the body's own statements
writes those variables meanwhile. The body's text shows its own writes (check/rules/for_counter.py);
this module adds what the text cannot show, from the whole project:

- a call of a method, action or property of the same instance (THIS), or THIS handed to a call;
- for an instance that other code can name or point at ("reached": a global holds one, a
  REFERENCE/POINTER/REF_TO or an interface may lead to one, THIS is used in its code, a variable
  holding one has its address taken or is a VAR_IN_OUT): any code that writes through a global, a
  pointer, a reference, an interface or a VAR_IN_OUT ("reaching"), called directly or further down.

It errs on the safe side: what it cannot rule out, it assumes; the price is speed, never a value.
"""

from __future__ import annotations

from ...model import types as T
from ...model.program import Project
from .. import ast as A
from ..check import ActionCall, FbCall, FunctionCall, MethodCall
from ..syntax import action_of, decl_of


class Writes:
    """The project-wide facts, computed once per compilation (lower())."""

    def __init__(self, project: Project):
        self.project = project
        self._contained: dict[int, frozenset] = {}
        self._facts: dict[int, tuple[list, _Facts]] = {}
        self._by_name = _callables(project)
        self.reaching = self._reaching()
        self.reached = self._reached()

    # ------------------------------------------------------------------ the questions
    def shared(self, body: list, block: T.POUType | None) -> bool:
        """May code that `body` runs (its calls) write the variables of the instance of `block` it
        runs on, or may the body write them through another path? (`block` None: a FUNCTION or a
        unit test, which has no instance.)"""
        if block is None:
            return False
        f = self.facts(body)
        if f.own:
            return True
        if id(block) not in self.reached:
            return False
        return f.direct or bool(f.callees & self.reaching)

    def in_outs_aliased(self, fn: T.POUType) -> bool:
        """May a FUNCTION's or METHOD's VAR_IN_OUT be written another way while it runs (then it
        is used through the caller's reference, not copied in and out)? When it has two parameters
        that may name one variable (VAR_IN_OUT, REFERENCE TO), when its body reaches a global, a
        pointer, a reference or an interface or calls code that does, and for a METHOD when its
        body uses its instance (the caller may have passed one of its variables)."""
        by_ref = [p for p in fn.params() if p.section == "VAR_IN_OUT" or T.is_reference(p.type)]
        if (
            fn.library
            or fn.decl is None
            or not any(p.section == "VAR_IN_OUT" and not T.unalias(p.type).is_aggregate for p in by_ref)
        ):
            return False
        if len(by_ref) > 1:
            return True
        f = self.facts(decl_of(fn).body)
        if f.direct or f.callees & self.reaching:
            return True
        return fn.owner_fb is not None and (f.own or any(sym.owner is not fn for sym in f.variables))

    def facts(self, body: list) -> _Facts:
        """What one statement list does, in one walk (kept per list)."""
        got = self._facts.get(id(body))
        if got is None:
            got = self._facts[id(body)] = (body, _Facts(body, self._by_name))  # the list kept: its id stays its
        return got[1]

    # ------------------------------------------------------------------ reaching code
    def _reaching(self) -> set:
        """Callables (by key) whose run may write variables other than their own through a
        global, a pointer, a reference or an interface, themselves or in what they call."""
        calls = {key: self.facts(body) for key, body in self._all_bodies()}
        out = {key for key, f in calls.items() if f.direct}
        changed = True
        while changed:
            changed = False
            for key, f in calls.items():
                if key not in out and f.callees & out:
                    out.add(key)
                    changed = True
        return out

    def _all_bodies(self):
        """(key, body) of every user body: POUs, methods, actions, property accessors."""
        for pou in self.project.pous.values():
            if pou.decl is None or pou.library:
                continue
            yield id(pou), getattr(pou.decl, "body", None) or []
            for key in pou.actions:
                act = action_of(pou, key)
                yield id(act), act.body
            for mt in pou.methods.values():
                if mt.decl is not None and mt.owner_fb is pou:
                    yield id(mt), decl_of(mt).body
            for ps in pou.properties.values():
                for acc in (ps.get, ps.set):
                    if acc is not None and acc.decl is not None and ps.owner is pou:
                        yield id(acc), decl_of(acc).body

    # ------------------------------------------------------------------ reached instances
    def _reached(self) -> set:
        """Block types (by id) an instance of which other code may name or point at while its body
        runs; a derived block is reached where its base is pointed at."""
        out: set[int] = set()
        for g in self.project.globals.values():
            out |= self._blocks_in(g.type)
        for sym in self._all_vars():
            if sym.address_taken or sym.section == "VAR_IN_OUT":
                out |= self._blocks_in(sym.type)
            u = T.unalias(sym.type)
            if isinstance(u, T.RefType):
                out |= self._blocks_in(u.target)
        for pou in self.project.pous.values():
            if pou.pou_kind in ("FUNCTION_BLOCK", "PROGRAM") and (pou.interfaces or self._mentions_this(pou)):
                out.add(id(pou))
        for _key, body in self._all_bodies():  # a program's variables named from outside: Prg.var
            out |= self.facts(body).programs_named
        # a base's body and methods run on its derived instances, a reference to a base may lead
        # to a derived instance: one reached block makes its whole family reached
        families: dict[int, set] = {}
        for pou in self.project.pous.values():
            if pou.pou_kind == "FUNCTION_BLOCK":
                root = pou
                while isinstance(root.base, T.POUType):
                    root = root.base
                families.setdefault(id(root), set()).add(id(pou))
        for family in families.values():
            if family & out:
                out |= family
        return out

    def _mentions_this(self, pou: T.POUType) -> bool:
        """THIS or SUPER in the body, a method, an action or an accessor of a user block."""
        if pou.library or pou.decl is None:
            return False
        lists = [getattr(pou.decl, "body", None) or []]
        lists += [action_of(pou, key).body for key in pou.actions]
        lists += [decl_of(mt).body for mt in pou.methods.values() if mt.decl is not None]
        lists += [decl_of(acc).body for ps in pou.properties.values() for acc in (ps.get, ps.set) if acc and acc.decl]
        return any(self.facts(body).this for body in lists)

    def _blocks_in(self, t: T.Type) -> frozenset:
        """The block types whose instances a value of type `t` holds (itself, members, elements)."""
        u = T.unalias(t)
        key = id(u)
        got = self._contained.get(key)
        if got is not None:
            return got
        self._contained[key] = frozenset()  # a type inside itself was refused by the checker (E046)
        out: set = set()
        if isinstance(u, T.POUType) and u.pou_kind in ("FUNCTION_BLOCK", "PROGRAM"):
            out.add(key)
            for v in u.vars.values():
                if v.section not in ("VAR_EXTERNAL", "VAR_TEMP", "VAR_IN_OUT"):
                    out |= self._blocks_in(v.type)
        elif isinstance(u, T.POUType) and u.pou_kind == "INTERFACE":
            out |= {id(p) for p in self.project.pous.values() if T.implements(p, u)}
        elif isinstance(u, T.ArrayType):
            out |= self._blocks_in(u.element)
        elif isinstance(u, T.StructType):
            for m in u.members.values():
                out |= self._blocks_in(m.type)
        got = self._contained[key] = frozenset(out)
        return got

    def _all_vars(self):
        for pou in self.project.pous.values():
            yield from pou.vars.values()
            for mt in pou.methods.values():
                yield from mt.vars.values()
        for t in self.project.types.values():
            u = T.unalias(t)
            if isinstance(u, T.StructType):
                for m in u.members.values():
                    yield T.VarSym(m.name, m.type, "VAR", m.span)


class _Facts:
    """One statement list in one walk: `own` (THIS or SUPER, or a method, action or property of
    its own instance called), `this` (THIS or SUPER), `direct` (it reaches beyond its own
    variables: a global or VAR_EXTERNAL, a reference, pointer or interface, a program's variable
    named from outside; a VAR_IN_OUT leads only to what its caller passed, which the caller's own
    analysis sees at the call), `callees` (the keys of the user bodies it may run: blocks and
    functions called, methods, actions and accessors of that name anywhere, since an override or
    an interface's implementation may be what runs), `programs_named`, `variables` (used)."""

    __slots__ = ("own", "this", "direct", "callees", "programs_named", "variables")

    def __init__(self, body: list, by_name: dict):
        own = this = direct = False
        callees: set = set()
        programs: set = set()
        variables: set = set()
        for n in A.walk_nodes(body):
            if isinstance(n, A.Name):
                sym = n.sym
                if getattr(sym, "kind", "") in ("this", "super"):
                    own = this = True
                elif isinstance(sym, T.VarSym):
                    variables.add(sym)
                    u = T.unalias(sym.type)
                    if (
                        sym.is_global
                        or sym.section in ("VAR_EXTERNAL", "VAR_STAT")
                        or isinstance(u, T.RefType)
                        or (isinstance(u, T.POUType) and u.pou_kind == "INTERFACE")
                    ):
                        direct = True
                elif isinstance(sym, T.POUType) and sym.pou_kind == "PROGRAM":
                    direct = True
                    programs.add(id(sym))
            elif isinstance(n, A.Deref):
                direct = True
            elif isinstance(n, A.Call):
                match n.target:
                    case FbCall(pou=pou) | FunctionCall(pou=pou):
                        callees.add(id(pou))
                    case MethodCall(pou=mt, obj=obj):
                        callees |= by_name.get(("method", mt.name.lower()), set())
                        own = own or obj is None
                    case ActionCall(name=act, inst=inst):
                        callees |= by_name.get(("action", act), set())
                        own = own or inst is None
            elif isinstance(n, A.AccessorCall) and n.accessor is not None:
                callees |= by_name.get(("accessor", n.accessor.name.lower()), set())
                own = own or n.obj is None
        self.own, self.this, self.direct = own, this, direct
        self.callees, self.programs_named, self.variables = frozenset(callees), frozenset(programs), variables


def _callables(project: Project) -> dict:
    """("method" | "action" | "accessor", lower name) → the keys of every user body of that name."""
    out: dict = {}
    for pou in project.pous.values():
        if pou.library:
            continue
        for name, act in pou.actions.items():
            if act is not None:
                out.setdefault(("action", name.lower()), set()).add(id(act))
        for mt in pou.methods.values():
            if mt.decl is not None and mt.owner_fb is pou:
                out.setdefault(("method", mt.name.lower()), set()).add(id(mt))
        for ps in pou.properties.values():
            for acc in (ps.get, ps.set):
                if acc is not None and acc.decl is not None and ps.owner is pou:
                    out.setdefault(("accessor", acc.name.lower()), set()).add(id(acc))
    return out
