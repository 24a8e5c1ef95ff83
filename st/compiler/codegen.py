"""Checked AST → Python `ast` → code objects.

One Python module per ST source file, all executed into one namespace per PLC.
Every generated statement carries its ST line, and each module is compiled
with the ST file name, so tracebacks, profilers and coverage speak ST.

Shapes (see docs/ARCHITECTURE.md): a FUNCTION becomes a Python function
(`_fn_Name`), a FUNCTION_BLOCK or PROGRAM a slotted class (`_fb_Name`,
`_prg_Name`) whose `_body()` runs one call, a STRUCT a slotted class
(`_st_Name`). Inside `_body()` the instance's variables are read into Python
locals once and written back on exit (locals are the fastest thing CPython
has); variables that something else may reach while the body runs (through a
reference, an action or an SFC) stay attributes.
"""
from __future__ import annotations

import ast as py
import struct
from typing import Optional

from . import ast as A
from . import types as T
from .check import STEP, CallTarget
from .model import Project

_F32 = struct.Struct("<f")
DAY_NS = 86_400_000_000_000


def f32(v: float) -> float:
    try:
        return _F32.unpack(_F32.pack(v))[0]
    except OverflowError:
        return float("inf") if v > 0 else float("-inf")


def _name(n: str, ctx=None) -> py.Name:
    return py.Name(n, ctx or py.Load())


def _const(v) -> py.Constant:
    return py.Constant(v)


def _attr(obj: py.expr, name: str, ctx=None) -> py.Attribute:
    return py.Attribute(obj, name, ctx or py.Load())


def _call(fn: str | py.expr, *args) -> py.Call:
    f = _name(fn) if isinstance(fn, str) else fn
    return py.Call(f, list(args), [])


def _store(node: py.expr) -> py.expr:
    """Turn a Load expression into a Store target."""
    if isinstance(node, py.Name):
        return py.Name(node.id, py.Store())
    if isinstance(node, py.Attribute):
        return py.Attribute(node.value, node.attr, py.Store())
    if isinstance(node, py.Subscript):
        return py.Subscript(node.value, node.slice, py.Store())
    raise TypeError(node)


def _set_lines(node: py.AST, line: int) -> py.AST:
    """Give a node and its children without a position the ST line `line`.

    Children that already have a line (inner statements, placed earlier) are
    not descended into, so placing a whole body costs one pass.
    """
    stack = [node]
    pop, push = stack.pop, stack.append
    while stack:
        n = pop()
        if "lineno" in n._attributes:
            if getattr(n, "lineno", None) is not None and n is not node:
                continue
            if getattr(n, "lineno", None) is None:
                n.lineno = n.end_lineno = line
                n.col_offset = n.end_col_offset = 0
        for f in n._fields:
            v = getattr(n, f, None)
            if isinstance(v, list):
                for x in v:
                    if isinstance(x, py.AST):
                        push(x)
            elif isinstance(v, py.AST):
                push(v)
    return node


def default_value(t: T.Type):
    """The Python value of a scalar type's default, or None for aggregates."""
    t = T.unalias(t)
    if isinstance(t, T.SubrangeType):
        return t.lo                             # IEC: a subrange starts at its lower limit
    if isinstance(t, T.ElemType):
        if t.kind == "char":
            return "\0"
        return t.default
    if isinstance(t, T.StringType):
        return ""
    if isinstance(t, T.EnumType):
        return t.default_value
    if isinstance(t, T.RefType):
        return None
    return None


class Unsupported(Exception):
    def __init__(self, span, msg):
        self.span = span
        self.msg = msg


class ModuleGen:
    """Generates the Python modules for a checked project."""

    def __init__(self, project: Project, sink):
        self.p = project
        self.sink = sink
        self.tmp = 0

    # ------------------------------------------------------------------ modules
    def generate(self) -> dict[str, py.Module]:
        """Returns {st file path: Python module AST}."""
        by_file: dict[str, list] = {}

        def add(path, node):
            by_file.setdefault(path, []).append(node)

        for key, t in self.p.types.items():
            if isinstance(t, T.StructType):
                span = t.members and next(iter(t.members.values())).span
                path = span.file if span else "<types>"
                add(path, self.struct_class(t))
        for pou in self.p.pous.values():
            d = pou.decl
            if d is None:
                continue
            try:
                if pou.pou_kind == "FUNCTION":
                    node = FuncGen(self, pou).function()
                else:
                    node = BodyGen(self, pou).klass()
            except Unsupported as u:
                self.sink.error("E040", u.span, u.msg)
                continue
            if isinstance(node, list):
                for n in node:
                    add(d.span.file, n)
            else:
                add(d.span.file, node)
        # module-level globals: VAR_GLOBAL and directly addressed variables
        init_stmts = []
        for g in self.p.globals.values():
            gen = InitGen(self)
            val = gen.initial(g.type, g.init)
            init_stmts.append(_set_lines(py.Assign([_name(g.pyname, py.Store())], val), g.span.line if g.span else 1))
        for addr, (pyname, t) in self.p.direct_vars.items():
            init_stmts.append(_set_lines(py.Assign([_name(pyname, py.Store())], _const(default_value(t))), 1))
        if init_stmts:
            # globals go first so that POU code executed later finds them
            path = next(iter(self.p.globals.values())).span.file if self.p.globals else "<globals>"
            by_file.setdefault(path, [])
            by_file[path] = init_stmts + by_file[path]
        for cfg in self.p.configs:
            for im in cfg.instances:
                if im.args:
                    path = im.span.file if im.span else "<config>"
                    by_file.setdefault(path, []).extend(self.connections(im))
        modules = {}
        for path, body in by_file.items():
            m = py.Module(body=body, type_ignores=[])
            for node in body:
                _set_lines(node, getattr(node, "lineno", None) or 1)
            modules[path] = m
        return modules

    def connections(self, im) -> list:
        """A configuration's `PROGRAM inst WITH t : P (in := x, out => y)`: copy-in and copy-out functions."""
        line = im.span.line if im.span else 1
        g_in = StmtGen(self, None)
        g_in.self_name = None
        ins, outs = [], []
        for p, value, is_out in im.args:
            if not is_out:
                v = g_in.coerce(g_in.expr(value), value, p.type)
                ins.append(py.Assign([_attr(_name("inst"), p.pyname, py.Store())], v))
        g_out = StmtGen(self, None)
        g_out.self_name = None
        for p, value, is_out in im.args:
            if is_out:
                outs.extend(g_out.assign(value, g_out.coerce(_attr(_name("inst"), p.pyname), _Typed(p.type),
                                                             value.ty), None))
        fns = []
        for name, body, gen in (("_cfg_in_", ins, g_in), ("_cfg_out_", outs, g_out)):
            if body:
                if gen.globals_written:
                    body.insert(0, py.Global(sorted(gen.globals_written)))
                fn = py.FunctionDef(name + im.name.lower(), _args(["inst"]), body, [], None, None)
                fns.append(_set_lines(fn, line))
        return fns

    def struct_class(self, st: T.StructType) -> py.ClassDef:
        init = InitGen(self)
        body = []
        for m in st.members.values():
            body.append(_set_lines(py.Assign([_attr(_name("self"), m.pyname, py.Store())],
                                              init.initial(m.type, m.init)), m.span.line if m.span else 1))
        fn = py.FunctionDef("__init__", _args(["self"]), body or [py.Pass()], [], None, None)
        slots = py.Assign([_name("__slots__", py.Store())],
                          py.Tuple([_const(m.pyname) for m in st.members.values()], py.Load()))
        line = next(iter(st.members.values())).span.line if st.members else 1
        cls = py.ClassDef(st.pyname, [_name("_Struct")], [], [slots, fn], [])
        return _set_lines(cls, line)


