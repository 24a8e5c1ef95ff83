"""Expressions: typing of literals, names, operators, fields, indices (the rules they apply: rules/)."""

from __future__ import annotations

from collections.abc import Callable
from typing import cast

from ...diagnostics import Code
from ...model import types as T
from ...model.addresses import canonical
from ...model.literals import NS_MAX, fits_real, real_range_text, time_range_text
from .. import ast as A
from ..syntax import decl_of
from .common import (
    _CMP,
    _DIRECT,
    _DIRECT_TYPES,
    _LOGIC,
    _NULL,
    STEP,
    SUPER,
    THIS,
    Scope,
    image_problem,
    same_type,
)
from .context import CheckContext
from .part import Part
from .rules import access, array_bounds, unsigned_negation
from .rules.openplc_address import openplc_address

# the type a typed time or date literal has, by its prefix
_TIME_LITERALS = {
    "T": "TIME",
    "TIME": "TIME",
    "LT": "LTIME",
    "LTIME": "LTIME",
    "D": "DATE",
    "DATE": "DATE",
    "LD": "LDATE",
    "LDATE": "LDATE",
    "TOD": "TOD",
    "TIME_OF_DAY": "TOD",
    "LTOD": "LTOD",
    "LTIME_OF_DAY": "LTOD",
    "DT": "DT",
    "DATE_AND_TIME": "DT",
    "LDT": "LDT",
    "LDATE_AND_TIME": "LDT",
}
_BIT_ACCESS = {"X": T.BOOL, "B": T.BYTE, "W": T.WORD, "D": T.DWORD, "L": T.LWORD}
_UNQUALIFIED = object()  # a field access that is no qualified name (GVL.x, Enum.Value)


