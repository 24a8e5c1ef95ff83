"""One generated `_body` (or user FUNCTION) made ready for Cython: C types where they are exact,
the rest unchanged.

Input: the body's Python AST as the code generator printed it, the facts the code generator
recorded while printing it (codegen/facts.py: the locals holding ST variables and their IEC
types, the loop guards, the runtime helpers called and what for, the calls of block bodies and
FUNCTIONs, the intervals it proved), the kinds of the instances' variables (kinds.py) and the
names that may change between calls (globals). What codegen meant comes from the facts, never
from the shape of its output; the AST gives the statements to compile. Output: the same
statements with
- the locals that cache a BOOL/integer/REAL variable, and the temporaries that only ever hold
  such values, declared as C variables (`cdef` lines, added by pyx.py);
- an element read from a one-dimensional ARRAY of such values converted to C where it is read;
- a slot of an instance of a generated class read and written at its offset (`_k_ld`/`_k_st`,
  which check the exact type first), and a call of a block's body made directly (`_k_run`,
  resolved by pyx.py);
- an operation that C's int64 might compute differently done on Python objects (`_k_obj`);
- the hot runtime helpers (index checks, DIV, MOD, REAL division and rounding, MIN/MAX/ABS, as
  the facts name them) replaced by C functions with the same results and faults (pyx.py's
  prelude), and the standard functions with a C twin (SQRT, SEL, …) computed by it where the
  PLC's namespace binds the very helper the twin copies (pyx.TWINS);
- each loop guard (`if _wd_armed: _wd_check()`) replaced by a call of `_wd_check()` every 1024
  iterations: a compiled loop holds the GIL, so the watchdog thread's flag would never come,
  while `_wd_check` itself compares the clock with the job's deadline;
- inside a FOR loop that does not write its counter, the counter's interval is the loop's;
- a global that the runtime or ST code rebinds (VAR_GLOBALs) read from the PLC's namespace at
  each use, the job's time `_now` once per body; every other global (helpers, classes,
  functions) bound once per PLC.
"""

from __future__ import annotations

import ast as py
import builtins
import copy
from dataclasses import dataclass, field
from typing import Any, TypeVar

from .. import intervals as I
from ..codegen.facts import WATCHDOG_CHECK, BodyFacts, Helper, deepcopy_with, facts_of
from .kinds import (
    FLOAT,
    Arr,
    Bool,
    Float,
    Inst,
    Int,
    Kind,
    as_int,
    ctype,
    divides,
    exact_float,
    fits,
    int_binop,
    join,
    of_type,
)

NS = "_k_ns"  # the PLC's namespace, a parameter of the module's make()
GUARD_EVERY = 1024  # loop iterations between two watchdog checks
_BUILTINS = frozenset(dir(builtins))
_C_INT_MAX = (1 << 31) - 1
# names this module's code uses unqualified, and Cython's own words: an ST variable (ST names
# are not mangled unless they begin with '_' or are Python keywords) called so keeps its body Python
_RESERVED = frozenset(
    "range abs min max cython cdef cpdef cimport ctypedef struct union enum extern include inline public "
    "readonly api sizeof typeof NULL gil nogil noexcept const volatile signed unsigned short long int char "
    "float double bint void size_t Py_ssize_t int64_t copysign NAN INFINITY DEF IF ELIF ELSE by new "
    "sqrt log log10 exp sin cos tan asin acos atan TWINS".split()
)
CAST = {"int64_t": "_k_i64", "double": "_k_f64", "bint": "_k_b"}
# a slot read to a C value, and a C value stored in a slot (pyx.PRELUDE)
_LOAD = {"int64_t": "_k_ldi", "double": "_k_ldf", "bint": "_k_ldb"}
_STORE = {"int64_t": "_k_sti", "double": "_k_stf", "bint": "_k_stb"}
# standard functions with a C twin in pyx.PRELUDE (`_k_m` + name), used when the PLC's namespace
# binds the standard helper (pyx.TWINS): the same libm, the same edge cases
MATH_TWINS = frozenset(
    "_std_sqrt _std_ln _std_log _std_exp _std_sin _std_cos _std_tan _std_asin _std_acos _atan".split()
)
_EXACT_INT = (1 << 53) - 1  # REAL → integer bounds computed in C (beyond: Python)