def _args(names: list[str], defaults=None) -> py.arguments:
    return py.arguments([], [py.arg(n) for n in names], None, [], [], None, defaults or [])


class InitGen:
    """Initial values: for declarations (constant initializers and defaults)."""

    def __init__(self, mod: ModuleGen):
        self.mod = mod

    def initial(self, t: T.Type, init) -> py.expr:
        ut = T.unalias(t)
        if init is None and isinstance(t, T.AliasType):
            # the alias's own initializer, else its target's
            a = t
            while isinstance(a, T.AliasType):
                if a.init is not None:
                    return self.initial(a.target, a.init)
                a = a.target
        if isinstance(ut, T.ArrayType):
            return self.array(ut, init)
        if isinstance(ut, T.StructType):
            obj = _call(ut.pyname)
            if isinstance(init, A.StructInit):
                return self._with_fields(obj, init, lambda n: ut.members.get(n.lower()))
            return obj
        if isinstance(ut, T.POUType):
            obj = _call(ut.pyname)
            if isinstance(init, A.StructInit):
                return self._with_fields(obj, init, lambda n: _member_of_pou(ut, n))
            return obj
        if init is None:
            return _const(default_value(t))
        return ExprGen.constant_expr(self.mod, init, t)

    def _with_fields(self, obj: py.expr, init: A.StructInit, lookup) -> py.expr:
        # _init_fields(obj, (('name', value), ...)) returns obj
        pairs = []
        for name, sp, val in init.fields:
            m = lookup(name)
            if m is None:
                continue
            mt = m.type
            pairs.append(py.Tuple([_const(m.pyname), self.initial(mt, val)], py.Load()))
        return _call("_init_fields", obj, py.Tuple(pairs, py.Load()))

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
                comp = py.ListComp(proto, [py.comprehension(_name("_", py.Store()), _call("_range", _const(rest)), [], 0)])
                if elts:
                    return py.BinOp(py.List(elts, py.Load()), py.Add(), comp)
                return comp
            return py.List(elts, py.Load())
        d = default_value(elem)
        if not values:
            return py.BinOp(py.List([_const(d)], py.Load()), py.Mult(), _const(n))
        elts = [self.initial(elem, v) for v in values]
        rest = n - len(values)
        lst = py.List(elts, py.Load())
        if rest:
            return py.BinOp(lst, py.Add(), py.BinOp(py.List([_const(d)], py.Load()), py.Mult(), _const(rest)))
        return lst


def _member_of_pou(pou: T.POUType, name: str):
    return pou.vars.get(name.lower())


# ====================================================================== expressions