class Expressions(Part):
    # ---------------------------------------------------------------- expressions
    def expr(
        self, e: A.Expr, scope: Scope | None, expected: T.Type | None = None, *, lvalue: bool = False
    ) -> T.Type | None:
        t = self._expr(e, scope or Scope(None, {}), expected, lvalue)
        e.ty = t
        return t

    def _expr(self, e, scope: Scope, expected, lvalue):
        handler = _HANDLERS.get(type(e))
        if handler is None:
            raise AssertionError(e)
        return handler(self, e, scope, expected, lvalue)

    def _literal_expr(self, e: A.Literal, scope: Scope, expected, lvalue):
        return self._literal(e, expected)

    def _name_expr(self, e: A.Name, scope: Scope, expected, lvalue):
        t = self._name(e, scope, expected)
        self._property_read(e, lvalue)
        return t

    def _binary_expr(self, e: A.Binary, scope: Scope, expected, lvalue):
        return self._binary(e, scope, expected)

    def _unary_expr(self, e: A.Unary, scope: Scope, expected, lvalue):
        return self._unary(e, scope, expected)

    def _call_expr(self, e: A.Call, scope: Scope, expected, lvalue):
        t = self.calls.call(e, scope, expected=expected)
        if t is not None and T.is_reference(t):  # a REFERENCE TO result: the variable it refers to
            e.deref = True
            return cast(T.RefType, T.unalias(t)).target
        return t

    def _field_expr(self, e: A.Field, scope: Scope, expected, lvalue):
        t = self._field(e, scope, lvalue)
        self._property_read(e, lvalue)
        return t

    def _index_expr(self, e: A.Index, scope: Scope, expected, lvalue):
        return self._index(e, scope)

    def _bit(self, e: A.Bit, scope: Scope, expected, lvalue):
        bt = self.expr(e.base, scope)
        b = T.base_of(bt) if bt is not None else None
        if b is None:
            return T.BOOL
        rt = _BIT_ACCESS[e.size]
        if not b.is_intlike:
            self.err(Code.BAD_ACCESS, e.span, f"bit access needs an integer or bit-string variable, not {bt}")
            return rt
        array_bounds.check_bit_number(
            self.ctx, e, cast(T.Type, bt), cast(T.ElemType, b).bits, 1 if e.size == "X" else rt.bits
        )
        return rt

    def _deref(self, e: A.Deref, scope: Scope, expected, lvalue):
        bt = self.expr(e.base, scope)
        b = T.unalias(bt) if bt is not None else None
        if not isinstance(b, T.RefType):
            if bt is not None:  # else the base already has its error
                self.err(Code.BAD_ACCESS, e.span, f"'^' needs a reference, not {bt}")
            return None
        return b.target

    def _enum_lit(self, e: A.EnumLit, scope: Scope, expected, lvalue):
        et = self.decls.resolve_named_type(e.type_name.lower(), e.span)
        et = T.unalias(et) if et is not None else None
        if not isinstance(et, T.EnumType):
            self.err(Code.BAD_TYPE, e.span, f"'{e.type_name}' is not an enumeration type")
            return None
        m = et.members.get(e.member.lower())
        if m is None:
            self.err(Code.UNDECLARED, e.span, f"'{e.member}' is not a value of {e.type_name}")
            return et
        e.const = m[1]
        return et

    def _direct(self, e: A.Direct, scope: Scope, expected, lvalue):
        e.address = openplc_address(self.ctx, e.address, e.span)
        match = _DIRECT.fullmatch(e.address.upper())
        if not match or match.group(3) == "*":
            self.err(Code.MALFORMED_LITERAL, e.span, f"malformed address '{e.address}'")
            return T.BOOL
        problem = image_problem(e.address)
        if problem:
            self.err(Code.MALFORMED_LITERAL, e.span, problem)
            return _DIRECT_TYPES[match.group(2)]
        t = _DIRECT_TYPES[match.group(2)]
        e.address = canonical(e.address)  # %q0.1 and %QX0.1 are one variable
        located = self._located_at(e.address, scope)
        if located is not None:
            # the variable declared AT this address (named or not) is what %QW2 reads and writes
            located.used = True
            e.sym = located
            return located.type
        self.p.direct_vars[e.address] = ("_d_" + e.address[1:].replace(".", "_"), t)
        e.const = None
        return t

    def _located_at(self, address: str, scope: Scope) -> T.VarSym | None:
        """The variable of this POU, or else the global, declared AT `address` (canonical)."""
        for sym in list(scope.vars.values()) + list(self.p.globals.values()):
            loc = getattr(sym, "location", "")
            if loc and "*" not in loc and canonical(loc) == address:
                return sym
        return None

    def _property_read(self, e, lvalue: bool) -> None:
        if isinstance(e.sym, T.PropSym) and not lvalue and e.sym.get is None:
            self.err(Code.BAD_ACCESS, e.span, f"property {e.sym.name} has no GET: it cannot be read")

    # ---------------------------------------------------------------- literals
    def _literal(self, e: A.Literal, expected):
        if e.kind == "int" and not e.type_name and e.value in (0, 1) and expected is not None:
            if T.base_of(expected).is_bool:
                # IEC 61131-3: 0 and 1 are BOOL literals too (RST : BOOL := 0; SEL(0, a, b); IF 1 THEN)
                e.kind, e.value = "bool", bool(e.value)
                return T.BOOL
        if e.type_name:
            return self._typed_literal(e)
        return self._plain_literal(e, expected)

    def _typed_literal(self, e: A.Literal):
        """INT#5, T#1s, MyEnumBase#3, ...: the type the prefix names, which the value must belong to."""
        tn, k = e.type_name, e.kind
        if k in ("time", "date", "tod", "dt"):
            if k == "time" and isinstance(e.value, int) and e.value > NS_MAX:  # LTIME#213503d...: unsigned
                if self.ctx.dialect is not None and not self.ctx.dialect.unsigned_ltime:
                    self.err(Code.OUT_OF_RANGE, e.span, f"{e.text} does not fit in LTIME ({time_range_text('LTIME')})")
                    return None
                e.value -= 1 << 64  # the same 64 bits in st's signed LTIME
            return T.ELEMENTARY[_TIME_LITERALS[tn]]
        t = T.ELEMENTARY.get(tn)
        if t is None:
            at = self.decls.resolve_named_type(tn.lower(), e.span)
            if at is not None and T.base_of(at).is_elementary:
                t = at
        if t is None:
            self.err(Code.BAD_TYPE, e.span, f"unknown type '{tn}' in literal {e.text}")
            return None
        b = T.base_of(t)
        if k == "int":
            self._typed_int(e, t, b)
        elif k == "real" and not b.is_real:
            self.err(Code.TYPE_MISMATCH, e.span, f"{e.text}: a real number is not a {t}")
        elif k == "real":
            self._real_fits(e, b)
        elif k == "bool" and not (b.is_bool or b.is_intlike):
            self.err(Code.TYPE_MISMATCH, e.span, f"{e.text}: a BOOL is not a {t}")
        elif k in ("string", "wstring") and not (b.is_string or b.kind == "char"):
            self.err(Code.TYPE_MISMATCH, e.span, f"{e.text}: a string is not a {t}")
        if k == "bool" and b.is_intlike:
            e.value = int(e.value)
        return t

    def _typed_int(self, e: A.Literal, t: T.Type, b: T.Type) -> None:
        if b.is_bool:
            if e.value not in (0, 1):
                self.err(Code.OUT_OF_RANGE, e.span, f"{e.text} is not a BOOL value")
            e.value = bool(e.value)
        elif b.is_real:
            self._real_fits(e, b)
            e.value = float(e.value) if fits_real(e.value, 64) else 0.0
        elif b.is_intlike:
            if not T.literal_fits(e.value, t):
                self.err(Code.OUT_OF_RANGE, e.span, f"{e.text} does not fit in {t}")
        else:
            self.err(Code.TYPE_MISMATCH, e.span, f"{e.text}: an integer is not a {t}")

    def _plain_literal(self, e: A.Literal, expected):
        k = e.kind
        if k in ("int", "real") and expected is not None and T.base_of(expected) is T.REAL:
            self._real_fits(e, T.REAL)  # a number the context makes a REAL: r := 1E39; r * 1E39
        if k == "int":
            return T.LIT_INT
        if k == "real":
            return T.LIT_REAL
        if k == "bool":
            return T.BOOL
        if k == "string":
            if expected is not None and T.base_of(expected).kind == "char" and len(e.value) == 1:
                return T.base_of(expected)
            return T.StringType(max(1, len(e.value)), False)
        if k == "wstring":
            return T.StringType(max(1, len(e.value)), True)
        return T.ELEMENTARY.get(k.upper(), T.TIME)

    def _real_fits(self, e: A.Literal, b) -> bool:
        """A number that becomes a REAL or LREAL must stay finite there (E021): 1E39 is no REAL,
        1E309 no LREAL (the builder reports that one); a value that only rounds (1E-50) is fine."""
        bits = cast(T.ElemType, b).bits
        if fits_real(e.value, bits):
            return True
        self.err(Code.OUT_OF_RANGE, e.span, f"{e.text} does not fit in {b.name} ({real_range_text(bits)})")
        return False

    # ---------------------------------------------------------------- names
    def lookup(self, key: str, scope: Scope):
        sym = scope.vars.get(key)
        if sym is not None:
            return sym
        if scope.pou is not None and scope.pou.pou_kind == "FUNCTION" and key == scope.pou.name.lower():
            return "RESULT"
        if key in scope.steps:
            return "STEP"
        if key == "this" and scope.fb is not None and self.ctx.feature_quiet("oop"):
            return THIS
        if scope.fb is not None and key in scope.fb.properties:
            return scope.fb.properties[key]
        if key == "super" and scope.fb is not None and scope.fb.base is not None and self.ctx.feature_quiet("oop"):
            return SUPER
        own = self.ctx.gvls.get(self.ctx.current_gvl, {}) if self.ctx.current_gvl is not None else {}
        for g in self.p.global_names.get(key, ()):
            # a {attribute 'qualified_only'} list's member is reachable bare only inside its own list;
            # another global of the name (a library's: Tc2_System's PI beside struckig's Constants.Pi) is
            if id(g) not in self.ctx.qualified_only or own.get(key) is g:
                return g
        pou = self.p.pous.get(key)
        if pou is not None and pou.pou_kind == "PROGRAM" and self.ctx.feature_quiet("vendor"):
            return self.ctx.program_instance(pou)  # CODESYS, TwinCAT: a PROGRAM's name is its instance
        return None

    def names_gvl(self, e: A.Expr, scope: Scope) -> bool:
        """Is `e` the name of a global variable list (GVL_Main in GVL_Main.x), not a variable?"""
        return isinstance(e, A.Name) and e.name.lower() in self.ctx.gvls and self.lookup(e.name.lower(), scope) is None

    def _shadowed_enum_value(self, e: A.Field, scope: Scope) -> bool:
        """`state : State := State.IDLE`: ST is case-insensitive, so the variable hides its enumeration
        type. A variable with no fields cannot mean `.IDLE`, so the type's value is meant (as CODESYS
        and STruC++ read it)."""
        assert isinstance(e.base, A.Name)
        sym = self.lookup(e.base.name.lower(), scope)
        if not isinstance(sym, T.VarSym) or isinstance(T.unalias(sym.type), (T.StructType, T.POUType, T.RefType)):
            return False
        et = self.decls.resolve_named_type(e.base.name.lower(), e.base.span)
        named = T.unalias(et) if et is not None else None
        if not isinstance(named, T.EnumType) or e.name.lower() not in named.members:
            return False
        e.const = named.members[e.name.lower()][1]
        e.sym = named
        return True

    def self_reference_sugar(self, e: A.Field, scope: Scope) -> None:
        """IEC 61131-3 3rd edition writes THIS.x and SUPER.M() (THIS/SUPER as references);
        CODESYS writes THIS^.x. Where the dialect reads THIS as the instance (`this_as_instance`:
        iec, and the default) the first is read as the second."""
        b = e.base
        if (
            isinstance(b, A.Name)
            and b.name.upper() in ("THIS", "SUPER")
            and self.lookup(b.name.lower(), scope) in (THIS, SUPER)
            and (self.ctx.dialect is None or self.ctx.dialect.this_as_instance)
        ):
            e.base = A.Deref(b.span, b)

    def _name(self, e: A.Name, scope: Scope, expected):
        key = e.name.lower()
        sym = self.lookup(key, scope)
        if isinstance(sym, (str, T.PropSym)) or sym is THIS or sym is SUPER:
            return self._pseudo_name(e, sym, key, scope)
        eb = T.base_of(expected) if expected is not None else None
        if (
            isinstance(sym, T.VarSym)
            and isinstance(eb, T.EnumType)
            and key in eb.members
            and not isinstance(T.base_of(sym.type), T.EnumType)
        ):
            sym = None  # an enum value of the expected type wins over a same-named variable
        if isinstance(sym, T.VarSym):
            return self._variable(e, sym, scope)
        if key == "null":
            e.sym = _NULL
            return _NULL
        mems = self.p.enum_members.get(key)
        if mems:
            return self._enum_value(e, mems, expected)
        return self._unknown_name(e, key, scope)

    def _pseudo_name(self, e: A.Name, sym, key: str, scope: Scope):
        """A name that is no variable: a FUNCTION's result, an SFC step, THIS, SUPER, a property."""
        if sym == "RESULT":
            pou = cast(T.POUType, scope.pou)
            e.sym = pou
            if T.is_reference(pou.return_type):  # a REFERENCE TO result: written and read through it
                return cast(T.RefType, T.unalias(cast(T.Type, pou.return_type))).target
            return pou.return_type
        if sym == "STEP":
            e.sym = STEP
            e.const = scope.steps[key]
            return STEP
        if sym is THIS:
            e.sym = THIS
            assert scope.fb is not None  # lookup gives THIS inside a block only
            return T.RefType(scope.fb)
        if isinstance(sym, T.PropSym):
            e.sym = sym
            return _through_reference(sym.type)
        e.sym = SUPER
        base = scope.fb.base if scope.fb is not None else None
        assert base is not None  # lookup gives SUPER inside a block that extends another only
        return T.RefType(base)

    def _variable(self, e: A.Name, sym: T.VarSym, scope: Scope):
        if sym.access:
            access.check_access(self.ctx, (sym.access,), sym.owner, f"variable {sym.name}", scope, e.span)
        sym.used = True
        e.sym = sym
        if T.is_reference(sym.type):
            return cast(T.RefType, T.unalias(sym.type)).target  # REFERENCE TO: the variable it refers to
        if sym.constant and sym.const_value is not None:
            e.const = sym.const_value
        return sym.type

    def _enum_value(self, e: A.Name, mems: list, expected):
        """A bare enumeration value: of the expected enumeration, else the only one of that name."""
        pick = None
        if expected is not None:
            et = T.base_of(expected)
            for m in mems:
                if m[0] is et:
                    pick = m
        if pick is None:
            if len(mems) > 1:
                self.err(
                    Code.UNDECLARED,
                    e.span,
                    f"'{e.name}' is a value of several enumerations",
                    f"qualify it, e.g. {mems[0][0].name}#{e.name}",
                )
            pick = mems[0]
        e.sym = pick[0]
        e.const = pick[2]
        return pick[0]

    def _unknown_name(self, e: A.Name, key: str, scope: Scope):
        pou = self.p.pous.get(key)
        if pou is not None and pou.pou_kind == "PROGRAM":
            self.feature("vendor", e.span, "a PROGRAM used by its name (its instance)")
            return None
        if pou is not None or self.ctx.native(key) is not None:
            self.err(Code.POU_AS_VALUE, e.span, f"'{e.name}' is a POU, not a value")
            return None
        if key in ("this", "super") and self.ctx.feature_quiet("oop"):
            where = (
                "a function block or one of its methods"
                if key == "this"
                else "a function block that EXTENDS another (or one of its methods)"
            )
            self.err(Code.UNDECLARED, e.span, f"{e.name.upper()} exists only inside {where}")
            return None
        gs = self.p.global_names.get(key)
        if gs and id(gs[0]) in self.ctx.qualified_only:
            low = next(n for n, vs in self.ctx.gvls.items() if vs.get(key) is gs[0])
            gvl = next(v.rstrip("!") for v in self.ctx.gvl_of_block.values() if v.rstrip("!").lower() == low)
            self.err(
                Code.UNDECLARED,
                e.span,
                f"'{e.name}' belongs to {gvl}, a {{attribute 'qualified_only'}} list",
                f"write it qualified: {gvl}.{e.name}",
            )
            return None
        self.err(Code.UNDECLARED, e.span, f"undeclared identifier '{e.name}'", self._suggest(key, scope))
        return None

    def _suggest(self, key: str, scope: Scope) -> str:
        import difflib

        names = [s.name for s in scope.vars.values()] + [s[0].name for s in self.p.global_names.values()]
        m = difflib.get_close_matches(key, [n.lower() for n in names], n=1, cutoff=0.75)
        if m:
            for n in names:
                if n.lower() == m[0]:
                    return f"did you mean '{n}'?"
        return ""

    # ---------------------------------------------------------------- operators
    def _binary(self, e: A.Binary, scope: Scope, expected):
        op = e.op
        lt, rt = self._operands(e, scope, expected)
        if lt is None or rt is None:
            return T.BOOL if op in _CMP else (lt or rt)
        if op in ("+", "-", "<", ">", "<=", ">=") and (_is_pointer(lt) or _is_pointer(rt)):
            return self._pointer_arithmetic(e, lt, rt)
        if op in ("+", "-") and _is_address(e.left, lt) or op == "+" and _is_address(e.right, rt):
            return self._pointer_arithmetic(e, lt, rt)  # ADR(x) + n
        lt, rt = self._enums_as_ints(lt, rt)
        if op in ("=", "<>"):  # CODESYS: p = 0 tests a POINTER for NULL
            if _zero_pointer(self.ctx, e.right, lt):
                e.right, rt = _null_at(e.right), _NULL
            elif _zero_pointer(self.ctx, e.left, rt):
                e.left, lt = _null_at(e.left), _NULL
        family = _OPERATORS.get(op)
        if family is None:
            raise AssertionError(op)
        return family(self, e, T.base_of(lt), T.base_of(rt), lt, rt)

    def _operands(self, e: A.Binary, scope: Scope, expected):
        """The operands' types: the left one (or the context's) is the right one's expected type,
        and a literal on the left is typed again as the right side's type."""
        op = e.op
        hint = expected if op not in _CMP and op not in ("MOD", "**") else None
        lt = self.expr(e.left, scope, hint)
        rt = self.expr(e.right, scope, lt if lt is not None and not isinstance(lt, T.LiteralType) else hint)
        if isinstance(lt, T.LiteralType) and rt is not None and not isinstance(rt, T.LiteralType):
            lt = self.expr(e.left, scope, rt)
        return lt, rt

    def _enums_as_ints(self, lt: T.Type, rt: T.Type) -> tuple[T.Type, T.Type]:
        """CODESYS (non-strict enumerations): an enumeration value next to a number is its integer."""
        la, rb = T.base_of(lt), T.base_of(rt)
        if self.ctx.enum_as_int(la) and not isinstance(rb, T.EnumType) and (rb.is_num or rb is T.LIT_INT):
            lt = cast(T.EnumType, la).base
        elif self.ctx.enum_as_int(rb) and not isinstance(la, T.EnumType) and (la.is_num or la is T.LIT_INT):
            rt = cast(T.EnumType, rb).base
        return lt, rt

    def _logic(self, e: A.Binary, a, b, lt, rt):
        if a.is_bool and b.is_bool:
            return T.BOOL
        if e.op in ("AND_THEN", "OR_ELSE"):
            return self._bad_operands(e, lt, rt)
        if (a.is_intlike or a is T.LIT_INT) and (b.is_intlike or b is T.LIT_INT):
            c = T.common_type(a, b) or self._bits_and_numbers(a, b)
            if c is None:
                return self._bad_operands(e, lt, rt)
            return c if not isinstance(c, T.LiteralType) else T.default_type_for_literal(c)
        return self._bad_operands(e, lt, rt)

    def _compare(self, e: A.Binary, a, b, lt, rt):
        if isinstance(a, T.EnumType) or isinstance(b, T.EnumType):
            if a is b:
                return T.BOOL
            return self._bad_operands(e, lt, rt)
        if _comparable_links(e.op, a, b):
            return T.BOOL
        c = T.common_type(a, b) or self._bits_and_numbers(a, b)
        if c is None or isinstance(c, (T.ArrayType, T.StructType, T.POUType)):
            return self._bad_operands(e, lt, rt)
        return T.BOOL

    def _arithmetic(self, e: A.Binary, a, b, lt, rt):
        tt = self._time_arith(e.op, a, b)
        if tt is not None:
            return tt
        if (a.is_num or isinstance(a, T.LiteralType)) and (b.is_num or isinstance(b, T.LiteralType)):
            c = T.common_type(a, b)
            if c is None:
                return self._bad_operands(e, lt, rt)
            if c is T.REAL and self.ctx.dialect is not None and self.ctx.dialect.c_float_arithmetic:
                e.single = _c_float(e.left) and _c_float(e.right)
            return c
        if a.is_bit and b.is_bit or a.is_bit and b is T.LIT_INT or b.is_bit and a is T.LIT_INT:
            # IEC has no arithmetic on bit strings, but every dialect allows it
            return T.common_type(a, b)
        c = self._bits_and_numbers(a, b)
        if c is not None:
            return c
        return self._bad_operands(e, lt, rt)

    def _mod(self, e: A.Binary, a, b, lt, rt):
        if (a.is_intlike or a is T.LIT_INT) and (b.is_intlike or b is T.LIT_INT):
            c = T.common_type(a, b) or self._bits_and_numbers(a, b)
            if c is not None:
                return c
        return self._bad_operands(e, lt, rt)

    def _power(self, e: A.Binary, a, b, lt, rt):
        if (a.is_num or isinstance(a, T.LiteralType)) and (b.is_num or isinstance(b, T.LiteralType)):
            if a.is_real:
                return a
            if a is T.LIT_REAL or a is T.LIT_INT:
                return T.LIT_REAL if (b is T.LIT_INT or b is T.LIT_REAL) else T.LREAL
            return T.REAL if cast(T.ElemType, a).bits <= 16 else T.LREAL
        return self._bad_operands(e, lt, rt)

    def _bits_and_numbers(self, a: T.Type, b: T.Type) -> T.Type | None:
        """A bit string with a number (INT + BYTE) where the dialect converts between them."""
        return T.bits_numbers_common(a, b) if self.ctx.bits_as_numbers() else None

    def _time_arith(self, op, a, b):
        ka, kb = a.kind, b.kind
        num_b = b.is_num or isinstance(b, T.LiteralType)
        num_a = a.is_num or isinstance(a, T.LiteralType)
        if ka == "time" and kb == "time" and op in ("+", "-"):
            return a if a.long or not b.long else b
        if ka == "time" and num_b and op in ("*", "/"):
            return a
        if kb == "time" and num_a and op == "*":
            return b
        if ka in ("dt", "tod") and kb == "time" and op in ("+", "-"):
            return a
        if ka == "time" and kb in ("dt", "tod") and op == "+":
            return b
        if ka == kb and ka in ("dt", "tod", "date") and op == "-":
            return T.LTIME if a.long else T.TIME
        return None

    def _bad_operands(self, e: A.Binary, lt, rt):
        self.err(Code.BAD_OPERANDS, e.span, f"operator {e.op} cannot combine {lt} and {rt}", self._conv_hint(lt, rt))
        return T.BOOL if e.op in _CMP else lt

    def _conv_hint(self, lt, rt) -> str:
        a, b = T.base_of(lt), T.base_of(rt)
        if isinstance(a, T.ElemType) and isinstance(b, T.ElemType) and a.is_elementary and b.is_elementary:
            return f"convert one side, e.g. {b.name}_TO_{a.name}(...)"
        return ""

    def _unary(self, e: A.Unary, scope: Scope, expected):
        t = self.expr(e.operand, scope, expected)
        if t is None:
            return None
        b = T.base_of(t)
        if e.op == "NOT":
            if b.is_bool or b.is_intlike:
                return t
            if b is T.LIT_INT:
                return T.default_type_for_literal(b)
        elif b.is_num or isinstance(b, T.LiteralType) or b.is_time:
            unsigned_negation.check_negation(self.ctx, e, t)
            return t
        elif unsigned_negation.negates_bits(self.ctx, e, t):
            return t  # CODESYS, TwinCAT: a bit string negated as an unsigned number
        self.err(Code.BAD_OPERANDS, e.span, f"operator {e.op} cannot be applied to {t}")
        return t

    # ---------------------------------------------------------------- fields and indexes
    def _field(self, e: A.Field, scope: Scope, lvalue: bool = False):
        if isinstance(e.base, A.Name):
            got = self._qualified(e, scope, lvalue)
            if got is not _UNQUALIFIED:
                return got
        self.self_reference_sugar(e, scope)
        bt = self.expr(e.base, scope)
        if bt is None:
            return None
        b = T.unalias(bt)
        if b is STEP:
            return self._step_flag(e)
        if isinstance(b, T.StructType):
            member = b.members.get(e.name.lower())
            if member is None:
                self.err(Code.BAD_ACCESS, e.name_span, f"'{bt}' has no field '{e.name}'")
                return None
            e.sym = member
            return member.type
        if isinstance(b, T.POUType) and b.pou_kind != "FUNCTION":
            return self._member(e, b, scope, lvalue)
        if isinstance(b, T.ElemType) and b.is_intlike and e.name.isdigit():
            return T.BOOL
        self.err(
            Code.BAD_ACCESS,
            e.span,
            f"'{bt}' is not a structure or function block instance, it has no field '{e.name}'",
            f"dereference it first: {e.base.name}^.{e.name}"
            if isinstance(b, T.RefType) and isinstance(e.base, A.Name)
            else "",
        )
        return None

    def _qualified(self, e: A.Field, scope: Scope, lvalue: bool):
        """X.y where X is no variable: a global variable list's variable (GVL_Main.x), an
        enumeration's value (Color.Red, also where a variable hides the type); _UNQUALIFIED if not."""
        base = cast(A.Name, e.base)
        if not lvalue and self._shadowed_enum_value(e, scope):
            return e.sym
        if self.lookup(base.name.lower(), scope) is not None:
            return _UNQUALIFIED
        gvl = self.ctx.gvls.get(base.name.lower())
        if gvl is not None:
            # GVL_Main.x: a variable of a named global variable list (TwinCAT)
            sym = gvl.get(e.name.lower())
            if sym is None:
                self.err(Code.UNDECLARED, e.name_span, f"'{e.name}' is not a variable of {base.name}")
                return None
            sym.used = True
            e.sym = sym
            return sym.type
        et = self.decls.resolve_named_type(base.name.lower(), base.span)
        named = T.unalias(et) if et is not None else None
        if not isinstance(named, T.EnumType):
            return _UNQUALIFIED
        # Color.Red: CODESYS's qualified enumeration value
        m = named.members.get(e.name.lower())
        if m is None:
            self.err(Code.UNDECLARED, e.name_span, f"'{e.name}' is not a value of {named.name}")
            return named
        e.const = m[1]
        e.sym = named
        return named

    def _step_flag(self, e: A.Field):
        up = e.name.upper()
        if up == "X":
            return T.BOOL
        if up == "T":
            return T.TIME
        self.err(Code.BAD_ACCESS, e.name_span, f"a step has only the flags .X and .T, not .{e.name}")
        return None

    def _member(self, e: A.Field, b: T.POUType, scope: Scope, lvalue: bool):
        """inst.x: a variable or property of a block instance (or interface)."""
        self.decls.resolve_interface(b)
        key = e.name.lower()
        v = b.vars.get(key)
        if v is None and key in b.properties:
            e.sym = ps = b.properties[key]
            acc = (ps.set if lvalue else ps.get) or ps.get or ps.set  # GET and SET may differ in access
            if acc is not None and acc.decl is not None:
                access.check_access(
                    self.ctx, decl_of(acc).modifiers, ps.owner, f"property {ps.name}", scope, e.name_span
                )
            return _through_reference(ps.type)
        if v is None:
            if key in b.actions or key in b.methods:
                kind = "an action" if key in b.actions else "a method"
                self.err(Code.POU_AS_VALUE, e.name_span, f"'{e.name}' is {kind}; call it: {e.name}()")
                return None
            what = "method or property" if b.pou_kind == "INTERFACE" else "variable"
            self.err(Code.BAD_ACCESS, e.name_span, f"{b.name} has no {what} '{e.name}'")
            return None
        # IEC hides an FB's internal variables; most dialects let you read them, so only an
        # explicit `VAR PRIVATE` / `VAR PROTECTED` section restricts them
        if v.access:
            access.check_access(self.ctx, (v.access,), v.owner, f"variable {v.name}", scope, e.name_span)
        v.used = True
        e.sym = v
        if T.is_reference(v.type):  # inst.r of a REFERENCE TO: what it refers to
            return cast(T.RefType, T.unalias(v.type)).target
        return v.type

    def _pointer_arithmetic(self, e: A.Binary, lt: T.Type, rt: T.Type):
        """CODESYS/TwinCAT: POINTER + n and POINTER - n move by n bytes, POINTER - POINTER is the
        distance in bytes, and pointers compare by address (st: within one array)."""
        self.ctx.feature("vendor", e.span, "pointer arithmetic")
        a, b = T.base_of(lt), T.base_of(rt)
        num = lambda t: t.is_intlike or t is T.LIT_INT  # noqa: E731
        if e.op in ("+", "-") and _is_pointer(lt) and num(b):
            return lt
        if e.op == "+" and num(a) and _is_pointer(rt):
            return rt
        ul, ur = T.unalias(lt), T.unalias(rt)
        # ADR(x) + n (CODESYS: an address n bytes on): a POINTER TO BYTE over x's bytes
        for ref, other in ((ul, b), (ur, a)) if e.op == "+" else ((ul, b),):
            if isinstance(ref, T.RefType) and num(other) and T.pointer_view(ref.target, T.BYTE) is not None:
                return T.RefType(T.BYTE, "POINTER")
        if (
            e.op != "+"
            and isinstance(ul, T.RefType)
            and isinstance(ur, T.RefType)
            and (same_type(ul.target, ur.target) or T.byte_format(ul.target) == T.byte_format(ur.target) is not None)
        ):  # p - ADR(arr): into the same elements
            return T.DINT if e.op == "-" else T.BOOL
        return self._bad_operands(e, lt, rt)

    def _index(self, e: A.Index, scope: Scope):
        bt = self.expr(e.base, scope)
        for i in e.indices:
            it = self.expr(i, scope, T.DINT)
            if it is not None and not (
                T.base_of(it).is_intlike or it is T.LIT_INT or isinstance(T.base_of(it), T.EnumType)
            ):
                self.err(Code.TYPE_MISMATCH, i.span, f"an array index must be an integer, not {it}")
        if bt is None:
            return None
        b = T.unalias(bt)
        if isinstance(b, T.StringType):
            self.err(Code.BAD_ACCESS, e.span, "strings cannot be indexed; use MID()")
            return None
        if _is_pointer(b) and len(e.indices) == 1:  # p[i] = (p + i * SIZEOF(p^))^ (CODESYS)
            self.ctx.feature("vendor", e.span, "indexing a POINTER")
            return cast(T.RefType, b).target
        if not isinstance(b, T.ArrayType):
            self.err(Code.BAD_ACCESS, e.span, f"'{bt}' is not an array")
            return None
        if len(e.indices) != len(b.dims):
            # ARRAY OF ARRAY written a[i, j] is not allowed; a[i][j] is
            self.err(Code.BAD_ACCESS, e.span, f"this array has {len(b.dims)} dimension(s), not {len(e.indices)}")
            return b.element
        for i, (lo, hi) in zip(e.indices, b.dims):
            array_bounds.check_index(self.ctx, i, self.consts.value(i, scope), lo, hi)
        return b.element


