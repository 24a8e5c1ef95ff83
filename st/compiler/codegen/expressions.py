"""Expressions and initial values: typed ST expressions → Python expressions."""

from __future__ import annotations

import ast as py
from typing import TYPE_CHECKING, cast

from ...model import types as T
from .. import ast as A
from .. import intervals as I
from ..check import (
    STEP,
    BoundCall,
    FunctionCall,
    IsValidRefCall,
    MethodCall,
    NativeCall,
    NewCall,
    QueryItfCall,
    RefCall,
    SizeofCall,
)
from ..check.binding import passed_on_any
from ..check.common import same_type
from ..check.rules.initialization_order import late_default, names_variables

if TYPE_CHECKING:
    from .module import ModuleGen
from .facts import UserFunctionCall, current, note_range
from .pyast import DAY_NS, Unsupported, _args, _attr, _call, _const, _name, default_value, f32

# an array of more elements than this is built by the runtime's `_fill`, a chunk at a time (so that
# building a program beside the running one, an online change, does not hold the interpreter)
BIG_ARRAY = 1 << 16


class InitGen:
    """Initial values: for declarations (constant initializers and defaults)."""

    def __init__(self, mod: ModuleGen, pou: T.POUType | None = None, gen: ExprGen | None = None):
        self.mod = mod
        self.pou = pou  # a block's or program's constructor: initial values may name its variables
        # a FUNCTION's or METHOD's code: its locals' initial values may name its variables
        self.gen = gen

    def initial(self, t: T.Type, init, construct: bool = True) -> py.expr:
        """The initial value of a `t` declared with `init`; `construct` False: an instance without
        its FB_init call (made later: `constructor_call`)."""
        ut = T.unalias(t)
        if init is None and isinstance(t, T.AliasType):
            # the alias's own initializer, else its target's
            a: T.Type = t
            while isinstance(a, T.AliasType):
                if a.init is not None:
                    return self.initial(a.target, a.init)
                a = a.target
        if isinstance(init, A.Expr) and self._in_place() and names_variables(init):
            return self._bound(init, t)  # a value computed from variables, a reference, an instance
        if isinstance(ut, T.ArrayType):
            return self.array(ut, init)
        obj: py.expr
        if isinstance(ut, T.StructType):
            obj = _call(ut.pyname)
            if isinstance(init, A.StructInit):
                return self._with_fields(obj, init, lambda n: ut.members.get(n.lower()))
            return obj
        if isinstance(ut, T.POUType) and ut.pou_kind == "INTERFACE":
            return _const(None)  # an interface variable: no instance yet (NULL)
        if isinstance(ut, T.POUType):
            ctor = init if isinstance(init, A.CtorInit) else None
            if ctor is not None:
                init = ctor.inner
            obj = _call(ut.pyname)
            if construct:
                obj = self.constructor_call(obj, ut, ctor)
            if isinstance(init, A.StructInit):
                # the declaration's values for its variables are set after FB_init ran (CODESYS,
                # TwinCAT: they are not yet there inside FB_init, and what FB_init set is replaced)
                obj = self._with_fields(obj, init, lambda n: _member_of_pou(ut, n))
            return obj
        if init is None or _zero_link(init, ut):
            return _const(default_value(t))  # (a POINTER's, a REF_TO's: NULL, as a literal 0 there)
        return ExprGen.constant_expr(self.mod, init, t)

    def constructed_later(self, obj: py.expr, ut: T.POUType, ctor: A.CtorInit) -> py.expr:
        """An instance made before (`initial(..., construct=False)`) constructed now: FB_init with
        the declaration's arguments, then the declaration's values for its variables again (they
        come after FB_init)."""
        made = self.constructor_call(obj, ut, ctor)
        if isinstance(ctor.inner, A.StructInit) and made is not obj:
            made = self._with_fields(made, ctor.inner, lambda n: _member_of_pou(ut, n))
        return made

    def constructor_call(self, obj: py.expr, ut: T.POUType, ctor: A.CtorInit | None) -> py.expr:
        """`obj._ctor({...})` with the declaration's FB_init arguments where the block has an FB_init
        chain, else `obj`."""
        block = self.mod.blocks.get(ut)
        if block is None or block.constructor is None:
            return obj
        keys: list[py.expr | None] = []
        values: list[py.expr] = []
        if ctor is not None:
            inputs = block.constructor.inputs
            for name, _sp, val in ctor.args:
                keys.append(_const(name.lower()))
                values.append(self.initial(inputs[name.lower()].type, val))
        return _call(_attr(obj, "_ctor"), py.Dict(keys, values))

    def _in_place(self) -> bool:
        """Are the initial values made where the variables they may name exist (a block's
        constructor, a function's or method's code)?"""
        return self.pou is not None or self.gen is not None

    def _bound(self, init, t: T.Type) -> py.expr:
        """An initial value that names variables: a reference to one, its address, an instance (an
        interface's value), or a value computed from them (a copy of an array, a structure or an
        instance); see the checker's _bound_initializer and rules/initialization_order.py."""
        g = self.gen if self.gen is not None else ExprGen(self.mod, self.pou)
        if T.is_reference(t) and not isinstance(init, A.Call):
            return g.ref_to(init)
        value = g.coerce(g.expr(init), init, t)
        if T.unalias(t).is_aggregate:
            value = _call("_copy", value)
        return value

    def _with_fields(self, obj: py.expr, init: A.StructInit, lookup) -> py.expr:
        # _init_fields(obj, (('name', value), ...)) returns obj; a block's properties are then
        # given theirs through their SET: _init_props(obj, (('_ps_name', value), ...))
        pairs: list[py.expr] = []
        props: list[py.expr] = []
        for name, _sp, val in init.fields:
            m = lookup(name)
            if isinstance(m, T.PropSym) and m.set is not None:
                props.append(py.Tuple([_const(m.set.pyname), self.initial(m.type, val)], py.Load()))
                continue
            if m is None:
                continue
            mt = m.type
            pairs.append(py.Tuple([_const(m.pyname), self.initial(mt, val)], py.Load()))
        made = _call("_init_fields", obj, py.Tuple(pairs, py.Load()))
        return _call("_init_props", made, py.Tuple(props, py.Load())) if props else made

    def array(self, at: T.ArrayType, init) -> py.expr:
        n = at.size
        elem = at.element
        ue = T.unalias(elem)
        values: list = []
        if isinstance(init, A.ArrayInit):
            for item in init.items:
                if isinstance(item, A.RepeatInit):
                    sub = item.items or [None]
                    for _ in range(item.count):
                        values.extend(sub)
                else:
                    values.append(item)
        values = values[:n]
        if ue.is_aggregate:
            elts = [self.initial(elem, v) for v in values]
            rest = n - len(values)
            if rest:
                proto = self.initial(elem, None)
                comp = py.ListComp(
                    proto, [py.comprehension(_name("_", py.Store()), _call("_range", _const(rest)), [], 0)]
                )
                if elts:
                    return py.BinOp(py.List(elts, py.Load()), py.Add(), comp)
                return comp
            return py.List(elts, py.Load())
        d = default_value(elem)
        if not values:
            if n > BIG_ARRAY:
                return _call("_fill", _const(d), _const(n))
            return py.BinOp(py.List([_const(d)], py.Load()), py.Mult(), _const(n))
        elts = [self.initial(elem, v) for v in values]
        rest = n - len(values)
        lst = py.List(elts, py.Load())
        if rest > BIG_ARRAY:
            return _call("_fill", _const(d), _const(n), lst)
        if rest:
            return py.BinOp(lst, py.Add(), py.BinOp(py.List([_const(d)], py.Load()), py.Mult(), _const(rest)))
        return lst


