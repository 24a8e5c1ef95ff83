"""Bodies: statements, assignability and lvalues (the rules they apply: rules/)."""

from __future__ import annotations

from collections.abc import Callable
from typing import cast

from ...diagnostics import Code
from ...model import types as T
from ...source import Span
from .. import ast as A
from .common import _NULL, Scope, same_type, take_address
from .expressions import _null_at, _zero_pointer
from .part import Part
from .rules import (
    access,
    assignment_attempt,
    conditions,
    exception_variable,
    exit_outside_loop,
    for_counter,
    for_loop,
    narrowing,
    not_assignable,
    reference_binding,
    set_reset,
    truncated_string,
    write_to_constant,
    write_to_input,
)
from .rules.case_labels import CaseLabels


class Statements(Part):
    # ================================================================ statements
    def stmt_list(self, body: list, scope: Scope) -> None:
        for s in body:
            try:
                self.stmt(s, scope)
            except Exception as exc:
                if not hasattr(exc, "st_span"):
                    exc.st_span = s.span  # type: ignore[attr-defined]  # where the internal error happened, for the report
                raise

    def stmt(self, s: A.Stmt, scope: Scope) -> None:
        handler = _HANDLERS.get(type(s))
        if handler is None:  # pragma: no cover
            raise AssertionError(s)
        handler(self, s, scope)

    def _assign(self, s: A.Assign, scope: Scope) -> None:
        if s.kind == "REF=":
            return self._ref_assign(s, scope)
        if s.kind == "?=":
            return self._attempt_assign(s, scope)
        if s.chained:
            self.feature("vendor", s.span, "chained assignment (a := b := c)")
        if s.in_condition:
            self.feature("vendor", s.span, "an assignment as a condition (IF b := f() THEN)")
        tt = self.lvalue(s.target, scope)
        if s.kind in ("S=", "R="):
            vt = self.exprs.expr(s.value, scope, T.BOOL)
            set_reset.check_set_reset(self.ctx, s, tt, vt)
            return None
        vt = self.exprs.expr(s.value, scope, tt)
        if _zero_pointer(self.ctx, s.value, tt):
            s.value, vt = _null_at(s.value), _NULL  # p := 0 (CODESYS): NULL
        if tt is not None:
            self.assignable(s.value, vt, tt, s.value.span)
        return None

    def _call_stmt(self, s: A.CallStmt, scope: Scope) -> None:
        rt = self.calls.call(s.call, scope, statement=True)
        if s.call.ty is None:
            s.call.ty = rt  # a function's result, unused: code generation still needs its type

    def _if(self, s: A.If, scope: Scope) -> None:
        for cond, body in s.branches:
            self.condition(cond, scope, "IF")
            self.stmt_list(body, scope)
        if s.orelse:
            self.stmt_list(s.orelse, scope)

    def _for(self, s: A.For, scope: Scope) -> None:
        vt = self.lvalue(s.var, scope)
        for_loop.check_counter_type(self.ctx, s.var, vt)
        for e in (s.start, s.end, s.step):
            if e is not None:
                et = self.exprs.expr(e, scope, vt)
                if vt is not None:
                    self.assignable(e, et, vt, e.span)
        if isinstance(s.step, A.Expr):
            for_loop.check_step(self.ctx, s.step, self.consts.value(s.step, scope))
        self._loop_body(s.body, scope)
        for_counter.check_for_counter(self.ctx, s, scope.library)

    def _while(self, s: A.While, scope: Scope) -> None:
        self.condition(s.cond, scope, "WHILE")
        self._loop_body(s.body, scope)

    def _repeat(self, s: A.Repeat, scope: Scope) -> None:
        self._loop_body(s.body, scope)
        self.condition(s.cond, scope, "UNTIL")

    def _loop_body(self, body: list, scope: Scope) -> None:
        scope.loop_depth += 1
        self.stmt_list(body, scope)
        scope.loop_depth -= 1

    def _try(self, s: A.Try, scope: Scope) -> None:
        allowed = self.feature("vendor", s.span, "exception handling (__TRY … __ENDTRY)")
        self.stmt_list(s.body, scope)
        if s.catch_var is not None:
            t = self.lvalue(s.catch_var, scope)
            if allowed:  # (elsewhere __SYSTEM.ExceptionCode is no type either: reported once, as E044)
                exception_variable.check_exception_variable(self.ctx, s.catch_var, t)
        for body in (s.handler, s.final):
            if body:
                self.stmt_list(body, scope)

    def _exit(self, s: A.Exit | A.Continue, scope: Scope) -> None:
        exit_outside_loop.check_exit(self.ctx, s, scope.loop_depth)

    def _nothing(self, s: A.Stmt, scope: Scope) -> None:
        pass

    def _mock(self, s: A.Mock, scope: Scope) -> None:
        self.tests.mock(s, scope)

    def _mock_function(self, s: A.MockFunction, scope: Scope) -> None:
        self.tests.mock_function(s, scope)

    def condition(self, e: A.Expr, scope: Scope, what: str) -> None:
        conditions.check_condition(self.ctx, e, self.exprs.expr(e, scope, T.BOOL), what)

    def _case(self, s: A.Case, scope: Scope) -> None:
        st = self.exprs.expr(s.selector, scope)
        labels = CaseLabels(self.ctx, s.selector, st)
        for br in s.branches:
            for lo, hi in br.labels:
                values = [self._case_label(labels, e, st, scope) for e in (lo, hi) if e is not None]
                labels.add(lo.span, values)
            self.stmt_list(br.body, scope)
        if s.orelse:
            self.stmt_list(s.orelse, scope)

    def _case_label(self, labels: CaseLabels, e: A.Expr, selector: T.Type | None, scope: Scope):
        labels.check_type(e, self.exprs.expr(e, scope, selector))
        return labels.check_constant(e, self.consts.value(e, scope))

    # ---------------------------------------------------------------- REF= and ?=
    def _ref_assign(self, s: A.Assign, scope: Scope) -> None:
        """r REF= x: bind the REFERENCE TO variable r to the variable x."""
        self.feature("vendor", s.span, "REF=")
        tgt = s.target
        sym = self.exprs.lookup(tgt.name.lower(), scope) if isinstance(tgt, A.Name) else None
        if sym == "RESULT" and T.is_reference(cast(T.POUType, scope.pou).return_type):
            pou = cast(T.POUType, scope.pou)  # GetX REF= x: the REFERENCE TO a function or method returns
            cast(A.Name, tgt).sym = pou
            tgt.ty = pou.return_type
            self._ref_source(s, cast(T.RefType, T.unalias(cast(T.Type, pou.return_type))).target, scope)
            return
        if isinstance(tgt, A.Field):  # inst.r REF= x: an instance's REFERENCE TO
            sym = self._instance_reference(tgt, scope)
        ref = reference_binding.check_ref_target(self.ctx, tgt, sym)
        if ref is None:
            return
        sym = ref
        sym.used = sym.written = True
        cast(A.Name, tgt).sym = sym  # a Name or a Field
        tgt.ty = sym.type
        self._ref_source(s, cast(T.RefType, T.unalias(sym.type)).target, scope)

    def _instance_reference(self, tgt: A.Field, scope: Scope):
        """The variable `inst.r` names (None if inst is no block instance)."""
        bt = self.exprs.expr(tgt.base, scope)
        b = T.unalias(bt) if bt is not None else None
        if not isinstance(b, T.POUType):
            return None
        sym = b.vars.get(tgt.name.lower())
        if isinstance(sym, T.VarSym) and sym.access:
            access.check_access(self.ctx, (sym.access,), sym.owner, f"variable {sym.name}", scope, tgt.name_span)
        return sym

    def _ref_source(self, s: A.Assign, want: T.Type | None, scope: Scope) -> None:
        """What REF= binds to: a variable, NULL (or 0), or the REFERENCE TO a call returns."""
        v = s.value
        if isinstance(v, A.Literal) and v.kind == "int" and v.value == 0 and not v.type_name:
            s.value = v = A.Name(v.span, "NULL")  # CODESYS: r REF= 0 unbinds, as REF= NULL
        if isinstance(v, A.Name) and v.name.upper() == "NULL":
            self.exprs.expr(v, scope)
            return
        if isinstance(v, A.Call):
            return self._ref_call_source(v, want, scope)
        if not isinstance(v, (A.Name, A.Field, A.Index, A.Deref)):
            self.err(Code.NOT_A_VARIABLE, v.span, "REF= needs a variable to refer to")
            self.exprs.expr(v, scope)
            return
        vt = self.lvalue(v, scope)
        take_address(v)
        reference_binding.check_ref_source(self.ctx, v, want, vt)

    def _ref_call_source(self, v: A.Call, want: T.Type | None, scope: Scope) -> None:
        rt = self.calls.call(v, scope)
        v.ty = rt
        if rt is None:
            return
        if not T.is_reference(rt):
            self.err(Code.NOT_A_VARIABLE, v.span, f"REF= needs a variable to refer to; this call returns a {rt}")
            return
        reference_binding.check_ref_source(self.ctx, v, want, cast(T.RefType, T.unalias(rt)).target)

    def _attempt_assign(self, s: A.Assign, scope: Scope) -> None:
        """dest ?= src (assignment attempt): dest, an interface or a REF_TO a block, receives src's
        instance when it is of dest's kind at run time, else NULL."""
        self.feature("oop", s.span, "?= (assignment attempt)")
        tt = self.lvalue(s.target, scope)
        vt = self.exprs.expr(s.value, scope)
        if tt is None or vt is None:
            return
        found = assignment_attempt.attempt(self.ctx, s, tt, vt)
        if found is not None:
            s.attempt = found

    # ---------------------------------------------------------------- assignability
    def assignable(self, e, src: T.Type | None, dst: T.Type | None, span: Span, what: str = "") -> bool:
        """May a value `e` of type `src` go where `dst` is needed (assigned, passed, initialised)?
        Reports why not; the conversions the dialect makes on the way are rules/narrowing.py's."""
        if src is None or dst is None:
            return True
        s, d = T.base_of(src), T.base_of(dst)
        if s is d:
            return self._in_subrange(e, dst, span)
        what = what or "assign"
        verdict = self._literal_into(e, s, d, dst, span)
        if verdict is None:
            verdict = self._text_into(e, s, d, src, dst, span, what)
        if verdict is not None:
            return verdict
        if T.widens_to(s, d):
            return True
        if self.ctx.bits_as_numbers() and T.bits_numbers_convert(s, d):
            return True  # CODESYS, TwinCAT: BYTE into INT or REAL, INT into WORD (the value is kept)
        if narrowing.lossy_conversion(self.ctx, s, d, src, dst, span) or self._enum_as_int(s, d):
            return True
        if isinstance(s, T.ArrayType) and isinstance(d, T.ArrayType) and same_type(s, d):
            return True
        verdict = self._link_into(s, d, src, dst, span, what)
        if verdict is not None:
            return verdict
        if not narrowing.narrowing(self.ctx, s, d, src, dst, span):
            self.err(Code.TYPE_MISMATCH, span, f"type mismatch: cannot {what} {src} to {dst}")
        return False

    def _in_subrange(self, e, dst: T.Type, span: Span) -> bool:
        """A constant of the right base type that must also lie within a subrange `dst`."""
        if isinstance(T.unalias(dst), T.SubrangeType) and isinstance(e, A.Expr):
            c = self.consts.value(e, None) if isinstance(e, (A.Literal, A.Unary)) else None
            sub = cast(T.SubrangeType, T.unalias(dst))
            if isinstance(c, int) and not (sub.lo <= c <= sub.hi):
                self.err(Code.OUT_OF_RANGE, span, f"{c} is outside the range {sub.lo}..{sub.hi} of {dst}")
                return False
        return True

    def _literal_into(self, e, s: T.Type, d: T.Type, dst: T.Type, span: Span) -> bool | None:
        """A number literal: it fits an integer target, or a REAL takes it (None: not decided here)."""
        if s is T.LIT_INT:
            if d.is_intlike or isinstance(T.unalias(dst), T.SubrangeType):
                return self._int_fits(e, dst, span)
            if d.is_real:
                return True
        if s is T.LIT_REAL and d.is_real:
            return True
        return None

    def _int_fits(self, e, dst: T.Type, span: Span) -> bool:
        v = self.consts.value(e, None) if isinstance(e, A.Expr) else None
        if isinstance(v, int) and not T.literal_fits(v, dst):
            shown = v if v.bit_length() < 256 else f"a value of {v.bit_length()} bits"
            u = T.unalias(dst)
            b = u if isinstance(u, T.SubrangeType) else cast(T.ElemType, T.base_of(dst))
            self.err(Code.OUT_OF_RANGE, span, f"{shown} does not fit in {dst} ({b.lo}..{b.hi})")
            return False
        return True

    def _text_into(self, e, s: T.Type, d: T.Type, src: T.Type, dst: T.Type, span: Span, what: str) -> bool | None:
        """Strings and characters (None: neither is one)."""
        if isinstance(s, T.StringType) and isinstance(d, T.StringType):
            if s.wide != d.wide:
                self.err(
                    Code.TYPE_MISMATCH,
                    span,
                    f"cannot {what} {src} to {dst}",
                    "use STRING_TO_WSTRING / WSTRING_TO_STRING",
                )
                return False
            truncated_string.check_truncation(self.ctx, e, d, span)
            return True
        if isinstance(s, T.ElemType) and s.kind == "char" and isinstance(d, T.StringType):
            return True
        if isinstance(d, T.ElemType) and d.kind == "char" and isinstance(e, A.Literal) and isinstance(e.value, str):
            if len(e.value) != 1:
                self.err(Code.TYPE_MISMATCH, span, f"a {d} literal holds exactly one character")
                return False
            return True
        return None

    def _enum_as_int(self, s: T.Type, d: T.Type) -> bool:
        """CODESYS: an enumeration value as its integer (a 'strict' one too), an integer into a
        non-strict one."""
        if (
            self.ctx.enum_read_as_int(s)
            and (d.is_intlike or d.is_real)
            and (cast(T.EnumType, s).base is d or T.widens_to(cast(T.EnumType, s).base, d) or d.is_real)
        ):
            return True
        return self.ctx.enum_as_int(d) and (s.is_intlike or s is T.LIT_INT) and not s.is_bool

    def _link_into(self, s: T.Type, d: T.Type, src: T.Type, dst: T.Type, span: Span, what: str) -> bool | None:
        """References, NULL and interfaces (None: not decided here)."""
        if isinstance(s, T.RefType) and isinstance(d, T.RefType) and self._reference_into(s, d):
            return True
        if s is _NULL and isinstance(d, T.RefType):
            return True
        if isinstance(d, T.POUType) and d.pou_kind == "INTERFACE":
            # an interface variable holds an instance that provides it, or NULL
            if s is _NULL or (isinstance(s, T.POUType) and T.implements(s, d)):
                return True
            self.err(Code.TYPE_MISMATCH, span, f"cannot {what} {src} to {dst}: {src} does not implement {dst}")
            return False
        return None

    def _reference_into(self, s: T.RefType, d: T.RefType) -> bool:
        if same_type(s.target, d.target) or s.target is None:
            return True
        st_, dt_ = T.unalias(s.target), T.unalias(d.target)
        if isinstance(st_, T.POUType) and isinstance(dt_, T.POUType) and T.implements(st_, dt_):
            return True  # a reference to a derived block is a reference to its base
        if d.ref_kind == "POINTER" and isinstance(st_, T.ArrayType) and same_type(st_.element, dt_):
            return self.ctx.feature_quiet("vendor")  # ADR(arr) as a POINTER TO its first element
        # ADR(x) into a POINTER TO BYTE: its bytes (CODESYS)
        return d.ref_kind == "POINTER" and T.pointer_view(st_, dt_) is not None and self.ctx.feature_quiet("vendor")

    # ---------------------------------------------------------------- lvalues
    def lvalue(self, e: A.Expr, scope: Scope) -> T.Type | None:
        """Type `e` as something written: a variable (a part of one), a property with SET."""
        t = self.exprs.expr(e, scope, lvalue=True)
        if isinstance(e.sym if isinstance(e, (A.Name, A.Field)) else None, T.PropSym):
            write_to_constant.check_property_write(self.ctx, e, cast(T.PropSym, cast(A.Name, e).sym))
            return t
        root = e
        while isinstance(root, (A.Field, A.Index, A.Bit)):
            root = root.base
        if isinstance(root, A.Name) and isinstance(root.sym, T.VarSym):
            sym = root.sym  # (e itself when it is a Name)
            sym.written = True
            if not write_to_constant.check_constant_write(self.ctx, e, sym):
                write_to_input.check_write_to_input(self.ctx, e, sym, scope)
        elif not not_assignable.check_not_assignable(self.ctx, e):
            write_to_constant.check_enum_value_write(self.ctx, e)
        return t


_HANDLERS: dict[type, Callable[..., None]] = {
    A.Assign: Statements._assign,
    A.CallStmt: Statements._call_stmt,
    A.If: Statements._if,
    A.Case: Statements._case,
    A.For: Statements._for,
    A.While: Statements._while,
    A.Repeat: Statements._repeat,
    A.Try: Statements._try,
    A.Exit: Statements._exit,
    A.Continue: Statements._exit,
    A.Return: Statements._nothing,
    A.Empty: Statements._nothing,
    A.Mock: Statements._mock,
    A.MockFunction: Statements._mock_function,
}
