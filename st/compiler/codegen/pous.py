"""POUs: FUNCTIONs → Python functions; FUNCTION_BLOCKs and PROGRAMs → slotted classes."""

from __future__ import annotations

import ast as py
from typing import TYPE_CHECKING, cast

from ...model import types as T
from .. import ast as A
from ..check.rules.initialization_order import Step, late_default
from ..lower.fb_init import Constructor
from ..lower.walk import walk_stmts
from ..names import mangle
from ..syntax import decl_of
from .expressions import InitGen
from .facts import BodyFacts, Local, attach, recording
from .pyast import _args, _attr, _call, _const, _name, _set_lines, _store
from .statements import StmtGen, _by_ref_names, _walk_exprs_in

if TYPE_CHECKING:
    from .module import ModuleGen


class FuncGen(StmtGen):
    pou: T.POUType
    facts_kind = "function"  # BodyFacts.kind

    def __init__(self, mod: ModuleGen, pou: T.POUType):
        super().__init__(mod, pou)
        self.self_name = None
        self.result_name = mangle_result(pou)
        self.param_facts: list[tuple[str, T.Type | None]] = []

    def function(self) -> py.FunctionDef:
        """The Python function, with its facts (facts.py): the variables it holds in locals and
        their IEC types, its parameters, and what `recording` notes while it is printed."""
        facts = BodyFacts(self.facts_kind)
        with recording(facts):
            fn = self._function()
        pou = self.pou
        held = self.cached if self.self_name is not None else set(pou.vars.values())
        for v in held:
            if v.section in _LOCAL_SECTIONS and v not in self.boxed and v.pyname:
                facts.locals[v.pyname] = Local(v.type, v.section)
        if pou.return_type is not None and not self._result_boxed():
            facts.locals[self.result_name] = Local(pou.return_type, "RESULT")
        facts.params = self.param_facts
        return attach(fn, facts)

    def _function(self) -> py.FunctionDef:
        pou = self.pou
        d = decl_of(pou)
        by_ref = _by_ref_names(d.body)
        # (a method's VAR_INST lives in the instance, not in a local: it is reached as an attribute)
        self.boxed = {
            v for v in by_ref if v.owner is pou and v.section != "VAR_INST" and not T.unalias(v.type).is_aggregate
        }
        self.boxed |= {
            v
            for v in pou.vars.values()
            if v.address_taken
            and v.owner is pou
            and v.section in ("VAR", "VAR_TEMP", "VAR_INPUT", "VAR_OUTPUT")
            and not T.unalias(v.type).is_aggregate
        }
        # an in-out whose address is taken (REF=, REF, ADR) is used through the caller's reference
        # itself (it works as the one-element box), so a reference made here outlives the call; so
        # is every in-out when the variable behind it may be written another way meanwhile
        # (lower/writes.py), as CODESYS's references see such a write
        aliased = self.mod.writes.in_outs_aliased(pou)
        through = {
            p
            for p in pou.params()
            if p.section == "VAR_IN_OUT" and (p.address_taken or aliased) and not T.unalias(p.type).is_aggregate
        }
        self.boxed |= through
        self.through = through
        params: list[str] = []
        prologue: list[py.stmt] = []
        epilogue: list[py.stmt] = []

        def box(v, value):
            return py.Assign([_name(v.pyname, py.Store())], py.List([value], py.Load()) if v in self.boxed else value)

        def unbox(v):
            return self.var_load(v)

        for p in pou.params():
            if p.section == "VAR_INPUT":
                params.append(p.pyname)
                if p in self.boxed:
                    prologue.append(box(p, _name(p.pyname)))
            elif p.section == "VAR_IN_OUT":
                if T.unalias(p.type).is_aggregate:
                    params.append(p.pyname)
                elif p in through:
                    params.append(p.pyname)
                else:
                    params.append("_r_" + p.pyname)
                    prologue.append(box(p, _call(_attr(_name("_r_" + p.pyname), "get"))))
                    epilogue.append(py.Expr(_call(_attr(_name("_r_" + p.pyname), "set"), unbox(p))))
            else:
                params.append("_r_" + p.pyname)
                prologue.append(box(p, InitGen(self.mod).initial(p.type, p.init)))
                epilogue.append(
                    py.If(
                        py.Compare(_name("_r_" + p.pyname), [py.IsNot()], [_const(None)]),
                        [py.Expr(_call(_attr(_name("_r_" + p.pyname), "set"), unbox(p)))],
                        [],
                    )
                )
        locals_init = []
        if pou.return_type is not None:
            locals_init.append(self.result_init(InitGen(self.mod).initial(pou.return_type, None)))
        steps = self.mod.initial_orders.get(pou)
        if steps is None:
            for v in pou.vars.values():
                if v.section in ("VAR", "VAR_TEMP"):
                    locals_init.append(_set_lines(box(v, InitGen(self.mod).initial(v.type, v.init)), v.span.line))
        else:  # initial values that name the function's variables (lower/initial_values.py)
            init = InitGen(self.mod, gen=self)
            for step in steps:
                v = step.var
                if v.section == "VAR_INPUT":  # its default, where the caller omitted it
                    if step.part != "create":
                        value = init.initial(v.type, v.init)
                        late = py.Compare(self.var_load(v), [py.Is()], [_name("_LATE")])
                        locals_init.append(_set_lines(py.If(late, [box(v, value)], []), v.span.line))
                elif step.part == "construct":
                    ut, ctor = cast(T.POUType, T.unalias(v.type)), cast(A.CtorInit, v.init)
                    made = init.constructed_later(self.var_load(v), ut, ctor)
                    locals_init.append(_set_lines(py.Expr(made), v.span.line))
                else:
                    value = init.initial(v.type, v.init, construct=step.part == "all")
                    locals_init.append(_set_lines(box(v, value), v.span.line))
        body = self.stmts(d.body)
        ret = py.Return(self.result_load() if pou.return_type is not None else None)
        end_line = d.end_span.line if d.end_span else d.span.line
        _set_lines(ret, end_line)
        main = prologue + locals_init + body + [ret]
        if epilogue:
            main = [py.Try(prologue + locals_init + body + [ret], [], [], _lines(epilogue, end_line))]
        gl = sorted(self.globals_written)
        if gl:
            main.insert(0, py.Global(gl))
        # BodyFacts.params: the IEC type of a parameter that receives a value (not a reference or a box)
        by_value = {
            p.pyname: p.type
            for p in pou.params()
            if p.section == "VAR_INPUT" and p not in self.boxed and not late_default(p)  # (_LATE: an object)
        }
        self.param_facts = [(name, by_value.get(name)) for name in params]
        fn = py.FunctionDef(pou.pyname, _args(params), main, [], None, None)
        return _set_lines(fn, d.span.line)