class ExprGen:
    """Expression and statement generation shared by functions and FB bodies."""

    def __init__(self, mod: ModuleGen, pou: Optional[T.POUType]):
        self.mod = mod
        self.pou = pou
        self.cached: set = set()        # VarSyms held in Python locals
        self.boxed: set = set()         # VarSyms held in one-element lists (passed by reference)
        self.self_name = "self"
        self.globals_written: set = set()
        self.loop_vars: list = []
        self.written_locals: set = set()
        self.result_name = ""

    @classmethod
    def constant_expr(cls, mod, e, t: T.Type) -> py.expr:
        g = cls(mod, None)
        g.self_name = "_NO_SELF"
        return g.coerce(g.expr(e), e, t)

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
        return _attr(_name(self.self_name), sym.pyname)

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
        return _attr(_name(self.self_name), sym.pyname, py.Store())

    # ------------------------------------------------------------------ conversions
    def coerce(self, node: py.expr, e, dst: Optional[T.Type]) -> py.expr:
        """Make a value of `e`'s type fit `dst`: widen, wrap, round, truncate, check."""
        if dst is None:
            return node
        src = getattr(e, "ty", None) if e is not None else None
        d = T.base_of(dst)
        s = T.base_of(src) if src is not None else None
        if isinstance(node, py.Constant) and node.value is not None and not isinstance(node.value, str):
            v = node.value
            if d.is_real:
                v = float(v)
                return _const(f32(v) if d is T.REAL else v)
            if d.is_intlike and isinstance(v, (int, bool)) and not isinstance(v, bool):
                return _const(_wrap_value(v, d))
            if d.is_bool:
                return _const(bool(v))
        if d.is_real:
            if s is not None and (s.is_intlike or s is T.LIT_INT):
                node = _call("_float", node)
                if d is T.REAL and not (s.is_intlike and s.bits <= 16):
                    node = _call("_f32", node)
                return node
            if d is T.REAL and not self.is_f32(e):
                return _call("_f32", node)
            return node
        if d.is_intlike:
            sub = T.unalias(dst)
            if isinstance(sub, T.SubrangeType):
                return _call("_subrange", node, _const(sub.lo), _const(sub.hi))
            if s is not None and s.is_bool:
                node = _call("_int", node)
            if not self.in_range(e, d):
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
        if isinstance(e, (A.Name, A.Field, A.Index, A.Deref)):
            return T.base_of(e.ty) is T.REAL if e.ty is not None else False
        if isinstance(e, A.Literal):
            return True
        if isinstance(e, A.Call) and isinstance(e.target, CallTarget) and e.target.kind == "function":
            return T.base_of(e.ty) is T.REAL if e.ty is not None else False
        return False

    def in_range(self, e, d: T.ElemType) -> bool:
        """Can this integer expression's value never leave d's range? (Then its store needs no wrap.)"""
        r = self.value_range(e)
        return r is not None and d.lo <= r[0] and r[1] <= d.hi

    def value_range(self, e):
        """The (lo, hi) interval an integer expression's value lies in, or None if unknown."""
        if e is None:
            return None
        if isinstance(e, A.Literal):
            return (int(e.value), int(e.value)) if isinstance(e.value, (int, bool)) else None
        if isinstance(e.const, int):
            return (e.const, e.const)
        t = T.base_of(e.ty) if e.ty is not None else None
        if t is None:
            return None
        if t.is_bool:
            return (0, 1)
        if isinstance(t, T.EnumType):
            vals = [v for _, v in t.members.values()] or [0]
            return (min(vals), max(vals))
        sub = T.unalias(e.ty)
        declared = (sub.lo, sub.hi) if isinstance(sub, T.SubrangeType) else (
            (t.lo, t.hi) if t.is_intlike else None)
        if isinstance(e, (A.Name, A.Field, A.Index, A.Deref, A.Bit)) or (
                isinstance(e, A.Call) and isinstance(e.target, CallTarget) and e.target.kind == "function"):
            return declared
        if isinstance(e, A.Binary):
            op = e.op
            if op in ("=", "<>", "<", ">", "<=", ">="):
                return (0, 1)
            l, r = self.value_range(e.left), self.value_range(e.right)
            if l is None or r is None:
                return None
            if op == "+":
                return (l[0] + r[0], l[1] + r[1])
            if op == "-":
                return (l[0] - r[1], l[1] - r[0])
            if op == "*":
                ps = [x * y for x in l for y in r]
                return (min(ps), max(ps))
            if op == "/":
                m = max(abs(l[0]), abs(l[1]))
                return (-m, m) if l[0] < 0 or r[0] < 0 else (0, m)
            if op == "MOD":
                m = max(abs(r[0]), abs(r[1]))
                return (-(m - 1) if l[0] < 0 else 0, max(m - 1, 0))
            if op in ("AND", "OR", "XOR") and declared is not None:
                # bitwise results of in-range operands stay in the operands' (common) type
                if declared[0] <= l[0] and l[1] <= declared[1] and declared[0] <= r[0] and r[1] <= declared[1]:
                    return declared
            return None
        if isinstance(e, A.Unary):
            v = self.value_range(e.operand)
            if v is None:
                return None
            if e.op == "-":
                return (-v[1], -v[0])
            if e.op == "+":
                return v
            if e.op == "NOT":
                # ~x on a signed value stays in its type; unsigned NOT is masked
                return declared if declared is not None and declared[0] <= v[0] and v[1] <= declared[1] else None
        if isinstance(e, A.Call) and isinstance(e.target, CallTarget) and e.target.kind == "native":
            sig = e.target.sig
            if getattr(sig, "exact", False):
                return declared
            if sig.name in ("SEL", "MAX", "MIN", "LIMIT", "MUX", "MOVE"):
                skip = 1 if sig.name in ("SEL", "MUX") else 0
                rs = [self.value_range(a.value) for a in e.target.args[skip:]]
                if rs and None not in rs:
                    return (min(r[0] for r in rs), max(r[1] for r in rs))
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
            return self.var_load(sym)
        if isinstance(sym, T.POUType):      # a function's own result variable
            return _name(self.result_name)
        if sym is STEP:
            return _const(e.const)
        if isinstance(sym, T.EnumType):
            return _const(e.const)
        if getattr(sym, "kind", "") == "null":
            return _const(None)
        raise Unsupported(e.span, f"cannot use '{e.name}' here")

    def x_Direct(self, e: A.Direct) -> py.expr:
        addr = e.address
        for key, (pyname, t) in self.mod.p.direct_vars.items():
            if key == addr or key == addr[:2] + "X" + addr[2:]:
                return _name(pyname)
        raise Unsupported(e.span, f"unknown address {addr}")

    def x_Field(self, e: A.Field) -> py.expr:
        if isinstance(e.sym, T.EnumType):
            return _const(e.const)
        bt = T.unalias(e.base.ty) if e.base.ty is not None else None
        if bt is STEP:
            idx = e.base.const
            if e.name.upper() == "X":
                return py.Subscript(_attr(_name(self.self_name), "_sfc_x"), _const(idx), py.Load())
            return _call(_attr(_attr(_name(self.self_name), "_sfc"), "elapsed"), _const(idx))
        base = self.expr(e.base)
        if isinstance(bt, T.ElemType) and bt.is_intlike:
            return self._bit_read(base, int(e.name), bt)
        sym = e.sym
        return _attr(base, sym.pyname)

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
        return py.Subscript(self.expr(e.base), self.index_of(e), py.Load())

    def index_of(self, e: A.Index) -> py.expr:
        at = T.unalias(e.base.ty)
        dims = at.dims
        flat: Optional[py.expr] = None
        stride = 1
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
                if hi < lo:          # ARRAY[*]: bounds known only at run time
                    term = iv
                else:
                    term = _call("_ix", iv, _const(lo), _const(hi)) if not self._index_safe(i, lo, hi) else (
                        py.BinOp(iv, py.Sub(), _const(lo)) if lo else iv)
                if st != 1:
                    term = py.BinOp(term, py.Mult(), _const(st))
            flat = term if flat is None else py.BinOp(flat, py.Add(), term)
        return flat

    def _index_safe(self, i, lo, hi) -> bool:
        t = T.base_of(i.ty) if i.ty is not None else None
        if isinstance(t, T.SubrangeType):
            return lo <= t.lo and t.hi <= hi
        if isinstance(t, T.ElemType) and t.is_intlike:
            return lo <= t.lo and t.hi <= hi
        return False

    def x_Deref(self, e: A.Deref) -> py.expr:
        return _call(_attr(self.expr(e.base), "get"))

    def x_Unary(self, e: A.Unary) -> py.expr:
        v = self.expr(e.operand)
        t = T.base_of(e.ty) if e.ty is not None else None
        if e.op == "NOT":
            if t is not None and t.is_bool:
                return py.UnaryOp(py.Not(), v)
            if t is not None and t.is_intlike and not t.signed:
                return py.BinOp(py.UnaryOp(py.Invert(), v), py.BitAnd(), _const(t.hi))
            return py.UnaryOp(py.Invert(), v)
        if e.op == "-":
            return py.UnaryOp(py.USub(), v)
        return v

    def x_Binary(self, e: A.Binary) -> py.expr:
        op = e.op
        lt = T.base_of(e.left.ty) if e.left.ty is not None else None
        rt = T.base_of(e.right.ty) if e.right.ty is not None else None
        res = T.base_of(e.ty) if e.ty is not None else None
        l, r = self.expr(e.left), self.expr(e.right)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            pyop = {"=": py.Eq(), "<>": py.NotEq(), "<": py.Lt(), ">": py.Gt(), "<=": py.LtE(), ">=": py.GtE()}[op]
            return py.Compare(l, [pyop], [r])
        if op == "AND_THEN":
            return py.BoolOp(py.And(), [l, r])
        if op == "OR_ELSE":
            return py.BoolOp(py.Or(), [l, r])
        if op in ("AND", "OR", "XOR"):
            pyop = {"AND": py.BitAnd(), "OR": py.BitOr(), "XOR": py.BitXor()}[op]
            return py.BinOp(l, pyop, r)
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
            if lt is not None and rt is not None and lt.is_intlike and rt.is_intlike and not lt.signed and not rt.signed:
                return py.BinOp(l, py.FloorDiv(), r)
            return _call("_idiv", l, r)
        if op == "MOD":
            if lt is not None and rt is not None and lt.is_intlike and not lt.signed and not rt.signed:
                return _call("_umod", l, r)
            return _call("_imod", l, r)
        if op == "**":
            return _call("_pow", l, r)
        raise Unsupported(e.span, f"operator {op}")

    # ------------------------------------------------------------------ calls
    def x_Call(self, e: A.Call) -> py.expr:
        tgt = e.target
        if not isinstance(tgt, CallTarget):
            raise Unsupported(e.span, "unresolved call")
        if tgt.kind == "function":
            return self.function_call(e, tgt)
        if tgt.kind == "native":
            return self.native_call(e, tgt)
        if tgt.kind == "ref":
            return self.ref_to(tgt.arg)
        raise Unsupported(e.span, "a function block call has no value")

    def native_call(self, e: A.Call, tgt) -> py.expr:
        sig = tgt.sig
        args = []
        # settle each argument to its parameter's type (group or concrete)
        for i, a in enumerate(tgt.args):
            p = sig.params[min(i, len(sig.params) - 1)]
            v = self.expr(a.value)
            want = None
            if p.group:
                want = _group_type(tgt, sig, p.group)
            else:
                want = T.ELEMENTARY.get(p.constraint)
            if want is not None and (T.base_of(want).is_num) and a.value.ty is not None and \
                    T.base_of(a.value.ty) is not T.base_of(want):
                v = self.coerce(v, a.value, want)
            args.append(v)
        if sig.emit is not None:
            node = sig.emit(self, args, tgt.arg_types, e.ty)
        else:
            extra = sig.extra(tgt.arg_types, e.ty) if sig.extra else ()
            node = _call(sig.helper, *args, *[_const(x) for x in extra])
        if tgt.en is not None:
            node = py.IfExp(self.expr(tgt.en.value), node, _const(default_value(e.ty) if e.ty is not None else None))
        return node

    def function_call(self, e: A.Call, tgt) -> py.expr:
        pou: T.POUType = tgt.pou
        bind = tgt.bind["params"]
        args = []
        for p in pou.params():
            a = bind.get(p.name.lower())
            if p.section == "VAR_INPUT":
                if a is None:
                    args.append(InitGen(self.mod).initial(p.type, p.init))
                else:
                    v = self.expr(a.value)
                    ut = T.unalias(p.type)
                    if ut.is_aggregate and p.written:
                        v = _call("_copy", v)
                    args.append(self.coerce(v, a.value, p.type))
            elif p.section == "VAR_IN_OUT":
                args.append(self.ref_to(a.value) if not T.unalias(p.type).is_aggregate else self.expr(a.value))
            else:  # VAR_OUTPUT
                if a is None:
                    args.append(_const(None))
                else:
                    args.append(self.ref_to(a.value, negated=a.negated))
        node = _call(pou.pyname, *args)
        en = tgt.bind.get("en")
        if en is not None:
            rt = pou.return_type
            node = py.IfExp(self.expr(en.value), node, _const(default_value(rt) if rt is not None else None))
        return node

    def ref_to(self, e, negated: bool = False) -> py.expr:
        """A reference object for an output or in-out argument, or REF(x) (runtime.helpers)."""
        if negated:
            return _call("_NegRef", self.ref_to(e))
        if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym):
            sym = e.sym
            t = sym.type
            if sym.is_global or sym.section == "VAR_EXTERNAL":
                name = sym.global_ref.pyname if sym.global_ref else sym.pyname
                return _call("_ItemRef", _name("_ns"), _const(name), _const(_wrap_spec(t)))
            if sym in self.boxed:
                return _call("_ItemRef", _name(sym.pyname), _const(0), _const(_wrap_spec(t)))
            if sym in self.cached or self.self_name is None:
                raise Unsupported(e.span, f"internal: '{sym.name}' is held in a local but passed by reference")
            return _call("_AttrRef", _name(self.self_name), _const(sym.pyname), _const(_wrap_spec(t)))
        if isinstance(e, A.Field):
            return _call("_AttrRef", self.expr(e.base), _const(e.sym.pyname), _const(_wrap_spec(e.ty)))
        if isinstance(e, A.Index):
            return _call("_ItemRef", self.expr(e.base), self.index_of(e), _const(_wrap_spec(e.ty)))
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
    if b is not None and b.is_intlike:
        return (b.bits, b.signed)
    if b is T.REAL:
        return "f32"
    if isinstance(b, T.StringType):
        return ("str", b.length)
    return None


