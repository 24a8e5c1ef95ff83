"""Statements: typed ST statements → Python statements (loops, calls, assignments)."""

from __future__ import annotations

import ast as py
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import cast

from ...model import types as T
from .. import ast as A
from .. import intervals as I
from ..check import (
    ActionCall,
    CallTarget,
    DeleteCall,
    FbCall,
    FunctionCall,
    MethodCall,
    NativeCall,
    QueryItfCall,
    TestCall,
)
from ..lower.walk import walk_stmts
from .expressions import ExprGen, index_key, wrap
from .facts import WATCHDOG_ARMED, WATCHDOG_CHECK, BodyCall, Loop, current
from .inline import exact_instance, inline_body
from .pyast import Unsupported, _attr, _call, _const, _name, _set_lines


class StmtGen(ExprGen):
    # test statements (kind "test") occur in TEST blocks only (E033), printed by codegen/tests.py's TestGen
    test_call: Callable[[CallTarget], list[py.stmt]]

    @property
    def covered(self) -> bool:
        """Coverage probes go into user POUs only (not the library, not the tests themselves)."""
        pou = self.pou
        return self.mod.coverage and pou is not None and not pou.library and pou.pou_kind != "TEST"

    def stmts(self, body: list) -> list:
        out: list[py.stmt] = []
        covered = self.covered
        for s in body:
            try:
                r = self.stmt(s)
            except Unsupported:
                raise
            except Exception as exc:
                if not hasattr(exc, "st_span"):
                    # where the internal error happened, for the report (read with getattr)
                    exc.st_span = s.span  # type: ignore[attr-defined]
                raise
            if covered and r and not isinstance(s, A.LoopGuard):
                r.insert(0, self.mod.probe(s.span.file, s.span.line, "line"))
            for n in r:
                _set_lines(n, s.span.line)
            out.extend(r)
        return out

    def _arm(self, body: list, decision, label: str) -> list:
        """The statements of one arm of a decision, with its branch probe when measuring coverage."""
        code = self.stmts(body)
        if not self.covered:
            return code or [py.Pass()]
        target = body[0].span.line if body else 0
        probe = _set_lines(
            self.mod.probe(decision.span.file, decision.span.line, "branch", label, target),
            target or decision.span.line,
        )
        return [probe] + code

    def block(self, body) -> list:
        b = self.stmts(body)
        return b or [py.Pass()]

    def loop_body(self, body: list, before: Sequence[py.stmt] = ()) -> list:
        """A loop's Python body: its guard first, then what the printer needs each round
        (`before`), then the statements."""
        if body and isinstance(body[0], A.LoopGuard):
            return self.stmts(body[:1]) + list(before) + self.stmts(body[1:])
        return list(before) + self.stmts(body)

    def s_LoopGuard(self, s: A.LoopGuard) -> list:
        guard = py.If(_name(WATCHDOG_ARMED), [py.Expr(_call(WATCHDOG_CHECK))], [])
        facts = current()
        if facts is not None:
            facts.guards.append(guard)
        return [guard]

    def stmt(self, s) -> list:
        return getattr(self, "s_" + type(s).__name__)(s)

    def s_Empty(self, s):
        return []

    def s_Exit(self, s):
        return [py.Break()]

    def s_Continue(self, s):
        return [py.Continue()]

    def s_Return(self, s):
        has_result = self.result_name and getattr(self.pou, "return_type", None) is not None
        return [py.Return(self.result_load() if has_result else None)]

    def s_Assign(self, s: A.Assign) -> list:
        tgt = s.target
        tt = tgt.ty
        if s.kind == "REF=":  # bind a REFERENCE TO variable
            v = s.value
            ref: py.expr
            if isinstance(v, A.Name) and getattr(v.sym, "kind", "") == "null":
                ref = _const(None)
            elif isinstance(v, A.Call):
                ref = self.expr(v)  # the REFERENCE TO the call returns (not dereferenced)
            else:
                ref = self.ref_to(v)
            if isinstance(tgt, A.Name) and isinstance(tgt.sym, T.POUType):  # a function's REFERENCE TO result
                return [py.Assign([self.result_store()], ref)]
            if isinstance(tgt, A.Field):
                return [py.Assign([_attr(self.expr(tgt.base), tgt.sym.pyname, py.Store())], ref)]
            assert isinstance(tgt, A.Name)  # the checker allows REF= to a name or a field only
            return [py.Assign([self.var_store(tgt.sym)], ref)]
        if isinstance(tgt, A.AccessorCall):
            # a property: its SET with the value (S=/R= only when the condition holds)
            def setter(value):
                return py.Expr(self.x_AccessorCall(tgt, value))

            if s.kind in ("S=", "R="):
                return [py.If(self.expr(s.value), [setter(_const(s.kind == "S="))], [])]
            return [setter(self.coerce(self.expr(s.value), s.value, tt))]
        if s.kind in ("S=", "R="):
            return [py.If(self.expr(s.value), self.assign(tgt, _const(s.kind == "S="), None), [])]
        if s.kind == "?=":
            assert s.attempt is not None  # the checker sets it on every ?=
            kind, src_ref, dest_ref = s.attempt
            return self.assign(
                tgt, _call("_attempt", self.expr(s.value), _const(kind), _const(src_ref), _const(dest_ref)), None
            )
        # a call with EN: assign only when enabled
        v = s.value
        if isinstance(v, A.Call):
            match v.target:
                case FunctionCall(bind=bind) | MethodCall(bind=bind) if (
                    bind.get("en") is not None or bind.get("eno") is not None
                ):
                    return self._en_call_assign(s, v)
                case NativeCall(en=en, eno=eno) as native if en is not None or eno is not None:
                    v.target = replace(native, en=None)  # the value, called: EN decides around it
                    try:
                        body = self.assign(tgt, self.coerce(self.expr(v), v, tt), v)
                    finally:
                        v.target = native
                    return self._en_wrap(en, eno, body, ok=self._native_eno(native, eno))
        ut = T.unalias(tt) if tt is not None else None
        if ut is not None and ut.is_aggregate:
            return [py.Expr(_call("_assign", self.expr(tgt), self.expr(v)))]
        if isinstance(tgt, A.Index):
            return self._element_update(tgt, v, tt)
        return self.assign(tgt, self.coerce(self.expr(v), v, tt), v)

    def _element_update(self, tgt: A.Index, v, tt) -> list:
        """`a[i] := a[i] + 1`: an element the value reads too is located (its index checked) once."""
        key = index_key(tgt)
        if key is None or not _reads_element(v, key) or key in self.index_memo:
            return self.assign(tgt, self.coerce(self.expr(v), v, tt), v)
        index = self.index_of(tgt)
        if isinstance(index, (py.Name, py.Constant)):
            return self.assign(tgt, self.coerce(self.expr(v), v, tt), v)
        tmp = self.new_tmp()
        self.index_memo[key] = tmp
        try:
            return [py.Assign([_name(tmp, py.Store())], index)] + self.assign(tgt, self.coerce(self.expr(v), v, tt), v)
        finally:
            del self.index_memo[key]

    def _en_wrap(
        self, en, eno, body: list, eno_bound: bool = False, own_eno: py.expr | None = None, ok: py.expr | None = None
    ) -> list:
        """EN := FALSE skips the call and gives ENO FALSE; else ENO is TRUE (or what the callee set, or
        `ok`). `own_eno`: the instance's own ENO (inst.ENO), FALSE too when the call is skipped."""
        done = ok if ok is not None else _const(True)
        if en is None:
            out = body
            if eno is not None and not eno_bound:
                out = out + self.assign(eno.value, done, None)
            return out
        yes = body + (self.assign(eno.value, done, None) if eno is not None and not eno_bound else [])
        no = self.assign(eno.value, _const(False), None) if eno is not None else []
        if own_eno is not None:
            no.append(py.Assign([own_eno], _const(False)))
        return [py.If(self.expr(en.value), yes, no or [py.Pass()])]

    def _native_eno(self, tgt, eno) -> py.expr | None:
        """ENO after a native call that ran, when the function says (FuncSig.eno_ok), else None (TRUE)."""
        if eno is None or tgt.sig.eno_ok is None:
            return None
        return tgt.sig.eno_ok(len(tgt.args))([self.expr(a.value) for a in tgt.args])

    def _en_call_assign(self, s, v):
        bind = v.target.bind
        en, eno = bind.get("en"), bind.get("eno")
        bind["en"] = None
        body = self.assign(s.target, self.coerce(self.expr(v), v, s.target.ty), v)
        bind["en"] = en
        return self._en_wrap(en, eno, body, "eno" in bind["params"])

    def assign(self, tgt, value: py.expr, src_expr) -> list:
        if isinstance(tgt, A.Name) and isinstance(tgt.sym, T.VarSym) and T.is_reference(tgt.sym.type):
            return [py.Expr(_call(_attr(self.var_load(tgt.sym), "set"), value))]  # through the reference
        if isinstance(tgt, A.Field) and isinstance(tgt.sym, T.VarSym) and T.is_reference(tgt.sym.type):
            return [py.Expr(_call(_attr(_attr(self.expr(tgt.base), tgt.sym.pyname), "set"), value))]
        if isinstance(tgt, A.Name):
            sym = tgt.sym
            if isinstance(sym, T.POUType) and T.is_reference(sym.return_type):
                return [py.Expr(_call(_attr(self.result_load(), "set"), value))]  # through the result
            if isinstance(sym, T.POUType):
                return [py.Assign([self.result_store()], value)]
            return [py.Assign([self.var_store(sym)], value)]
        if isinstance(tgt, A.Field):
            bt = T.unalias(tgt.base.ty)
            if isinstance(bt, T.ElemType) and bt.is_intlike:
                return self._bit_write(tgt.base, int(tgt.name), value)
            return [py.Assign([_attr(self.expr(tgt.base), tgt.sym.pyname, py.Store())], value)]
        if isinstance(tgt, A.Index):
            return [py.Assign([py.Subscript(self.array_of(tgt), self.index_of(tgt), py.Store())], value)]
        if isinstance(tgt, A.Bit):
            if tgt.size != "X":
                width = {"B": 8, "W": 16, "D": 32, "L": 64}[tgt.size]
                bt = T.base_of(tgt.base.ty)
                assert isinstance(bt, T.ElemType)  # the checker allows partial access to ANY_BIT/ANY_INT only
                new = _call(
                    "_setbits",
                    self.expr(tgt.base),
                    _const(tgt.index * width),
                    _const(width),
                    value,
                    _const(bt.bits),
                    _const(bt.signed),
                )
                return self.assign(tgt.base, new, None)
            return self._bit_write(tgt.base, tgt.index, value)
        if isinstance(tgt, A.Deref):
            return [py.Expr(_call(_attr(self.expr(tgt.base), "set"), value))]
        if isinstance(tgt, A.Direct):
            name = self.x_Direct(tgt).id
            self.globals_written.add(name)
            return [py.Assign([_name(name, py.Store())], value)]
        raise Unsupported(tgt.span, "cannot assign to this")

    def _bit_write(self, base_e, n: int, value: py.expr) -> list:
        bt = T.base_of(base_e.ty)
        assert isinstance(bt, T.ElemType)  # the checker allows bit access to ANY_BIT/ANY_INT only
        new = _call("_setbit", self.expr(base_e), _const(n), value, _const(bt.bits), _const(bt.signed))
        return self.assign(base_e, new, None)

    def s_CallStmt(self, s: A.CallStmt) -> list:
        c = s.call
        match c.target:
            case FbCall() as tgt:
                return self.fb_call(c, tgt)
            case ActionCall(bind=bind, name=name) as tgt if bind is not None:  # inst.A(in := ...) (TwinCAT)
                return self.fb_call(c, tgt, run="_act_" + name)
            case ActionCall(inst=inst, name=name):
                owner = self.expr(inst) if inst is not None else self.this()
                return [py.Expr(_call(_attr(owner, "_act_" + name)))]
            case FunctionCall(bind=bind) | MethodCall(bind=bind) as tgt:
                en, eno = bind.get("en"), bind.get("eno")
                bind["en"] = None
                call = self.method_call(c, tgt) if isinstance(tgt, MethodCall) else self.function_call(c, tgt)
                body = [py.Expr(call)]
                bind["en"] = en
                return self._en_wrap(en, eno, body, "eno" in bind["params"])
            case DeleteCall(itself=True):
                return []  # __DELETE(THIS): freed once nothing refers to it (check/intrinsics.py)
            case DeleteCall(arg=arg):
                return self.assign(arg, _const(None), None)
            case TestCall() as tgt:
                return self.test_call(tgt)
            case NativeCall(en=en, eno=eno) as tgt:
                body = [py.Expr(self.native_call(c, replace(tgt, en=None)))]
                return self._en_wrap(en, eno, body, ok=self._native_eno(tgt, eno))
            case None:
                raise Unsupported(s.span, "unresolved call")
        raise Unsupported(s.span, "cannot call this")

    def fb_call(self, c: A.Call, tgt: FbCall | ActionCall, run: str = "_body") -> list:
        """An instance call: inputs in, the body (or, `run`, one of its actions), outputs out."""
        if isinstance(tgt, ActionCall):  # TwinCAT's inst.A(in := ...): the block's inputs and outputs
            assert tgt.block is not None and tgt.bind is not None and tgt.inst is not None  # the checker's
            fb, binding, callee, nonvirtual = tgt.block, tgt.bind, tgt.inst, None
        else:
            fb, binding, callee, nonvirtual = tgt.pou, tgt.bind, c.callee, tgt.nonvirtual
        bind = binding["params"]
        out: list[py.stmt] = []
        inst = self.expr(callee)
        if not isinstance(inst, py.Name):
            tmp = self.new_tmp()
            out.append(py.Assign([_name(tmp, py.Store())], inst))
            inst = _name(tmp)
        after = []
        for key, a in bind.items():
            p = fb.vars[key]
            if a.output:
                continue
            ut = T.unalias(p.type)
            if p.section == "VAR_IN_OUT":
                if ut.is_aggregate:
                    out.append(
                        py.Assign(
                            [_attr(inst, p.pyname, py.Store())],
                            self.conformant_arg(self.expr(a.value), a.value.ty, p.type),
                        )
                    )
                elif a.temporary:  # VAR_IN_OUT CONSTANT := expression: its value, nothing to copy back
                    out.append(
                        py.Assign([_attr(inst, p.pyname, py.Store())], self.coerce(self.expr(a.value), a.value, p.type))
                    )
                else:
                    out.append(py.Assign([_attr(inst, p.pyname, py.Store())], self.expr(a.value)))
                    after.extend(
                        self.assign(a.value, self.coerce(_attr(inst, p.pyname), _Typed(p.type), a.value.ty), None)
                    )
            elif T.is_reference(p.type):  # an input REFERENCE TO: bound to the argument
                out.append(py.Assign([_attr(inst, p.pyname, py.Store())], self.ref_to(a.value)))
            elif p.any_input:
                out.append(py.Assign([_attr(inst, p.pyname, py.Store())], self.any_arg(a.value, p)))
            elif ut.is_aggregate:
                out.append(py.Expr(_call("_assign", _attr(inst, p.pyname), self.expr(a.value))))
            else:
                out.append(
                    py.Assign([_attr(inst, p.pyname, py.Store())], self.coerce(self.expr(a.value), a.value, p.type))
                )
        own = fb.vars.get("eno")
        if own is not None:  # IEC: a call that runs starts with ENO TRUE; the body may clear it
            out.append(py.Assign([_attr(inst, own.pyname, py.Store())], _const(True)))
        inline_fn = self.mod.inline_body_of(fb) if run == "_body" and nonvirtual is None else None
        if run == "_body" and nonvirtual is not None:  # SUPER^(): the base block's body on this instance
            out.append(py.Expr(_call(_attr(_name(nonvirtual.pyname), "_body"), inst)))
        elif inline_fn is not None and isinstance(inst, py.Name) and exact_instance(callee):
            out.extend(inline_body(inline_fn, inst.id, self.new_tmp() + "_", c.span.line))
        else:
            call = _call(_attr(inst, run))
            facts = current()
            if facts is not None and run == "_body":
                facts.body_calls.append(BodyCall(call, fb.pyname))
            out.append(py.Expr(call))
        out.extend(after)
        for key, a in bind.items():
            p = fb.vars[key]
            if not a.output:
                continue
            val: py.expr = _attr(inst, p.pyname)
            if a.negated:
                val = py.UnaryOp(py.Not(), val)
            if T.unalias(p.type).is_aggregate:
                out.append(py.Expr(_call("_assign", self.expr(a.value), val)))
            else:
                out.extend(self.assign(a.value, self.coerce(val, _Typed(p.type), a.value.ty), None))
        own_eno = _attr(self.expr(callee), own.pyname, py.Store()) if own is not None else None
        return self._en_wrap(binding.get("en"), binding.get("eno"), out, "eno" in bind, own_eno)

    def s_If(self, s: A.If) -> list:
        # arms first, in source order (coverage probes are numbered in that order)
        arms = [
            self._arm(body, s, "THEN" if i == 0 else f"ELSIF (line {cond.span.line})")
            for i, (cond, body) in enumerate(s.branches)
        ]
        if s.orelse is not None:
            orelse = self._arm(s.orelse, s, "ELSE") if s.orelse or self.covered else []
        else:
            orelse = self._arm([], s, "implicit ELSE") if self.covered else []
        for (cond, _body), arm in reversed(list(zip(s.branches[1:], arms[1:]))):
            node = py.If(self.cond(cond), arm, orelse)
            _set_lines(node, cond.span.line)
            orelse = [node]
        return [py.If(self.cond(s.branches[0][0]), arms[0], orelse)]

    def cond(self, e) -> py.expr:
        """A condition (IF, ELSIF, WHILE, UNTIL). AND/OR of BOOL operands that can neither fault nor
        act (`_inert`) are short-circuited: the same truth value, without evaluating the rest once
        it is decided."""
        if (
            isinstance(e, A.Binary)
            and e.op in ("AND", "OR")
            and e.ty is not None
            and T.base_of(e.ty).is_bool
            and _inert(e.left)
            and _inert(e.right)
        ):
            return py.BoolOp(py.And() if e.op == "AND" else py.Or(), [self.cond(e.left), self.cond(e.right)])
        return self.expr(e)

    def s_Case(self, s: A.Case) -> list:
        out = []
        sel = self.expr(s.selector)
        if not isinstance(sel, (py.Name, py.Constant)):
            tmp = self.new_tmp()
            out.append(py.Assign([_name(tmp, py.Store())], sel))
            sel = _name(tmp)
        arms = [self._arm(br.body, s, "CASE " + _labels_text(br.labels)) for br in s.branches]
        if s.orelse is not None:
            orelse = self._arm(s.orelse, s, "CASE ELSE") if s.orelse or self.covered else []
        elif self.covered and not _covers_enum(s):
            orelse = self._arm([], s, "implicit ELSE")
        else:
            orelse = []
        for br, arm in reversed(list(zip(s.branches, arms))):
            singles = []
            ranges = []
            for lo, hi in br.labels:
                lv = lo.const if lo.const is not None else (lo.value if isinstance(lo, A.Literal) else None)
                if hi is None:
                    singles.append(lv)
                else:
                    hv = hi.const if hi.const is not None else (hi.value if isinstance(hi, A.Literal) else None)
                    ranges.append((lv, hv))
            tests: list[py.expr] = []
            if len(singles) == 1:
                tests.append(py.Compare(sel, [py.Eq()], [_const(singles[0])]))
            elif singles:
                tests.append(py.Compare(sel, [py.In()], [py.Set([_const(v) for v in singles])]))
            for lv, hv in ranges:
                tests.append(py.Compare(_const(lv), [py.LtE(), py.LtE()], [sel, _const(hv)]))
            test = tests[0] if len(tests) == 1 else py.BoolOp(py.Or(), tests)
            node = py.If(test, arm, orelse)
            _set_lines(node, br.span.line)
            orelse = [node]
        out.extend(orelse)
        return out

    def s_While(self, s: A.While) -> list:
        return [py.While(self.cond(s.cond), self.loop_body(s.body) or [py.Pass()], [])]

    def s_Repeat(self, s: A.Repeat) -> list:
        if _has_continue(s.body):
            flag = self.new_tmp()
            init = py.Assign([_name(flag, py.Store())], _const(True))
            test = py.BoolOp(py.Or(), [_name(flag), py.UnaryOp(py.Not(), self.cond(s.cond))])
            body = self.loop_body(s.body, [py.Assign([_name(flag, py.Store())], _const(False))])
            return [init, py.While(test, body, [])]
        body = self.loop_body(s.body)
        cond = self.cond(s.cond)
        br = _set_lines(py.If(cond, [py.Break()], []), s.cond.span.line)
        return [py.While(_const(True), body + [br], [])]

    def s_Try(self, s: A.Try) -> list:
        """`__TRY`: a Python try. Its `except` takes what may carry a fault (`_catchable`); one a
        __CATCH does not handle (`_exc_code` gives None: the watchdog's, an endless FOR's) is raised
        again as it was, so the PLC faults where it happened. __FINALLY is the `finally`."""
        body = self.block(s.body)
        handlers = []
        if s.handler is not None:
            exc, code = self.new_tmp(), self.new_tmp()
            catch = [
                py.Assign([_name(code, py.Store())], _call("_exc_code", _name(exc))),
                py.If(py.Compare(_name(code), [py.Is()], [_const(None)]), [py.Raise()], []),
            ]
            if s.catch_var is not None:
                catch += self.assign(s.catch_var, _name(code), None)
                for n in catch:
                    _set_lines(n, s.catch_var.span.line)
            catch += self.stmts(s.handler)
            handlers.append(py.ExceptHandler(_name("_catchable"), exc, catch))
        final = self.stmts(s.final) if s.final else []
        if not handlers and not final:
            return body
        return [py.Try(body, handlers, [], final)]

    def s_CountedFor(self, s: A.CountedFor) -> list:
        """A FOR in the form lower/loops.py chose: a Python `for` over `_range` (the counter ends
        one step past the limit, wrapped, as IEC says) or, for the "while" form, `_for_while`."""
        var = s.var
        vt = T.base_of(var.ty)
        start = self.coerce(self.expr(s.start), s.start, var.ty)
        end = self.expr(s.end)
        step_c = s.step_value
        out: list[py.stmt] = []
        if s.form == "while":
            return self._for_while(s, start, end, step_c)
        step: py.expr
        stop: py.expr
        # start, end and step are evaluated once, in that order, when the loop starts: the start
        # is used twice below (the range and the counter's value if it runs no round), and the
        # range is made after that value is set, so a bound that reads the counter is read before
        sym = var.sym if isinstance(var, A.Name) and isinstance(var.sym, T.VarSym) else None
        direct = (
            sym is not None
            and (sym in self.cached or self.self_name is None)
            and sym not in self.boxed  # an addressed local of a function is a box
            and not (sym.is_global or sym.section == "VAR_EXTERNAL")
        )
        counter = sym.pyname if sym is not None and direct else None
        take_end = not isinstance(end, py.Constant) and (step_c is None or _reads(end, counter))
        if not _plain(start) or _reads(start, counter) or (take_end and not isinstance(start, py.Constant)):
            start = self._once(start, out)
        if take_end:
            end = self._once(end, out)
        if step_c is None:
            stp = self.new_tmp()
            out.append(py.Assign([_name(stp, py.Store())], self.expr(s.step)))
            step = _name(stp)
            stop = py.BinOp(end, py.Add(), _call("_for_dir", step))
        else:
            step = _const(step_c)
            stop = (
                py.BinOp(end, py.Add(), _const(1 if step_c > 0 else -1))
                if not isinstance(end, py.Constant)
                else _const(cast(int, end.value) + (1 if step_c > 0 else -1))  # a FOR's limit is an integer
            )
        rng = _call("_range", start, stop, step) if step_c != 1 else _call("_range", start, stop)
        # the loop variable, or a Python local that mirrors it
        pre: list[py.stmt] = []
        # the counter's interval holds only in a Python local, which nothing but the body (that
        # does not write it) can change; a global or addressed one can change behind its back
        known = self._counter_range(s, step_c) if direct else None
        if sym is not None and known is not None:
            self.loop_ranges[sym] = known  # index checks and wraps in the body can use it
        try:
            if sym is not None and direct:
                loopvar = sym.pyname
                self.written_locals.add(sym)
                body = self.loop_body(s.body) or [py.Pass()]
            else:
                loopvar = self.new_tmp()
                body = self.loop_body(s.body, self.assign(var, _name(loopvar), None))
        finally:
            if sym is not None:
                self.loop_ranges.pop(sym, None)
        # before: loopvar = start - step (so that 'else' can add step: the IEC final value)
        init = py.Assign([_name(loopvar, py.Store())], py.BinOp(start, py.Sub(), step))
        final: py.expr = py.BinOp(_name(loopvar), py.Add(), step)
        if vt.is_intlike:
            final = wrap(final, vt)
        orelse: list[py.stmt] = [py.Assign([_name(loopvar, py.Store())], final)]
        if not direct:
            orelse += self.assign(var, _name(loopvar), None)
        loop = py.For(_name(loopvar, py.Store()), rng, body, orelse)
        facts = current()
        if facts is not None and sym is not None and direct and known is not None:
            facts.loops.append(Loop(loop, loopvar, known))
        return out + pre + [init, loop]

    def _once(self, value: py.expr, out: list) -> py.Name:
        """`value` evaluated into a temporary (appended to `out`), read from there."""
        tmp = self.new_tmp()
        out.append(py.Assign([_name(tmp, py.Store())], value))
        return _name(tmp)

    def _counter_range(self, s: A.CountedFor, step_c) -> I.Interval | None:
        """The values a FOR counter takes in its body (range form: the body does not write it)."""
        a, b = self.value_range(s.start), self.value_range(s.end)
        if a is None or b is None:
            return None
        if step_c is not None and step_c > 0:
            return I.Interval(a.lo, b.hi) if a.lo <= b.hi else None
        if step_c is not None and step_c < 0:
            return I.Interval(b.lo, a.hi) if b.lo <= a.hi else None
        return I.hull(a, b)

    def _for_while(self, s: A.CountedFor, start, end, step_c):
        """FOR whose body writes the loop variable: a faithful while loop."""
        var = s.var
        vt = T.base_of(var.ty)
        out: list[py.stmt] = []
        step_e = self.expr(s.step) if step_c is None else _const(step_c)
        # start, end and step once and in that order, then the counter (a bound may read it): the
        # start goes through a temporary unless the order cannot matter
        if not (
            isinstance(start, py.Constant)
            or (_plain(start) and _plain(end) and _plain(step_e))
            or (isinstance(end, py.Constant) and isinstance(step_e, py.Constant))
        ):
            start = self._once(start, out)
        endt = self.new_tmp()
        out.append(py.Assign([_name(endt, py.Store())], end))
        step: py.expr
        test: py.expr
        if step_c is None:
            stp = self.new_tmp()
            out.append(py.Assign([_name(stp, py.Store())], step_e))
            step = _name(stp)
        out += self.assign(var, start, None)
        if step_c is None:
            test = py.IfExp(
                py.Compare(step, [py.Gt()], [_const(0)]),
                py.Compare(self.expr(var), [py.LtE()], [_name(endt)]),
                py.Compare(self.expr(var), [py.GtE()], [_name(endt)]),
            )
        else:
            step = _const(step_c)
            test = py.Compare(self.expr(var), [py.LtE() if step_c > 0 else py.GtE()], [_name(endt)])
        incr = self.assign(var, wrap(py.BinOp(self.expr(var), py.Add(), step), vt), None)
        # CONTINUE must still increment: use try/finally-free form: increment at loop top after the first pass
        first = self.new_tmp()
        out.append(py.Assign([_name(first, py.Store())], _const(True)))
        body = self.loop_body(
            s.body,
            [
                py.If(_name(first), [py.Assign([_name(first, py.Store())], _const(False))], incr),
                py.If(py.UnaryOp(py.Not(), test), [py.Break()], []),
            ],
        )
        out.append(py.While(_const(True), body, []))
        return out