def _zero_link(init, ut: T.Type) -> bool:
    """The literal 0 as a POINTER's or REF_TO's initial value: NULL (the checker allows it where
    the preset does, as CODESYS)."""
    return isinstance(ut, T.RefType) and isinstance(init, A.Literal) and init.kind == "int" and init.value == 0


def _member_of_pou(pou: T.POUType, name: str):
    """A block's variable (or property) that a declaration's `(name := value)` gives a value."""
    return pou.vars.get(name.lower()) or pou.properties.get(name.lower())


class ExprGen:
    """Expression and statement generation shared by functions and FB bodies."""

    def __init__(self, mod: ModuleGen, pou: T.POUType | None):
        self.mod = mod
        self.pou = pou
        self.cached: set = set()  # VarSyms held in Python locals
        self.boxed: set = set()  # VarSyms held in one-element lists (passed by reference)
        self.through: set = set()  # in-outs used through the caller's reference (their box)
        self.self_name: str | None = "self"  # None: a FUNCTION's code (no instance)
        self.globals_written: set = set()
        self.loop_vars: list = []
        self.written_locals: set = set()
        self.result_name = ""
        self.loop_ranges: dict[T.VarSym, I.Interval] = {}  # a FOR counter inside its body (range form)
        self.index_memo: dict = {}  # index_key → temp: an element's checked index, computed once

    def _result_boxed(self) -> bool:
        return bool(getattr(self.pou, "result_address_taken", False))

    def result_load(self) -> py.expr:
        """The function's (or method's) own result variable, read."""
        if self._result_boxed():  # ADR(F): the result lives in a one-element box
            return py.Subscript(_name(self.result_name), _const(0), py.Load())
        return _name(self.result_name)

    def result_store(self) -> py.expr:
        if self._result_boxed():
            return py.Subscript(_name(self.result_name), _const(0), py.Store())
        return _name(self.result_name, py.Store())

    def result_init(self, value: py.expr) -> py.stmt:
        box = py.List([value], py.Load()) if self._result_boxed() else value
        return py.Assign([_name(self.result_name, py.Store())], box)

    @classmethod
    def constant_expr(cls, mod, e, t: T.Type) -> py.expr:
        g = cls(mod, None)
        g.self_name = "_NO_SELF"
        return g.coerce(g.expr(e), e, t)

    def this(self) -> py.Name:
        """The instance the code runs on (THIS, SUPER^, an action or method of this instance)."""
        assert self.self_name is not None  # the checker allows those only where there is an instance
        return _name(self.self_name)

    def new_tmp(self) -> str:
        self.mod.tmp += 1
        return f"_t{self.mod.tmp}"

    # ------------------------------------------------------------------ variables
    def var_load(self, sym: T.VarSym) -> py.expr:
        if sym.is_global or sym.section == "VAR_EXTERNAL":
            return _name(sym.global_ref.pyname if sym.global_ref else sym.pyname)
        if sym in self.boxed:
            return py.Subscript(_name(sym.pyname), _const(0), py.Load())
        if sym in self.cached or self.self_name is None:
            return _name(sym.pyname)
        return _attr(self.this(), sym.pyname)

    def var_store(self, sym: T.VarSym) -> py.expr:
        if sym.is_global or sym.section == "VAR_EXTERNAL":
            name = sym.global_ref.pyname if sym.global_ref else sym.pyname
            self.globals_written.add(name)
            return _name(name, py.Store())
        if sym in self.boxed:
            return py.Subscript(_name(sym.pyname), _const(0), py.Store())
        if sym in self.cached or self.self_name is None:
            self.written_locals.add(sym)
            return _name(sym.pyname, py.Store())
        return _attr(self.this(), sym.pyname, py.Store())

    # ------------------------------------------------------------------ conversions
    def coerce(self, node: py.expr, e, dst: T.Type | None) -> py.expr:
        """Make a value of `e`'s type fit `dst`: widen, wrap, round, truncate, check."""
        if dst is None:
            return node
        src = getattr(e, "ty", None) if e is not None else None
        d = T.base_of(dst)
        s = T.base_of(src) if src is not None else None
        if isinstance(d, T.RefType) and isinstance(s, T.RefType) and d.ref_kind == "POINTER":
            arr = T.unalias(s.target)
            if isinstance(arr, T.ArrayType) and same_type(arr.element, d.target):
                return _call("_ptr_elems", node)  # ADR(arr) as a POINTER TO its element: the first one
            view = T.pointer_view(s.target, d.target)
            if view is None:
                return node
            if isinstance(T.unalias(s.target), T.ArrayType) and not isinstance(T.unalias(d.target), T.ArrayType):
                node = _call("_ptr_elems", node)  # ADR(arr) as a POINTER TO its element: the first one
            if view[0] != view[1]:  # ADR(dw) as a POINTER TO BYTE: its bytes
                node = _call("_ptr_bytes", node, _const(view[0]), _const(view[1]))
            return node
        if isinstance(node, py.Constant) and node.value is not None and not isinstance(node.value, str):
            v = node.value
            if d.is_real:
                v = float(cast(float, v))  # a number: not None, not a string
                return _const(f32(v) if d is T.REAL else v)
            if d.is_intlike and isinstance(v, (int, bool)) and not isinstance(v, bool):
                return _const(_wrap_value(v, d))
            if d.is_bool:
                return _const(bool(v))
        if d.is_real:
            if s is not None and (s.is_intlike or s is T.LIT_INT):
                node = _call("_float", node)
                if d is T.REAL and not (isinstance(s, T.ElemType) and s.is_intlike and s.bits <= 16):
                    node = _call("_f32", node)
                return node
            if d is T.REAL and not self.is_f32(e):
                return _call("_f32", node)
            return node
        if isinstance(d, T.ElemType) and d.is_intlike:  # (base_of: only an ElemType is int-like)
            sub = T.unalias(dst)
            if isinstance(sub, T.SubrangeType) and sub.outside == "fault":
                return _call("_subrange", node, _const(sub.lo), _const(sub.hi))
            if isinstance(sub, T.SubrangeType) and sub.outside == "clamp":  # MatIEC's check functions
                return _call("_clamp_subrange", node, _const(sub.lo), _const(sub.hi))
            if isinstance(sub, T.SubrangeType):  # CODESYS/TwinCAT without CheckRange: kept, as the base type
                return wrap(node, d) if not self._proven(node, e, d) else node
            if s is not None and s.is_bool:
                node = _call("_int", node)
            if not self._proven(node, e, d):
                return wrap(node, d)
            return node
        if isinstance(d, T.StringType):
            if s is not None and isinstance(s, T.StringType) and s.length <= d.length:
                return node
            if isinstance(e, A.Literal) and isinstance(e.value, str) and len(e.value) <= d.length:
                return node
            return py.Subscript(node, py.Slice(None, _const(d.length), None), py.Load())
        if d.kind == "tod" and s is not None and s.kind == "tod":
            return node
        return node

    def is_f32(self, e) -> bool:
        """Is this REAL-typed expression already exactly a float32 value?"""
        if e is None:
            return False
        if isinstance(e, (A.Name, A.Field, A.Index, A.Deref, A.AccessorCall)):
            return T.base_of(e.ty) is T.REAL if e.ty is not None else False
        if isinstance(e, A.Literal):
            return True
        if isinstance(e, A.Call) and isinstance(e.target, (FunctionCall, MethodCall)):
            return T.base_of(e.ty) is T.REAL if e.ty is not None else False
        return False

    def in_range(self, e, d: T.ElemType) -> bool:
        """Can this integer expression's value never leave d's range? (Then its store needs no wrap.)"""
        r = self.value_range(e)
        return r is not None and d.lo <= r[0] and r[1] <= d.hi

    def _proven(self, node: py.expr, e, d: T.ElemType) -> bool:
        """`in_range`, noting the interval of `node` (e's value) where it holds (facts.py)."""
        r = self.value_range(e)
        if r is None or not (d.lo <= r[0] and r[1] <= d.hi):
            return False
        note_range(node, r)
        return True

    def value_range(self, e) -> I.Interval | None:
        """The interval an integer expression's value lies in, or None if unknown (the arithmetic:
        compiler/intervals.py)."""
        if e is None:
            return None
        if isinstance(e, A.Literal):
            return I.point(int(e.value)) if isinstance(e.value, (int, bool)) else None
        if isinstance(e.const, int):
            return I.point(e.const)
        if isinstance(e, (A.Name, A.Field)) and isinstance(e.sym, T.VarSym):
            c = e.sym.global_ref or e.sym  # a CONSTANT's known value (GVL_Param.N, a VAR_EXTERNAL CONSTANT)
            if c.constant and isinstance(c.const_value, int):
                return I.point(int(c.const_value))
        t = T.base_of(e.ty) if e.ty is not None else None
        if t is None:
            return None
        if t.is_bool:
            return I.Interval(0, 1)
        if isinstance(t, T.EnumType):
            vals = [v for _, v in t.members.values()] or [0]
            return I.Interval(min(vals), max(vals))
        # a subrange variable's interval is its base type's: a POINTER, a REFERENCE or a byte view
        # writes it without the check (and codesys/twincat keep a value outside it)
        declared = I.of_type(t)
        if isinstance(e, A.Name) and e.sym in self.loop_ranges:
            return self.loop_ranges[e.sym]  # a FOR counter its body does not write: start..end
        if isinstance(e, (A.Name, A.Field, A.Index, A.Deref, A.Bit, A.AccessorCall)) or (
            isinstance(e, A.Call) and isinstance(e.target, (FunctionCall, MethodCall))
        ):
            return declared
        if isinstance(e, A.Binary):
            op = e.op
            if op in ("=", "<>", "<", ">", "<=", ">="):
                return I.Interval(0, 1)
            l, r = self.value_range(e.left), self.value_range(e.right)
            if l is None or r is None:
                return None
            arith = _ARITH.get(op)
            if arith is not None:
                return arith(l, r)
            if op in ("AND", "OR", "XOR") and declared is not None:
                # bitwise results of in-range operands stay in the operands' (common) type
                if I.within(l, declared) and I.within(r, declared):
                    return declared
            return None
        if isinstance(e, A.Unary):
            v = self.value_range(e.operand)
            if v is None:
                return None
            if e.op == "-":
                return I.neg(v)
            if e.op == "+":
                return v
            if e.op == "NOT":
                # ~x on a signed value stays in its type; unsigned NOT is masked
                return declared if declared is not None and I.within(v, declared) else None
        if isinstance(e, A.Call) and isinstance(e.target, NativeCall):
            sig = e.target.sig
            if getattr(sig, "exact", False):
                return declared
            if sig.name in ("SEL", "MAX", "MIN", "LIMIT", "MUX", "MOVE"):
                skip = 1 if sig.name in ("SEL", "MUX") else 0
                rs = [self.value_range(a.value) for a in e.target.args[skip:]]
                if rs and None not in rs:
                    known = cast(list[I.Interval], rs)
                    if sig.name == "MIN":
                        return I.minimum(known)
                    if sig.name == "MAX":
                        return I.maximum(known)
                    if sig.name == "LIMIT" and len(known) == 3:  # MN, MX, or IN between them
                        return I.hull(known[0], known[2])
                    return I.hull(*known)
        return None

    # ------------------------------------------------------------------ expressions
    def expr(self, e) -> py.expr:
        m = getattr(self, "x_" + type(e).__name__)
        return m(e)

    def x_Literal(self, e: A.Literal) -> py.expr:
        v = e.value
        t = T.base_of(e.ty) if e.ty is not None else None
        if t is not None and t.is_real:
            v = float(v)
            if t is T.REAL:
                v = f32(v)
        elif e.kind == "bool":
            v = bool(v) if not (t is not None and t.is_intlike) else int(v)
        return _const(v)

    def x_EnumLit(self, e: A.EnumLit) -> py.expr:
        return _const(e.const if e.const is not None else 0)

    def x_Name(self, e: A.Name) -> py.expr:
        sym = e.sym
        if isinstance(sym, T.VarSym):
            if sym.constant and sym.const_value is not None and not isinstance(sym.const_value, (list, dict)):
                v = sym.const_value
                t = T.base_of(sym.type)
                if t.is_real:
                    v = float(v)
                    if t is T.REAL:
                        v = f32(v)
                return _const(v)
            if T.is_reference(sym.type):  # REFERENCE TO: through the reference
                return _call(_attr(self.var_load(sym), "get"))
            return self.var_load(sym)
        if isinstance(sym, T.POUType):  # a function's own result variable
            if T.is_reference(sym.return_type):
                return _call(_attr(self.result_load(), "get"))
            return self.result_load()
        if sym is STEP:
            return _const(e.const)
        if isinstance(sym, T.EnumType):
            return _const(e.const)
        if getattr(sym, "kind", "") == "null":
            return _const(None)
        if getattr(sym, "kind", "") == "this":
            return _call("_ObjRef", self.this())
        raise Unsupported(e.span, f"cannot use '{e.name}' here")

    def x_Direct(self, e: A.Direct) -> py.Name:
        found = self.mod.p.direct_vars.get(e.address)  # the checker made the address canonical
        if found is None:
            raise Unsupported(e.span, f"unknown address {e.address}")
        return _name(found[0])

    def x_Field(self, e: A.Field) -> py.expr:
        if isinstance(e.sym, T.EnumType):
            return _const(e.const)
        if isinstance(e.base, A.Name) and e.base.sym is None and getattr(e.sym, "is_global", False):
            name = A.Name(e.span, e.sym.name, e.sym)  # GVL_Main.x in an initial value (bodies are
            name.ty = e.ty  # lowered to the plain name, lower/qualified.py)
            return self.x_Name(name)
        bt = T.unalias(e.base.ty) if e.base.ty is not None else None
        if bt is STEP:
            idx = e.base.const
            if e.name.upper() == "X":
                return py.Subscript(_attr(self.this(), "_sfc_x"), _const(idx), py.Load())
            return _call(_attr(_attr(self.this(), "_sfc"), "elapsed"), _const(idx))
        base = self.expr(e.base)
        if isinstance(bt, T.ElemType) and bt.is_intlike:
            return self._bit_read(base, int(e.name), bt)
        sym = e.sym
        if isinstance(sym, T.VarSym) and T.is_reference(sym.type):
            return _call(_attr(_attr(base, sym.pyname), "get"))  # inst.r: through the reference
        return _attr(base, sym.pyname)

    def x_AccessorCall(self, e: A.AccessorCall, *args) -> py.expr:
        """A property's accessor on its instance (`args`: SET's value); non-virtual: the base's."""
        acc = e.accessor
        if e.nonvirtual:
            node = _call(_attr(_name(acc.owner_fb.pyname), acc.pyname), self.this(), *args)
        else:
            obj = self.this() if e.obj is None else self.expr(e.obj)
            node = _call(_attr(obj, acc.pyname), *args)
        if not args and T.is_reference(acc.return_type):  # a REFERENCE TO property: what it refers to
            return _call(_attr(node, "get"))
        return node

    def _bit_read(self, base: py.expr, n: int, t) -> py.expr:
        return py.Compare(py.BinOp(base, py.BitAnd(), _const(1 << n)), [py.NotEq()], [_const(0)])

    def x_Bit(self, e: A.Bit) -> py.expr:
        base = self.expr(e.base)
        bt = T.base_of(e.base.ty)
        if e.size == "X":
            return self._bit_read(base, e.index, bt)
        width = {"B": 8, "W": 16, "D": 32, "L": 64}[e.size]
        return py.BinOp(py.BinOp(base, py.RShift(), _const(e.index * width)), py.BitAnd(), _const((1 << width) - 1))

    def x_Index(self, e: A.Index) -> py.expr:
        return py.Subscript(self.array_of(e), self.index_of(e), py.Load())

    def array_of(self, e: A.Index) -> py.expr:
        """The list an index goes into: an ARRAY[*] parameter's is the caller's list, a POINTER's
        the elements from where it points on (p[i])."""
        base = self.expr(e.base)
        pt = T.unalias(e.base.ty)
        if isinstance(pt, T.RefType):
            return _call("_PtrView", base, _const(T.size_of(pt.target)[0]))
        return _attr(base, "data") if T.is_conformant(e.base.ty) else base

    def conformant_arg(self, value: py.expr, arg_type, param_type) -> py.expr:
        """An array passed to an ARRAY[*] parameter carries its bounds along."""
        if not T.is_conformant(param_type) or T.is_conformant(arg_type):
            return value
        at = T.unalias(arg_type)
        assert isinstance(at, T.ArrayType)  # the checker passes only arrays to ARRAY[*]
        return _call("_conf", value, _const(tuple(at.dims)))

    def index_of(self, e: A.Index) -> py.expr:
        if self.index_memo:
            tmp = self.index_memo.get(index_key(e))
            if tmp is not None:
                return _name(tmp)
        at = T.unalias(e.base.ty)
        if isinstance(at, T.RefType):
            return self.expr(e.indices[0])
        assert isinstance(at, T.ArrayType)  # the checker indexes arrays only
        dims = at.dims
        if T.is_conformant(at):
            return _call("_cix", self.expr(e.base), *[self.expr(i) for i in e.indices])
        flat: py.expr | None = None
        parts = []
        for i, (lo, hi) in zip(e.indices, dims):
            parts.append((i, lo, hi))
        # row-major: last index varies fastest
        strides = []
        s = 1
        for lo, hi in reversed(dims):
            strides.append(s)
            s *= hi - lo + 1
        strides.reverse()
        for (i, lo, hi), st in zip(parts, strides):
            c = i.const if i.const is not None else (i.value if isinstance(i, A.Literal) else None)
            if isinstance(c, int):
                term: py.expr = _const((c - lo) * st)
            else:
                iv = self.expr(i)
                if hi < lo:  # ARRAY[*]: bounds known only at run time
                    term = iv
                else:
                    safe = self._index_safe(i, lo, hi)
                    if safe is not None:
                        note_range(iv, safe)
                        term = py.BinOp(iv, py.Sub(), _const(lo)) if lo else iv
                    else:
                        term = _call("_ix", iv, _const(lo), _const(hi))
                if st != 1:
                    term = py.BinOp(term, py.Mult(), _const(st))
            flat = term if flat is None else py.BinOp(flat, py.Add(), term)
        assert flat is not None  # an index has one term per dimension, at least one
        return flat

    def _index_safe(self, i, lo, hi) -> I.Interval | None:
        """The values of an index that can never leave lo..hi (then it needs no check: a FOR over
        the array's range, `i + 1` in a FOR to hi - 1, a subrange-typed index, …), else None."""
        r = self.value_range(i)
        if r is not None and lo <= r[0] and r[1] <= hi:
            return r
        t = T.base_of(i.ty) if i.ty is not None else None
        if isinstance(t, T.ElemType) and t.is_intlike and lo <= t.lo and t.hi <= hi:
            return I.Interval(t.lo, t.hi)
        return None

    def x_Deref(self, e: A.Deref) -> py.expr:
        if isinstance(e.base, A.Name) and getattr(e.base.sym, "kind", "") in ("this", "super"):
            return self.this()  # THIS^ (and SUPER^): the instance itself
        return _call(_attr(self.expr(e.base), "get"))

    def x_Unary(self, e: A.Unary) -> py.expr:
        v = self.expr(e.operand)
        t = T.base_of(e.ty) if e.ty is not None else None
        if e.op == "NOT":
            if t is not None and t.is_bool:
                return py.UnaryOp(py.Not(), v)
            if isinstance(t, T.ElemType) and t.is_intlike and not t.signed:
                return py.BinOp(py.UnaryOp(py.Invert(), v), py.BitAnd(), _const(t.hi))
            return py.UnaryOp(py.Invert(), v)
        if e.op == "-":
            return py.UnaryOp(py.USub(), v)
        return v

    def x_Binary(self, e: A.Binary) -> py.expr:
        if e.single:  # openplc: REAL op REAL in single precision, as MatIEC's generated C
            e.single = False
            try:
                return _call("_f32", self.x_Binary(e))
            finally:
                e.single = True
        op = e.op
        lt = T.base_of(e.left.ty) if e.left.ty is not None else None
        rt = T.base_of(e.right.ty) if e.right.ty is not None else None
        res = T.base_of(e.ty) if e.ty is not None else None
        l, r = self.expr(e.left), self.expr(e.right)
        if op in ("+", "-", "*") and res is not None and res.is_real:
            # a float operand converts the other's integer itself, as float() does: no call. Only
            # one side: with both conversions gone, two integers would multiply exactly (a UDINT_TO_LREAL
            # product of 2^32-1 by itself is an int of 64 bits, not the double LREAL arithmetic gives)
            l2 = _unfloat(l) if rt is not None and rt.is_real else l
            r2 = _unfloat(r) if lt is not None and lt.is_real else r
            if r2 is not r:
                r = r2
            elif l2 is not l:
                l = l2
        pl, pr = (T.unalias(x.ty) if x.ty is not None else None for x in (e.left, e.right))
        if isinstance(pl, T.RefType) or isinstance(pr, T.RefType):
            if op in ("+", "-") and not (isinstance(pl, T.RefType) and isinstance(pr, T.RefType)):
                p, n = (l, r) if isinstance(pl, T.RefType) else (r, l)
                ptr = cast(T.RefType, pl if isinstance(pl, T.RefType) else pr)
                size = T.size_of(ptr.target)[0]
                if ptr.ref_kind != "POINTER":  # ADR(x) + n: the byte address n bytes into x
                    side = e.left if isinstance(pl, T.RefType) else e.right
                    p, size = self.coerce(p, side, T.RefType(T.BYTE, "POINTER")), 1
                return _call("_ptr_add", p, n if op == "+" else py.UnaryOp(py.USub(), n), _const(size))
            if op not in ("=", "<>"):  # p - q, p < q: by the distance in bytes
                ptr = cast(T.RefType, pl if _is_pointer(pl) else pr)
                size = T.size_of(ptr.target)[0]
                l, r = self.coerce(l, e.left, ptr), self.coerce(r, e.right, ptr)  # ADR(arr): its first element
                d = _call("_ptr_diff", l, r, _const(size))
                if op == "-":
                    return d
                l, r = d, _const(0)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            pyop = {"=": py.Eq(), "<>": py.NotEq(), "<": py.Lt(), ">": py.Gt(), "<=": py.LtE(), ">=": py.GtE()}[op]
            return py.Compare(l, [pyop], [r])
        if op == "AND_THEN":
            return py.BoolOp(py.And(), [l, r])
        if op == "OR_ELSE":
            return py.BoolOp(py.Or(), [l, r])
        if op in ("AND", "OR", "XOR"):
            bitop = {"AND": py.BitAnd(), "OR": py.BitOr(), "XOR": py.BitXor()}[op]
            return py.BinOp(l, bitop, r)
        if res is not None and res.kind == "tod" and op in ("+", "-"):
            return py.BinOp(py.BinOp(l, py.Add() if op == "+" else py.Sub(), r), py.Mod(), _const(DAY_NS))
        if res is not None and res.is_time and op in ("*", "/") and lt is not None and lt.is_time:
            other = rt
            if op == "*":
                if other is not None and (other.is_real or other is T.LIT_REAL):
                    return _call("_round", py.BinOp(l, py.Mult(), r))
                return py.BinOp(l, py.Mult(), r)
            if other is not None and (other.is_real or other is T.LIT_REAL):
                return _call("_round", _call("_fdiv", l, r))
            return _call("_idiv", l, r)
        if res is not None and res.is_time and op == "*" and rt is not None and rt.is_time:
            if lt is not None and (lt.is_real or lt is T.LIT_REAL):
                return _call("_round", py.BinOp(l, py.Mult(), r))
            return py.BinOp(l, py.Mult(), r)
        if op == "+":
            return py.BinOp(l, py.Add(), r)
        if op == "-":
            return py.BinOp(l, py.Sub(), r)
        if op == "*":
            return py.BinOp(l, py.Mult(), r)
        if op == "/":
            if res is not None and (res.is_real or res is T.LIT_REAL):
                return _call("_fdiv", l, r)
            if (
                isinstance(lt, T.ElemType)
                and isinstance(rt, T.ElemType)
                and lt.is_intlike
                and rt.is_intlike
                and not lt.signed
                and not rt.signed
            ):
                return py.BinOp(l, py.FloorDiv(), r)
            inline = self._by_constant(e, l, py.FloorDiv())
            return inline if inline is not None else _call("_idiv", l, r)
        if op == "MOD":
            if (
                isinstance(lt, T.ElemType)
                and isinstance(rt, T.ElemType)
                and lt.is_intlike
                and rt.is_intlike
                and not lt.signed
                and not rt.signed
            ):
                return _call("_umod", l, r)
            inline = self._by_constant(e, l, py.Mod())
            return inline if inline is not None else _call("_imod", l, r)
        if op == "**":
            return _call("_pow", l, r)
        raise Unsupported(e.span, f"operator {op}")

    def _by_constant(self, e: A.Binary, l: py.expr, op: py.operator) -> py.expr | None:
        """Integer DIV or MOD by a positive constant, inline (no call): truncating toward zero and
        with the dividend's sign as IEC says — Python's // and % directly when the dividend cannot
        be negative, else `t op m if (t := x) >= 0 else -(-t op m)`. None: keep the helper."""
        m = e.right.const if isinstance(e.right.const, int) else None
        if m is None and isinstance(e.right, A.Literal) and isinstance(e.right.value, int):
            m = e.right.value
        if m is None or isinstance(m, bool) or m <= 0:
            return None
        r = self.value_range(e.left)
        if r is not None and r[0] >= 0:
            return py.BinOp(l, op, _const(m))
        t = self.new_tmp()
        test = py.Compare(py.NamedExpr(_name(t, py.Store()), l), [py.GtE()], [_const(0)])
        neg = py.UnaryOp(py.USub(), py.BinOp(py.UnaryOp(py.USub(), _name(t)), op, _const(m)))
        return py.IfExp(test, py.BinOp(_name(t), op, _const(m)), neg)

    # ------------------------------------------------------------------ calls
    def x_Call(self, e: A.Call) -> py.expr:
        if e.deref:  # a REFERENCE TO result: the variable it refers to
            e.deref = False
            try:
                return _call(_attr(self.x_Call(e), "get"))
            finally:
                e.deref = True
        match e.target:
            case FunctionCall() as tgt:
                return self.function_call(e, tgt)
            case NativeCall() as tgt:
                return self.native_call(e, tgt)
            case RefCall(arg=arg):
                return self.ref_to(arg)
            case MethodCall() as tgt:
                return self.method_call(e, tgt)
            case SizeofCall(value=value):
                return _const(value)
            case BoundCall(value=value) if value is not None:  # LOWER_BOUND / UPPER_BOUND of a fixed array
                return _const(value)
            case BoundCall(arg=arg, dim=dim, upper=upper):  # of an ARRAY[*]: from the caller's bounds
                dims = _attr(self.expr(arg), "dims")
                return py.Subscript(
                    py.Subscript(dims, _const(dim - 1), py.Load()), _const(1 if upper else 0), py.Load()
                )
            case NewCall(type=t, count=count) if (
                count is not None
            ):  # __NEW(T, n): n fresh values, a pointer to the first
                make = py.Lambda(_args([]), InitGen(self.mod).initial(t, None))
                return _call("_new_items", make, self.expr(count), _const(_wrap_spec(t)))
            case NewCall(type=t, init=init):  # a one-element box the pointer refers to
                return _call(
                    "_ItemRef",
                    py.List([InitGen(self.mod, gen=self).initial(t, init)], py.Load()),
                    _const(0),
                    _const(_wrap_spec(t)),
                )
            case IsValidRefCall(arg=a):
                return self.is_valid_ref(a)
            case QueryItfCall(src=src, dst=dst, itf=itf):
                return _call("_query_itf", self.expr(src), _const(itf.name.lower()), self.ref_to(dst))
            case None:
                raise Unsupported(e.span, "unresolved call")
        raise Unsupported(e.span, "a function block call has no value")

    def method_call(self, e: A.Call, tgt: MethodCall) -> py.expr:
        """inst.M(...): a Python method call on the instance, so a derived block's override runs;
        SUPER^.M(...): the base block's method on this instance (not virtual)."""
        if tgt.nonvirtual is not None:
            return self.function_call(e, tgt, fn=_attr(_name(tgt.nonvirtual.pyname), tgt.pou.pyname), first=self.this())
        obj = self.this() if tgt.obj is None else self.expr(tgt.obj)
        return self.function_call(e, tgt, fn=_attr(obj, tgt.pou.pyname))

    def native_call(self, e: A.Call, tgt: NativeCall) -> py.expr:
        sig = tgt.sig
        args = []
        # settle each argument to its parameter's type (group or concrete)
        for i, a in enumerate(tgt.args):
            v = self.expr(a.value)
            want = _param_type(tgt, sig, i)
            if (
                want is not None
                and (T.base_of(want).is_num)
                and a.value.ty is not None
                and T.base_of(a.value.ty) is not T.base_of(want)
            ):
                v = self.coerce(v, a.value, want)
            elif want is T.REAL and not self.is_f32(a.value):
                v = _call("_f32", v)  # a REAL parameter holds a single-precision value (rounded on store)
            elif sig.typed_args is not None:
                st = self._arg_store(a.value, want)
                if st is not None and sig.typed_args(i, st):
                    v = wrap(v, st)  # USINT_TO_DWORD(u - w) converts the USINT u - w
            args.append(v)
        if sig.emit is not None:
            try:
                node = sig.emit(self, args, tgt.arg_types, e.ty)
            except TypeError as exc:  # e.g. TO_TOD of a REAL: no such conversion
                raise Unsupported(e.span, f"{sig.name}: {exc}") from None
        else:
            extra = sig.extra(tgt.arg_types, e.ty) if sig.extra else ()
            node = _call(sig.helper, *args, *[_const(x) for x in extra])
        if tgt.en is not None:
            node = py.IfExp(self.expr(tgt.en.value), node, _const(default_value(e.ty) if e.ty is not None else None))
        return node

    def _arg_store(self, a, want) -> T.ElemType | None:
        """The integer type a native function's argument of its parameter's own type (or of a generic
        parameter) is wrapped to when its value can leave that type (an exact intermediate), else None."""
        at = T.base_of(a.ty) if a.ty is not None else None
        if not (isinstance(at, T.ElemType) and at.is_intlike):
            return None
        if want is not None and T.base_of(want) is not at:
            return None
        return None if self.in_range(a, at) else at

    def function_call(self, e: A.Call, tgt, fn=None, first=None) -> py.expr:
        pou: T.POUType = tgt.pou
        bind = tgt.bind["params"]
        args = [] if first is None else [first]
        for p in pou.params():
            a = bind.get(p.name.lower())
            if p.section == "VAR_INPUT":
                if a is None:
                    if late_default(p):
                        args.append(_name("_LATE"))  # the callee computes it (pous.py)
                    else:
                        args.append(InitGen(self.mod).initial(p.type, p.init))
                elif p.any_input:
                    args.append(self.any_arg(a.value, p))
                elif T.is_reference(p.type):  # bound to the argument
                    args.append(self.ref_to(a.value))
                else:
                    v = self.expr(a.value)
                    ut = T.unalias(p.type)
                    # inputs are copies: an FB instance too, since calling it (or its methods) changes it
                    if ut.is_aggregate and (p.written or isinstance(ut, T.POUType)):
                        v = _call("_copy", v)
                    args.append(self.coerce(v, a.value, p.type))
            elif p.section == "VAR_IN_OUT":
                if a.temporary and not T.unalias(p.type).is_aggregate:  # VAR_IN_OUT CONSTANT := expression
                    args.append(self.temporary_ref(a.value, p.type))
                elif not T.unalias(p.type).is_aggregate:
                    args.append(self.ref_to(a.value))
                else:
                    args.append(self.conformant_arg(self.expr(a.value), a.value.ty, p.type))
            else:  # VAR_OUTPUT
                if a is None:
                    args.append(_const(None))
                else:
                    args.append(self.ref_to(a.value, negated=a.negated))
        node: py.expr = _call(fn if fn is not None else pou.pyname, *args)
        facts = current()
        if facts is not None and fn is None and isinstance(node, py.Call):
            facts.function_calls.append(UserFunctionCall(node, pou.pyname))
        en = tgt.bind.get("en")
        if en is not None:
            rt = pou.return_type
            node = py.IfExp(self.expr(en.value), node, _const(default_value(rt) if rt is not None else None))
        return node

    def any_arg(self, e, p: T.VarSym) -> py.expr:
        """The AnyType for an ANY input: over the argument variable's bytes (so pValue reads the
        caller's variable, as CODESYS passes its address), or over a temporary for an expression."""
        t = e.ty
        if passed_on_any(e) is not None:  # the caller's own ANY input, handed on as it is
            return self.expr(e)
        if isinstance(e, (A.Name, A.Field, A.Index, A.Deref)):
            ref = self.ref_to(e)
        else:
            ref = _call("_ItemRef", py.List([self.expr(e)], py.Load()), _const(0), _const(_wrap_spec(t)))
        st = cast(T.StructType, T.unalias(p.type))
        names = tuple(st.members[k].pyname for k in ("pvalue", "disize", "typeclass"))
        return _call(
            "_any_value", _name(st.pyname), ref, _const(T.byte_layout(t)), _const(T.type_class(t)), _const(names)
        )

    def is_valid_ref(self, a) -> py.expr:
        """__ISVALIDREF(a): the reference a REFERENCE TO variable or member holds (not what it refers
        to) is not NULL; a FUNCTION's or METHOD's VAR_IN_OUT is always bound (every call gives it),
        a block's is once a call gave it (it starts unbound: pous.py)."""
        sym = a.sym if isinstance(a, (A.Name, A.Field)) else None
        if isinstance(sym, T.VarSym) and sym.section == "VAR_IN_OUT" and not T.is_reference(sym.type):
            if not isinstance(sym.owner, T.POUType) or sym.owner.pou_kind == "FUNCTION":
                return _const(True)
            raw = self.var_load(sym)
        elif isinstance(a, A.Name) and isinstance(sym, T.VarSym) and T.is_reference(sym.type):
            raw = self.var_load(sym)
        elif isinstance(a, A.Field) and isinstance(sym, T.VarSym) and T.is_reference(sym.type):
            raw = _attr(self.expr(a.base), sym.pyname)  # the reference inst.r holds
        else:
            raw = self.expr(a)
        return py.Compare(raw, [py.IsNot()], [_const(None)])

    def temporary_ref(self, e, t: T.Type) -> py.expr:
        """A reference to a fresh temporary holding the value of `e` as a `t` (a VAR_IN_OUT
        CONSTANT's literal or expression)."""
        value = self.coerce(self.expr(e), e, t)
        return _call("_ItemRef", py.List([value], py.Load()), _const(0), _const(_wrap_spec(t)))

    def ref_to(self, e, negated: bool = False) -> py.expr:
        """A reference object for an output or in-out argument, or REF(x) (runtime.helpers)."""
        if negated:
            return _call("_NegRef", self.ref_to(e))
        if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym) and T.is_reference(e.sym.type):
            return self.var_load(e.sym)  # the reference a REFERENCE TO variable holds
        if isinstance(e, A.Name) and isinstance(e.sym, T.POUType) and self._result_boxed():
            return _call("_ItemRef", _name(self.result_name), _const(0), _const(_wrap_spec(e.ty)))  # ADR(F)
        if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym):
            sym = e.sym
            t = sym.type
            if sym.is_global or sym.section == "VAR_EXTERNAL":
                name = sym.global_ref.pyname if sym.global_ref else sym.pyname
                return _call("_ItemRef", _name("_ns"), _const(name), _const(_wrap_spec(t)))
            if sym in self.through:
                return _name(sym.pyname)  # the caller's own reference
            if sym in self.boxed:
                return _call("_ItemRef", _name(sym.pyname), _const(0), _const(_wrap_spec(t)))
            if (sym in self.cached or self.self_name is None) and T.unalias(t).is_aggregate:
                # an array or structure in a local: the object itself (aggregates are written in place)
                return _call("_ItemRef", py.List([self.var_load(sym)], py.Load()), _const(0), _const(None))
            if sym in self.cached or self.self_name is None:
                raise Unsupported(e.span, f"internal: '{sym.name}' is held in a local but passed by reference")
            return _call("_AttrRef", self.this(), _const(sym.pyname), _const(_wrap_spec(t)))
        if isinstance(e, A.Field) and isinstance(e.sym, T.VarSym) and T.is_reference(e.sym.type):
            return _attr(self.expr(e.base), e.sym.pyname)  # the reference inst.r holds
        if isinstance(e, A.Field):
            return _call("_AttrRef", self.expr(e.base), _const(e.sym.pyname), _const(_wrap_spec(e.ty)))
        if isinstance(e, A.Index):
            return _call("_ItemRef", self.array_of(e), self.index_of(e), _const(_wrap_spec(e.ty)))
        if isinstance(e, A.Deref):
            return self.expr(e.base)
        if isinstance(e, A.Direct):
            return _call("_ItemRef", _name("_ns"), _const(self.x_Direct(e).id), _const(None))
        if isinstance(e, A.Bit) or isinstance(e, A.Field):
            raise Unsupported(e.span, "a bit cannot be passed as an output or in-out argument")
        raise Unsupported(e.span, "this argument needs a variable")