_HANDLERS: dict[type, Callable[..., T.Type | None]] = {
    A.Literal: Expressions._literal_expr,
    A.Name: Expressions._name_expr,
    A.Binary: Expressions._binary_expr,
    A.Unary: Expressions._unary_expr,
    A.Call: Expressions._call_expr,
    A.Field: Expressions._field_expr,
    A.Index: Expressions._index_expr,
    A.Bit: Expressions._bit,
    A.Deref: Expressions._deref,
    A.EnumLit: Expressions._enum_lit,
    A.Direct: Expressions._direct,
}
_OPERATORS = {
    **{op: Expressions._logic for op in _LOGIC},
    **{op: Expressions._compare for op in _CMP},
    **{op: Expressions._arithmetic for op in ("+", "-", "*", "/")},
    "MOD": Expressions._mod,
    "**": Expressions._power,
}


def _comparable_links(op: str, a, b) -> bool:
    """Do = <> < ... compare these without a common type: strings (a CHAR with a string),
    references (with NULL), and for = and <> interfaces with instances or NULL?"""
    if isinstance(a, T.StringType) and isinstance(b, T.StringType):
        return True
    if a.kind == "char" and isinstance(b, (T.StringType,)) or b.kind == "char" and isinstance(a, T.StringType):
        return True
    if isinstance(a, T.RefType) and (isinstance(b, T.RefType) or b is _NULL) or a is _NULL:
        return True
    return (
        op in ("=", "<>")
        and any(isinstance(x, T.POUType) and x.pou_kind == "INTERFACE" for x in (a, b))
        and all(x is _NULL or isinstance(x, T.POUType) and x.pou_kind != "FUNCTION" for x in (a, b))
    )  # the same instance (or NULL) behind both?


