"""Argument binding: a call's arguments matched to the parameters of the POU it calls (a function
block instance, a FUNCTION, a METHOD, TwinCAT's action with arguments), each checked as its
parameter takes it: an input by value (assignable), an output (=>) or a VAR_IN_OUT as a variable,
a REFERENCE TO input bound to a variable, an ANY input by address; EN and ENO. The result is the
call target's `Binding`."""

from __future__ import annotations

from typing import cast

from ...diagnostics import Code
from ...model import types as T
from .. import ast as A
from .common import _SECTIONS_PARAM, Scope, _satisfies, names_constant, same_type, take_address
from .expressions import _null_at, _zero_pointer
from .part import Part
from .rules import dialect_features, reference_binding
from .targets import Binding

_VARIABLE = (A.Name, A.Field, A.Index, A.Bit, A.Deref, A.Direct)  # what an output or in-out argument may be


def bind_args(part: Part, c: A.Call, pou: T.POUType, scope: Scope, is_fb: bool) -> Binding:
    """Match the arguments of `c` to the parameters of `pou`: {lower param: Arg} plus EN/ENO.
    `is_fb`: a function block's call, which may leave any parameter out."""
    return _Binder(part, c, pou, scope).bind(is_fb)


class _Binder:
    def __init__(self, part: Part, c: A.Call, pou: T.POUType, scope: Scope) -> None:
        self.part, self.ctx = part, part.ctx
        self.c, self.pou, self.scope = c, pou, scope
        self.params = pou.params()
        self.bound: dict[str, A.Arg] = {}
        self.extras: dict[str, A.Arg] = {}  # EN and ENO
        self.npos = 0  # positional arguments bound

    def bind(self, is_fb: bool) -> Binding:
        place = 0  # the argument's place in the call: after named ones, a positional one takes its place's parameter
        for a in self.c.args:
            key = a.name.lower()
            if key not in ("en", "eno"):
                place += 1
            if not a.name:
                self._positional(a, place)
            elif key in ("en", "eno"):
                self.extras[key] = a
                if key == "eno" and "eno" in self.pou.vars:
                    self.bound[key] = a  # the body sets ENO itself
            else:
                self._named(a, key)
        for key, a in self.bound.items():
            self._check(a, self.pou.vars[key])
        self._check_en_eno()
        if not is_fb:
            self._check_count()
        return {"params": self.bound, "en": self.extras.get("en"), "eno": self.extras.get("eno")}

    def _positional(self, a: A.Arg, place: int) -> None:
        if place > len(self.params):
            self.part.err(
                Code.ARGUMENT_COUNT,
                a.span,
                f"too many arguments for {self.pou.name} (it has {len(self.params)} parameters)",
            )
            self.part.exprs.expr(a.value, self.scope)
            return
        p = self.params[place - 1]
        self.npos += 1
        if p.section == "VAR_OUTPUT":
            a.output = True
        self.bound[p.name.lower()] = a

    def _named(self, a: A.Arg, key: str) -> None:
        p = self.pou.vars.get(key)
        if p is None or p.section not in _SECTIONS_PARAM:
            names = ", ".join(x.name for x in self.params) or "none"
            self.part.err(
                Code.BAD_PARAMETER, a.span, f"{self.pou.name} has no parameter '{a.name}' (parameters: {names})"
            )
            if not a.output:
                self.part.exprs.expr(a.value, self.scope)
            return
        if key in self.bound:
            self.part.err(Code.BAD_PARAMETER, a.span, f"parameter '{a.name}' is given twice")
            return
        if a.output and p.section != "VAR_OUTPUT":
            self.part.err(Code.BAD_PARAMETER, a.span, f"'{a.name}' is not an output; use ':=' to pass it")
        elif not a.output and p.section == "VAR_OUTPUT":
            self.part.err(Code.BAD_PARAMETER, a.span, f"'{a.name}' is an output; use '=>' to read it")
            a.output = True
        self.bound[key] = a

    def _check(self, a: A.Arg, p: T.VarSym) -> None:
        """The argument `a` as the parameter `p` takes it."""
        if a.output:
            self._output(a, p)
        elif p.section == "VAR_IN_OUT":
            self._in_out(a, p)
        elif T.is_reference(p.type):  # an input REFERENCE TO is bound to the argument
            self._reference_input(a, p)
        elif p.any_input:
            self._any_input(a, p)
        else:
            if _zero_pointer(self.ctx, a.value, p.type):
                a.value = _null_at(a.value)  # a literal 0 for a POINTER (CODESYS): NULL, as in `p := 0`
            vt = self.part.exprs.expr(a.value, self.scope, p.type)
            self.part.stmts.assignable(a.value, vt, p.type, a.value.span, "pass")

    def _output(self, a: A.Arg, p: T.VarSym) -> None:
        if not isinstance(a.value, _VARIABLE):
            self.part.err(Code.NOT_A_VARIABLE, a.value.span, "an output argument must be a variable")
            return
        vt = self.part.stmts.lvalue(a.value, self.scope)
        pt = p.type
        if vt is not None and pt is not None and not (T.base_of(pt) is T.base_of(vt) or T.widens_to(pt, vt)):
            self.part.stmts.assignable(None, pt, vt, a.value.span, "assign output")

    def _in_out(self, a: A.Arg, p: T.VarSym) -> None:
        if p.constant and self.ctx.feature_quiet("vendor") and not self._storage(a.value):
            self._in_out_temporary(a, p)
            return
        if not isinstance(a.value, _VARIABLE):
            hint = ""
            if p.constant:  # iec, openplc
                hint = f"{dialect_features.presets_with('vendor')} pass an expression to a VAR_IN_OUT CONSTANT"
            self.part.err(
                Code.NOT_A_VARIABLE, a.value.span, f"VAR_IN_OUT '{p.name}' needs a variable, not an expression", hint
            )
            return
        vt = self.part.stmts.lvalue(a.value, self.scope)
        if (
            vt is not None
            and not same_type(vt, p.type)
            and not T.extends(vt, p.type)
            and not (T.is_conformant(p.type) and _fits_conformant(vt, p.type))
            and not (isinstance(T.base_of(vt), T.StringType) and isinstance(T.base_of(p.type), T.StringType))
        ):
            self.part.err(Code.TYPE_MISMATCH, a.value.span, f"VAR_IN_OUT '{p.name}' is {p.type}; {vt} cannot be passed")

    def _storage(self, e: A.Expr) -> bool:
        """Is `e` a variable's storage an in-out can refer to (not an expression, a bit of a
        variable or a CONSTANT)?"""
        if not isinstance(e, _VARIABLE) or isinstance(e, A.Bit):
            return False
        return not names_constant(self.part, e, self.scope)

    def _in_out_temporary(self, a: A.Arg, p: T.VarSym) -> None:
        """A literal, an expression or a constant for a VAR_IN_OUT CONSTANT (CODESYS, TwinCAT: the
        callee only reads it): checked as an input's value, passed through a temporary."""
        vt = self.part.exprs.expr(a.value, self.scope, p.type)
        self.part.stmts.assignable(a.value, vt, p.type, a.value.span, "pass")
        a.temporary = True

    def _reference_input(self, a: A.Arg, p: T.VarSym) -> None:
        want = cast(T.RefType, T.unalias(p.type)).target
        if not isinstance(a.value, (A.Name, A.Field, A.Index, A.Deref)):
            self.part.err(Code.NOT_A_VARIABLE, a.value.span, f"'{p.name}' is a REFERENCE TO {want}: pass a variable")
            self.part.exprs.expr(a.value, self.scope)
            return
        vt = self.part.stmts.lvalue(a.value, self.scope)
        take_address(a.value)
        reference_binding.check_reference_argument(self.ctx, a, p, want, vt)

    def _any_input(self, a: A.Arg, p: T.VarSym) -> None:
        """An argument for an ANY input: any value of the family that has bytes; a variable is
        passed by address (pValue points at it), an expression as a temporary. Codegen reads the
        type from `a.value.ty`."""
        vt = self.part.exprs.expr(a.value, self.scope)
        if vt is None:
            return
        handed_on = passed_on_any(a.value)
        if handed_on is not None:  # an ANY input handed on: its descriptor as it is (CODESYS)
            if p.any_input != "ANY" and handed_on != p.any_input:
                self.part.err(
                    Code.TYPE_MISMATCH,
                    a.value.span,
                    f"'{p.name}' is {p.any_input}; an {handed_on} input cannot be handed on to it",
                )
            return
        if isinstance(T.base_of(vt), T.LiteralType):
            vt = T.default_type_for_literal(T.base_of(vt))
            a.value.ty = vt
        if T.byte_layout(vt) is None or not _satisfies(vt, p.any_input):
            self.part.err(Code.TYPE_MISMATCH, a.value.span, f"'{p.name}' is {p.any_input}; {vt} cannot be passed to it")
            return
        if isinstance(a.value, (A.Name, A.Field, A.Index, A.Deref)):
            take_address(a.value)

    def _check_en_eno(self) -> None:
        en, eno = self.extras.get("en"), self.extras.get("eno")
        if en is not None:
            et = self.part.exprs.expr(en.value, self.scope, T.BOOL)
            if et is not None and not T.base_of(et).is_bool:
                self.part.err(Code.TYPE_MISMATCH, en.span, "EN must be BOOL")
        if eno is not None:
            if not eno.output:
                self.part.err(Code.BAD_PARAMETER, eno.span, "ENO is an output; use 'ENO => var'")
            else:
                self.part.stmts.lvalue(eno.value, self.scope)

    def _check_count(self) -> None:
        """A function's or method's call: a non-formal call gives every input and in-out, in order
        (IEC 61131-3 6.6.1.4.2), a formal one every in-out."""
        c, pou = self.c, self.pou
        if self.npos and not any(a.name and a.name.lower() not in ("en", "eno") for a in c.args):
            needed = [p for p in self.params if p.section != "VAR_OUTPUT"]
            if self.npos < len(needed):
                self.part.err(
                    Code.ARGUMENT_COUNT,
                    c.span,
                    f"{pou.name} takes {len(needed)} argument(s), not {self.npos}",
                    "name the arguments (x := ...) to leave some out",
                )
                return
        for p in pou.in_outs():
            if p.name.lower() not in self.bound:
                self.part.err(Code.ARGUMENT_COUNT, c.span, f"VAR_IN_OUT '{p.name}' of {pou.name} must be given")


def _fits_conformant(arg, param) -> bool:
    """An array for an ARRAY[*] parameter: as many dimensions, the same element type."""
    a, p = T.unalias(arg), cast(T.ArrayType, T.unalias(param))
    return isinstance(a, T.ArrayType) and len(a.dims) == len(p.dims) and same_type(a.element, p.element)


def passed_on_any(e: A.Expr) -> str | None:
    """The family of the caller's own ANY input that `e` names (handed on to another ANY input as
    its descriptor, pValue still pointing at the first caller's value), else None."""
    sym = e.sym if isinstance(e, A.Name) else None
    return sym.any_input if isinstance(sym, T.VarSym) and sym.any_input else None