def _group_type(tgt, sig, group):
    ts = [t for t, i in zip(tgt.arg_types, range(len(tgt.arg_types)))
          if sig.params[min(i, len(sig.params) - 1)].group == group]
    out = None
    for t in ts:
        out = t if out is None else (T.common_type(out, t) or out)
    return out


def _wrap_value(v: int, d) -> int:
    bits = d.bits
    if d.signed:
        h = 1 << (bits - 1)
        return ((v + h) & ((1 << bits) - 1)) - h
    return v & ((1 << bits) - 1)


def wrap(node: py.expr, d) -> py.expr:
    """Two's-complement wrap of an int expression to d's width."""
    mask = (1 << d.bits) - 1
    if d.signed:
        h = 1 << (d.bits - 1)
        return py.BinOp(py.BinOp(py.BinOp(node, py.Add(), _const(h)), py.BitAnd(), _const(mask)), py.Sub(), _const(h))
    return py.BinOp(node, py.BitAnd(), _const(mask))


# ====================================================================== statements


class StmtGen(ExprGen):
    def stmts(self, body: list) -> list:
        out = []
        for s in body:
            try:
                r = self.stmt(s)
            except Unsupported:
                raise
            except Exception as exc:
                if not hasattr(exc, "st_span"):
                    exc.st_span = s.span      # where the internal error happened, for the report
                raise
            for n in r:
                _set_lines(n, s.span.line)
            out.extend(r)
        return out

    def block(self, body) -> list:
        b = self.stmts(body)
        return b or [py.Pass()]

    def stmt(self, s) -> list:
        return getattr(self, "s_" + type(s).__name__)(s)

    def s_Empty(self, s):
        return []

    def s_Exit(self, s):
        return [py.Break()]

    def s_Continue(self, s):
        return [py.Continue()]

    def s_Return(self, s):
        return [py.Return(_name(self.result_name) if self.result_name else None)]

    def s_Assign(self, s: A.Assign) -> list:
        tgt = s.target
        tt = tgt.ty
        if s.kind in ("S=", "R="):
            return [py.If(self.expr(s.value), self.assign(tgt, _const(s.kind == "S="), None), [])]
        # a call with EN: assign only when enabled
        v = s.value
        if isinstance(v, A.Call) and isinstance(v.target, CallTarget) and v.target.kind == "function" \
                and (v.target.bind.get("en") is not None or v.target.bind.get("eno") is not None):
            return self._en_call_assign(s, v)
        if isinstance(v, A.Call) and isinstance(v.target, CallTarget) and v.target.kind == "native" \
                and (v.target.en is not None or v.target.eno is not None):
            en, eno = v.target.en, v.target.eno
            v.target.en = None
            body = self.assign(tgt, self.coerce(self.expr(v), v, tt), v)
            return self._en_wrap(en, eno, body)
        ut = T.unalias(tt) if tt is not None else None
        if ut is not None and ut.is_aggregate:
            return [py.Expr(_call("_assign", self.expr(tgt), self.expr(v)))]
        return self.assign(tgt, self.coerce(self.expr(v), v, tt), v)

    def _en_wrap(self, en, eno, body: list, eno_bound: bool = False) -> list:
        """EN := FALSE skips the call and gives ENO FALSE; else ENO is TRUE (or what the callee set)."""
        if en is None:
            out = body
            if eno is not None and not eno_bound:
                out = out + self.assign(eno.value, _const(True), None)
            return out
        yes = body + (self.assign(eno.value, _const(True), None) if eno is not None and not eno_bound else [])
        no = self.assign(eno.value, _const(False), None) if eno is not None else []
        return [py.If(self.expr(en.value), yes, no or [py.Pass()])]

    def _en_call_assign(self, s, v):
        bind = v.target.bind
        en, eno = bind.get("en"), bind.get("eno")
        bind["en"] = None
        body = self.assign(s.target, self.coerce(self.expr(v), v, s.target.ty), v)
        bind["en"] = en
        return self._en_wrap(en, eno, body, "eno" in bind["params"])

    def assign(self, tgt, value: py.expr, src_expr) -> list:
        if isinstance(tgt, A.Name):
            sym = tgt.sym
            if isinstance(sym, T.POUType):
                return [py.Assign([_name(self.result_name, py.Store())], value)]
            return [py.Assign([self.var_store(sym)], value)]
        if isinstance(tgt, A.Field):
            bt = T.unalias(tgt.base.ty)
            if isinstance(bt, T.ElemType) and bt.is_intlike:
                return self._bit_write(tgt.base, int(tgt.name), value)
            return [py.Assign([_attr(self.expr(tgt.base), tgt.sym.pyname, py.Store())], value)]
        if isinstance(tgt, A.Index):
            return [py.Assign([py.Subscript(self.expr(tgt.base), self.index_of(tgt), py.Store())], value)]
        if isinstance(tgt, A.Bit):
            if tgt.size != "X":
                width = {"B": 8, "W": 16, "D": 32, "L": 64}[tgt.size]
                bt = T.base_of(tgt.base.ty)
                new = _call("_setbits", self.expr(tgt.base), _const(tgt.index * width), _const(width), value,
                            _const(bt.bits), _const(bt.signed))
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
        new = _call("_setbit", self.expr(base_e), _const(n), value, _const(bt.bits), _const(bt.signed))
        return self.assign(base_e, new, None)

    def s_CallStmt(self, s: A.CallStmt) -> list:
        c = s.call
        tgt = c.target
        if not isinstance(tgt, CallTarget):
            raise Unsupported(s.span, "unresolved call")
        if tgt.kind == "fb":
            return self.fb_call(c, tgt)
        if tgt.kind == "action":
            return [py.Expr(_call(_attr(_name(self.self_name), "_act_" + tgt.name)))]
        if tgt.kind == "function":
            en, eno = tgt.bind.get("en"), tgt.bind.get("eno")
            tgt.bind["en"] = None
            body = [py.Expr(self.function_call(c, tgt))]
            tgt.bind["en"] = en
            return self._en_wrap(en, eno, body, "eno" in tgt.bind["params"])
        if tgt.kind == "native":
            en, eno = tgt.en, tgt.eno
            tgt.en = None
            body = [py.Expr(self.native_call(c, tgt))]
            tgt.en = en
            return self._en_wrap(en, eno, body)
        raise Unsupported(s.span, "cannot call this")

    def fb_call(self, c: A.Call, tgt) -> list:
        fb: T.POUType = tgt.pou
        bind = tgt.bind["params"]
        out = []
        inst = self.expr(c.callee)
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
                    out.append(py.Assign([_attr(inst, p.pyname, py.Store())], self.expr(a.value)))
                else:
                    out.append(py.Assign([_attr(inst, p.pyname, py.Store())], self.expr(a.value)))
                    after.extend(self.assign(a.value, self.coerce(_attr(inst, p.pyname), _Typed(p.type), a.value.ty), None))
            elif ut.is_aggregate:
                out.append(py.Expr(_call("_assign", _attr(inst, p.pyname), self.expr(a.value))))
            else:
                out.append(py.Assign([_attr(inst, p.pyname, py.Store())], self.coerce(self.expr(a.value), a.value, p.type)))
        out.append(py.Expr(_call(_attr(inst, "_body"))))
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
        return self._en_wrap(tgt.bind.get("en"), tgt.bind.get("eno"), out, "eno" in bind)

    def s_If(self, s: A.If) -> list:
        orelse = self.stmts(s.orelse) if s.orelse else []
        for cond, body in reversed(s.branches[1:]):
            node = py.If(self.expr(cond), self.block(body), orelse)
            _set_lines(node, cond.span.line)
            orelse = [node]
        cond, body = s.branches[0]
        return [py.If(self.expr(cond), self.block(body), orelse)]

    def s_Case(self, s: A.Case) -> list:
        out = []
        sel = self.expr(s.selector)
        if not isinstance(sel, (py.Name, py.Constant)):
            tmp = self.new_tmp()
            out.append(py.Assign([_name(tmp, py.Store())], sel))
            sel = _name(tmp)
        orelse = self.stmts(s.orelse) if s.orelse else []
        for br in reversed(s.branches):
            singles = []
            ranges = []
            for lo, hi in br.labels:
                lv = lo.const if lo.const is not None else (lo.value if isinstance(lo, A.Literal) else None)
                if hi is None:
                    singles.append(lv)
                else:
                    hv = hi.const if hi.const is not None else (hi.value if isinstance(hi, A.Literal) else None)
                    ranges.append((lv, hv))
            tests = []
            if len(singles) == 1:
                tests.append(py.Compare(sel, [py.Eq()], [_const(singles[0])]))
            elif singles:
                tests.append(py.Compare(sel, [py.In()], [py.Set([_const(v) for v in singles])]))
            for lv, hv in ranges:
                tests.append(py.Compare(_const(lv), [py.LtE(), py.LtE()], [sel, _const(hv)]))
            test = tests[0] if len(tests) == 1 else py.BoolOp(py.Or(), tests)
            node = py.If(test, self.block(br.body), orelse)
            _set_lines(node, br.span.line)
            orelse = [node]
        out.extend(orelse)
        return out

    def s_While(self, s: A.While) -> list:
        return [py.While(self.expr(s.cond), self.block(s.body) + self._loop_guard(), [])]

    def _loop_guard(self) -> list:
        """A cheap check that lets the runtime's watchdog end an endless loop."""
        return [py.If(_name("_wd_armed"), [py.Expr(_call("_wd_check"))], [])]

    def s_Repeat(self, s: A.Repeat) -> list:
        if _has_continue(s.body):
            flag = self.new_tmp()
            init = py.Assign([_name(flag, py.Store())], _const(True))
            test = py.BoolOp(py.Or(), [_name(flag), py.UnaryOp(py.Not(), self.expr(s.cond))])
            body = [py.Assign([_name(flag, py.Store())], _const(False))] + self.stmts(s.body) + self._loop_guard()
            return [init, py.While(test, body, [])]
        body = self.stmts(s.body) + self._loop_guard()
        cond = self.expr(s.cond)
        br = _set_lines(py.If(cond, [py.Break()], []), s.cond.span.line)
        return [py.While(_const(True), body + [br], [])]

    def s_For(self, s: A.For) -> list:
        var = s.var
        vt = T.base_of(var.ty)
        start = self.coerce(self.expr(s.start), s.start, var.ty)
        end = self.expr(s.end)
        step_c = 1
        out = []
        if s.step is not None:
            c = s.step.const if s.step.const is not None else (s.step.value if isinstance(s.step, A.Literal) else None)
            step_c = c if isinstance(c, int) else None
        if _assigns_var(s.body, var):
            return self._for_while(s, start, end, step_c)
        if step_c is None:
            stp = self.new_tmp()
            out.append(py.Assign([_name(stp, py.Store())], self.expr(s.step)))
            step = _name(stp)
            stop = py.BinOp(end, py.Add(), _call("_for_dir", step))
        else:
            step = _const(step_c)
            stop = py.BinOp(end, py.Add(), _const(1 if step_c > 0 else -1)) if not isinstance(end, py.Constant) \
                else _const(end.value + (1 if step_c > 0 else -1))
        rng = _call("_range", start, stop, step) if step_c != 1 else _call("_range", start, stop)
        # the loop variable, or a Python local that mirrors it
        direct = isinstance(var, A.Name) and isinstance(var.sym, T.VarSym) and \
            (var.sym in self.cached or self.self_name is None) and not var.sym.is_global
        if direct:
            loopvar = var.sym.pyname
            self.written_locals.add(var.sym)
            pre = []
            body = self.block(s.body)
        else:
            loopvar = self.new_tmp()
            pre = []
            body = self.assign(var, _name(loopvar), None) + self.stmts(s.body)
        # before: loopvar = start - step (so that 'else' can add step: the IEC final value)
        init = py.Assign([_name(loopvar, py.Store())], py.BinOp(start, py.Sub(), step))
        final = py.BinOp(_name(loopvar), py.Add(), step)
        if vt.is_intlike:
            final = wrap(final, vt)
        orelse = [py.Assign([_name(loopvar, py.Store())], final)]
        if not direct:
            orelse += self.assign(var, _name(loopvar), None)
        return out + pre + [init, py.For(_name(loopvar, py.Store()), rng, body, orelse)]

    def _for_while(self, s, start, end, step_c):
        """FOR whose body writes the loop variable: a faithful while loop."""
        var = s.var
        vt = T.base_of(var.ty)
        out = self.assign(var, start, None)
        endt = self.new_tmp()
        out.append(py.Assign([_name(endt, py.Store())], end))
        if step_c is None:
            stp = self.new_tmp()
            out.append(py.Assign([_name(stp, py.Store())], self.expr(s.step)))
            step = _name(stp)
            test = py.IfExp(py.Compare(step, [py.Gt()], [_const(0)]),
                            py.Compare(self.expr(var), [py.LtE()], [_name(endt)]),
                            py.Compare(self.expr(var), [py.GtE()], [_name(endt)]))
        else:
            step = _const(step_c)
            test = py.Compare(self.expr(var), [py.LtE() if step_c > 0 else py.GtE()], [_name(endt)])
        incr = self.assign(var, wrap(py.BinOp(self.expr(var), py.Add(), step), vt), None)
        # CONTINUE must still increment: use try/finally-free form: increment at loop top after the first pass
        first = self.new_tmp()
        out.append(py.Assign([_name(first, py.Store())], _const(True)))
        body = [py.If(_name(first), [py.Assign([_name(first, py.Store())], _const(False))], incr),
                py.If(py.UnaryOp(py.Not(), test), [py.Break()], [])] + self.stmts(s.body)
        out.append(py.While(_const(True), body, []))
        return out


