"""Calls: FB instances, user functions, native (library) functions, REF(); argument binding."""

from __future__ import annotations

import re
from typing import cast

from ...model import types as T
from .. import ast as A
from ..library import FuncSig
from .common import _SECTIONS_PARAM, Scope, _satisfies, method_of, same_type, take_address
from .part import Part
from .targets import (
    ActionCall,
    Binding,
    BoundCall,
    DeleteCall,
    FbCall,
    FunctionCall,
    IsValidRefCall,
    MethodCall,
    NativeCall,
    NewCall,
    QueryItfCall,
    RefCall,
    SizeofCall,
)
from .tests import TEST_CALLS


class Calls(Part):
    # ---------------------------------------------------------------- calls
    def call(self, c: A.Call, scope: Scope, statement: bool = False, expected=None) -> T.Type | None:
        callee = c.callee
        if isinstance(callee, A.Name):
            key = callee.name.lower()
            sym = self.exprs.lookup(key, scope)
            if (
                isinstance(sym, T.VarSym)
                and not isinstance(T.unalias(sym.type), T.POUType)
                and (key in self.p.pous or self.ctx.native(key) is not None)
            ):
                sym = None  # LEN(x) is the function even where a variable is called len
            if isinstance(sym, T.VarSym):
                sym.used = True
                callee.sym = sym
                callee.ty = sym.type
                return self._fb_call(c, sym.type, scope, statement)
            mt = method_of(scope.fb, key) if not isinstance(sym, T.VarSym) else None
            if (
                mt is not None
                and len(c.args) > len(mt.params())
                and (self.ctx.native(key) is not None or key in self.p.pous)
            ):
                mt = None  # LEN(s) inside a block with a method Len(): the arguments say which
            if mt is not None:  # a method of this instance: THIS^.M(...)
                fn = self.p.pous.get(key)
                sig = self.ctx.native(key)
                n = len([a for a in c.args if not a.name or a.name.lower() not in ("en", "eno")])
                fits = (sig is not None and (n == len(sig.params) or (sig.extensible and n >= len(sig.params)))) or (
                    fn is not None
                    and fn.pou_kind == "FUNCTION"
                    and n == len([p for p in fn.params() if p.section != "VAR_OUTPUT"])
                )
                if fits:  # the call would fit the function too: say which runs
                    self.warn(
                        "W007",
                        callee.span,
                        f"'{callee.name}' calls the method {mt.name} of "
                        f"{mt.owner_fb.name}, not the function of that name",
                        f"write THIS^.{mt.name}(...) to say so, or rename the method",
                    )
                return self._method_call(c, mt, scope, None)
            if key in ("__new", "__delete") and sym is None:
                self.feature("vendor", callee.span, key.upper())
                return self._new_delete(c, key, scope, statement)
            if key in ("adr", "sizeof", "__isvalidref", "__queryinterface") and sym is None and key not in self.p.pous:
                self.feature("vendor", callee.span, key.upper())
            if key in ("ref", "adr") and sym is None and key not in self.p.pous:
                return self._ref_call(c, scope)  # ADR: a POINTER TO the variable (no arithmetic)
            if key == "sizeof" and sym is None and key not in self.p.pous:
                return self._sizeof(c, scope)
            if key in ("lower_bound", "upper_bound") and sym is None and key not in self.p.pous:
                return self._bound(c, key, scope)
            if key == "__isvalidref" and sym is None:
                if len(c.args) != 1 or c.args[0].name:
                    self.err("E017", c.span, "__ISVALIDREF takes one reference")
                    return T.BOOL
                t = self.exprs.expr(c.args[0].value, scope)
                arg = c.args[0].value
                is_ref = isinstance(arg, A.Name) and isinstance(arg.sym, T.VarSym) and T.is_reference(arg.sym.type)
                if not is_ref and not isinstance(T.unalias(t) if t is not None else None, T.RefType):
                    self.err("E013", arg.span, f"__ISVALIDREF needs a reference, not {t}")
                    return T.BOOL
                c.target = IsValidRefCall(arg)
                return T.BOOL
            if key == "__queryinterface" and sym is None:
                return self._query_interface(c, scope)
            if key in TEST_CALLS and sym is None and key not in self.p.pous:
                return self.tests.test_call(c, key, scope, statement)
            if (
                key in scope.actions
                or (scope.pou is not None and key in scope.pou.actions)
                or (scope.fb is not None and key in scope.fb.actions)
            ):  # from a method too
                if c.args:
                    self.err("E017", c.span, "an action takes no arguments")
                c.target = ActionCall(key)
                return None
            pou = self.p.pous.get(key)
            if pou is not None:
                if pou.pou_kind != "FUNCTION":
                    self.err(
                        "E020",
                        c.span,
                        f"'{callee.name}' is a {pou.pou_kind.replace('_', ' ')} type; "
                        f"declare an instance and call that",
                        f"VAR inst : {pou.name}; END_VAR ... inst(...);",
                    )
                    return None
                self.decls.resolve_interface(pou)
                return self._function_call(c, pou, scope)
            sig = self.ctx.native(key)
            if sig is not None:
                return self._native_call(c, sig, scope, expected)
            if self.p.enum_members.get(key) or sym is not None:
                self.err("E020", c.span, f"'{callee.name}' is not callable")
                return None
            self.err("E010", c.span, f"undeclared function or function block '{callee.name}'")
            for a in c.args:
                if not a.output:
                    self.exprs.expr(a.value, scope)
            return None
        # a method: inst.M(...), THIS^.M(...); GVL_Name.inst(...) is an instance call below
        if isinstance(callee, A.Field) and not self.exprs.names_gvl(callee.base, scope):
            self.exprs.self_reference_sugar(callee, scope)
            bt = self.exprs.expr(callee.base, scope)
            b = T.unalias(bt) if bt is not None else None
            if isinstance(b, T.POUType) and b.pou_kind != "FUNCTION":
                self.decls.resolve_interface(b)
                mt = method_of(b, callee.name.lower())
                if mt is not None:
                    return self._method_call(c, mt, scope, callee.base)
                if callee.name.lower() in b.actions and b.pou_kind == "FUNCTION_BLOCK":
                    # inst.Action(): CODESYS and TwinCAT call actions so; TwinCAT also passes the
                    # block's inputs and reads its outputs there, as in a call of the instance
                    c.target = ActionCall(callee.name.lower(), callee.base)
                    if c.args:
                        self.feature("vendor", c.span, "an action call with arguments")
                        c.target = ActionCall(callee.name.lower(), callee.base, b, self._bind_args(c, b, scope, True))
                    return None
                key = callee.name.lower()
                if key not in b.vars and key not in b.properties:
                    what = "method" if b.pou_kind == "INTERFACE" else "method, action or instance"
                    self.err("E023", callee.name_span, f"{b.name} has no {what} '{callee.name}'")
                    for a in c.args:
                        if not a.output:
                            self.exprs.expr(a.value, scope)
                    return None
        # a call through a path: inst.sub(...), arr[i](...)
        t = self.exprs.expr(callee, scope)
        if t is None:
            return None
        return self._fb_call(c, t, scope, statement)

    def _bound(self, c: A.Call, key: str, scope: Scope):
        """LOWER_BOUND(arr, dim) / UPPER_BOUND(arr, dim): a DINT; a constant unless arr is ARRAY[*]."""
        what = key.upper()
        if len(c.args) != 2 or any(a.name or a.output for a in c.args):
            self.err("E017", c.span, f"{what} takes an array and a dimension: {what}(arr, 1)")
            return T.DINT
        at = self.exprs.expr(c.args[0].value, scope)
        dim = self.consts.value(c.args[1].value, scope)
        self.exprs.expr(c.args[1].value, scope, T.DINT)
        u = T.unalias(at) if at is not None else None
        if at is None:
            return T.DINT
        if not isinstance(u, T.ArrayType):
            self.err("E013", c.args[0].value.span, f"{what} needs an array, not {at}")
            return T.DINT
        if not isinstance(dim, int) or not 1 <= dim <= len(u.dims):
            self.err("E029", c.args[1].value.span, f"the dimension must be a constant from 1 to {len(u.dims)}")
            return T.DINT
        lo, hi = u.dims[dim - 1]
        value = None if T.is_conformant(u) else (hi if key == "upper_bound" else lo)
        c.target = BoundCall(c.args[0].value, dim, key == "upper_bound", value)
        return T.DINT

    def check_access(self, mods, owner, what: str, scope: Scope, span) -> None:
        """PRIVATE: only inside its own block; PROTECTED: there and in blocks that extend it."""
        if "PRIVATE" in mods and scope.fb is not owner:
            self.err("E043", span, f"{what} of {owner.name} is PRIVATE: only {owner.name} itself may use it")
        elif "PROTECTED" in mods and (scope.fb is None or not T.implements(scope.fb, owner)):
            self.err(
                "E043",
                span,
                f"{what} of {owner.name} is PROTECTED: only {owner.name} and the blocks that extend it may use it",
            )

    def _new_delete(self, c: A.Call, key: str, scope: Scope, statement: bool):
        """__NEW(type): a POINTER TO a fresh value of that type; __NEW(type, n): to the first of n
        (NULL if n < 1); __DELETE(p): p becomes NULL (the value is freed when nothing refers to it any
        more, so a dangling pointer cannot happen)."""
        most = 2 if key == "__new" else 1
        if not 1 <= len(c.args) <= most or any(a.name for a in c.args):
            self.err(
                "E017",
                c.span,
                "__NEW takes a type and an optional count" if most == 2 else "__DELETE takes one argument",
            )
            return None
        arg = c.args[0].value
        if key == "__delete":
            if not statement:
                self.err("E049", c.span, "__DELETE(p) is a statement; it has no value")
            t = self.stmts.lvalue(arg, scope)
            u = T.unalias(t) if t is not None else None
            if t is not None and not (isinstance(u, T.RefType) and u.ref_kind == "POINTER"):
                self.err("E013", arg.span, f"__DELETE needs a POINTER, not {t}")
            c.target = DeleteCall(arg)
            return None
        name = arg.name if isinstance(arg, A.Name) else ""
        t = (
            (
                T.ELEMENTARY.get(name.upper())
                or self.decls.resolve_named_type(name.lower(), arg.span)
                or self.p.pous.get(name.lower())
            )
            if name
            else None
        )
        if t is None or (isinstance(t, T.POUType) and t.pou_kind not in ("FUNCTION_BLOCK",)):
            self.err("E012", arg.span, "__NEW needs a data type or a FUNCTION_BLOCK type")
            return None
        if isinstance(t, T.POUType) and t.decl is not None and "ABSTRACT" in t.decl.modifiers:
            self.err("E043", arg.span, f"'{t.name}' is ABSTRACT and cannot be instantiated")
        count = c.args[1].value if len(c.args) == 2 else None
        if count is not None:
            if isinstance(t, T.POUType):  # as CODESYS: a count only for data types
                self.err("E017", count.span, f"__NEW of a FUNCTION_BLOCK makes one instance; '{t.name}' takes no count")
            ct = self.exprs.expr(count, scope, T.DINT)
            if ct is not None and not (T.base_of(ct).is_int or T.base_of(ct) is T.LIT_INT):
                self.err("E013", count.span, f"the count of __NEW must be an integer, not {ct}")
        c.target = NewCall(t, count)
        return T.RefType(t, "POINTER")

    def _sizeof(self, c: A.Call, scope: Scope):
        """SIZEOF(variable or type): its size in bytes, a constant (natural alignment, as a 64-bit target)."""
        if len(c.args) != 1 or c.args[0].name:
            self.err("E017", c.span, "SIZEOF takes one variable or type")
            return T.LIT_INT
        arg = c.args[0].value
        t = None
        if isinstance(arg, A.Name) and self.exprs.lookup(arg.name.lower(), scope) is None:
            t = (
                T.ELEMENTARY.get(arg.name.upper())
                or self.decls.resolve_named_type(arg.name.lower(), arg.span)
                or self.p.pous.get(arg.name.lower())
            )
            if t is None:
                self.err("E010", arg.span, f"'{arg.name}' is neither a variable nor a type")
                return T.LIT_INT
        else:
            t = self.exprs.expr(arg, scope)
        if t is None:
            return T.LIT_INT
        size, _align = T.size_of(t)
        c.target = SizeofCall(size)
        c.const = size
        return T.LIT_INT

    def _query_interface(self, c: A.Call, scope: Scope):
        """__QUERYINTERFACE(source, dest): does the instance behind `source` provide dest's
        interface? If so dest refers to it and the result is TRUE (CODESYS)."""
        if len(c.args) != 2 or any(a.name for a in c.args):
            self.err(
                "E017",
                c.span,
                "__QUERYINTERFACE takes two arguments: an interface (or instance) and an interface variable",
            )
            return T.BOOL
        st = self.exprs.expr(c.args[0].value, scope)
        dt = self.stmts.lvalue(c.args[1].value, scope)
        s, d = (T.unalias(x) if x is not None else None for x in (st, dt))
        if not (isinstance(s, T.POUType) and s.pou_kind in ("INTERFACE", "FUNCTION_BLOCK")):
            self.err("E013", c.args[0].span, f"__QUERYINTERFACE needs an interface or an instance, not {st}")
        if not (isinstance(d, T.POUType) and d.pou_kind == "INTERFACE"):
            self.err("E013", c.args[1].span, f"__QUERYINTERFACE needs an interface variable to fill, not {dt}")
            return T.BOOL
        c.target = QueryItfCall(c.args[0].value, c.args[1].value, d)
        return T.BOOL

    def _ref_call(self, c: A.Call, scope: Scope):
        """REF(x): a reference to a variable (IEC 61131-3 3rd edition)."""
        if len(c.args) != 1 or c.args[0].name:
            self.err("E017", c.span, "REF takes exactly one variable")
            return None
        arg = c.args[0].value
        if not isinstance(arg, (A.Name, A.Field, A.Index)):
            self.err("E031", arg.span, "REF needs a variable")
            return None
        t = self.stmts.lvalue(arg, scope)
        take_address(arg)
        if isinstance(arg, A.Name) and isinstance(arg.sym, T.POUType):  # ADR(F) inside F: its result
            arg.sym.result_address_taken = True
        c.target = RefCall(arg)
        return T.RefType(t) if t is not None else None

    def _fb_call(self, c: A.Call, t: T.Type, scope: Scope, statement: bool):
        fb = T.unalias(t)
        if (
            not isinstance(fb, T.POUType)
            or fb.pou_kind in ("FUNCTION", "INTERFACE")
            or (fb.decl is not None and "CLASS" in fb.decl.modifiers)
        ):
            what = (
                "an instance of the CLASS " + fb.name + " has no body; call its methods"
                if isinstance(fb, T.POUType) and fb.decl is not None and "CLASS" in fb.decl.modifiers
                else f"a {t} is not callable"
            )
            self.err("E020", c.span, what)
            return None
        self.decls.resolve_interface(fb)
        if not statement:
            self.err(
                "E049",
                c.span,
                "a function block call is a statement; it has no value",
                "call it, then read its outputs, e.g. inst(...); x := inst.Q;",
            )
        bind = self._bind_args(c, fb, scope, is_fb=True)
        c.target = FbCall(fb, bind)
        return None

    def _method_call(self, c: A.Call, mt: T.POUType, scope: Scope, obj):
        """A METHOD call; obj is the instance expression (None: this instance)."""
        self.check_access(mt.decl.modifiers, mt.owner_fb, f"method {mt.name}", scope, c.span)
        if (
            "ABSTRACT" in mt.decl.modifiers
            and isinstance(obj, A.Deref)
            and isinstance(obj.base, A.Name)
            and getattr(obj.base.sym, "kind", "") == "super"
        ):
            self.err(
                "E043", c.span, f"method {mt.name} of {mt.owner_fb.name} is ABSTRACT: it has no implementation to call"
            )
        bind = self._bind_args(c, mt, scope, is_fb=False)
        c.target = MethodCall(mt, bind, obj)
        return mt.return_type

    def _function_call(self, c: A.Call, pou: T.POUType, scope: Scope):
        bind = self._bind_args(c, pou, scope, is_fb=False)
        c.target = FunctionCall(pou, bind)
        return pou.return_type

    def _bind_args(self, c: A.Call, pou: T.POUType, scope: Scope, is_fb: bool) -> Binding:
        """Match arguments to parameters: {lower param: Arg} plus EN/ENO."""
        params = pou.params()
        pos_params = params
        bind: dict = {}
        extras: dict = {}
        npos = 0
        place = 0  # the argument's place in the call: after named ones, a positional one takes its place's parameter
        p: T.VarSym | None
        for a in c.args:
            key = a.name.lower()
            if key not in ("en", "eno"):
                place += 1
            if not a.name:
                if place > len(pos_params):
                    self.err("E017", a.span, f"too many arguments for {pou.name} (it has {len(pos_params)} parameters)")
                    self.exprs.expr(a.value, scope)
                    continue
                p = pos_params[place - 1]
                npos += 1
                if p.section == "VAR_OUTPUT":
                    a.output = True
                bind[p.name.lower()] = a
            elif key in ("en", "eno"):
                extras[key] = a
                if key == "eno" and "eno" in pou.vars:
                    bind[key] = a  # the body sets ENO itself
            else:
                p = pou.vars.get(key)
                if p is None or p.section not in _SECTIONS_PARAM:
                    names = ", ".join(x.name for x in params) or "none"
                    self.err("E016", a.span, f"{pou.name} has no parameter '{a.name}' (parameters: {names})")
                    if not a.output:
                        self.exprs.expr(a.value, scope)
                    continue
                if key in bind:
                    self.err("E011", a.span, f"parameter '{a.name}' is given twice")
                    continue
                if a.output and p.section != "VAR_OUTPUT":
                    self.err("E016", a.span, f"'{a.name}' is not an output; use ':=' to pass it")
                elif not a.output and p.section == "VAR_OUTPUT":
                    self.err("E016", a.span, f"'{a.name}' is an output; use '=>' to read it")
                    a.output = True
                bind[key] = a
        for key, a in bind.items():
            p = pou.vars[key]
            if a.output:
                if not isinstance(a.value, (A.Name, A.Field, A.Index, A.Bit, A.Deref, A.Direct)):
                    self.err("E031", a.value.span, "an output argument must be a variable")
                    continue
                vt = self.stmts.lvalue(a.value, scope)
                pt = p.type
                if vt is not None and pt is not None and not (T.base_of(pt) is T.base_of(vt) or T.widens_to(pt, vt)):
                    self.stmts.assignable(None, pt, vt, a.value.span, "assign output")
            elif p.section == "VAR_IN_OUT":
                if not isinstance(a.value, (A.Name, A.Field, A.Index, A.Bit, A.Deref, A.Direct)):
                    self.err("E031", a.value.span, f"VAR_IN_OUT '{p.name}' needs a variable, not an expression")
                    continue
                vt = self.stmts.lvalue(a.value, scope)
                if (
                    vt is not None
                    and not same_type(vt, p.type)
                    and not T.extends(vt, p.type)
                    and not (T.is_conformant(p.type) and _fits_conformant(vt, p.type))
                ):
                    if not (isinstance(T.base_of(vt), T.StringType) and isinstance(T.base_of(p.type), T.StringType)):
                        self.err("E013", a.value.span, f"VAR_IN_OUT '{p.name}' is {p.type}; {vt} cannot be passed")
            elif T.is_reference(p.type):  # an input REFERENCE TO is bound to the argument
                want = cast(T.RefType, T.unalias(p.type)).target
                if not isinstance(a.value, (A.Name, A.Field, A.Index, A.Deref)):
                    self.err("E031", a.value.span, f"'{p.name}' is a REFERENCE TO {want}: pass a variable")
                    self.exprs.expr(a.value, scope)
                    continue
                vt = self.stmts.lvalue(a.value, scope)
                take_address(a.value)
                if vt is not None and not same_type(vt, want) and not T.extends(vt, want):
                    self.err("E013", a.value.span, f"'{p.name}' is a REFERENCE TO {want}; {vt} cannot be bound to it")
            elif p.any_input:
                self._any_arg(a, p, scope)
            else:
                vt = self.exprs.expr(a.value, scope, p.type)
                self.stmts.assignable(a.value, vt, p.type, a.value.span, "pass")
        if "en" in extras:
            et = self.exprs.expr(extras["en"].value, scope, T.BOOL)
            if et is not None and not T.base_of(et).is_bool:
                self.err("E013", extras["en"].span, "EN must be BOOL")
        if "eno" in extras:
            a = extras["eno"]
            if not a.output:
                self.err("E016", a.span, "ENO is an output; use 'ENO => var'")
            else:
                self.stmts.lvalue(a.value, scope)
        if not is_fb:
            if npos and not any(a.name and a.name.lower() not in ("en", "eno") for a in c.args):
                # a non-formal call gives every input and in-out, in order (IEC 61131-3 6.6.1.4.2)
                needed = [p for p in params if p.section != "VAR_OUTPUT"]
                if npos < len(needed):
                    self.err(
                        "E017",
                        c.span,
                        f"{pou.name} takes {len(needed)} argument(s), not {npos}",
                        "name the arguments (x := ...) to leave some out",
                    )
                    return {"params": bind, "en": extras.get("en"), "eno": extras.get("eno")}
            for p in pou.in_outs():
                if p.name.lower() not in bind:
                    self.err("E017", c.span, f"VAR_IN_OUT '{p.name}' of {pou.name} must be given")
        return {"params": bind, "en": extras.get("en"), "eno": extras.get("eno")}

    def _vendor_argument(self, t: T.Type, constraint: str) -> T.Type | None:
        """CODESYS/TwinCAT (and the default) pass a value to a function's elementary parameter where
        it converts implicitly without loss: an integer as a bit string of its width or wider
        (DWORD_TO_LWORD(udint)), a non-strict enumeration as its integer (UDINT_TO_INT(class)).
        The type the argument is then read as, or None."""
        want = T.ELEMENTARY.get(constraint)
        if want is None or not self.ctx.bits_as_numbers():
            return None
        b = T.base_of(t)
        if isinstance(b, T.EnumType):
            if not self.ctx.enum_as_int(b):
                return None
            b = T.base_of(b.base) if b.base is not None else T.INT
        w = T.base_of(want)
        if (
            isinstance(b, T.ElemType)
            and isinstance(w, T.ElemType)
            and b.kind in ("int", "bit")
            and w.kind in ("int", "bit")
            and (b.bits < w.bits or (b.bits == w.bits and (w.kind == "bit" or b.kind == "bit" or b.signed == w.signed)))
        ):
            return b
        return None

    def _any_arg(self, a: A.Arg, p: T.VarSym, scope: Scope) -> None:
        """An argument for an ANY input: any value of the family that has bytes; a variable is
        passed by address (pValue points at it), an expression as a temporary. Codegen reads the
        type from `a.value.ty`."""
        vt = self.exprs.expr(a.value, scope)
        if vt is None:
            return
        if isinstance(T.base_of(vt), T.LiteralType):
            vt = T.default_type_for_literal(T.base_of(vt))
            a.value.ty = vt
        if T.byte_layout(vt) is None or not _satisfies(vt, p.any_input):
            self.err("E013", a.value.span, f"'{p.name}' is {p.any_input}; {vt} cannot be passed to it")
            return
        if isinstance(a.value, (A.Name, A.Field, A.Index, A.Deref)):
            take_address(a.value)

    def _native_call(self, c: A.Call, sig: FuncSig, scope: Scope, expected=None):
        args = []
        en = eno = None
        # TwinCAT's parameter names (LEN(STR := s)) where the dialect has vendor extensions
        aliases = sig.aliases if self.ctx.feature_quiet("vendor") else {}
        named = {}
        for a in c.args:
            if a.name.lower() == "en":
                en = a
                continue
            if a.name.lower() == "eno":
                eno = a
                continue
            if a.output:
                self.err("E016", a.span, f"{sig.name} has no output '{a.name}'")
                continue
            if a.name:
                named[aliases.get(a.name.lower(), a.name.lower())] = a
            args.append(a)
        # named arguments in declaration order
        if named:
            ordered = []
            names = [p.name.lower() for p in sig.params]
            for a in args:
                if a.name:
                    key = aliases.get(a.name.lower(), a.name.lower())
                    if key not in names:
                        m = re.fullmatch(r"in(\d+)", key)
                        if sig.extensible and m:
                            continue
                        self.err(
                            "E016",
                            a.span,
                            f"{sig.name} has no parameter '{a.name}' "
                            f"(parameters: {', '.join(p.name for p in sig.params)})",
                        )
                        return None
            pos = [a for a in args if not a.name]
            for p in sig.params:
                arg = named.get(p.name.lower())
                if arg is None and pos:
                    arg = pos.pop(0)
                if arg is not None:
                    ordered.append(arg)
            if sig.extensible:
                extra = sorted(
                    ((int(k[2:]), a) for k, a in named.items() if re.fullmatch(r"in\d+", k) and k not in names),
                    key=lambda x: x[0],
                )
                ordered.extend(a for _, a in extra)
            ordered.extend(pos)
            args = ordered
        n = len(args)
        nmin = sig.min_args or len(sig.params)
        if n < nmin or (not sig.extensible and n > len(sig.params)):
            count = f"at least {nmin}" if sig.extensible else str(len(sig.params))
            self.err("E017", c.span, f"{sig.name} takes {count} argument(s), not {n}")
            for a in args:
                self.exprs.expr(a.value, scope)
            return None
        # types
        arg_types = []
        groups: dict = {}
        for i, a in enumerate(args):
            p = sig.params[min(i, len(sig.params) - 1)]
            want = T.ELEMENTARY.get(p.constraint)
            t = self.exprs.expr(a.value, scope, want)
            arg_types.append(t)
            if t is None:
                continue
            if not _satisfies(t, p.constraint):
                stand_in = self._vendor_argument(t, p.constraint)
                if stand_in is None:
                    self.err("E013", a.value.span, f"argument {i + 1} of {sig.name} must be {p.constraint}, not {t}")
                    arg_types[-1] = None
                    continue
                t = arg_types[-1] = a.value.ty = stand_in
            if p.group:
                prev = groups.get(p.group)
                if prev is None:
                    groups[p.group] = t
                else:
                    ct = T.common_type(prev, t)
                    if (
                        ct is None
                        and isinstance(T.base_of(prev), T.StringType)
                        and isinstance(T.base_of(t), T.StringType)
                    ):
                        ct = prev
                    if ct is None and isinstance(T.base_of(prev), T.EnumType) and T.base_of(prev) is T.base_of(t):
                        ct = prev
                    if ct is None:
                        self.err(
                            "E013", a.value.span, f"arguments of {sig.name} have incompatible types {prev} and {t}"
                        )
                    else:
                        groups[p.group] = ct
            elif want is not None:
                self.stmts.assignable(a.value, t, want, a.value.span, "pass")
        if any(t is None for t in arg_types):
            return None
        for g, t in list(groups.items()):
            if isinstance(t, T.LiteralType):
                # all-literal arguments take the type the context expects (IEC: ANY_NUM literals)
                eb = T.base_of(expected) if expected is not None else None
                if (
                    sig.result == g
                    and eb is not None
                    and isinstance(eb, T.ElemType)
                    and (eb.is_num or (eb.is_bit and t is T.LIT_INT))
                    and not (t is T.LIT_REAL and not eb.is_real)
                ):
                    groups[g] = eb
                else:
                    groups[g] = T.default_type_for_literal(t)
        # settle literal arguments to their group's type
        for i, a in enumerate(args):
            p = sig.params[min(i, len(sig.params) - 1)]
            if p.group and isinstance(arg_types[i], T.LiteralType):
                gt = groups[p.group]
                if isinstance(a.value, A.Literal) and isinstance(a.value.value, int) and T.base_of(gt).is_intlike:
                    if not T.literal_fits(a.value.value, gt):
                        self.err("E021", a.value.span, f"{a.value.value} does not fit in {gt}")
                a.value.ty = gt
                arg_types[i] = gt
        res = sig.result
        eb = T.base_of(expected) if expected is not None else None
        if (
            callable(res)
            and arg_types
            and all(isinstance(t, T.LiteralType) for t in arg_types)
            and isinstance(eb, T.ElemType)
            and eb.is_real
        ):
            # SQRT(2.0) in a REAL context computes in REAL
            for a in args:
                a.value.ty = eb
            arg_types = [eb] * len(arg_types)
        rt: T.Type | None
        if getattr(sig, "result_from_context", False) and isinstance(eb, T.ElemType) and eb.is_int:
            rt = eb  # TRUNC: ANY_REAL → the integer type the context wants
        elif callable(res):
            rt = res(arg_types)
            if isinstance(rt, str):
                self.err("E013", c.span, rt)
                return None
            if isinstance(rt, T.LiteralType):
                # all-literal arguments: the type the context expects
                if isinstance(eb, T.ElemType) and (eb.is_real or (eb.is_intlike and rt is T.LIT_INT)):
                    rt = eb
                else:
                    rt = T.default_type_for_literal(rt)
        elif res in groups:
            rt = groups[res]
        elif res is None:
            rt = None
        else:
            rt = T.ELEMENTARY[res]
        if en is not None:
            self.exprs.expr(en.value, scope, T.BOOL)
        if eno is not None:
            self.stmts.lvalue(eno.value, scope)
        c.target = NativeCall(sig, args, arg_types, en, eno)
        return rt


def _fits_conformant(arg, param) -> bool:
    """An array for an ARRAY[*] parameter: as many dimensions, the same element type."""
    a, p = T.unalias(arg), cast(T.ArrayType, T.unalias(param))
    return isinstance(a, T.ArrayType) and len(a.dims) == len(p.dims) and same_type(a.element, p.element)


size_of = T.size_of  # (bytes, alignment) of a type, as SIZEOF counts: for libraries (MEMCPY's layouts)