class _Typed:
    """A stand-in expression carrying only a type (for coercions of FB outputs)."""

    def __init__(self, ty):
        self.ty = ty
        self.const = None


def _plain(node: py.expr) -> bool:
    """An operand read twice at no cost and with no effect: a constant, a name, `self.x`, `-1`."""
    if isinstance(node, py.UnaryOp) and isinstance(node.operand, py.Constant):
        return True
    if isinstance(node, py.Attribute):
        node = node.value
    return isinstance(node, (py.Name, py.Constant))


def _reads(node: py.expr, name: str | None) -> bool:
    """Does `node` read the Python local `name`?"""
    return name is not None and any(isinstance(n, py.Name) and n.id == name for n in py.walk(node))


def _label_text(e) -> str:
    if isinstance(e, A.Name):
        return e.name
    if isinstance(e, A.EnumLit):
        return f"{e.type_name}#{e.member}" if e.type_name else e.member
    if isinstance(e, A.Literal) and e.text:
        return e.text
    return str(e.const if e.const is not None else getattr(e, "value", "?"))


def _labels_text(labels) -> str:
    return ", ".join(_label_text(lo) + (".." + _label_text(hi) if hi is not None else "") for lo, hi in labels)


def _covers_enum(s: A.Case) -> bool:
    """A CASE on an enum whose labels name every value has no reachable implicit ELSE."""
    et = T.unalias(s.selector.ty) if s.selector.ty is not None else None
    if not isinstance(et, T.EnumType):
        return False
    seen = set()
    for br in s.branches:
        for lo, hi in br.labels:
            if hi is None:
                seen.add(lo.const)
            elif lo.const is not None and hi.const is not None:
                seen.update(range(lo.const, hi.const + 1))
    return all(v in seen for _, v in et.members.values())