class NotEligible(Exception):
    """The body stays Python (the reason is reported with --native's summary)."""


@dataclass
class Typed:
    fn: py.FunctionDef
    decls: dict[str, str]  # local → C type
    captured: set[str] = field(default_factory=set)  # globals bound once per PLC
    slots: set[tuple[str, str]] = field(default_factory=set)  # (class, slot) read or written at its offset
    twins: set[str] = field(default_factory=set)  # helpers computed by their C twin (pyx.TWINS)
    calls: set[str] = field(default_factory=set)  # FUNCTIONs called (pyx.py: in C where compiled too)
    function: FuncInfo | None = None  # a FUNCTION's (fn is then the function itself, not a `_body`)


_BOTTOM = object()  # a temporary whose kind is not known yet (no assignment seen)
_N = TypeVar("_N", bound=py.AST)


@dataclass
class FuncInfo:
    """A user FUNCTION: the kinds of its parameters (in order) and of its result."""

    params: list[Kind]
    result: Kind


@dataclass
class ClassInfo:
    """A generated class: its slots, and the kinds of those that hold one variable of a kind."""

    slots: frozenset[str]
    kinds: dict[str, Kind]


def type_body(
    fn: py.FunctionDef,
    own: str,
    classes: dict[str, ClassInfo],
    volatile: frozenset[str],
    funcs: dict[str, FuncInfo] | None = None,
    facts: BodyFacts | None = None,
) -> Typed:
    """The `_body` of class `own`, or (with `own` a key of `funcs`) the FUNCTION `own` itself;
    `classes`: every generated class (block or STRUCT) by name; `funcs`: every user FUNCTION;
    `facts`: what the code generator recorded for `fn` (by default, the facts kept on it)."""
    funcs = funcs or {}
    function = funcs.get(own)
    facts = facts if facts is not None else facts_of(fn)
    if facts is None:
        raise NotEligible("the code generator recorded no facts for it")
    memo: dict[int, object] = {}
    fn = deepcopy_with(fn, facts, memo)
    index = _Facts(facts, memo)
    fn = _unshared(fn, index)
    _check_eligible(fn)
    if function is not None and (
        fn.args.vararg or fn.args.kwarg or fn.args.kwonlyargs or fn.args.defaults or fn.args.posonlyargs
    ):
        raise NotEligible("its parameters are not plain positional ones")
    stores = _stores(fn)
    params = {a.arg for a in fn.args.args}
    env: dict[str, Kind] = {}
    if function is None and fn.args.args:
        env[fn.args.args[0].arg] = Inst(own)  # a body's instance (`self`)
    for name, local in facts.locals.items():
        kind = of_type(local.type)
        if kind is None or (local.section == "VAR_IN_OUT" and not isinstance(kind, Inst)):
            continue  # an elementary in-out holds what the caller passed, copied in unconverted
        if isinstance(kind, (Arr, Inst)) and len(stores.get(name, ())) > 1:
            continue  # a list or an instance only where nothing else is stored in the local
        if name in params and ctype(kind) is not None:
            continue  # a parameter is a C value only where the signature says so (below, pyx.py)
        env[name] = kind
    if function is not None:
        for a, k in zip(fn.args.args, function.params, strict=True):
            if ctype(k) is not None:
                env[a.arg] = k  # a C parameter: the caller passes a value of its type (codegen wraps it)
    temps = {
        name: values
        for name, values in stores.items()
        if name not in env and name not in params and all(v is not None for v in values)
    }
    locals_ = set(stores) | params
    _infer_temps(temps, env, classes, locals_, funcs, index)
    t = _Transformer(env, classes, locals_, volatile, funcs, index)
    t.generic_visit(fn)
    if t.uses_now:
        now = py.Assign([py.Name("_k_now", py.Store())], py.Subscript(py.Name(NS, py.Load()), py.Constant("_now")))
        fn.body.insert(0, py.copy_location(now, fn.body[0]))
    py.fix_missing_locations(fn)
    decls = {name: c for name, k in env.items() if (c := ctype(k)) is not None and name not in params}
    return Typed(fn, decls, t.captured, t.slots, t.twins, t.calls, function)