def _wrap_spec(t):
    """(lo, hi, signed bits) for integer refs so that stores through them wrap, else None."""
    b = T.base_of(t) if t is not None else None
    if isinstance(b, T.ElemType) and b.is_intlike:
        return (b.bits, b.signed)
    if b is T.REAL:
        return "f32"
    if isinstance(b, T.StringType):
        return ("str", b.length)
    return None


def _param_type(tgt, sig, i: int):
    """The type argument i of a native function is passed as: its group's, its parameter's, or None (generic)."""
    p = sig.params[min(i, len(sig.params) - 1)]
    return _group_type(tgt, sig, p.group) if p.group else T.ELEMENTARY.get(p.constraint)


def _group_type(tgt, sig, group):
    ts = [
        t
        for t, i in zip(tgt.arg_types, range(len(tgt.arg_types)))
        if sig.params[min(i, len(sig.params) - 1)].group == group
    ]
    out = None
    for t in ts:
        out = t if out is None else (T.common_type(out, t) or out)
    return out


# ST's arithmetic operators on the intervals of their operands
_ARITH = {"+": I.add, "-": I.sub, "*": I.mul, "/": I.div_trunc, "MOD": I.mod_trunc}


def _wrap_value(v: int, d) -> int:
    bits = d.bits
    if d.signed:
        h = 1 << (bits - 1)
        return ((v + h) & ((1 << bits) - 1)) - h
    return v & ((1 << bits) - 1)