def _has_continue(body) -> bool:
    for s in body:
        if isinstance(s, A.Continue):
            return True
        if isinstance(s, A.If):
            if any(_has_continue(b) for _, b in s.branches) or _has_continue(s.orelse or []):
                return True
        if isinstance(s, A.Case):
            if any(_has_continue(b.body) for b in s.branches) or _has_continue(s.orelse or []):
                return True
        if isinstance(s, A.Try):
            if any(_has_continue(b or []) for b in (s.body, s.handler, s.final)):
                return True
    return False


def _reads_element(e, key) -> bool:
    """Does the value read the element `key` names, and otherwise only read, without a fault of its
    own (an operand that may act, a call, could change the index in between; a division by a
    variable could fault before the element's index is checked, as it would not)?"""
    found = False
    stack = [e]
    while stack:
        x = stack.pop()
        if isinstance(x, A.Index):
            k = index_key(x)
            if k is None:
                return False
            found = found or k == key
            continue
        if isinstance(x, A.Binary) and (x.op in _INERT_OPS or _by_nonzero_literal(x)):
            stack += [x.left, x.right]
        elif isinstance(x, A.Unary) and x.op in ("NOT", "-", "+"):
            stack.append(x.operand)
        elif not _inert(x):
            return False
    return found


def _by_nonzero_literal(e: A.Binary) -> bool:
    r = e.right
    return e.op in ("/", "MOD") and isinstance(r, A.Literal) and type(r.value) is int and r.value != 0