class _Typed:
    """A stand-in expression carrying only a type (for coercions of FB outputs)."""

    def __init__(self, ty):
        self.ty = ty
        self.const = None


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
    return False


def _assigns_var(body, var) -> bool:
    if not isinstance(var, A.Name):
        return True
    key = var.name.lower()
    for s in _walk_stmts(body):
        if isinstance(s, A.Assign) and isinstance(s.target, A.Name) and s.target.name.lower() == key:
            return True
        if isinstance(s, A.For) and isinstance(s.var, A.Name) and s.var.name.lower() == key:
            return True
        if isinstance(s, A.CallStmt):
            for a in s.call.args:
                if (a.output or isinstance(s.call.target, CallTarget)) and isinstance(a.value, A.Name) \
                        and a.value.name.lower() == key and a.output:
                    return True
    return False


def _walk_stmts(body):
    for s in body:
        yield s
        if isinstance(s, A.If):
            for _, b in s.branches:
                yield from _walk_stmts(b)
            yield from _walk_stmts(s.orelse or [])
        elif isinstance(s, A.Case):
            for b in s.branches:
                yield from _walk_stmts(b.body)
            yield from _walk_stmts(s.orelse or [])
        elif isinstance(s, (A.For, A.While, A.Repeat)):
            yield from _walk_stmts(s.body)