def _zero_pointer(ctx: CheckContext, e, other) -> bool:
    """The literal 0 (or an integer constant that is 0: TcLog's `_logger <> InvalidLoggerReference`)
    where a POINTER, a REF_TO or an interface is compared or assigned: NULL, as CODESYS and TwinCAT
    write it (a vendor extension)."""
    u = T.unalias(other) if other is not None else None
    is_link = (
        isinstance(u, T.RefType)
        and u.ref_kind in ("POINTER", "REF_TO")
        or isinstance(u, T.POUType)
        and u.pou_kind == "INTERFACE"
    )
    zero = (isinstance(e, A.Literal) and e.value == 0 and e.kind == "int") or (
        isinstance(e, A.Name)
        and isinstance(e.sym, T.VarSym)
        and e.sym.constant
        and e.sym.const_value == 0
        and T.base_of(e.sym.type).is_intlike
        and not T.base_of(e.sym.type).is_bool
    )
    return zero and is_link and ctx.feature_quiet("vendor")


def _null_at(e) -> A.Name:
    """NULL in the place of e. A constant's name stays in the tree, read as NULL: a later check of
    the same tree (the language server's) finds the constant again, used, and reads it as NULL again."""
    n = e if isinstance(e, A.Name) else A.Name(e.span, "NULL")
    n.sym = _NULL
    n.ty = _NULL
    n.const = None
    return n


