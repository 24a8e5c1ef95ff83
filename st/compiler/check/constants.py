"""Constant expressions: evaluated on demand wherever a constant is needed (array bounds, CASE
labels, string lengths, initial values of CONSTANTs), before and after the globals are declared."""

from __future__ import annotations

from collections.abc import Callable

from ...model import types as T
from .. import ast as A
from .common import Scope
from .part import Part


class Constants(Part):
    def value(self, e, scope: Scope | None):
        """Evaluate a constant expression (literals, CONSTANT variables, enum values), or None."""
        evaluate = _EVALUATE.get(type(e))
        return evaluate(self, e, scope) if evaluate is not None else None

    def _field(self, e: A.Field, scope: Scope | None):
        if isinstance(e.sym, T.EnumType):
            return e.const
        if isinstance(e.base, A.Name) and (scope is None or e.base.name.lower() not in scope.vars):
            et = self.p.types.get(e.base.name.lower())
            if isinstance(et, T.EnumType):  # E_Axis.Z, before the expression is typed (array bounds)
                m = et.members.get(e.name.lower())
                return m[1] if m else None
            return self._raw_global_constant(e.name.lower(), e.base.name.lower())  # GVL_Param.N
        return None

    def _literal(self, e: A.Literal, scope: Scope | None):
        return e.value

    def _enum_lit(self, e: A.EnumLit, scope: Scope | None):
        et = self.decls.resolve_named_type(e.type_name.lower(), e.span)
        if isinstance(et, T.EnumType):
            m = et.members.get(e.member.lower())
            return m[1] if m else None
        return None

    def _name(self, e: A.Name, scope: Scope | None):
        key = e.name.lower()
        sym = scope.vars.get(key) if scope is not None else None
        own = sym is not None and sym.global_ref is None  # the POU's own: its initial value may name others
        if sym is None:
            gs = self.p.global_names.get(key)
            sym = gs[0] if gs else None
        if sym is not None:
            return self._constant_variable(key, sym, scope if own else None)
        mems = self.p.enum_members.get(key)
        if mems and len({m[2] for m in mems}) == 1:
            return mems[0][2]
        local = self._raw_local_constant(key, scope)
        return local if local is not None else self._raw_global_constant(key)

    def _constant_variable(self, key: str, sym: T.VarSym, scope: Scope | None):
        """The value of a declared CONSTANT (a VAR_EXTERNAL's global's), or None for a variable."""
        if sym.global_ref is not None:
            sym = sym.global_ref
        if not (sym.constant and sym.init is not None and isinstance(sym.init, A.Expr)):
            return None
        sym.used = True
        if key in self.ctx.raw_const_busy:
            return None
        self.ctx.raw_const_busy.add(key)
        try:
            return self.value(sym.init, scope)
        finally:
            self.ctx.raw_const_busy.discard(key)

    def _unary(self, e: A.Unary, scope: Scope | None):
        v = self.value(e.operand, scope)
        if v is None or isinstance(v, str):
            return None
        if e.op == "-":
            return -v
        if e.op == "+":
            return v
        if e.op == "NOT" and isinstance(v, bool):
            return not v
        return None

    def _binary(self, e: A.Binary, scope: Scope | None):
        a, b = self.value(e.left, scope), self.value(e.right, scope)
        if a is None or b is None or isinstance(a, str) or isinstance(b, str):
            return None
        op = _OPERATORS.get(e.op)
        if op is None:
            return None
        try:
            return op(a, b)
        except (ZeroDivisionError, OverflowError):
            return None

    def _call(self, e: A.Call, scope: Scope | None):
        """SIZEOF, or a type conversion of a constant (`ANY_TO_DINT(Color.Red)`, `INT_TO_DINT(N)`,
        `TO_UDINT(5)`: enumeration values computed from another's, TwinCAT) whose value the target
        type holds as it is."""
        if not (isinstance(e.callee, A.Name) and len(e.args) == 1 and not e.args[0].name):
            return None
        fn = e.callee.name.upper()
        if fn == "SIZEOF":
            return self._sizeof(e, scope)
        target = T.ELEMENTARY.get(fn.rpartition("TO_")[2]) if "TO_" in fn else None
        if not isinstance(target, T.ElemType) or not fn.endswith("TO_" + target.name):
            return None
        v = self.value(e.args[0].value, scope)
        if isinstance(v, bool) or not isinstance(v, int | float):
            return None
        if target.is_intlike:
            return v if isinstance(v, int) and target.lo <= v <= target.hi else None
        return float(v) if target.name in ("REAL", "LREAL") else None

    def _sizeof(self, e: A.Call, scope: Scope | None):
        """SIZEOF(type or variable) in a constant expression (CODESYS: array bounds from sizes)."""
        if not (isinstance(e.callee, A.Name) and e.callee.name.upper() == "SIZEOF" and len(e.args) == 1):
            return None
        arg = e.args[0].value
        if not isinstance(arg, A.Name) or e.args[0].name:
            return None
        key = arg.name.lower()
        sym = scope.vars.get(key) if scope is not None else None
        t = sym.type if sym is not None else T.ELEMENTARY.get(arg.name.upper())
        if t is None:
            t = self.decls.resolve_named_type(key, arg.span) or self.p.pous.get(key)
        return T.size_of(t)[0] if t is not None else None

    def _raw_local_constant(self, key: str, scope: Scope | None):
        """A VAR CONSTANT of the POU being declared whose section comes later (CODESYS lets
        `ARRAY[1..N]` use an N declared below it)."""
        decl = scope.pou.decl if scope is not None and scope.pou is not None else None
        blocks = getattr(decl, "var_blocks", None) or []
        if key in self.ctx.raw_const_busy:
            return None
        for b in blocks:
            if "CONSTANT" not in b.qualifiers:
                continue
            for d in b.decls:
                if any(n.lower() == key for n, _ in d.names) and isinstance(d.init, A.Expr):
                    self.ctx.raw_const_busy.add(key)
                    try:
                        return self.value(d.init, scope)
                    finally:
                        self.ctx.raw_const_busy.discard(key)
        return None

    def _raw_global_constant(self, key: str, gvl: str = ""):
        """A VAR_GLOBAL CONSTANT not declared yet (types and POU interfaces are resolved first);
        `gvl`: of that named list only (GVL_Param.N)."""
        if key in self.ctx.raw_const_busy:
            return None
        blocks = list(self.ctx.global_blocks)
        for cfg in self.ctx.configs:
            blocks += [("", b) for b in cfg.var_blocks]
            for r in cfg.resources:
                blocks += [("", b) for b in r.var_blocks]
        for _, b in blocks:
            if "CONSTANT" not in b.qualifiers:
                continue
            if gvl and self.ctx.gvl_of_block.get(id(b), "").rstrip("!").lower() != gvl:
                continue
            for d in b.decls:
                if any(n.lower() == key for n, _ in d.names) and isinstance(d.init, A.Expr):
                    self.ctx.raw_const_busy.add(key)
                    try:
                        return self.value(d.init, None)
                    finally:
                        self.ctx.raw_const_busy.discard(key)
        return None


def _divide(a, b):
    if isinstance(a, int) and isinstance(b, int):  # integers divide towards zero
        q = abs(a) // abs(b)
        return q if (a >= 0) == (b >= 0) else -q
    return a / b


_OPERATORS: dict[str, Callable] = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": _divide,
    "MOD": lambda a, b: 0 if b == 0 else a - b * int(a / b),
    "**": lambda a, b: float(a) ** b,
    "AND": lambda a, b: a & b,
    "OR": lambda a, b: a | b,
    "XOR": lambda a, b: a ^ b,
}
_EVALUATE: dict[type, Callable] = {
    A.Field: Constants._field,
    A.Literal: Constants._literal,
    A.Call: Constants._call,
    A.EnumLit: Constants._enum_lit,
    A.Name: Constants._name,
    A.Unary: Constants._unary,
    A.Binary: Constants._binary,
}
