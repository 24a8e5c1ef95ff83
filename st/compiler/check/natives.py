"""Library (native) calls: a call of a function a library implements in Python (the standard
functions, the vendor library's), typed from its signature (`FuncSig`): named arguments put in
the declaration's order (TwinCAT's parameter names where the dialect has vendor extensions),
the count, each argument against its parameter's constraint, the arguments of one generic group
(ANY_NUM's T) brought to a common type, literals settled to the type the context expects, and
the result's type."""

from __future__ import annotations

import re

from ...diagnostics import Code
from ...model import types as T
from .. import ast as A
from ..library import FuncSig
from .common import Scope, _satisfies
from .part import Part
from .targets import NativeCall

_EXTRA_INPUT = re.compile(r"in(\d+)")  # IN3, IN4, ... of an extensible function (ADD, MAX, MUX, ...)


def native_call(part: Part, c: A.Call, sig: FuncSig, scope: Scope, expected: T.Type | None) -> T.Type | None:
    """Type the call `c` of the library function `sig` (in a context that expects `expected`)."""
    return _NativeCall(part, c, sig, scope, expected).type()


class _NativeCall:
    def __init__(self, part: Part, c: A.Call, sig: FuncSig, scope: Scope, expected: T.Type | None) -> None:
        self.part, self.ctx = part, part.ctx
        self.c, self.sig, self.scope = c, sig, scope
        self.eb = T.base_of(expected) if expected is not None else None  # the base type the context expects
        self.args: list[A.Arg] = []
        self.en: A.Arg | None = None
        self.eno: A.Arg | None = None
        self.named: dict[str, A.Arg] = {}
        # TwinCAT's parameter names (LEN(STR := s)) where the dialect has vendor extensions
        self.aliases = sig.aliases if self.ctx.feature_quiet("vendor") else {}

    def type(self) -> T.Type | None:
        self._sort_args()
        if self.named and not self._order_named():
            return None
        if not self._check_count():
            return None
        arg_types, groups = self._argument_types()
        if any(t is None for t in arg_types):
            return None
        self._settle_literal_groups(groups)
        self._settle_literal_arguments(arg_types, groups)
        arg_types = self._real_context(arg_types)
        ok, rt = self._result(arg_types, groups)
        if not ok:
            return None
        if self.en is not None:
            self.part.exprs.expr(self.en.value, self.scope, T.BOOL)
        if self.eno is not None:
            self.part.stmts.lvalue(self.eno.value, self.scope)
        self.c.target = NativeCall(self.sig, self.args, arg_types, self.en, self.eno)
        return rt

    def _sort_args(self) -> None:
        """EN, ENO and the arguments (a native function has no outputs)."""
        for a in self.c.args:
            key = a.name.lower()
            if key == "en":
                self.en = a
            elif key == "eno":
                self.eno = a
            elif a.output:
                self.part.err(Code.BAD_PARAMETER, a.span, f"{self.sig.name} has no output '{a.name}'")
            else:
                if a.name:
                    self.named[self.aliases.get(key, key)] = a
                self.args.append(a)

    def _order_named(self) -> bool:
        """Named arguments in declaration order, positional ones in the places left, an extensible
        function's INn after its declared parameters (False after an unknown name, reported)."""
        sig = self.sig
        names = [p.name.lower() for p in sig.params]
        for a in self.args:
            if not a.name:
                continue
            key = self.aliases.get(a.name.lower(), a.name.lower())
            if key not in names and not (sig.extensible and _EXTRA_INPUT.fullmatch(key)):
                self.part.err(
                    Code.BAD_PARAMETER,
                    a.span,
                    f"{sig.name} has no parameter '{a.name}' (parameters: {', '.join(p.name for p in sig.params)})",
                )
                return False
        pos = [a for a in self.args if not a.name]
        ordered = []
        for p in sig.params:
            arg = self.named.get(p.name.lower())
            if arg is None and pos:
                arg = pos.pop(0)
            if arg is not None:
                ordered.append(arg)
        if sig.extensible:
            extra = sorted(
                ((int(k[2:]), a) for k, a in self.named.items() if _EXTRA_INPUT.fullmatch(k) and k not in names),
                key=lambda x: x[0],
            )
            ordered.extend(a for _, a in extra)
        ordered.extend(pos)
        self.args = ordered
        return True

    def _check_count(self) -> bool:
        sig, n = self.sig, len(self.args)
        nmin = sig.min_args or len(sig.params)
        if n < nmin or (not sig.extensible and n > len(sig.params)):
            count = f"at least {nmin}" if sig.extensible else str(len(sig.params))
            self.part.err(Code.ARGUMENT_COUNT, self.c.span, f"{sig.name} takes {count} argument(s), not {n}")
            for a in self.args:
                self.part.exprs.expr(a.value, self.scope)
            return False
        return True

    def _param(self, i: int):
        """The parameter the i-th argument goes to (an extensible function's last one repeats)."""
        return self.sig.params[min(i, len(self.sig.params) - 1)]

    def _argument_types(self) -> tuple[list[T.Type | None], dict]:
        """Each argument's type (None: wrong, reported) and each generic group's common type."""
        arg_types: list[T.Type | None] = []
        groups: dict = {}
        for i, a in enumerate(self.args):
            p = self._param(i)
            want = T.ELEMENTARY.get(p.constraint)
            t = self._argument_type(i, a, p, want)
            arg_types.append(t)
            if t is None:
                continue
            if p.group:
                self._join_group(groups, p.group, a, t)
            elif want is not None:
                self.part.stmts.assignable(a.value, t, want, a.value.span, "pass")
        return arg_types, groups

    def _argument_type(self, i: int, a: A.Arg, p, want) -> T.Type | None:
        t = self.part.exprs.expr(a.value, self.scope, want)
        if t is None or _satisfies(t, p.constraint):
            return t
        stand_in = self._vendor_argument(t, p.constraint)
        if stand_in is None:
            self.part.err(
                Code.TYPE_MISMATCH, a.value.span, f"argument {i + 1} of {self.sig.name} must be {p.constraint}, not {t}"
            )
            return None
        a.value.ty = stand_in
        return stand_in

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

    def _join_group(self, groups: dict, group: str, a: A.Arg, t: T.Type) -> None:
        """The arguments of one generic group (ADD's ANY_NUM T) share a type: the common one."""
        prev = groups.get(group)
        if prev is None:
            groups[group] = t
            return
        ct = T.common_type(prev, t)
        if ct is None and isinstance(T.base_of(prev), T.StringType) and isinstance(T.base_of(t), T.StringType):
            ct = prev
        if ct is None and isinstance(T.base_of(prev), T.EnumType) and T.base_of(prev) is T.base_of(t):
            ct = prev
        if ct is None:
            self.part.err(
                Code.TYPE_MISMATCH, a.value.span, f"arguments of {self.sig.name} have incompatible types {prev} and {t}"
            )
        else:
            groups[group] = ct

    def _settle_literal_groups(self, groups: dict) -> None:
        """All-literal arguments take the type the context expects (IEC: ANY_NUM literals)."""
        eb = self.eb
        for g, t in list(groups.items()):
            if not isinstance(t, T.LiteralType):
                continue
            if (
                self.sig.result == g
                and eb is not None
                and isinstance(eb, T.ElemType)
                and (eb.is_num or (eb.is_bit and t is T.LIT_INT))
                and not (t is T.LIT_REAL and not eb.is_real)
            ):
                groups[g] = eb
            else:
                groups[g] = T.default_type_for_literal(t)

    def _settle_literal_arguments(self, arg_types: list, groups: dict) -> None:
        """A literal argument of a group takes the group's type (and must fit it)."""
        for i, a in enumerate(self.args):
            p = self._param(i)
            if not (p.group and isinstance(arg_types[i], T.LiteralType)):
                continue
            gt = groups[p.group]
            if isinstance(a.value, A.Literal) and isinstance(a.value.value, int) and T.base_of(gt).is_intlike:
                if not T.literal_fits(a.value.value, gt):
                    self.part.err(Code.OUT_OF_RANGE, a.value.span, f"{a.value.value} does not fit in {gt}")
            a.value.ty = gt
            arg_types[i] = gt

    def _real_context(self, arg_types: list) -> list:
        """SQRT(2.0) in a REAL context computes in REAL."""
        eb = self.eb
        if (
            callable(self.sig.result)
            and arg_types
            and all(isinstance(t, T.LiteralType) for t in arg_types)
            and isinstance(eb, T.ElemType)
            and eb.is_real
        ):
            for a in self.args:
                a.value.ty = eb
            return [eb] * len(arg_types)
        return arg_types

    def _result(self, arg_types: list, groups: dict) -> tuple[bool, T.Type | None]:
        """(False, None) after a combination the function refuses (reported), else (True, its type)."""
        res, eb = self.sig.result, self.eb
        if getattr(self.sig, "result_from_context", False) and isinstance(eb, T.ElemType) and eb.is_int:
            return True, eb  # TRUNC: ANY_REAL → the integer type the context wants
        if callable(res):
            rt = res(arg_types)
            if isinstance(rt, str):
                self.part.err(Code.TYPE_MISMATCH, self.c.span, rt)
                return False, None
            if isinstance(rt, T.LiteralType):
                # all-literal arguments: the type the context expects
                if isinstance(eb, T.ElemType) and (eb.is_real or (eb.is_intlike and rt is T.LIT_INT)):
                    return True, eb
                return True, T.default_type_for_literal(rt)
            return True, rt
        if res in groups:
            # the group's type, or what the function makes of it (SUB of two dates: a TIME)
            of_group = getattr(self.sig, "group_result", None)
            return True, groups[res] if of_group is None else of_group(groups[res])
        if res is None:
            return True, None
        return True, T.ELEMENTARY[res]