def wrap(node: py.expr, d) -> py.expr:
    """Two's-complement wrap of an int expression to d's width (its values: d's, a fact)."""
    mask = (1 << d.bits) - 1
    out: py.expr
    if d.signed:
        h = 1 << (d.bits - 1)
        out = py.BinOp(py.BinOp(py.BinOp(node, py.Add(), _const(h)), py.BitAnd(), _const(mask)), py.Sub(), _const(h))
        note_range(out, I.Interval(-h, h - 1))
    else:
        out = py.BinOp(node, py.BitAnd(), _const(mask))
        note_range(out, I.Interval(0, mask))
    return out


def _is_pointer(t) -> bool:
    return isinstance(t, T.RefType) and t.ref_kind == "POINTER"


def _unfloat(node: py.expr) -> py.expr:
    """`_float(x)` → `x` (where Python's float arithmetic converts x the same way)."""
    if (
        isinstance(node, py.Call)
        and isinstance(node.func, py.Name)
        and node.func.id == "_float"
        and len(node.args) == 1
    ):
        return node.args[0]
    return node


def index_key(e) -> tuple | None:
    """A structural key of an element access whose parts only read variables (`a[i + 1]`,
    `s.v[i, j]`): equal keys name the same element within one statement. None: not such an access."""
    if isinstance(e, A.Literal):
        return ("L", e.value) if isinstance(e.value, int) else None
    if isinstance(e, A.Name):
        sym = e.sym
        if isinstance(sym, T.VarSym) and sym.section != "VAR_IN_OUT" and not isinstance(T.unalias(sym.type), T.RefType):
            return ("N", id(sym))
        return None
    if isinstance(e, A.Field):
        base = index_key(e.base)
        return ("F", base, e.name.lower()) if base is not None and isinstance(e.sym, T.VarSym) else None
    if isinstance(e, A.Unary):
        inner = index_key(e.operand)
        return ("U", e.op, inner) if inner is not None and e.op in ("-", "+") else None
    if isinstance(e, A.Binary):
        if e.op not in ("+", "-", "*"):
            return None
        left, right = index_key(e.left), index_key(e.right)
        return ("B", e.op, left, right) if left is not None and right is not None else None
    if isinstance(e, A.Index):
        if not isinstance(T.unalias(e.base.ty), T.ArrayType) or T.is_conformant(e.base.ty):
            return None
        base = index_key(e.base)
        parts = [index_key(i) for i in e.indices]
        return ("I", base, tuple(parts)) if base is not None and None not in parts else None
    return None