def _c_float(e: A.Expr) -> bool:
    """Is this operand a C `float` (or an integer, which C turns into one) in the code MatIEC
    generates? A REAL literal is a C double, and so is anything it takes part in."""
    if isinstance(e, A.Literal):
        return not isinstance(e.value, float)
    if isinstance(e, A.Unary):
        return _c_float(e.operand)
    if isinstance(e, A.Binary):
        t = T.base_of(e.ty) if e.ty is not None else None
        return e.single if t is T.REAL else t is not None and t.is_intlike
    t = T.base_of(e.ty) if e.ty is not None else None
    return t is not None and (t is T.REAL or t.is_intlike)


def _is_address(e: A.Expr, t) -> bool:
    """ADR(x) itself (CODESYS: an address, on which + and - count bytes)."""
    return (
        isinstance(e, A.Call)
        and isinstance(e.callee, A.Name)
        and e.callee.name.upper() == "ADR"
        and isinstance(T.unalias(t), T.RefType)
    )


def _is_pointer(t) -> bool:
    u = T.unalias(t) if t is not None else None
    return isinstance(u, T.RefType) and u.ref_kind == "POINTER"


def _through_reference(t: T.Type) -> T.Type:
    """A property of a REFERENCE TO type reads (and writes) what it refers to (TcLog's
    `logger.Error.Info`); codegen dereferences the GET's result."""
    return cast(T.RefType, T.unalias(t)).target if T.is_reference(t) else t