_INERT_OPS = frozenset(("=", "<>", "<", ">", "<=", ">=", "AND", "OR", "XOR", "+", "-", "*"))


def _inert(e) -> bool:
    """An expression that can neither fault nor act: literals, variables and members (no
    reference, pointer, VAR_IN_OUT, property or call), and comparisons, logic and + - * of such."""
    if isinstance(e, (A.Literal, A.EnumLit)):
        return True
    if e.ty is not None and isinstance(T.unalias(e.ty), T.RefType):
        return False
    if isinstance(e, A.Name):
        sym = e.sym
        return isinstance(sym, T.VarSym) and sym.section != "VAR_IN_OUT" and not T.is_reference(sym.type)
    if isinstance(e, A.Field):
        sym = e.sym
        return (
            isinstance(sym, T.VarSym)
            and sym.section != "VAR_IN_OUT"
            and not T.is_reference(sym.type)
            and _inert(e.base)
        )
    if isinstance(e, A.Unary):
        return e.op in ("NOT", "-", "+") and _inert(e.operand)
    if isinstance(e, A.Binary):
        return e.op in _INERT_OPS and _inert(e.left) and _inert(e.right)
    return False


def _walk_exprs_in(body):
    """Every expression node in a statement list (for pre-scans)."""
    stack: list[A.Expr | None] = []
    for s in walk_stmts(body):
        if isinstance(s, A.Assign):
            stack += [s.target, s.value]
        elif isinstance(s, A.CallStmt):
            stack.append(s.call)
        elif isinstance(s, A.If):
            stack += [c for c, _ in s.branches]
        elif isinstance(s, A.Case):
            stack.append(s.selector)
        elif isinstance(s, A.CountedFor):
            stack += [s.var, s.start, s.end] + ([s.step] if s.step else [])
        elif isinstance(s, A.While):
            stack.append(s.cond)
        elif isinstance(s, A.Repeat):
            stack.append(s.cond)
        elif isinstance(s, A.Try):
            stack.append(s.catch_var)
        elif isinstance(s, A.Mock):
            stack.append(s.target)
        elif isinstance(s, A.MockFunction):
            stack.append(s.value)
    while stack:
        e = stack.pop()
        if e is None:
            continue
        yield e
        if isinstance(e, A.Binary):
            stack += [e.left, e.right]
        elif isinstance(e, A.Unary):
            stack.append(e.operand)
        elif isinstance(e, (A.Field, A.Bit, A.Deref)):
            stack.append(e.base)
        elif isinstance(e, A.AccessorCall):
            stack.append(e.obj)
        elif isinstance(e, A.Index):
            stack.append(e.base)
            stack += e.indices
        elif isinstance(e, A.Call):
            stack.append(e.callee)
            stack += [a.value for a in e.args]


def _by_ref_names(body) -> set:
    """Variables passed to functions as outputs / in-outs: they must stay attributes."""
    names = set()

    def root_of(e):
        while isinstance(e, (A.Field, A.Index, A.Bit)):
            e = e.base
        if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym):
            names.add(e.sym)

    for e in _walk_exprs_in(body):
        if not isinstance(e, A.Call):
            continue
        match e.target:
            case FunctionCall(pou=pou, bind=bind) | MethodCall(pou=pou, bind=bind):
                for key, a in bind["params"].items():
                    p = pou.vars[key]
                    if p.section == "VAR_OUTPUT" or (
                        p.section == "VAR_IN_OUT" and not T.unalias(p.type).is_aggregate and not a.temporary
                    ):
                        root_of(a.value)
            case QueryItfCall(dst=dst):
                root_of(dst)
            case NativeCall(sig=sig, args=args) if sig.name.upper() in ("REF", "ADR"):
                for a in args:
                    root_of(a.value)
    return names