MAX_DEPTH = 100  # expression nesting Cython's recursive parser is given (it fails far beyond this)


def _check_eligible(fn: py.FunctionDef) -> None:
    if _depth(fn) > MAX_DEPTH:
        raise NotEligible(f"an expression is nested more than {MAX_DEPTH} deep")
    for node in py.walk(fn):
        if isinstance(node, (py.Global, py.Nonlocal)):
            raise NotEligible("it writes a global variable")
        if isinstance(node, (py.Yield, py.YieldFrom, py.Await, py.Lambda, py.ClassDef)):
            raise NotEligible(f"it contains a {type(node).__name__}")
        if isinstance(node, (py.FunctionDef, py.AsyncFunctionDef)) and node is not fn:
            raise NotEligible("it contains a nested function")
        if isinstance(node, py.Name) and (node.id.startswith("_k_") or node.id in _RESERVED):
            raise NotEligible(f"it uses the name {node.id}, which C or Cython reserve")
        if isinstance(node, py.Attribute) and node.attr in _RESERVED:
            raise NotEligible(f"it uses the name {node.attr}, which C or Cython reserve")


class _Facts:
    """A body's facts (codegen/facts.py) for its copy: each node a fact names, found by identity
    in the copied tree (and in any further copy made through `copy`)."""

    def __init__(self, facts: BodyFacts, memo: dict[int, object]):
        self.helpers = facts.helpers
        # id(node) → (node, what is known of it): the node is held, so its id stays its own
        self.guards: dict[int, tuple[object, Any]] = {}
        self.loops: dict[int, tuple[object, Any]] = {}  # (counter, its values in the loop's body)
        self.ranges: dict[int, tuple[object, Any]] = {}  # the values (Interval)
        self.body_calls: dict[int, tuple[object, Any]] = {}  # the block's class
        self.function_calls: dict[int, tuple[object, Any]] = {}  # the FUNCTION's name

        def add(table: dict[int, tuple[object, Any]], node: object, value: Any) -> None:
            c = memo.get(id(node))
            if c is not None:
                table[id(c)] = (c, value)

        for g in facts.guards:
            add(self.guards, g, None)
        for loop in facts.loops:
            add(self.loops, loop.node, (loop.counter, loop.values))
        for b in facts.body_calls:
            add(self.body_calls, b.node, b.cls)
        for f in facts.function_calls:
            add(self.function_calls, f.node, f.name)
        for r in facts.ranges:
            had = self.get(self.ranges, memo.get(id(r.node)))
            add(self.ranges, r.node, r.values if had is None else I.meet(had, r.values))

    def _tables(self) -> tuple[dict, ...]:
        return (self.guards, self.loops, self.ranges, self.body_calls, self.function_calls)

    def alias(self, memo: dict[int, object]) -> None:
        """The facts of nodes that a deep copy (its `memo`) copied hold for the copies too."""
        for table in self._tables():
            for key, (_node, value) in list(table.items()):
                c = memo.get(key)
                if c is not None:
                    table[id(c)] = (c, value)

    def copy(self, node: _N) -> _N:
        memo: dict[int, object] = {}
        out = copy.deepcopy(node, memo)
        self.alias(memo)
        return out

    @staticmethod
    def get(table: dict, node: object):
        got = table.get(id(node))
        return got[1] if got is not None and got[0] is node else None

    def is_guard(self, node: object) -> bool:
        got = self.guards.get(id(node))
        return got is not None and got[0] is node