def _walk_exprs_in(body):
    """Every expression node in a statement list (for pre-scans)."""
    stack = []
    for s in _walk_stmts(body):
        if isinstance(s, A.Assign):
            stack += [s.target, s.value]
        elif isinstance(s, A.CallStmt):
            stack.append(s.call)
        elif isinstance(s, A.If):
            stack += [c for c, _ in s.branches]
        elif isinstance(s, A.Case):
            stack.append(s.selector)
        elif isinstance(s, A.For):
            stack += [s.var, s.start, s.end] + ([s.step] if s.step else [])
        elif isinstance(s, A.While):
            stack.append(s.cond)
        elif isinstance(s, A.Repeat):
            stack.append(s.cond)
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
        elif isinstance(e, A.Index):
            stack.append(e.base)
            stack += e.indices
        elif isinstance(e, A.Call):
            stack.append(e.callee)
            stack += [a.value for a in e.args]


def _by_ref_names(body) -> set:
    """Variables passed to functions as outputs / in-outs: they must stay attributes."""
    names = set()
    for e in _walk_exprs_in(body):
        if isinstance(e, A.Call) and isinstance(e.target, CallTarget) and e.target.kind == "function":
            pou = e.target.pou
            for key, a in e.target.bind["params"].items():
                p = pou.vars[key]
                if p.section == "VAR_OUTPUT" or (p.section == "VAR_IN_OUT" and not T.unalias(p.type).is_aggregate):
                    root = a.value
                    while isinstance(root, (A.Field, A.Index, A.Bit)):
                        root = root.base
                    if isinstance(root, A.Name) and isinstance(root.sym, T.VarSym):
                        names.add(root.sym)
        if isinstance(e, A.Call) and isinstance(e.target, CallTarget) and e.target.kind == "native" \
                and e.target.sig.name.upper() in ("REF", "ADR"):
            for a in e.target.args:
                root = a.value
                while isinstance(root, (A.Field, A.Index, A.Bit)):
                    root = root.base
                if isinstance(root, A.Name) and isinstance(root.sym, T.VarSym):
                    names.add(root.sym)
    return names


