"""Call resolution: what a call names (an instance of a function block, a METHOD, an ACTION, a
user FUNCTION, an intrinsic: intrinsics.py, a library function: natives.py), its arguments bound
(binding.py) and its target (targets.py) set."""

from __future__ import annotations

from ...diagnostics import Code
from ...model import types as T
from .. import ast as A
from ..syntax import decl_of
from .binding import bind_args
from .common import Scope, method_of
from .intrinsics import INTRINSICS
from .natives import native_call
from .part import Part
from .rules import abstract, access, call_without_value
from .rules.method_shadows_function import check_method_shadows_function
from .targets import ActionCall, FbCall, FunctionCall, MethodCall


class Calls(Part):
    def call(self, c: A.Call, scope: Scope, statement: bool = False, expected=None) -> T.Type | None:
        callee = c.callee
        if isinstance(callee, A.Name):
            return self._named_call(c, callee, scope, statement, expected)
        # a method: inst.M(...), THIS^.M(...); GVL_Name.inst(...) is an instance call below
        if isinstance(callee, A.Field) and not self.exprs.names_gvl(callee.base, scope):
            done, t = self._member_call(c, callee, scope)
            if done:
                return t
        # a call through a path: inst.sub(...), arr[i](...)
        t = self.exprs.expr(callee, scope)
        if t is None:
            return None
        return self._fb_call(c, t, scope, statement)

    def _named_call(self, c: A.Call, callee: A.Name, scope: Scope, statement: bool, expected) -> T.Type | None:
        """NAME(...): an instance, a method of this one, an intrinsic, an action, a function."""
        key = callee.name.lower()
        sym = self.exprs.lookup(key, scope)
        if (
            isinstance(sym, T.VarSym)
            and not _an_instance(sym.type)
            and (key in self.p.pous or self.ctx.native(key) is not None)
        ):
            sym = None  # LEN(x) is the function even where a variable is called len
        if isinstance(sym, T.VarSym):
            sym.used = True
            callee.sym = sym
            callee.ty = sym.type
            if self.ctx.program_instances.get(key) is sym:
                self.ctx.called_programs.add(key)
            return self._fb_call(c, sym.type, scope, statement)
        mt = self._own_method(c, key, scope)
        if mt is not None:  # a method of this instance: THIS^.M(...)
            check_method_shadows_function(self.ctx, c, callee, mt)
            return self._method_call(c, mt, scope, None)
        entry = INTRINSICS.get(key)
        if entry is not None and sym is None and not (entry.pou_first and key in self.p.pous):
            if entry.vendor and (entry.vendor_beside_pou or key not in self.p.pous):
                self.feature("vendor", callee.span, key.upper())
            return entry.handler(self, c, key, scope, statement)
        if (
            key in scope.actions
            or (scope.pou is not None and key in scope.pou.actions)
            or (scope.fb is not None and key in scope.fb.actions)
        ):  # from a method too
            if c.args:
                self.err(Code.ARGUMENT_COUNT, c.span, "an action takes no arguments")
            c.target = ActionCall(key)
            return None
        return self._function_or_library_call(c, callee, key, sym, scope, expected)

    def _own_method(self, c: A.Call, key: str, scope: Scope) -> T.POUType | None:
        """The method `key` of the running instance, unless the arguments say that the function of
        that name is meant (LEN(s) inside a block with a method Len())."""
        mt = method_of(scope.fb, key)
        if (
            mt is not None
            and len(c.args) > len(mt.params())
            and (self.ctx.native(key) is not None or key in self.p.pous)
        ):
            return None
        return mt

    def _function_or_library_call(
        self, c: A.Call, callee: A.Name, key: str, sym, scope: Scope, expected
    ) -> T.Type | None:
        pou = self.p.pous.get(key)
        if pou is not None:
            if pou.pou_kind != "FUNCTION":
                self.err(
                    Code.NOT_CALLABLE,
                    c.span,
                    f"'{callee.name}' is a {pou.pou_kind.replace('_', ' ')} type; declare an instance and call that",
                    f"VAR inst : {pou.name}; END_VAR ... inst(...);",
                )
                return None
            self.decls.resolve_interface(pou)
            return self._function_call(c, pou, scope)
        sig = self.ctx.native(key)
        if sig is not None:
            return native_call(self, c, sig, scope, expected)
        if self.p.enum_members.get(key) or sym is not None:
            self.err(Code.NOT_CALLABLE, c.span, f"'{callee.name}' is not callable")
            return None
        self.err(Code.UNDECLARED, c.span, f"undeclared function or function block '{callee.name}'")
        self._type_inputs(c, scope)
        return None

    def _type_inputs(self, c: A.Call, scope: Scope) -> None:
        """The input arguments of a call that cannot be bound, typed for their own errors."""
        for a in c.args:
            if not a.output:
                self.exprs.expr(a.value, scope)

    def _member_call(self, c: A.Call, callee: A.Field, scope: Scope) -> tuple[bool, T.Type | None]:
        """inst.M(...), inst.Action(...): (True, its type) when it is one, (False, None) when the
        call is of an instance `inst.sub` instead."""
        self.exprs.self_reference_sugar(callee, scope)
        bt = self.exprs.expr(callee.base, scope)
        b = T.unalias(bt) if bt is not None else None
        if not (isinstance(b, T.POUType) and b.pou_kind != "FUNCTION"):
            return False, None
        self.decls.resolve_interface(b)
        key = callee.name.lower()
        mt = method_of(b, key)
        if mt is not None:
            return True, self._method_call(c, mt, scope, callee.base)
        if key in b.actions and b.pou_kind == "FUNCTION_BLOCK":
            # inst.Action(): CODESYS and TwinCAT call actions so; TwinCAT also passes the
            # block's inputs and reads its outputs there, as in a call of the instance
            c.target = ActionCall(key, callee.base)
            if c.args:
                self.feature("vendor", c.span, "an action call with arguments")
                c.target = ActionCall(key, callee.base, b, bind_args(self, c, b, scope, True))
            return True, None
        if key not in b.vars and key not in b.properties:
            what = "method" if b.pou_kind == "INTERFACE" else "method, action or instance"
            self.err(Code.BAD_ACCESS, callee.name_span, f"{b.name} has no {what} '{callee.name}'")
            self._type_inputs(c, scope)
            return True, None
        return False, None

    def _fb_call(self, c: A.Call, t: T.Type, scope: Scope, statement: bool):
        fb = T.unalias(t)
        if isinstance(fb, T.RefType) and fb.ref_kind == "REFERENCE":  # a REFERENCE TO a block: the block
            fb = T.unalias(fb.target)
        if (
            not isinstance(fb, T.POUType)
            or fb.pou_kind in ("FUNCTION", "INTERFACE")
            or (fb.decl is not None and "CLASS" in decl_of(fb).modifiers)
        ):
            what = (
                "an instance of the CLASS " + fb.name + " has no body; call its methods"
                if isinstance(fb, T.POUType) and fb.decl is not None and "CLASS" in decl_of(fb).modifiers
                else f"a {t} is not callable"
            )
            self.err(Code.NOT_CALLABLE, c.span, what)
            return None
        self.decls.resolve_interface(fb)
        call_without_value.check_statement_call(
            self.ctx,
            c,
            statement,
            "a function block call is a statement; it has no value",
            "call it, then read its outputs, e.g. inst(...); x := inst.Q;",
        )
        c.target = FbCall(fb, bind_args(self, c, fb, scope, is_fb=True))
        return None

    def _method_call(self, c: A.Call, mt: T.POUType, scope: Scope, obj):
        """A METHOD call; obj is the instance expression (None: this instance)."""
        access.check_access(self.ctx, decl_of(mt).modifiers, mt.block, f"method {mt.name}", scope, c.span)
        abstract.check_super_call(self.ctx, c, mt, obj)
        c.target = MethodCall(mt, bind_args(self, c, mt, scope, is_fb=False), obj)
        return mt.return_type

    def _function_call(self, c: A.Call, pou: T.POUType, scope: Scope):
        c.target = FunctionCall(pou, bind_args(self, c, pou, scope, is_fb=False))
        return pou.return_type


size_of = T.size_of  # (bytes, alignment) of a type, as SIZEOF counts: for libraries (MEMCPY's layouts)


def _an_instance(t: T.Type) -> bool:
    """A block instance, or a REFERENCE TO one (`otg : REFERENCE TO Otg; otg();`: the variable is
    called, not the type of the same name)."""
    u = T.unalias(t)
    if isinstance(u, T.RefType) and u.ref_kind == "REFERENCE":
        u = T.unalias(u.target)
    return isinstance(u, T.POUType)