def _unshared(fn: py.FunctionDef, index: _Facts) -> py.FunctionDef:
    """`fn` as a tree: the code generator may put one node in two places (a FOR loop's start is
    both the counter's first value and the range's), and this module rewrites nodes in place.
    A node's second place gets a copy, with the node's facts."""
    seen: set[int] = set()
    todo: list[py.AST] = [fn]
    while todo:
        node = todo.pop()
        for name, value in py.iter_fields(node):
            items = value if isinstance(value, list) else [value]
            fresh = []
            for item in items:
                if isinstance(item, py.AST):
                    if id(item) in seen:
                        item = index.copy(item)
                    seen.add(id(item))
                    todo.append(item)
                fresh.append(item)
            if isinstance(value, list):
                value[:] = fresh
            elif isinstance(value, py.AST):
                setattr(node, name, fresh[0])
    return fn


def _depth(fn: py.FunctionDef) -> int:
    """How deep expressions nest in `fn` (without recursion: a long operator chain is deep)."""
    deepest = 0
    todo: list[tuple[py.AST, int]] = [(fn, 0)]
    while todo:
        node, d = todo.pop()
        d = d + 1 if isinstance(node, py.expr) else 0
        deepest = max(deepest, d)
        todo.extend((child, d) for child in py.iter_child_nodes(node))
    return deepest


def _stores(fn: py.FunctionDef) -> dict[str, list[py.expr | None]]:
    """name → the values assigned to it (None where the form is not a plain `name = value`)."""
    out: dict[str, list[py.expr | None]] = {}
    plain: set[int] = set()
    for node in py.walk(fn):
        if isinstance(node, py.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], py.Name):
            out.setdefault(node.targets[0].id, []).append(node.value)
            plain.add(id(node.targets[0]))
        elif isinstance(node, py.NamedExpr):
            out.setdefault(node.target.id, []).append(node.value)
            plain.add(id(node.target))
    for node in py.walk(fn):
        if isinstance(node, py.Name) and isinstance(node.ctx, (py.Store, py.Del)) and id(node) not in plain:
            out.setdefault(node.id, []).append(None)
        elif isinstance(node, py.ExceptHandler) and node.name:
            out.setdefault(node.name, []).append(None)
    return out


def _infer_temps(
    temps: dict[str, list],
    env: dict[str, Kind],
    classes: dict,
    locals_: set[str],
    funcs: dict[str, FuncInfo],
    index: _Facts,
) -> None:
    """Kinds of the temporaries (the generated code's own locals, which hold no ST variable), to
    a fixed point (a few rounds; what does not settle stays an object)."""
    kinds: dict[str, object] = {name: _BOTTOM for name in temps}
    for _ in range(6):
        changed = False
        for name, values in temps.items():
            k: object = _BOTTOM
            for v in values:
                known = {n: kk for n, kk in kinds.items() if kk is not _BOTTOM}
                t = _Transformer({**env, **known}, classes, locals_, frozenset(), funcs, index)
                vk = t.expr(index.copy(v))[1]
                k = vk if k is _BOTTOM else join(k, vk)  # type: ignore[arg-type]
            if k != kinds[name]:
                kinds[name], changed = k, True
        if not changed:
            break
    else:
        return
    for name, k in kinds.items():
        if k is not _BOTTOM and k is not None:
            env[name] = k  # type: ignore[assignment]


def twin_name(helper: str) -> str:
    """The context's flag: which C twin computes `helper` for this PLC (0: none, its own binding)."""
    return "_k_tw" + helper


def _ll(v: py.expr) -> int | None:
    """The value of a literal printed as a C long long (`-2147483648LL`, x_Constant), else None."""
    if isinstance(v, py.Name) and v.id.endswith("LL"):
        try:
            return int(v.id[:-2])
        except ValueError:
            return None
    return None


def type_name(cls: str) -> str:
    return "_k_T" + cls


def offset_name(cls: str, attr: str) -> str:
    return f"_k_O{len(cls)}_{cls}_{attr}"  # the length first: no two (class, slot) pairs meet


def _call(name: str, *args: py.expr) -> py.Call:
    return py.Call(py.Name(name, py.Load()), list(args), [])


def _obj(node: py.expr, kind: Kind) -> py.expr:
    """`node` as a Python object (Cython then computes with Python's rules)."""
    return _call("_k_obj", node) if kind is not None else node