class MethodGen(FuncGen):
    """A METHOD: a function of the instance (`self`); its own variables are Python locals, the
    instance's are attributes."""

    facts_kind = "method"  # BodyFacts.kind

    def __init__(self, mod: ModuleGen, mt: T.POUType):
        super().__init__(mod, mt)
        self.self_name = "self"

    def _function(self) -> py.FunctionDef:
        mt = self.pou
        by_ref = _by_ref_names(decl_of(mt).body)
        boxed = {v for v in by_ref if v.owner is mt and not T.unalias(v.type).is_aggregate}
        boxed |= {
            v for v in mt.vars.values() if v.address_taken and v.owner is mt and not T.unalias(v.type).is_aggregate
        }
        self.cached = {v for v in mt.vars.values() if v not in boxed and v.section not in ("VAR_EXTERNAL", "VAR_INST")}
        fn = super()._function()
        fn.args.args.insert(0, _set_lines(py.arg("self"), decl_of(mt).span.line))
        return fn


# the sections of a POU's variables that a function holds in Python locals (when not boxed)
_LOCAL_SECTIONS = frozenset(("VAR", "VAR_TEMP", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"))


def _mentions_this(body) -> bool:
    """THIS or SUPER in a body: other code then works on the instance while it runs."""
    return any(isinstance(e, A.Name) and getattr(e.sym, "kind", "") in ("this", "super") for e in _walk_exprs_in(body))


def _lines(nodes, line):
    for n in nodes:
        _set_lines(n, line)
    return nodes


def mangle_result(pou: T.POUType) -> str:
    return mangle(pou.name)


# ====================================================================== FB / program classes


class BodyGen(StmtGen):
    pou: T.POUType

    def __init__(self, mod: ModuleGen, pou: T.POUType):
        super().__init__(mod, pou)

    def klass(self) -> py.ClassDef | list[py.stmt]:
        """The block's class; with an SFC, the SFC's description first, then the class."""
        pou = self.pou
        block = self.mod.blocks[pou]
        d = decl_of(pou)
        init = InitGen(self.mod, pou)
        sfc = self.mod.p.sfc.get(pou.name.lower())
        slots = [v.pyname for v in block.variables]
        edges = [v for v in pou.vars.values() if v.edge]
        slots += ["_e_" + v.pyname for v in edges]
        init_body: list[py.stmt] = []
        steps = self.mod.initial_orders.get(pou)
        for step in steps if steps is not None else [Step(v) for v in block.variables]:
            v = step.var
            if step.part == "construct":  # FB_init with arguments that name variables (lower/initial_values.py)
                ut, ctor = cast(T.POUType, T.unalias(v.type)), cast(A.CtorInit, v.init)
                made = init.constructed_later(_attr(_name("self"), v.pyname), ut, ctor)
                init_body.append(_set_lines(py.Expr(made), v.span.line))
                continue
            value = init.initial(v.type, v.init, construct=step.part == "all")
            if v in self.mod.unbound_in_outs:
                value = _const(None)  # a VAR_IN_OUT that __ISVALIDREF tests: unbound until a call gives it
            init_body.append(_set_lines(py.Assign([_attr(_name("self"), v.pyname, py.Store())], value), v.span.line))
        for v in edges:
            init_body.append(
                _set_lines(
                    py.Assign([_attr(_name("self"), "_e_" + v.pyname, py.Store())], _const(v.edge == "F_EDGE")),
                    v.span.line,
                )
            )
        for v in block.method_variables:  # METHOD VAR_INST: attributes of the instance
            slots.append(v.pyname)
            init_body.append(
                _set_lines(
                    py.Assign([_attr(_name("self"), v.pyname, py.Store())], init.initial(v.type, v.init)), v.span.line
                )
            )
        if sfc is not None:
            slots += ["_sfc", "_sfc_x"]
            init_body.append(
                _set_lines(
                    py.Assign(
                        [_attr(_name("self"), "_sfc", py.Store())], _call("_SfcState", _name("_sfc_" + pou.pyname))
                    ),
                    d.span.line,
                )
            )
            init_body.append(
                _set_lines(
                    py.Assign([_attr(_name("self"), "_sfc_x", py.Store())], _attr(_attr(_name("self"), "_sfc"), "x")),
                    d.span.line,
                )
            )
        members = [
            py.Assign([_name("__slots__", py.Store())], py.Tuple([_const(s) for s in slots], py.Load())),
            py.Assign([_name("_kinds", py.Store())], _const(block.kinds)),
            py.FunctionDef("__init__", _args(["self"]), init_body or [py.Pass()], [], None, None),
        ]
        if pou.library:  # a library's own block (a project's block of the same name keeps its own body)
            members.insert(2, py.Assign([_name("_from_library", py.Store())], _const(True)))
        # caching policy: with actions, methods, THIS or SFC, or when code the body calls may reach
        # the instance another way (lower/writes.py), other code touches the variables during the
        # body: keep them attributes
        can_cache = (
            not pou.actions
            and sfc is None
            and not pou.methods
            and not pou.properties
            and not _mentions_this(d.body)
            and not self.mod.writes.shared(d.body, pou)
        )
        if sfc is not None:
            run = py.Expr(_call(_attr(_attr(_name("self"), "_sfc"), "run"), _name("self"), _name("_now")))
            sfc_body = py.FunctionDef("_body", _args(["self"]), [run], [], None, None)
            members.append(attach(_set_lines(sfc_body, d.span.line), BodyFacts("body")))
        else:
            body_fn = self.method(
                "_body", d.body, can_cache, edges, d.span.line, d.end_span.line if d.end_span else d.span.line
            )
            members.append(body_fn)
            if d.span.file in self.mod.inline_files and not self.mod.coverage:
                self.mod.inline_candidates[pou] = body_fn
        if block.constructor is not None:
            members.append(self._constructor(block.constructor, d.span.line))
        for act in block.actions:  # its own and inherited ones
            g = BodyGen(self.mod, pou)
            members.append(g.method("_act_" + act.name.lower(), act.body, False, [], act.span.line, act.span.line))
        for mt in block.methods:
            members.append(MethodGen(self.mod, mt).function())
        for acc in block.accessors:
            members.append(MethodGen(self.mod, acc).function())
        if sfc is not None:
            members.extend(self.sfc_methods(sfc))
        cls = py.ClassDef(pou.pyname, [_name("_FB")], [], members, [])
        _set_lines(cls, d.span.line)
        if sfc is not None:
            return [self.sfc_desc(sfc), cls]
        return cls

    def sfc_desc(self, sfc) -> py.stmt:
        pou = self.pou
        initial = next((s.index for s in sfc.steps if s.initial), 0)
        trans = tuple((tuple(t.sources), tuple(t.targets), f"_tr_{t.index}") for t in sfc.transitions)
        steps = []
        for s in sfc.steps:
            assoc = []
            for i, (act, q, texpr) in enumerate(s.actions):
                assoc.append((sfc.action_index[act], q, f"_at_{s.index}_{i}" if texpr is not None else ""))
            steps.append(tuple(assoc))
        actions = []
        for name in sfc.actions:
            if name in pou.actions:
                actions.append(("act", "_act_" + name))
            else:
                actions.append(("var", pou.vars[name].pyname))
        desc = _call(
            "_SfcDesc",
            _const(len(sfc.steps)),
            _const(initial),
            _const(trans),
            _const(tuple(steps)),
            _const(tuple(actions)),
        )
        return _set_lines(py.Assign([_name("_sfc_" + pou.pyname, py.Store())], desc), decl_of(pou).span.line)

    def _constructor(self, ctor: Constructor, line: int) -> py.FunctionDef:
        """_ctor(self, a): every FB_init call of the constructor in turn (a: the declaration's
        arguments by lower-case name); returns the instance."""
        init = InitGen(self.mod)

        def arg(a):
            if isinstance(a, bool):
                return _const(a)
            default = _name("_LATE") if late_default(a) else init.initial(a.type, a.init)
            return _call(_attr(_name("a"), "get"), _const(a.name.lower()), default)

        body: list[py.stmt] = [
            py.Expr(
                _call(_attr(_name(c.method.owner_fb.pyname), c.method.pyname), _name("self"), *[arg(a) for a in c.args])
            )
            for c in ctor.calls
        ]
        body.append(py.Return(_name("self")))
        return _set_lines(py.FunctionDef("_ctor", _args(["self", "a"]), body, [], None, None), line)

    def method(self, name, body, can_cache, edges, line, end_line) -> py.FunctionDef:
        """The block's `_body` (or one of its actions): its variables in Python locals where
        `can_cache` allows, written back at the end."""
        facts = BodyFacts("body")
        with recording(facts):
            fn = self._method(name, body, can_cache, edges, line, end_line)
        for v in self.cached:
            facts.locals[v.pyname] = Local(v.type, v.section)
        return attach(fn, facts)

    def _method(self, name, body, can_cache, edges, line, end_line) -> py.FunctionDef:
        pou = self.pou
        by_ref = _by_ref_names(body)
        used = set()
        uses: dict = {}
        for e in _walk_exprs_in(body):
            if (
                isinstance(e, A.Name)
                and isinstance(e.sym, T.VarSym)
                and e.sym.owner is pou
                and e.sym.section != "VAR_EXTERNAL"
                and not e.sym.is_global
            ):
                used.add(e.sym)
                uses[e.sym] = uses.get(e.sym, 0) + 1
        for v in edges:
            used.add(v)
        temps = [v for v in pou.vars.values() if v.section == "VAR_TEMP"]
        if can_cache:
            # copied into Python locals (and back at the end), which pays where a loop uses them or
            # a variable is used often; in a straight-line body (most FB bodies: TON, a controller
            # step) a variable used once or twice is read and written on the instance directly
            loops = _loops_in(body)
            self.cached = {
                v for v in used if v not in by_ref and not v.address_taken and (loops or uses.get(v, 0) >= 3)
            }
        else:
            self.cached = set()
        # VAR_TEMP lives for one call: always a Python local (boxed if passed by reference)
        self.boxed = {v for v in temps if v in by_ref or v.address_taken}
        self.cached |= {v for v in temps if v not in self.boxed}
        code = self.stmts(body)
        prologue = []
        init = InitGen(self.mod)
        for v in temps:
            val = init.initial(v.type, v.init)
            prologue.append(
                py.Assign([_name(v.pyname, py.Store())], py.List([val], py.Load()) if v in self.boxed else val)
            )
        for v in sorted(self.cached, key=lambda s: s.pyname):
            if v.section == "VAR_TEMP":
                continue
            prologue.append(py.Assign([_name(v.pyname, py.Store())], _attr(_name("self"), v.pyname)))
        for v in edges:
            # an edge-declared input is TRUE only in the call that sees the edge
            prev = _attr(_name("self"), "_e_" + v.pyname)
            cur = _name(v.pyname) if v in self.cached else _attr(_name("self"), v.pyname)
            if v.edge == "R_EDGE":
                test = py.BoolOp(py.And(), [cur, py.UnaryOp(py.Not(), prev)])
            else:
                test = py.BoolOp(py.And(), [py.UnaryOp(py.Not(), cur), prev])
            prologue.append(py.Assign([prev], cur))
            prologue[-1] = py.Assign(
                [py.Tuple([_store(cur), _store(prev)], py.Store())], py.Tuple([test, cur], py.Load())
            )
        writeback = []
        for v in sorted(self.cached & self.written_locals, key=lambda s: s.pyname):
            if T.unalias(v.type).is_aggregate or v.section == "VAR_TEMP":
                continue
            writeback.append(py.Assign([_attr(_name("self"), v.pyname, py.Store())], _name(v.pyname)))
        main = prologue + (code or [])
        if writeback:
            main = prologue + [py.Try(code or [py.Pass()], [], [], _lines(writeback, end_line))]
        gl = sorted(self.globals_written)
        if gl:
            main.insert(0, py.Global(gl))
        fn = py.FunctionDef(name, _args(["self"]), main or [py.Pass()], [], None, None)
        _set_lines(fn, line)
        return fn

    def sfc_methods(self, sfc) -> list:
        """Transition conditions and the SFC description for the runtime engine."""
        out = []
        for t in sfc.transitions:
            g = BodyGen(self.mod, self.pou)
            g.cached = set()
            body: list[py.stmt]
            if t.cond is not None:
                body = [py.Return(g.expr(t.cond))]
            else:
                body = [py.Return(_const(False))]
            fn = py.FunctionDef(f"_tr_{t.index}", _args(["self"]), body, [], None, None)
            _set_lines(fn, t.span.line)
            out.append(fn)
        # timed qualifiers' durations are constant expressions or variables: a method returns them
        for s in sfc.steps:
            for i, (_act, _q, texpr) in enumerate(s.actions):
                if texpr is not None:
                    g = BodyGen(self.mod, self.pou)
                    fn = py.FunctionDef(
                        f"_at_{s.index}_{i}", _args(["self"]), [py.Return(g.expr(texpr))], [], None, None
                    )
                    _set_lines(fn, texpr.span.line)
                    out.append(fn)
        return out


def _loops_in(body) -> bool:
    """Does the statement list contain a loop (FOR, WHILE, REPEAT)?"""
    return any(isinstance(s, (A.For, A.CountedFor, A.While, A.Repeat)) for s in walk_stmts(body))
