"""Bodies: statements, SFC networks, assignability and lvalues."""

from __future__ import annotations

from typing import cast

from ...model import types as T
from ...source import Span
from .. import ast as A
from .common import _NULL, STEP, Scope, same_type, take_address
from .expressions import _null_at, _zero_pointer
from .for_counter import counter_writes, root_sym
from .part import Part


class Statements(Part):
    # ================================================================ bodies
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
            bt = self.exprs.expr(tgt.base, scope)
            b = T.unalias(bt) if bt is not None else None
            if isinstance(b, T.POUType):
                sym = b.vars.get(tgt.name.lower())
                if isinstance(sym, T.VarSym) and sym.access:
                    self.calls.check_access((sym.access,), sym.owner, f"variable {sym.name}", scope, tgt.name_span)
        if not (isinstance(sym, T.VarSym) and T.is_reference(sym.type)):
            self.err("E013", tgt.span, "REF= binds a REFERENCE TO variable; this is not one")
            return
        sym.used = sym.written = True
        cast(A.Name, tgt).sym = sym  # a Name or a Field
        tgt.ty = sym.type
        self._ref_source(s, cast(T.RefType, T.unalias(sym.type)).target, scope)

    def _ref_source(self, s: A.Assign, want: T.Type | None, scope: Scope) -> None:
        """What REF= binds to: a variable, NULL (or 0), or the REFERENCE TO a call returns."""
        v = s.value
        if isinstance(v, A.Literal) and v.kind == "int" and v.value == 0 and not v.type_name:
            s.value = v = A.Name(v.span, "NULL")  # CODESYS: r REF= 0 unbinds, as REF= NULL
        if isinstance(v, A.Name) and v.name.upper() == "NULL":
            self.exprs.expr(v, scope)
            return
        if isinstance(v, A.Call):
            rt = self.calls.call(v, scope)
            v.ty = rt
            if rt is None:
                return
            if not T.is_reference(rt):
                self.err("E031", v.span, f"REF= needs a variable to refer to; this call returns a {rt}")
                return
            got = cast(T.RefType, T.unalias(rt)).target
            if want is not None and got is not None and not same_type(got, want) and not T.extends(got, want):
                self.err("E013", v.span, f"REF= needs a {want} variable, not {got}")
            return
        if not isinstance(v, (A.Name, A.Field, A.Index, A.Deref)):
            self.err("E031", v.span, "REF= needs a variable to refer to")
            self.exprs.expr(v, scope)
            return
        vt = self.lvalue(v, scope)
        take_address(v)
        if vt is not None and want is not None and not same_type(vt, want) and not T.extends(vt, want):
            self.err("E013", v.span, f"REF= needs a {want} variable, not {vt}")

    def _attempt_assign(self, s: A.Assign, scope: Scope) -> None:
        """dest ?= src (assignment attempt): dest, an interface or a REF_TO a block, receives src's
        instance when it is of dest's kind at run time, else NULL."""
        self.feature("oop", s.span, "?= (assignment attempt)")
        tt = self.lvalue(s.target, scope)
        vt = self.exprs.expr(s.value, scope)
        if tt is None or vt is None:
            return

        def classify(t):
            u = T.unalias(t)
            if (
                isinstance(u, T.RefType)
                and isinstance(T.unalias(u.target), T.POUType)
                and T.unalias(u.target).pou_kind in ("FUNCTION_BLOCK", "INTERFACE")
            ):
                return T.unalias(u.target), True
            if isinstance(u, T.POUType) and u.pou_kind in ("FUNCTION_BLOCK", "INTERFACE"):
                return u, False
            return None, False

        kind, dest_ref = classify(tt)
        if kind is None or (not dest_ref and kind.pou_kind != "INTERFACE"):
            self.err("E013", s.target.span, f"?= needs an interface or a REF_TO a function block on the left, not {tt}")
            return
        if vt is _NULL:
            s.attempt = (kind.name.lower(), False, dest_ref)
            return
        src, src_ref = classify(vt)
        if src is None:
            self.err(
                "E013",
                s.value.span,
                f"?= needs an interface, a function block instance or a reference to one on the right, not {vt}",
            )
            return
        s.attempt = (kind.name.lower(), src_ref, dest_ref)

    # ---------------------------------------------------------------- SFC
    # ---------------------------------------------------------------- statements
    def stmt_list(self, body: list, scope: Scope) -> None:
        for s in body:
            try:
                self.stmt(s, scope)
            except Exception as exc:
                if not hasattr(exc, "st_span"):
                    exc.st_span = s.span  # type: ignore[attr-defined]  # where the internal error happened, for the report
                raise

    def stmt(self, s: A.Stmt, scope: Scope) -> None:
        if isinstance(s, A.Assign) and s.kind == "REF=":
            return self._ref_assign(s, scope)
        if isinstance(s, A.Assign) and s.kind == "?=":
            return self._attempt_assign(s, scope)
        if isinstance(s, A.Assign) and s.chained:
            self.feature("vendor", s.span, "chained assignment (a := b := c)")
        if isinstance(s, A.Assign):
            tt = self.lvalue(s.target, scope)
            if s.kind in ("S=", "R="):
                vt = self.exprs.expr(s.value, scope, T.BOOL)
                # a None type was reported already (an undeclared name, ...)
                if (tt is not None and not T.base_of(tt).is_bool) or (vt is not None and not T.base_of(vt).is_bool):
                    self.err("E013", s.span, f"'{s.kind}' needs BOOL operands")
                return
            vt = self.exprs.expr(s.value, scope, tt)
            if _zero_pointer(self.ctx, s.value, tt):
                s.value, vt = _null_at(s.value), _NULL  # p := 0 (CODESYS): NULL
            if tt is not None:
                self.assignable(s.value, vt, tt, s.value.span)
        elif isinstance(s, A.CallStmt):
            rt = self.calls.call(s.call, scope, statement=True)
            if s.call.ty is None:
                s.call.ty = rt  # a function's result, unused: code generation still needs its type
        elif isinstance(s, A.If):
            for cond, body in s.branches:
                self.condition(cond, scope, "IF")
                self.stmt_list(body, scope)
            if s.orelse:
                self.stmt_list(s.orelse, scope)
        elif isinstance(s, A.Case):
            self._case(s, scope)
        elif isinstance(s, A.For):
            vt = self.lvalue(s.var, scope)
            if vt is not None and not T.base_of(vt).is_intlike:
                self.err("E025", s.var.span, f"a FOR variable must be an integer, not {vt}")
            for e in (s.start, s.end, s.step):
                if e is not None:
                    et = self.exprs.expr(e, scope, vt)
                    if vt is not None:
                        self.assignable(e, et, vt, e.span)
            if isinstance(s.step, A.Expr):
                c = self.consts.value(s.step, scope)
                if c == 0:
                    self.err("E029", s.step.span, "a FOR step of 0 never ends")
            scope.loop_depth += 1
            self.stmt_list(s.body, scope)
            scope.loop_depth -= 1
            self._for_counter_written(s, scope)
        elif isinstance(s, A.While):
            self.condition(s.cond, scope, "WHILE")
            scope.loop_depth += 1
            self.stmt_list(s.body, scope)
            scope.loop_depth -= 1
        elif isinstance(s, A.Repeat):
            scope.loop_depth += 1
            self.stmt_list(s.body, scope)
            scope.loop_depth -= 1
            self.condition(s.cond, scope, "UNTIL")
        elif isinstance(s, (A.Exit, A.Continue)):
            if scope.loop_depth == 0:
                self.err("E024", s.span, f"{'EXIT' if isinstance(s, A.Exit) else 'CONTINUE'} outside a loop")
        elif isinstance(s, (A.Return, A.Empty)):
            pass
        elif isinstance(s, A.Mock):
            self.tests.mock(s, scope)
        elif isinstance(s, A.MockFunction):
            self.tests.mock_function(s, scope)
        else:  # pragma: no cover
            raise AssertionError(s)

    def _for_counter_written(self, s: A.For, scope: Scope) -> None:
        """E052 under a dialect that forbids writing a FOR's control variable in its body (st's own
        libraries are written for every dialect)."""
        d = self.ctx.dialect
        sym = root_sym(s.var)
        if d is None or d.writable_for_counter or sym is None or scope.library:
            return
        for span, how in counter_writes(s.body, sym):
            self.err(
                "E052",
                span,
                f"'{sym.name}' is the control variable of the FOR on line {s.span.line}: {how} in its body",
                f"IEC 61131-3 and MatIEC forbid it (the {d.name} dialect); count in another variable, or use WHILE",
            )

    def condition(self, e: A.Expr, scope: Scope, what: str) -> None:
        t = self.exprs.expr(e, scope, T.BOOL)
        if t is not None and not T.base_of(t).is_bool:
            self.err(
                "E015",
                e.span,
                f"the {what} condition must be BOOL, not {t}",
                "compare explicitly, e.g. x <> 0" if T.base_of(t).is_num else "",
            )

    def _case(self, s: A.Case, scope: Scope) -> None:
        st = self.exprs.expr(s.selector, scope)
        bst = T.base_of(st) if st is not None else None
        if bst is not None and not (bst.is_intlike or isinstance(bst, T.EnumType)):
            self.err("E019", s.selector.span, f"a CASE selector must be an integer or enumeration, not {st}")
            bst = None
        seen: list = []
        for br in s.branches:
            for lo, hi in br.labels:
                vals = []
                for e in (lo, hi):
                    if e is None:
                        continue
                    et = self.exprs.expr(e, scope, st)
                    if bst is not None and et is not None:
                        if isinstance(bst, T.EnumType):
                            if T.base_of(et) is not bst:
                                self.err("E019", e.span, f"CASE label of type {et} for a selector of type {st}")
                        elif not (
                            T.base_of(et).is_intlike or et is T.LIT_INT or self.ctx.enum_as_int(T.base_of(et))
                        ):  # CODESYS: a non-strict enumeration value labels an integer selector
                            self.err("E019", e.span, f"CASE label of type {et} for a selector of type {st}")
                    v = self.consts.value(e, scope)
                    if v is None:
                        self.err("E029", e.span, "a CASE label must be a constant")
                    vals.append(v)
                if not all(isinstance(v, int) for v in vals):
                    continue  # a wrong label type was reported above
                if len(vals) == 2:
                    a, b = vals
                    for c, d, _sp in seen:
                        if a <= d and c <= b:
                            self.err("E019", lo.span, f"CASE label {a}..{b} overlaps an earlier label")
                            break
                    seen.append((a, b, lo.span))
                elif len(vals) == 1:
                    a = vals[0]
                    for c, d, _sp in seen:
                        if c <= a <= d:
                            self.err("E019", lo.span, f"duplicate CASE label {a}")
                            break
                    seen.append((a, a, lo.span))
            self.stmt_list(br.body, scope)
        if s.orelse:
            self.stmt_list(s.orelse, scope)

    # ---------------------------------------------------------------- assignability
    def assignable(self, e, src: T.Type | None, dst: T.Type | None, span: Span, what: str = "") -> bool:
        if src is None or dst is None:
            return True
        s, d = T.base_of(src), T.base_of(dst)
        if s is d:
            if isinstance(T.unalias(dst), T.SubrangeType) and isinstance(e, A.Expr):
                c = self.consts.value(e, None) if isinstance(e, (A.Literal, A.Unary)) else None
                sub = cast(T.SubrangeType, T.unalias(dst))
                if isinstance(c, int) and not (sub.lo <= c <= sub.hi):
                    self.err("E021", span, f"{c} is outside the range {sub.lo}..{sub.hi} of {dst}")
                    return False
            return True
        what = what or "assign"
        if s is T.LIT_INT:
            if d.is_intlike or isinstance(T.unalias(dst), T.SubrangeType):
                v = self.consts.value(e, None) if isinstance(e, A.Expr) else None
                if isinstance(v, int) and not T.literal_fits(v, dst):
                    shown = v if v.bit_length() < 256 else f"a value of {v.bit_length()} bits"
                    u = T.unalias(dst)
                    b = u if isinstance(u, T.SubrangeType) else cast(T.ElemType, T.base_of(dst))
                    lo, hi = b.lo, b.hi
                    self.err("E021", span, f"{shown} does not fit in {dst} ({lo}..{hi})")
                    return False
                return True
            if d.is_real:
                return True
        if s is T.LIT_REAL and d.is_real:
            return True
        if isinstance(s, T.StringType) and isinstance(d, T.StringType):
            if s.wide != d.wide:
                self.err("E013", span, f"cannot {what} {src} to {dst}", "use STRING_TO_WSTRING / WSTRING_TO_STRING")
                return False
            if isinstance(e, A.Literal) and isinstance(e.value, str) and len(e.value) > d.length:
                self.warn("W003", span, f"the string ({len(e.value)} characters) is truncated to {d.length}")
            return True
        if isinstance(s, T.ElemType) and s.kind == "char" and isinstance(d, T.StringType):
            return True
        if isinstance(d, T.ElemType) and d.kind == "char" and isinstance(e, A.Literal) and isinstance(e.value, str):
            if len(e.value) != 1:
                self.err("E013", span, f"a {d} literal holds exactly one character")
                return False
            return True
        if T.widens_to(s, d):
            return True
        if self.ctx.bits_as_numbers() and T.bits_numbers_convert(s, d):
            return True  # CODESYS, TwinCAT: BYTE into INT or REAL, INT into WORD (the value is kept)
        if self.ctx.bits_as_numbers() and T.lossy_number_conversion(s, d):
            self.warn(
                "W008",
                span,
                f"implicit conversion from {src} to {dst} may lose data (the value is wrapped to {dst})"
                if not d.is_real
                else f"implicit conversion from {src} to {dst} may lose precision",
                f"convert explicitly with {s.name}_TO_{d.name}(...) to say it is meant",
            )
            return True
        if (
            self.ctx.enum_as_int(s)
            and (d.is_intlike or d.is_real)
            and (cast(T.EnumType, s).base is d or T.widens_to(cast(T.EnumType, s).base, d) or d.is_real)
        ):
            return True  # CODESYS: a (non-strict) enumeration value as its integer
        if self.ctx.enum_as_int(d) and (s.is_intlike or s is T.LIT_INT) and not s.is_bool:
            return True  # CODESYS: an integer into a non-strict enumeration (its value as the member's)
        if isinstance(s, T.ArrayType) and isinstance(d, T.ArrayType):
            if same_type(s, d):
                return True
        if isinstance(s, T.RefType) and isinstance(d, T.RefType):
            if same_type(s.target, d.target) or s.target is None:
                return True
            st_, dt_ = T.unalias(s.target), T.unalias(d.target)
            if isinstance(st_, T.POUType) and isinstance(dt_, T.POUType) and T.implements(st_, dt_):
                return True  # a reference to a derived block is a reference to its base
            if d.ref_kind == "POINTER" and T.pointer_view(st_, dt_) is not None and self.ctx.feature_quiet("vendor"):
                return True  # ADR(x) into a POINTER TO BYTE: its bytes (CODESYS)
        if s is _NULL and isinstance(d, T.RefType):
            return True
        if isinstance(d, T.POUType) and d.pou_kind == "INTERFACE":
            # an interface variable holds an instance that provides it, or NULL
            if s is _NULL or (isinstance(s, T.POUType) and T.implements(s, d)):
                return True
            self.err("E013", span, f"cannot {what} {src} to {dst}: {src} does not implement {dst}")
            return False
        if (
            isinstance(s, T.ElemType)
            and isinstance(d, T.ElemType)
            and (
                s.kind in ("int", "real", "bit")
                and d.kind in ("int", "real", "bit")
                or s.kind == d.kind
                and s.kind in ("time", "date", "tod", "dt")
                and s.long
                and not d.long
            )
        ):
            conv = f"{s.name}_TO_{d.name}"
            if s.kind != d.kind and "bit" in (s.kind, d.kind) and T.bits_numbers_convert(s, d):
                # nothing would be lost: the rule is the type family
                why = (
                    f"{src} is a bit string and {dst} a number: IEC 61131-3 converts between them only "
                    f"explicitly (the codesys and twincat dialects do it implicitly)"
                    if s.kind == "bit"
                    else f"{src} is a number and {dst} a bit string: IEC 61131-3 converts between them only "
                    f"explicitly (the codesys and twincat dialects do it implicitly)"
                )
            else:
                why = f"implicit conversion from {src} to {dst} may lose data"
            self.err("E027", span, why, f"convert explicitly with {conv}(...)")
            return False
        self.err("E013", span, f"type mismatch: cannot {what} {src} to {dst}")
        return False

    # ---------------------------------------------------------------- lvalues
    def lvalue(self, e: A.Expr, scope: Scope) -> T.Type | None:
        t = self.exprs.expr(e, scope, lvalue=True)
        root = e
        while isinstance(root, (A.Field, A.Index, A.Bit)):
            root = root.base
        if isinstance(e.sym if isinstance(e, (A.Name, A.Field)) else None, T.PropSym):
            prop = cast(T.PropSym, cast(A.Name, e).sym)
            if prop.set is None:
                self.err("E018", e.span, f"property {prop.name} has no SET: it cannot be written")
            return t
        if (
            isinstance(e, A.Name)
            and isinstance(e.sym, T.VarSym)
            or isinstance(root, A.Name)
            and isinstance(root.sym, T.VarSym)
        ):
            sym = cast(T.VarSym, e.sym if isinstance(e, A.Name) else cast(A.Name, root).sym)
            sym.written = True
            g = sym.global_ref or sym
            if g.constant or sym.constant:
                self.err("E018", e.span, f"'{sym.name}' is a CONSTANT")
                return t
            if (
                sym.section == "VAR_INPUT"
                and scope.pou is not None
                and sym.owner is scope.pou
                and not isinstance(T.unalias(sym.type), (T.POUType,))
                and isinstance(e, A.Name)
                and not T.is_reference(sym.type)
                and not (self.ctx.dialect is None or self.ctx.dialect.writable_inputs)
            ):
                self.err(
                    "E048",
                    e.span,
                    f"'{sym.name}' is an input of {scope.pou.name} and cannot be written here",
                    "copy it into a local variable first",
                )
                return t
        elif isinstance(e, (A.Literal, A.Call, A.Binary, A.Unary, A.EnumLit)):
            self.err("E013", e.span, "this expression cannot be assigned to")
        elif isinstance(e, A.Name) and e.sym is STEP:
            self.err("E013", e.span, "a step cannot be assigned to")
        elif isinstance(e, A.Name) and isinstance(e.sym, T.EnumType):
            self.err("E018", e.span, f"'{e.name}' is a value of the enumeration {e.sym.name}, not a variable")
        return t