class _Transformer(py.NodeTransformer):
    def __init__(
        self,
        env: dict,
        classes: dict[str, ClassInfo],
        locals_: set[str],
        volatile: frozenset[str],
        funcs: dict[str, FuncInfo],
        facts: _Facts,
    ):
        self.env, self.classes, self.locals, self.volatile = env, classes, locals_, volatile
        self.funcs = funcs
        self.facts = facts
        self.calls: set[str] = set()
        self.captured: set[str] = set()
        self.slots: set[tuple[str, str]] = set()
        self.twins: set[str] = set()
        self.uses_now = False

    def _slot(self, target: py.expr, kind: Kind, attr: str, load: bool = False) -> list[py.expr] | None:
        """The arguments (object, class, offset, name) of a slot access, when `target` is a local
        (or, to read, another slot read: `self.on_delay.Q`) holding an instance of a known class
        with that slot."""
        plain = isinstance(target, py.Name) or (
            load and isinstance(target, py.Call) and isinstance(target.func, py.Name) and target.func.id == "_k_ld"
        )
        if not isinstance(kind, Inst) or not plain:
            return None
        info = self.classes.get(kind.cls)
        if info is None or attr not in info.slots:
            return None
        self.slots.add((kind.cls, attr))
        return [
            target,
            py.Name(type_name(kind.cls), py.Load()),
            py.Name(offset_name(kind.cls, attr), py.Load()),
            py.Constant(attr),
        ]

    # ------------------------------------------------------------------ statements
    def visit(self, node):
        if isinstance(node, py.expr):
            return self.expr(node)[0]
        return super().visit(node)

    def visit_If(self, node: py.If):
        if self.facts.is_guard(node):  # a loop guard: the watchdog's check every GUARD_EVERY rounds
            self.captured.add(WATCHDOG_CHECK)
            count = py.AugAssign(py.Name("_k_wd", py.Store()), py.Add(), py.Constant(1))
            due = py.UnaryOp(py.Not(), py.BinOp(py.Name("_k_wd", py.Load()), py.BitAnd(), py.Constant(GUARD_EVERY - 1)))
            check = py.If(due, [py.Expr(_call(WATCHDOG_CHECK))], [])
            for s in (count, check, check.body[0]):
                py.copy_location(s, node)
            return [count, check]
        return self.generic_visit(node)

    def visit_For(self, node: py.For):
        """A FOR whose body does not write its counter: in the body, the counter's values are the
        loop's (codegen's Loop fact), often fewer than its type's."""
        loop = self.facts.get(self.facts.loops, node)
        known = self.env.get(loop[0]) if loop is not None else None
        if loop is None or not isinstance(known, Int) or not fits(loop[1].lo, loop[1].hi):
            return self.generic_visit(node)
        counter, values = loop
        node.target = self.visit(node.target)
        node.iter = self.visit(node.iter)
        self.env[counter] = values
        try:
            node.body = self._statements(node.body)
        finally:
            self.env[counter] = known
        node.orelse = self._statements(node.orelse)  # after the loop: any value of its type again
        return node

    def _statements(self, body: list[py.stmt]) -> list[py.stmt]:
        out: list[py.stmt] = []
        for stmt in body:
            got = self.visit(stmt)
            if isinstance(got, list):
                out.extend(got)
            elif got is not None:
                out.append(got)
        return out

    def visit_Assign(self, node: py.Assign):
        target = node.targets[0]
        if len(node.targets) == 1 and isinstance(target, py.Attribute):
            obj, kind = self.expr(target.value)
            args = self._slot(obj, kind, target.attr)
            if args is not None:
                value, vk = self.expr(node.value)
                store = _STORE.get(ctype(vk) or "", "_k_st")
                return py.copy_location(py.Expr(_call(store, *args, value)), node)
        return self.generic_visit(node)

    def visit_AugAssign(self, node: py.AugAssign):
        target = node.target
        if isinstance(target, py.Name) and target.id in self.env:
            # `x += v` on a C local: the operation's interval decides like any other
            load = py.copy_location(py.Name(target.id, py.Load()), target)
            value = py.copy_location(py.BinOp(load, node.op, node.value), node)
            return py.copy_location(py.Assign([target], self.expr(value)[0]), node)
        return self.generic_visit(node)

    # ------------------------------------------------------------------ expressions
    def expr(self, e: py.expr) -> tuple[py.expr, Kind]:
        m = getattr(self, "x_" + type(e).__name__, None)
        if m is None:
            self.generic_visit(e)
            return e, None
        proven = self.facts.get(self.facts.ranges, e)  # codegen's interval of this value
        out, kind = m(e)
        if proven is not None and isinstance(kind, Int):
            narrowed = I.meet(kind, proven)
            if narrowed.lo <= narrowed.hi:
                kind = narrowed
        return out, kind

    def x_Constant(self, e: py.Constant):
        v = e.value
        if isinstance(v, bool):
            return e, Bool()
        if isinstance(v, int):
            if not fits(v, v):
                return e, None
            if abs(v) > _C_INT_MAX:
                # Cython makes a literal beyond C int a Python object: spell it as a C long long
                return py.copy_location(py.Name(f"{v}LL", py.Load()), e), Int(v, v)
            return e, Int(v, v)
        if isinstance(v, float):
            return e, FLOAT
        return e, None

    def x_Name(self, e: py.Name):
        if not isinstance(e.ctx, py.Load):
            return e, None
        name = e.id
        if name in self.locals:
            return e, self.env.get(name)
        if self.facts.helpers.get(name) is Helper.RANGE:  # Cython's C loop over `range`
            return py.copy_location(py.Name("range", py.Load()), e), None
        if name == "_now":  # the job's release time: the same all through a body (read once, at its start)
            self.uses_now = True
            return py.copy_location(py.Name("_k_now", py.Load()), e), None
        if name in self.volatile:
            return py.copy_location(py.Subscript(py.Name(NS, py.Load()), py.Constant(name), py.Load()), e), None
        if name not in _BUILTINS:
            self.captured.add(name)
        return e, None

    def x_Subscript(self, e: py.Subscript):
        e.value, kind = self.expr(e.value)
        e.slice = self.expr(e.slice)[0]
        if isinstance(e.ctx, py.Load) and isinstance(kind, Arr):
            return py.copy_location(_call(CAST[ctype(kind.elem) or ""], e), e), kind.elem
        return e, None

    def x_Attribute(self, e: py.Attribute):
        e.value, kind = self.expr(e.value)
        if isinstance(e.ctx, py.Load):
            args = self._slot(e.value, kind, e.attr, load=True)
            if args is not None:
                assert isinstance(kind, Inst)
                k = self.classes[kind.cls].kinds.get(e.attr)
                return py.copy_location(_call(_LOAD.get(ctype(k) or "", "_k_ld"), *args), e), k
        return e, None

    def x_BinOp(self, e: py.BinOp):
        left, kl = self.expr(e.left)
        right, kr = self.expr(e.right)
        op = e.op
        il, ir = as_int(kl), as_int(kr)
        if il is not None and ir is not None and not isinstance(op, (py.Div, py.Pow, py.MatMult)):
            if isinstance(kl, Bool) and isinstance(kr, Bool) and isinstance(op, (py.BitAnd, py.BitOr, py.BitXor)):
                return py.copy_location(_call("_k_bint", py.BinOp(left, op, right)), e), Bool()
            r = int_binop(op, il, ir)
            if r is not None:
                return py.copy_location(py.BinOp(left, op, right), e), r
        elif (
            (isinstance(kl, Float) or isinstance(kr, Float) or isinstance(op, py.Div))
            and kl is not None
            and kr is not None
            and exact_float(kl)
            and exact_float(kr)
            and isinstance(op, (py.Add, py.Sub, py.Mult, py.Div))
        ):
            return py.copy_location(py.BinOp(left, op, right), e), FLOAT
        if kl is not None and kr is not None:
            left = _obj(left, kl)  # Python's arithmetic for this one
        return py.copy_location(py.BinOp(left, op, right), e), None

    def x_UnaryOp(self, e: py.UnaryOp):
        v, k = self.expr(e.operand)
        op = e.op
        if isinstance(op, py.Not):
            return py.copy_location(py.UnaryOp(op, v), e), Bool()
        i = as_int(k)
        r: Kind = None
        if isinstance(k, Float) and isinstance(op, (py.USub, py.UAdd)):
            r = FLOAT
        elif i is not None:
            if isinstance(op, py.USub):
                r = I.neg(i)
            elif isinstance(op, py.UAdd):
                r = i
            elif isinstance(op, py.Invert):
                r = I.invert(i)
            if isinstance(r, Int) and not fits(r.lo, r.hi):
                r = None
        if r is None:
            v = _obj(v, k)
        return py.copy_location(py.UnaryOp(op, v), e), r

    def x_BoolOp(self, e: py.BoolOp):
        parts = [self.expr(v) for v in e.values]
        if all(isinstance(k, Bool) for _, k in parts):
            return py.copy_location(py.BoolOp(e.op, [v for v, _ in parts]), e), Bool()
        return py.copy_location(py.BoolOp(e.op, [_obj(v, k) for v, k in parts]), e), None

    def x_Compare(self, e: py.Compare):
        parts = [self.expr(v) for v in [e.left, *e.comparators]]
        plain = all(isinstance(op, (py.Lt, py.LtE, py.Gt, py.GtE, py.Eq, py.NotEq)) for op in e.ops)
        mixed = any(isinstance(k, Float) for _, k in parts) and not all(
            exact_float(k) for _, k in parts if k is not None
        )
        if not plain or mixed:
            parts = [(_obj(v, k), None) for v, k in parts]
        return py.copy_location(py.Compare(parts[0][0], e.ops, [v for v, _ in parts[1:]]), e), Bool()

    def x_IfExp(self, e: py.IfExp):
        test = self.expr(e.test)[0]
        body, kb = self.expr(e.body)
        orelse, ko = self.expr(e.orelse)
        k = join(kb, ko)
        if k is None:
            body, orelse = _obj(body, kb), _obj(orelse, ko)
        return py.copy_location(py.IfExp(test, body, orelse), e), k

    def x_NamedExpr(self, e: py.NamedExpr):
        e.value = self.expr(e.value)[0]
        return e, self.env.get(e.target.id)

    def x_Call(self, e: py.Call):
        f = e.func
        cls = self.facts.get(self.facts.body_calls, e)
        if cls is not None and isinstance(f, py.Attribute) and not e.args and not e.keywords:
            obj, _kind = self.expr(f.value)
            if isinstance(obj, py.Name):
                # a block's call: pyx.py makes it a direct call of the compiled body when there is one
                return py.copy_location(_call("_k_run", obj, py.Constant(cls)), e), None
            f.value = obj
            return e, None
        name = e.func.id if isinstance(e.func, py.Name) else None
        if name is not None and not e.keywords and name not in self.locals:
            parts = [self.expr(a) for a in e.args]
            called = self.facts.get(self.facts.function_calls, e)
            info = self.funcs.get(called) if called == name else None
            if (
                info is not None
                and len(parts) == len(info.params)
                and not any(isinstance(a, py.Starred) for a in e.args)
            ):
                # a user FUNCTION: pyx.py calls its compiled form in C where there is one
                self.calls.add(name)
                self.captured.add(name)
                c = py.Constant(ctype(info.result) or "")
                return py.copy_location(_call("_k_callf", py.Constant(name), c, *(v for v, _ in parts)), e), info.result
            out = self._helper(name, parts)
            if out is not None:
                return py.copy_location(out[0], e), out[1]
            e.args = [v for v, _ in parts]
            e.func = self.expr(e.func)[0]
            return e, None
        self.generic_visit(e)
        return e, None

    def _helper(self, name: str, parts: list[tuple[py.expr, Kind]]) -> tuple[py.expr, Kind] | None:
        """A helper call computed in C, or None to call the Python helper: a runtime helper by
        what the facts say it computes, a standard function by its C twin."""
        ks = [k for _, k in parts]
        vs = [v for v, _ in parts]
        n = len(parts)
        what = self.facts.helpers.get(name)
        if what is Helper.ROUND and n == 1:
            if ks[0] is None:
                return _call("_k_f32", _call("_k_f64", vs[0])), FLOAT
            if exact_float(ks[0]):
                return _call("_k_f32", vs[0]), FLOAT
        if what is Helper.TO_REAL and n == 1 and ks[0] is not None and exact_float(ks[0]):
            return _call("_k_tofloat", vs[0]), FLOAT
        if what is Helper.ABS and n == 1:
            if isinstance(ks[0], Float):
                return _call("abs", vs[0]), FLOAT
            i = ks[0]
            if isinstance(i, Int) and fits(i.lo, i.hi, -(1 << 62), 1 << 62):
                return _call("abs", vs[0]), I.absolute(i)
        if what in (Helper.MIN, Helper.MAX) and n == 2:
            k = join(ks[0], ks[1])
            if isinstance(k, (Int, Float)) and isinstance(ks[0], type(ks[1])):
                return _call("min" if what is Helper.MIN else "max", *vs), k
        if what is Helper.INDEX and n == 3 and isinstance(ks[0], Int):
            first, last = (v.value if isinstance(v, py.Constant) and type(v.value) is int else None for v in vs[1:])
            if isinstance(first, int) and isinstance(last, int) and fits(first, last, -(1 << 62), 1 << 62):
                return _call("_k_ix", *vs), Int(0, max(last - first, 0))
        if what in (Helper.DIV, Helper.MOD, Helper.UMOD) and n == 2:
            a, b = (as_int(k) for k in ks)
            if a is not None and b is not None and divides(a, b):
                if what is Helper.DIV:
                    return _call("_k_idiv", *vs), I.div_trunc(a, b)
                return _call("_k_imod", *vs), I.mod_trunc(a, b)
        if what is Helper.REAL_DIV and n == 2 and all(k is not None and exact_float(k) for k in ks):
            return _call("_k_fdiv", *vs), FLOAT
        if name in MATH_TWINS and n == 1 and ks[0] is not None and exact_float(ks[0]):
            return self._twin(
                name, _call("_k_m" + name, vs[0]), _call("_k_f64", _call(name, copy.deepcopy(vs[0])))
            ), FLOAT
        if name == "_std_sel" and n == 3 and isinstance(ks[0], Bool):
            k = join(ks[1], ks[2])
            sel = {Int: "_k_sel_i", Float: "_k_sel_f", Bool: "_k_sel_b"}.get(type(k))
            if sel is not None and isinstance(ks[1], type(ks[2])):
                python = _call(CAST[ctype(k) or ""], _call(name, *copy.deepcopy(vs)))
                return self._twin(name, _call(sel, *vs), python), k
        if what is Helper.TO_INT and n == 1 and isinstance(ks[0], (Bool, Int)):  # BOOL_TO_DINT and the like
            c = _call("_k_bool_int", vs[0]) if isinstance(ks[0], Bool) else vs[0]
            k = Int(0, 1) if isinstance(ks[0], Bool) else ks[0]
            return self._twin(name, c, _call("_k_i64", _call(name, copy.deepcopy(vs[0])))), k
        if name == "_real_to_int" and n == 4 and ks[0] is not None and exact_float(ks[0]):
            first, last = (v.value if isinstance(v, py.Constant) and type(v.value) is int else _ll(v) for v in vs[1:3])
            if isinstance(first, int) and isinstance(last, int) and -_EXACT_INT <= first <= last <= _EXACT_INT:
                # in range: computed in C; out of range (and another binding): the Python helper raises
                self.twins.add(name)
                self.captured.add(name)
                flag = py.Name(twin_name(name), py.Load())
                return _call("_k_rti", flag, vs[0], vs[1], vs[2], py.Name(name, py.Load()), vs[3]), Int(first, last)
        return None

    def _twin(self, name: str, c: py.expr, python: py.expr) -> py.expr:
        """`c` where the namespace binds the standard `name`, else `python` (a call of the binding)."""
        self.twins.add(name)
        self.captured.add(name)
        return py.IfExp(py.Name(twin_name(name), py.Load()), c, python)