# ====================================================================== functions


class FuncGen(StmtGen):
    def __init__(self, mod: ModuleGen, pou: T.POUType):
        super().__init__(mod, pou)
        self.self_name = None
        self.result_name = mangle_result(pou)

    def function(self) -> py.FunctionDef:
        pou = self.pou
        d = pou.decl
        by_ref = _by_ref_names(d.body)
        self.boxed = {v for v in by_ref if v.owner is pou and not T.unalias(v.type).is_aggregate}
        params = []
        prologue = []
        epilogue = []

        def box(v, value):
            return py.Assign([_name(v.pyname, py.Store())], py.List([value], py.Load()) if v in self.boxed else value)

        def unbox(v):
            return self.var_load(v)

        for p in pou.params():
            if p.section == "VAR_INPUT":
                params.append(p.pyname)
                if p in self.boxed:
                    prologue.append(box(p, _name(p.pyname)))
            elif p.section == "VAR_IN_OUT":
                if T.unalias(p.type).is_aggregate:
                    params.append(p.pyname)
                else:
                    params.append("_r_" + p.pyname)
                    prologue.append(box(p, _call(_attr(_name("_r_" + p.pyname), "get"))))
                    epilogue.append(py.Expr(_call(_attr(_name("_r_" + p.pyname), "set"), unbox(p))))
            else:
                params.append("_r_" + p.pyname)
                prologue.append(box(p, InitGen(self.mod).initial(p.type, p.init)))
                epilogue.append(py.If(py.Compare(_name("_r_" + p.pyname), [py.IsNot()], [_const(None)]),
                                      [py.Expr(_call(_attr(_name("_r_" + p.pyname), "set"), unbox(p)))], []))
        locals_init = []
        if pou.return_type is not None:
            locals_init.append(py.Assign([_name(self.result_name, py.Store())],
                                         InitGen(self.mod).initial(pou.return_type, None)))
        for v in pou.vars.values():
            if v.section in ("VAR", "VAR_TEMP"):
                locals_init.append(_set_lines(box(v, InitGen(self.mod).initial(v.type, v.init)), v.span.line))
        body = self.stmts(d.body)
        ret = py.Return(_name(self.result_name) if pou.return_type is not None else None)
        end_line = d.end_span.line if d.end_span else d.span.line
        _set_lines(ret, end_line)
        main = prologue + locals_init + body + [ret]
        if epilogue:
            main = [py.Try(prologue + locals_init + body + [ret], [], [], _lines(epilogue, end_line))]
        gl = sorted(self.globals_written)
        if gl:
            main.insert(0, py.Global(gl))
        fn = py.FunctionDef(pou.pyname, _args(params), main, [], None, None)
        return _set_lines(fn, d.span.line)


def _lines(nodes, line):
    for n in nodes:
        _set_lines(n, line)
    return nodes


def mangle_result(pou: T.POUType) -> str:
    from .names import mangle
    return mangle(pou.name)


# ====================================================================== FB / program classes


class BodyGen(StmtGen):
    def __init__(self, mod: ModuleGen, pou: T.POUType):
        super().__init__(mod, pou)

    def klass(self) -> py.ClassDef:
        pou = self.pou
        d = pou.decl
        init = InitGen(self.mod)
        sfc = self.mod.p.sfc.get(pou.name.lower())
        slots = [v.pyname for v in pou.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_TEMP")]
        edges = [v for v in pou.vars.values() if v.edge]
        slots += ["_e_" + v.pyname for v in edges]
        init_body = []
        for v in pou.vars.values():
            if v.section in ("VAR_EXTERNAL", "VAR_TEMP"):
                continue
            init_body.append(_set_lines(py.Assign([_attr(_name("self"), v.pyname, py.Store())],
                                                  init.initial(v.type, v.init)), v.span.line))
        for v in edges:
            init_body.append(_set_lines(py.Assign([_attr(_name("self"), "_e_" + v.pyname, py.Store())],
                                                  _const(v.edge == "F_EDGE")), v.span.line))
        if sfc is not None:
            slots += ["_sfc", "_sfc_x"]
            init_body.append(_set_lines(py.Assign([_attr(_name("self"), "_sfc", py.Store())],
                                                  _call("_SfcState", _name("_sfc_" + pou.pyname))), d.span.line))
            init_body.append(_set_lines(py.Assign([_attr(_name("self"), "_sfc_x", py.Store())],
                                                  _attr(_attr(_name("self"), "_sfc"), "x")), d.span.line))
        members = [py.Assign([_name("__slots__", py.Store())], py.Tuple([_const(s) for s in slots], py.Load())),
                   py.FunctionDef("__init__", _args(["self"]), init_body or [py.Pass()], [], None, None)]
        # caching policy: with actions or SFC other methods touch the variables: keep attributes
        can_cache = not d.actions and sfc is None
        if sfc is not None:
            run = py.Expr(_call(_attr(_attr(_name("self"), "_sfc"), "run"), _name("self"), _name("_now")))
            members.append(_set_lines(py.FunctionDef("_body", _args(["self"]), [run], [], None, None),
                                      d.span.line))
        else:
            members.append(self.method("_body", d.body, can_cache, edges, d.span.line,
                                       d.end_span.line if d.end_span else d.span.line))
        for act in d.actions:
            g = BodyGen(self.mod, pou)
            members.append(g.method("_act_" + act.name.lower(), act.body, False, [], act.span.line, act.span.line))
        extra_module = []
        if sfc is not None:
            members.extend(self.sfc_methods(sfc))
        cls = py.ClassDef(pou.pyname, [_name("_FB")], [], members, [])
        _set_lines(cls, d.span.line)
        if sfc is not None:
            return [self.sfc_desc(sfc), cls]
        return cls

    def sfc_desc(self, sfc) -> py.stmt:
        pou = self.pou
        initial = next((s.index for s in sfc.steps if s.initial), 0)
        trans = tuple((tuple(t.sources), tuple(t.targets), f"_tr_{t.index}") for t in sfc.transitions)
        steps = []
        for s in sfc.steps:
            assoc = []
            for i, (act, q, texpr) in enumerate(s.actions):
                assoc.append((sfc.action_index[act], q, f"_at_{s.index}_{i}" if texpr is not None else ""))
            steps.append(tuple(assoc))
        actions = []
        for name in sfc.actions:
            if name in pou.actions:
                actions.append(("act", "_act_" + name))
            else:
                actions.append(("var", pou.vars[name].pyname))
        desc = _call("_SfcDesc", _const(len(sfc.steps)), _const(initial), _const(trans), _const(tuple(steps)),
                     _const(tuple(actions)))
        return _set_lines(py.Assign([_name("_sfc_" + pou.pyname, py.Store())], desc), pou.decl.span.line)

    def method(self, name, body, can_cache, edges, line, end_line) -> py.FunctionDef:
        pou = self.pou
        by_ref = _by_ref_names(body)
        used = set()
        for e in _walk_exprs_in(body):
            if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym) and e.sym.owner is pou \
                    and e.sym.section != "VAR_EXTERNAL" and not e.sym.is_global:
                used.add(e.sym)
        for v in edges:
            used.add(v)
        temps = [v for v in pou.vars.values() if v.section == "VAR_TEMP"]
        if can_cache:
            self.cached = {v for v in used if v not in by_ref and not v.address_taken}
        else:
            self.cached = set()
        # VAR_TEMP lives for one call: always a Python local (boxed if passed by reference)
        self.boxed = {v for v in temps if v in by_ref or v.address_taken}
        self.cached |= {v for v in temps if v not in self.boxed}
        code = self.stmts(body)
        prologue = []
        init = InitGen(self.mod)
        for v in temps:
            val = init.initial(v.type, v.init)
            prologue.append(py.Assign([_name(v.pyname, py.Store())],
                                      py.List([val], py.Load()) if v in self.boxed else val))
        for v in sorted(self.cached, key=lambda s: s.pyname):
            if v.section == "VAR_TEMP":
                continue
            prologue.append(py.Assign([_name(v.pyname, py.Store())], _attr(_name("self"), v.pyname)))
        for v in edges:
            # an edge-declared input is TRUE only in the call that sees the edge
            prev = _attr(_name("self"), "_e_" + v.pyname)
            cur = _name(v.pyname) if v in self.cached else _attr(_name("self"), v.pyname)
            if v.edge == "R_EDGE":
                test = py.BoolOp(py.And(), [cur, py.UnaryOp(py.Not(), prev)])
            else:
                test = py.BoolOp(py.And(), [py.UnaryOp(py.Not(), cur), prev])
            prologue.append(py.Assign([prev], cur))
            prologue[-1] = py.Assign([py.Tuple([_store(cur), _store(prev)], py.Store())],
                                     py.Tuple([test, cur], py.Load()))
        writeback = []
        for v in sorted(self.cached & self.written_locals, key=lambda s: s.pyname):
            if T.unalias(v.type).is_aggregate or v.section == "VAR_TEMP":
                continue
            writeback.append(py.Assign([_attr(_name("self"), v.pyname, py.Store())], _name(v.pyname)))
        main = prologue + (code or [])
        if writeback:
            main = prologue + [py.Try(code or [py.Pass()], [], [], _lines(writeback, end_line))]
        gl = sorted(self.globals_written)
        if gl:
            main.insert(0, py.Global(gl))
        fn = py.FunctionDef(name, _args(["self"]), main or [py.Pass()], [], None, None)
        _set_lines(fn, line)
        return fn

    def sfc_methods(self, sfc) -> list:
        """Transition conditions and the SFC description for the runtime engine."""
        out = []
        conds = []
        for t in sfc.transitions:
            g = BodyGen(self.mod, self.pou)
            g.cached = set()
            if t.cond is not None:
                body = [py.Return(g.expr(t.cond))]
            else:
                body = [py.Return(_const(False))]
            fn = py.FunctionDef(f"_tr_{t.index}", _args(["self"]), body, [], None, None)
            _set_lines(fn, t.span.line)
            out.append(fn)
        # timed qualifiers' durations are constant expressions or variables: a method returns them
        for s in sfc.steps:
            for i, (act, q, texpr) in enumerate(s.actions):
                if texpr is not None:
                    g = BodyGen(self.mod, self.pou)
                    fn = py.FunctionDef(f"_at_{s.index}_{i}", _args(["self"]), [py.Return(g.expr(texpr))], [], None, None)
                    _set_lines(fn, texpr.span.line)
                    out.append(fn)
        return out
