"""Semantic analysis: declarations → types and symbols; bodies → typed, checked AST.

The checker never raises on bad input: every problem becomes a diagnostic
and checking goes on, so one run reports all errors. Expression nodes get
their type in `.ty`; names get their symbol in `.sym`; calls get `.target`.
"""
from __future__ import annotations

import re
from typing import Optional

from ..diagnostics import DiagnosticSink
from ..source import Span
from . import ast as A
from . import types as T
from .library import FuncSig, Library
from .model import ConfigModel, InstanceModel, Project, SfcModel, StepModel, TaskModel, TransitionModel
from .names import mangle

_SECTIONS_PARAM = ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")
_LOGIC = {"AND", "OR", "XOR", "AND_THEN", "OR_ELSE"}
_CMP = {"=", "<>", "<", ">", "<=", ">="}
_DIRECT = re.compile(r"%([IQM])([XBWDL]?)(\*|[0-9]+(?:\.[0-9]+)*)")
_DIRECT_TYPES = {"X": T.BOOL, "": T.BOOL, "B": T.BYTE, "W": T.WORD, "D": T.DWORD, "L": T.LWORD}


class CallTarget:
    """What a call resolved to (kept on `Call.target` for code generation)."""

    def __init__(self, kind: str, **kw):
        self.kind = kind            # fb, function, native, action, conversion
        self.__dict__.update(kw)


class StepType(T.Type):
    kind = "step"
    name = "STEP"


STEP = StepType()


class Scope:
    def __init__(self, pou: Optional[T.POUType], vars: dict, *, library: str = ""):
        self.pou = pou
        self.vars = vars
        self.loop_depth = 0
        self.steps: dict = {}
        self.actions: dict = {}
        self.library = library


class Checker:
    def __init__(self, sink: DiagnosticSink, libraries: list[Library]):
        self.sink = sink
        self.libraries = libraries
        self.p = Project(libraries=libraries)
        self._resolving: set = set()
        self._decl_span: dict = {}
        self._unit_library: dict = {}
        self._pending_types: dict = {}
        self._raw_const_busy: set = set()
        self._deferred_inits: list = []
        self._calls: dict = {}         # caller lower name → [(callee lower name, span)]
        self._configs: list = []
        self._global_blocks: list = []

    # ================================================================ entry
    def run(self, units: list[A.Unit], library_units: set[str]) -> Project:
        self.library_units = library_units
        for u in units:
            self._collect(u)
        for key, (decl, lib) in list(self._pending_types.items()):
            self._resolve_named_type(key, decl.span)
        for pou in list(self.p.pous.values()):
            self._resolve_interface(pou)
        self._resolve_globals()
        for pou in list(self.p.pous.values()):
            if pou.decl is not None:
                self._check_body(pou)
        self._check_cycles()
        for cfg_decl in self._configs:
            self._check_configuration(cfg_decl)
        if not self.p.configs:
            self._implicit_configuration()
        self._warn_unused()
        return self.p

    # ================================================================ helpers
    def err(self, code: str, span: Span, msg: str, hint: str = "") -> None:
        self.sink.error(code, span, msg, hint)

    def warn(self, code: str, span: Span, msg: str, hint: str = "") -> None:
        if span is not None and span.file in self.library_units:
            return
        self.sink.warning(code, span, msg, hint)

    def _lib_of(self, span: Span) -> str:
        return "lib" if span is not None and span.file in self.library_units else ""

    # ================================================================ collection
    def _collect(self, u: A.Unit) -> None:
        for item in u.items:
            if isinstance(item, A.TypeBlock):
                for td in item.types:
                    key = td.name.lower()
                    if key in self._pending_types or key in self.p.pous:
                        self._dup(td.name, td.span)
                        continue
                    if key in T.ELEMENTARY:
                        self.err("E011", td.span, f"'{td.name}' is an elementary type and cannot be redefined")
                        continue
                    self._pending_types[key] = (td, self._lib_of(td.span))
                    self._decl_span[key] = td.span
            elif isinstance(item, A.POU):
                key = item.name.lower()
                if key in self.p.pous or key in self._pending_types:
                    old = self.p.pous.get(key)
                    if old is not None and old.library and not self._lib_of(item.span):
                        # a user POU replaces a library POU of the same name
                        self.warn("W004", item.span, f"'{item.name}' replaces the standard library's {item.name}")
                    else:
                        self._dup(item.name, item.span)
                        continue
                pt = T.POUType(item.name, item.kind, decl=item, library=self._lib_of(item.span))
                pt.pyname = {"FUNCTION": "_fn_", "FUNCTION_BLOCK": "_fb_", "PROGRAM": "_prg_"}[item.kind] + \
                    mangle(item.name)
                self.p.pous[key] = pt
                self._decl_span[key] = item.span
            elif isinstance(item, A.Configuration):
                self._configs.append(item)
            elif isinstance(item, A.VarBlock):
                if item.kind != "VAR_GLOBAL":
                    self.err("E003", item.span, f"{item.kind} is not allowed outside a POU")
                    continue
                self._global_blocks.append(("", item))
            elif isinstance(item, A.TestBlock):
                self.p.tests.append(item)

    def _dup(self, name: str, span: Span) -> None:
        prev = self._decl_span.get(name.lower())
        where = f" (first declared at {prev.file}:{prev.line})" if prev else ""
        self.err("E011", span, f"'{name}' is declared twice{where}")

    # ================================================================ types
    def _resolve_named_type(self, key: str, span: Span) -> Optional[T.Type]:
        if key in self.p.types:
            return self.p.types[key]
        if key not in self._pending_types:
            return None
        if key in self._resolving:
            self.err("E012", span, f"type '{key}' is defined in terms of itself")
            return None
        td, lib = self._pending_types[key]
        self._resolving.add(key)
        try:
            t = self._type_from_decl(td)
        finally:
            self._resolving.discard(key)
        self.p.types[key] = t
        return t

    def _type_from_decl(self, td: A.TypeDecl) -> T.Type:
        spec = td.spec
        if isinstance(spec, A.EnumType):
            if isinstance(td.init, A.Name) and not spec.default:
                spec.default = td.init.name       # TYPE E : (A, B) := B;
            elif td.init is not None and not spec.default:
                self.err("E013", td.init.span, "an enumeration's default must be one of its values")
            return self._enum(td.name, spec)
        if isinstance(spec, A.StructType):
            st = T.StructType(td.name, pyname="_st_" + mangle(td.name))
            self.p.types[td.name.lower()] = st     # allow references to itself through REF_TO
            for d in spec.members:
                mt = self.resolve_type(d.type, None)
                for n, sp in d.names:
                    if n.lower() in st.members:
                        self.err("E011", sp, f"field '{n}' is declared twice in {td.name}")
                        continue
                    st.members[n.lower()] = T.Member(n, mt, d.init, sp, mangle(n))
                    if d.init is not None:
                        self.check_initializer(d.init, mt, None)
            st.resolved = True
            return st
        if isinstance(spec, A.SubrangeType):
            t = self.resolve_type(spec, None)
            if isinstance(t, T.SubrangeType):
                t = T.SubrangeType(td.name, t.base, t.lo, t.hi)
            if td.init is not None:
                self.check_initializer(td.init, t, None)
                return T.AliasType(td.name, t, td.init)
            return t
        target = self.resolve_type(spec, None)
        if td.init is not None:
            self.check_initializer(td.init, target, None)
        return T.AliasType(td.name, target, td.init)

    def _enum(self, name: str, spec: A.EnumType) -> T.EnumType:
        base = T.INT
        if spec.base:
            b = T.ELEMENTARY.get(spec.base.upper())
            if b is None or not b.is_intlike:
                self.err("E012", spec.span, f"an enumeration's base type must be an integer type, not '{spec.base}'")
            else:
                base = b
        et = T.EnumType(name or "enum", base=base)
        nxt = 0
        for v in spec.values:
            if v.value is not None:
                c = self.const_value(v.value, None)
                if not isinstance(c, int):
                    self.err("E029", v.span, f"the value of '{v.name}' must be an integer constant")
                    c = nxt
                nxt = c
            if v.name.lower() in et.members:
                self.err("E011", v.span, f"'{v.name}' appears twice in the enumeration")
                continue
            et.members[v.name.lower()] = (v.name, nxt)
            et.names_by_value.setdefault(nxt, v.name)
            self.p.enum_members.setdefault(v.name.lower(), []).append((et, v.name, nxt))
            nxt += 1
        if et.members:
            et.default_value = next(iter(et.members.values()))[1]
        if spec.default:
            m = et.members.get(spec.default.lower())
            if m is None:
                self.err("E010", spec.span, f"'{spec.default}' is not a value of this enumeration")
            else:
                et.default_value = m[1]
        return et

    def resolve_type(self, spec: A.TypeSpec, scope: Optional[Scope]) -> T.Type:
        if isinstance(spec, A.NamedType):
            key = spec.name.lower()
            up = spec.name.upper()
            if up in T.ELEMENTARY:
                return T.ELEMENTARY[up]
            t = self._resolve_named_type(key, spec.span)
            if t is not None:
                return t
            pou = self.p.pous.get(key)
            if pou is not None:
                if pou.pou_kind == "FUNCTION":
                    self.err("E012", spec.span, f"'{spec.name}' is a FUNCTION, not a type")
                    return T.INT
                return pou
            self.err("E012", spec.span, f"unknown type '{spec.name}'")
            return T.INT
        if isinstance(spec, A.StringType):
            n = 80
            if spec.length is not None:
                c = self.const_value(spec.length, scope)
                if not isinstance(c, int) or c < 1:
                    self.err("E029", spec.span, "a string length must be a positive integer constant")
                else:
                    n = c
            return T.StringType(n, spec.wide)
        if isinstance(spec, A.ArrayType):
            dims = []
            for r in spec.ranges:
                if r is None:
                    dims.append((0, -1))      # ARRAY[*]: bounds come from the argument
                    continue
                lo, hi = self.const_value(r[0], scope), self.const_value(r[1], scope)
                if not isinstance(lo, int) or not isinstance(hi, int):
                    self.err("E029", spec.span, "array bounds must be integer constants")
                    lo, hi = 0, 0
                elif hi < lo:
                    self.err("E029", spec.span, f"empty array range {lo}..{hi}")
                    hi = lo
                dims.append((lo, hi))
            elem = self.resolve_type(spec.element, scope)
            return T.ArrayType(dims, elem)
        if isinstance(spec, A.RefType):
            return T.RefType(self.resolve_type(spec.target, scope), spec.kind)
        if isinstance(spec, A.SubrangeType):
            base = T.ELEMENTARY.get(spec.base.upper())
            if base is None or not base.is_intlike:
                self.err("E012", spec.span, f"a subrange needs an integer base type, not '{spec.base}'")
                base = T.INT
            lo, hi = self.const_value(spec.lo, scope), self.const_value(spec.hi, scope)
            if not isinstance(lo, int) or not isinstance(hi, int):
                self.err("E029", spec.span, "subrange bounds must be integer constants")
                lo, hi = base.lo, base.hi
            return T.SubrangeType(f"{base.name}({lo}..{hi})", base, lo, hi)
        if isinstance(spec, A.EnumType):
            return self._enum("", spec)
        if isinstance(spec, A.StructType):
            self.err("E012", spec.span, "STRUCT is only allowed in a TYPE declaration")
            return T.INT
        raise AssertionError(spec)

    # ================================================================ interfaces
    def _resolve_interface(self, pou: T.POUType) -> None:
        if pou.resolved or pou.decl is None:
            return
        pou.resolved = True
        d = pou.decl
        scope = Scope(pou, pou.vars)
        if d.kind == "FUNCTION":
            if d.return_type is not None:
                pou.return_type = self.resolve_type(d.return_type, scope)
        for block in d.var_blocks:
            self._declare_block(block, pou.vars, scope, pou)
        if d.kind in ("FUNCTION", "FUNCTION_BLOCK"):
            # EN and ENO are implicit in every function and FB; declare them when the body uses them
            mentioned = {n.name.lower() for n in _names_in(d.body)}
            for key, section in (("en", "VAR_INPUT"), ("eno", "VAR_OUTPUT")):
                if key in mentioned and key not in pou.vars:
                    true = A.Literal(d.span, "bool", True, "", "TRUE")
                    pou.vars[key] = T.VarSym(key.upper(), T.BOOL, section, d.span, true, pyname=key.upper(),
                                             owner=pou, used=True)
        for act in d.actions:
            if act.name.lower() in pou.actions:
                self.err("E011", act.span, f"action '{act.name}' is declared twice")
            pou.actions[act.name.lower()] = act

    def _declare_block(self, block: A.VarBlock, table: dict, scope: Optional[Scope], owner) -> None:
        kind = block.kind
        quals = set(block.qualifiers)
        if owner is not None:
            allowed = {
                "FUNCTION": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL"},
                "FUNCTION_BLOCK": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL",
                                   "VAR_INST", "VAR_STAT"},
                "PROGRAM": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL",
                            "VAR_GLOBAL"},
            }[owner.pou_kind]
            if kind not in allowed:
                self.err("E003", block.span, f"{kind} is not allowed in a {owner.pou_kind}")
                return
            if kind == "VAR_GLOBAL":
                self._global_blocks.append((owner.name, block))
                return
        for decl in block.decls:
            t = self.resolve_type(decl.type, scope)
            if isinstance(t, T.POUType) and t.pou_kind == "PROGRAM" and owner is not None:
                self.err("E012", decl.type.span, f"a PROGRAM ('{t.name}') cannot be instantiated inside a POU")
            for n, sp in decl.names:
                key = n.lower()
                if key in table:
                    self.err("E011", sp, f"'{n}' is declared twice")
                    continue
                if owner is not None and owner.pou_kind == "FUNCTION" and key == owner.name.lower():
                    self.err("E011", sp, f"'{n}' is the function's own name (its return value)")
                    continue
                sym = T.VarSym(n, t, kind, sp, decl.init, decl.location,
                               constant="CONSTANT" in quals, retain="RETAIN" in quals,
                               persistent="PERSISTENT" in quals, edge=decl.edge, pyname=mangle(n), owner=owner)
                if kind == "VAR_EXTERNAL":
                    sym.is_global = True
                table[key] = sym
                if decl.location:
                    self._check_location(decl.location, t, sp)
            if decl.init is not None and kind != "VAR_EXTERNAL" and owner is None:
                self._deferred_inits.append((decl, t))
            elif decl.init is not None and kind != "VAR_EXTERNAL":
                self.check_initializer(decl.init, t, scope)
                if "CONSTANT" in quals:
                    cv = self.const_value(decl.init, scope) if isinstance(decl.init, A.Expr) else None
                    if cv is not None:
                        for n, _ in decl.names:
                            table[n.lower()].const_value = cv
            if kind in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and owner is None:
                self.err("E003", decl.span, f"{kind} is only allowed in a POU")

    def _check_location(self, loc: str, t: T.Type, span: Span) -> None:
        m = _DIRECT.fullmatch(loc)
        if not m:
            self.err("E004", span, f"malformed address '{loc}'")
            return
        size = m.group(2)
        if m.group(3) == "*":
            return
        want = _DIRECT_TYPES[size]
        bt = T.base_of(t)
        if isinstance(bt, T.ElemType) and bt.bits != want.bits and not (size in ("", "X") and bt.is_bool):
            self.err("E013", span, f"'{loc}' is {want.bits} bit(s) wide; it cannot hold a {t}")

    def _resolve_globals(self) -> None:
        for cfg in self._configs:
            for b in cfg.var_blocks:
                self._global_blocks.append((cfg.name, b))
            for r in cfg.resources:
                for b in r.var_blocks:
                    self._global_blocks.append((cfg.name + "." + r.name, b))
        for prefix, block in self._global_blocks:
            table: dict = {}
            if block.kind == "VAR_CONFIG":
                continue
            self._declare_block(block, table, None, None)
            for key, sym in table.items():
                sym.section = "VAR_GLOBAL"
                sym.is_global = True
                scope_name = prefix.replace(".", "_")
                sym.pyname = "_g_" + (mangle(scope_name) + "_" if scope_name else "") + mangle(sym.name)
                uniq = sym.pyname
                if uniq in self.p.globals:
                    other = self.p.globals[uniq]
                    self.err("E011", sym.span, f"global '{sym.name}' is declared twice "
                             f"(first at {other.span.file}:{other.span.line})")
                    continue
                self.p.globals[uniq] = sym
                self.p.global_names.setdefault(key, []).append(sym)
        # global initializers may name other globals: check them once all are declared
        for decl, t in self._deferred_inits:
            self.check_initializer(decl.init, t, None)
        self._deferred_inits = []
        # bind VAR_EXTERNAL declarations
        for pou in self.p.pous.values():
            for sym in pou.vars.values():
                if sym.section == "VAR_EXTERNAL":
                    cands = self.p.global_names.get(sym.name.lower())
                    if not cands:
                        self.err("E010", sym.span, f"VAR_EXTERNAL '{sym.name}' has no matching VAR_GLOBAL")
                        continue
                    g = cands[0]
                    sym.global_ref = g
                    sym.pyname = g.pyname
                    if not self._same_type(g.type, sym.type):
                        self.err("E013", sym.span, f"VAR_EXTERNAL '{sym.name}' is declared {sym.type} "
                                 f"but the VAR_GLOBAL is {g.type}")

    def _same_type(self, a: T.Type, b: T.Type) -> bool:
        a, b = T.unalias(a), T.unalias(b)
        if a is b:
            return True
        if isinstance(a, T.StringType) and isinstance(b, T.StringType):
            return a.wide == b.wide
        if isinstance(a, T.ArrayType) and isinstance(b, T.ArrayType):
            return a.dims == b.dims and self._same_type(a.element, b.element)
        if isinstance(a, T.SubrangeType) or isinstance(b, T.SubrangeType):
            return T.base_of(a) is T.base_of(b)
        if isinstance(a, T.RefType) and isinstance(b, T.RefType):
            return self._same_type(a.target, b.target)
        return False

    # ================================================================ constants
    def const_value(self, e, scope: Optional[Scope]):
        """Evaluate a constant expression (literals, CONSTANT variables, enum values), or None."""
        if isinstance(e, A.Field):
            return e.const if isinstance(e.sym, T.EnumType) else None
        if isinstance(e, A.Literal):
            return e.value
        if isinstance(e, A.EnumLit):
            et = self._resolve_named_type(e.type_name.lower(), e.span)
            if isinstance(et, T.EnumType):
                m = et.members.get(e.member.lower())
                return m[1] if m else None
            return None
        if isinstance(e, A.Name):
            key = e.name.lower()
            sym = scope.vars.get(key) if scope is not None else None
            if sym is None:
                gs = self.p.global_names.get(key)
                sym = gs[0] if gs else None
            if sym is not None:
                if sym.global_ref is not None:
                    sym = sym.global_ref
                if sym.constant and sym.init is not None and isinstance(sym.init, A.Expr):
                    sym.used = True
                    return self.const_value(sym.init, None)
                return None
            mems = self.p.enum_members.get(key)
            if mems and len({m[2] for m in mems}) == 1:
                return mems[0][2]
            return self._raw_global_constant(key)
        if isinstance(e, A.Unary):
            v = self.const_value(e.operand, scope)
            if v is None:
                return None
            if e.op == "-":
                return -v
            if e.op == "+":
                return v
            if e.op == "NOT" and isinstance(v, bool):
                return not v
            return None
        if isinstance(e, A.Binary):
            a, b = self.const_value(e.left, scope), self.const_value(e.right, scope)
            if a is None or b is None or isinstance(a, str) or isinstance(b, str):
                return None
            try:
                op = e.op
                if op == "+":
                    return a + b
                if op == "-":
                    return a - b
                if op == "*":
                    return a * b
                if op == "/":
                    if isinstance(a, int) and isinstance(b, int):
                        q = abs(a) // abs(b)
                        return q if (a >= 0) == (b >= 0) else -q
                    return a / b
                if op == "MOD":
                    return 0 if b == 0 else a - b * int(a / b)
                if op == "**":
                    return float(a) ** b
                if op == "AND":
                    return a & b
                if op == "OR":
                    return a | b
                if op == "XOR":
                    return a ^ b
            except (ZeroDivisionError, OverflowError):
                return None
            return None
        return None

    def _raw_global_constant(self, key: str):
        """A VAR_GLOBAL CONSTANT not declared yet (types and POU interfaces are resolved first)."""
        if key in self._raw_const_busy:
            return None
        blocks = list(self._global_blocks)
        for cfg in getattr(self, "_configs", []):
            blocks += [("", b) for b in cfg.var_blocks]
            for r in cfg.resources:
                blocks += [("", b) for b in r.var_blocks]
        for _, b in blocks:
            if "CONSTANT" not in b.qualifiers:
                continue
            for d in b.decls:
                if any(n.lower() == key for n, _ in d.names) and isinstance(d.init, A.Expr):
                    self._raw_const_busy.add(key)
                    try:
                        return self.const_value(d.init, None)
                    finally:
                        self._raw_const_busy.discard(key)
        return None

    # ================================================================ initializers
    def check_initializer(self, init, t: T.Type, scope: Optional[Scope]) -> None:
        bt = T.unalias(t)
        if isinstance(init, A.ArrayInit):
            if not isinstance(bt, T.ArrayType):
                self.err("E013", init.span, f"an array initializer cannot initialize a {t}")
                return
            count = 0
            for item in init.items:
                if isinstance(item, A.RepeatInit):
                    for sub in item.items:
                        self.check_initializer(sub, bt.element, scope)
                    count += item.count * max(1, len(item.items))
                else:
                    self.check_initializer(item, bt.element, scope)
                    count += 1
            if count > bt.size:
                self.err("E022", init.span, f"{count} initial values for an array of {bt.size} elements")
            return
        if isinstance(init, A.StructInit):
            if isinstance(bt, T.StructType):
                fields, what = bt.members, "field"
            elif isinstance(bt, T.POUType) and bt.pou_kind != "FUNCTION":
                self._resolve_interface(bt)
                fields, what = bt.vars, "variable"
            else:
                self.err("E013", init.span, f"a structure initializer cannot initialize a {t}")
                return
            for name, sp, val in init.fields:
                m = fields.get(name.lower())
                if m is None:
                    self.err("E023", sp, f"'{t}' has no {what} '{name}'")
                    continue
                self.check_initializer(val, m.type, scope)
            return
        if isinstance(init, A.Expr):
            if isinstance(bt, T.ArrayType) and isinstance(init, A.Literal):
                # CODESYS-style: a single value initializes... no; IEC needs [..]
                self.err("E013", init.span, f"an array needs an initializer in brackets, e.g. [{init.text}]")
                return
            st = self.expr(init, scope or Scope(None, {}), t)
            for n in _names_in([init]):
                if isinstance(n.sym, T.VarSym) and not (n.sym.global_ref or n.sym).constant:
                    self.err("E029", n.span, f"an initial value must be a constant; '{n.name}' is a variable",
                             "assign it in the code instead, or declare it CONSTANT")
                    return
            self.assignable(init, st, t, init.span)

    # ================================================================ bodies
    def _check_body(self, pou: T.POUType) -> None:
        d = pou.decl
        scope = Scope(pou, pou.vars, library=pou.library)
        if d.steps or d.transitions:
            self._check_sfc(pou, scope)
        for act in d.actions:
            scope.actions[act.name.lower()] = act
        self.stmts(d.body, scope)
        for act in d.actions:
            self.stmts(act.body, scope)
        if pou.pou_kind == "FUNCTION" and pou.return_type is None and self._assigns_name(d.body, pou.name):
            self.err("E013", d.span, f"FUNCTION {pou.name} has no return type but assigns a result")

    def _assigns_name(self, body, name) -> bool:
        key = name.lower()
        for s in body:
            if isinstance(s, A.Assign) and isinstance(s.target, A.Name) and s.target.name.lower() == key:
                return True
        return False

    # ---------------------------------------------------------------- SFC
    def _check_sfc(self, pou: T.POUType, scope: Scope) -> None:
        d = pou.decl
        steps = []
        index = {}
        for s in d.steps:
            key = s.name.lower()
            if key in index:
                self.err("E011", s.span, f"step '{s.name}' is declared twice")
                continue
            if key in pou.vars:
                self.err("E011", s.span, f"step '{s.name}' has the name of a variable")
            index[key] = len(steps)
            steps.append(StepModel(s.name, len(steps), s.initial, [], s.span))
        initial = [s for s in steps if s.initial]
        if len(initial) != 1:
            self.err("E030", d.span, f"an SFC needs exactly one INITIAL_STEP (found {len(initial)})")
        scope.steps = index
        actions: dict = {}
        for act in d.actions:
            actions[act.name.lower()] = act
        action_names: list = []
        action_index: dict = {}
        for s, sm in zip(d.steps, steps):
            for aa in s.actions:
                key = aa.action.lower()
                if key not in actions:
                    sym = pou.vars.get(key)
                    if sym is None or not T.base_of(sym.type).is_bool:
                        self.err("E030", aa.span, f"'{aa.action}' is neither an ACTION of {pou.name} nor a BOOL variable")
                        continue
                    sym.used = sym.written = True
                q = aa.qualifier
                if q not in ("N", "R", "S", "P", "L", "D", "SD", "DS", "SL", "P0", "P1"):
                    self.err("E030", aa.span, f"unknown action qualifier '{q}'")
                    continue
                if q in ("L", "D", "SD", "DS", "SL"):
                    if aa.time is None:
                        self.err("E030", aa.span, f"qualifier {q} needs a time, e.g. {aa.action}({q}, T#1s)")
                        continue
                    tt = self.expr(aa.time, scope, T.TIME)
                    if tt is not None and not T.base_of(tt).is_time:
                        self.err("E013", aa.time.span, f"the time of qualifier {q} must be a TIME, not {tt}")
                if key not in action_index:
                    action_index[key] = len(action_names)
                    action_names.append(key)
                sm.actions.append((key, q, aa.time))
        transitions = []
        for i, t in enumerate(d.transitions):
            srcs, dsts = [], []
            for names, out in ((t.sources, srcs), (t.targets, dsts)):
                for n, sp in names:
                    if n.lower() not in index:
                        self.err("E030", sp, f"unknown step '{n}'")
                    else:
                        out.append(index[n.lower()])
            prio = 0
            if t.priority is not None:
                c = self.const_value(t.priority, scope)
                prio = c if isinstance(c, int) else 0
            if t.cond is not None:
                ct = self.expr(t.cond, scope, T.BOOL)
                if not T.base_of(ct).is_bool:
                    self.err("E015", t.cond.span, f"a transition condition must be BOOL, not {ct}")
                cond = t.cond
            else:
                cond = None
                self.stmts(t.body or [], scope)
            transitions.append(TransitionModel(i, srcs, dsts, cond, prio, t.span))
        self.p.sfc[pou.name.lower()] = SfcModel(steps, transitions, action_names, action_index)

    # ---------------------------------------------------------------- statements
    def stmts(self, body: list, scope: Scope) -> None:
        for s in body:
            try:
                self.stmt(s, scope)
            except Exception as exc:
                if not hasattr(exc, "st_span"):
                    exc.st_span = s.span      # where the internal error happened, for the report
                raise

    def stmt(self, s: A.Stmt, scope: Scope) -> None:
        if isinstance(s, A.Assign):
            tt = self.lvalue(s.target, scope)
            if s.kind in ("S=", "R="):
                vt = self.expr(s.value, scope, T.BOOL)
                if not T.base_of(tt).is_bool or not T.base_of(vt).is_bool:
                    self.err("E013", s.span, f"'{s.kind}' needs BOOL operands")
                return
            vt = self.expr(s.value, scope, tt)
            if tt is not None:
                self.assignable(s.value, vt, tt, s.value.span)
        elif isinstance(s, A.CallStmt):
            self.call(s.call, scope, statement=True)
        elif isinstance(s, A.If):
            for cond, body in s.branches:
                self.condition(cond, scope, "IF")
                self.stmts(body, scope)
            if s.orelse:
                self.stmts(s.orelse, scope)
        elif isinstance(s, A.Case):
            self._case(s, scope)
        elif isinstance(s, A.For):
            vt = self.lvalue(s.var, scope)
            if vt is not None and not T.base_of(vt).is_intlike:
                self.err("E025", s.var.span, f"a FOR variable must be an integer, not {vt}")
            for e in (s.start, s.end, s.step):
                if e is not None:
                    et = self.expr(e, scope, vt)
                    if vt is not None:
                        self.assignable(e, et, vt, e.span)
            if isinstance(s.step, A.Expr):
                c = self.const_value(s.step, scope)
                if c == 0:
                    self.err("E029", s.step.span, "a FOR step of 0 never ends")
            scope.loop_depth += 1
            self.stmts(s.body, scope)
            scope.loop_depth -= 1
        elif isinstance(s, A.While):
            self.condition(s.cond, scope, "WHILE")
            scope.loop_depth += 1
            self.stmts(s.body, scope)
            scope.loop_depth -= 1
        elif isinstance(s, A.Repeat):
            scope.loop_depth += 1
            self.stmts(s.body, scope)
            scope.loop_depth -= 1
            self.condition(s.cond, scope, "UNTIL")
        elif isinstance(s, (A.Exit, A.Continue)):
            if scope.loop_depth == 0:
                self.err("E024", s.span, f"{'EXIT' if isinstance(s, A.Exit) else 'CONTINUE'} outside a loop")
        elif isinstance(s, (A.Return, A.Empty)):
            pass
        else:  # pragma: no cover
            raise AssertionError(s)

    def condition(self, e: A.Expr, scope: Scope, what: str) -> None:
        t = self.expr(e, scope, T.BOOL)
        if t is not None and not T.base_of(t).is_bool:
            self.err("E015", e.span, f"the {what} condition must be BOOL, not {t}",
                     "compare explicitly, e.g. x <> 0" if T.base_of(t).is_num else "")

    def _case(self, s: A.Case, scope: Scope) -> None:
        st = self.expr(s.selector, scope)
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
                    et = self.expr(e, scope, st)
                    if bst is not None and et is not None:
                        if isinstance(bst, T.EnumType):
                            if T.base_of(et) is not bst:
                                self.err("E019", e.span, f"CASE label of type {et} for a selector of type {st}")
                        elif not (T.base_of(et).is_intlike or et is T.LIT_INT):
                            self.err("E019", e.span, f"CASE label of type {et} for a selector of type {st}")
                    v = self.const_value(e, scope)
                    if v is None:
                        self.err("E029", e.span, "a CASE label must be a constant")
                    vals.append(v)
                if not all(isinstance(v, int) for v in vals):
                    continue        # a wrong label type was reported above
                if len(vals) == 2:
                    a, b = vals
                    for (c, d, sp) in seen:
                        if a <= d and c <= b:
                            self.err("E019", lo.span, f"CASE label {a}..{b} overlaps an earlier label")
                            break
                    seen.append((a, b, lo.span))
                elif len(vals) == 1:
                    a = vals[0]
                    for (c, d, sp) in seen:
                        if c <= a <= d:
                            self.err("E019", lo.span, f"duplicate CASE label {a}")
                            break
                    seen.append((a, a, lo.span))
            self.stmts(br.body, scope)
        if s.orelse:
            self.stmts(s.orelse, scope)

    # ---------------------------------------------------------------- assignability
    def assignable(self, e, src: Optional[T.Type], dst: Optional[T.Type], span: Span, what: str = "") -> bool:
        if src is None or dst is None:
            return True
        s, d = T.base_of(src), T.base_of(dst)
        if s is d:
            if isinstance(T.unalias(dst), T.SubrangeType) and isinstance(e, A.Expr):
                c = self.const_value(e, None) if isinstance(e, (A.Literal, A.Unary)) else None
                sub = T.unalias(dst)
                if isinstance(c, int) and not (sub.lo <= c <= sub.hi):
                    self.err("E021", span, f"{c} is outside the range {sub.lo}..{sub.hi} of {dst}")
                    return False
            return True
        what = what or "assign"
        if s is T.LIT_INT:
            if d.is_intlike or isinstance(T.unalias(dst), T.SubrangeType):
                v = self.const_value(e, None) if isinstance(e, A.Expr) else None
                if isinstance(v, int) and not T.literal_fits(v, dst):
                    self.err("E021", span, f"{v} does not fit in {dst} ({T.base_of(dst).lo}..{T.base_of(dst).hi})")
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
        if isinstance(s, T.ArrayType) and isinstance(d, T.ArrayType):
            if self._same_type(s, d) or (d.dims and d.dims[0] == (0, -1)):
                return True
        if isinstance(s, T.RefType) and isinstance(d, T.RefType):
            if self._same_type(s.target, d.target) or s.target is None:
                return True
        if s is _NULL and isinstance(d, T.RefType):
            return True
        if isinstance(s, T.ElemType) and isinstance(d, T.ElemType) and (
                s.kind in ("int", "real", "bit") and d.kind in ("int", "real", "bit")
                or s.kind == d.kind and s.kind in ("time", "date", "tod", "dt") and s.long and not d.long):
            conv = f"{s.name}_TO_{d.name}"
            self.err("E027", span, f"implicit conversion from {src} to {dst} may lose data",
                     f"convert explicitly with {conv}(...)")
            return False
        self.err("E013", span, f"type mismatch: cannot {what} {src} to {dst}")
        return False

    # ---------------------------------------------------------------- lvalues
    def lvalue(self, e: A.Expr, scope: Scope) -> Optional[T.Type]:
        t = self.expr(e, scope, lvalue=True)
        root = e
        while isinstance(root, (A.Field, A.Index, A.Bit)):
            root = root.base
        if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym) or isinstance(root, A.Name) \
                and isinstance(root.sym, T.VarSym):
            sym = e.sym if isinstance(e, A.Name) else root.sym
            sym.written = True
            g = sym.global_ref or sym
            if g.constant or sym.constant:
                self.err("E018", e.span, f"'{sym.name}' is a CONSTANT")
                return t
            if sym.section == "VAR_INPUT" and scope.pou is not None and sym.owner is scope.pou \
                    and not isinstance(T.unalias(sym.type), (T.POUType,)) and isinstance(e, A.Name):
                self.err("E018", e.span, f"'{sym.name}' is an input of {scope.pou.name} and cannot be written here",
                         "copy it into a local variable first")
                return t
        elif isinstance(e, (A.Literal, A.Call, A.Binary, A.Unary, A.EnumLit)):
            self.err("E013", e.span, "this expression cannot be assigned to")
        elif isinstance(e, A.Name) and e.sym is STEP:
            self.err("E013", e.span, "a step cannot be assigned to")
        return t

    # ---------------------------------------------------------------- expressions
    def expr(self, e: A.Expr, scope: Optional[Scope], expected: Optional[T.Type] = None, *,
             lvalue: bool = False) -> Optional[T.Type]:
        t = self._expr(e, scope or Scope(None, {}), expected, lvalue)
        e.ty = t
        return t

    def _expr(self, e, scope: Scope, expected, lvalue):
        if isinstance(e, A.Literal):
            return self._literal(e, expected)
        if isinstance(e, A.Name):
            return self._name(e, scope, expected)
        if isinstance(e, A.Binary):
            return self._binary(e, scope, expected)
        if isinstance(e, A.Unary):
            return self._unary(e, scope, expected)
        if isinstance(e, A.Call):
            return self.call(e, scope, expected=expected)
        if isinstance(e, A.Field):
            return self._field(e, scope)
        if isinstance(e, A.Index):
            return self._index(e, scope)
        if isinstance(e, A.Bit):
            bt = self.expr(e.base, scope)
            b = T.base_of(bt) if bt is not None else None
            if b is None:
                return T.BOOL
            size = e.size
            rt = {"X": T.BOOL, "B": T.BYTE, "W": T.WORD, "D": T.DWORD, "L": T.LWORD}[size]
            width = 1 if size == "X" else rt.bits
            if not b.is_intlike:
                self.err("E023", e.span, f"bit access needs an integer or bit-string variable, not {bt}")
                return rt
            if (e.index + 1) * width > b.bits:
                self.err("E022", e.span, f"{bt} has no {'bit' if size == 'X' else size} {e.index}")
            return rt
        if isinstance(e, A.Deref):
            bt = self.expr(e.base, scope)
            b = T.unalias(bt) if bt is not None else None
            if not isinstance(b, T.RefType):
                self.err("E023", e.span, f"'^' needs a reference, not {bt}")
                return None
            return b.target
        if isinstance(e, A.EnumLit):
            et = self._resolve_named_type(e.type_name.lower(), e.span)
            et = T.unalias(et) if et is not None else None
            if not isinstance(et, T.EnumType):
                self.err("E012", e.span, f"'{e.type_name}' is not an enumeration type")
                return None
            m = et.members.get(e.member.lower())
            if m is None:
                self.err("E010", e.span, f"'{e.member}' is not a value of {e.type_name}")
                return et
            e.const = m[1]
            return et
        if isinstance(e, A.Direct):
            m = _DIRECT.fullmatch(e.address)
            if not m or m.group(3) == "*":
                self.err("E004", e.span, f"malformed address '{e.address}'")
                return T.BOOL
            t = _DIRECT_TYPES[m.group(2)]
            pyname = "_d_" + e.address[1:].replace(".", "_")
            self.p.direct_vars[e.address if m.group(2) else e.address[:2] + "X" + e.address[2:]] = (pyname, t)
            e.const = None
            return t
        raise AssertionError(e)

    def _literal(self, e: A.Literal, expected):
        k = e.kind
        if e.type_name:
            tn = e.type_name
            if k in ("time", "date", "tod", "dt"):
                name = {"T": "TIME", "TIME": "TIME", "LT": "LTIME", "LTIME": "LTIME", "D": "DATE",
                        "DATE": "DATE", "LD": "LDATE", "LDATE": "LDATE", "TOD": "TOD", "TIME_OF_DAY": "TOD",
                        "LTOD": "LTOD", "LTIME_OF_DAY": "LTOD", "DT": "DT", "DATE_AND_TIME": "DT", "LDT": "LDT",
                        "LDATE_AND_TIME": "LDT"}[tn]
                return T.ELEMENTARY[name]
            t = T.ELEMENTARY.get(tn)
            if t is None:
                at = self._resolve_named_type(tn.lower(), e.span)
                if at is not None and T.base_of(at).is_elementary:
                    t = at
            if t is None:
                self.err("E012", e.span, f"unknown type '{tn}' in literal {e.text}")
                return None
            b = T.base_of(t)
            if k == "int":
                if b.is_bool:
                    if e.value not in (0, 1):
                        self.err("E021", e.span, f"{e.text} is not a BOOL value")
                    e.value = bool(e.value)
                elif b.is_real:
                    e.value = float(e.value)
                elif b.is_intlike:
                    if not T.literal_fits(e.value, t):
                        self.err("E021", e.span, f"{e.text} does not fit in {t}")
                else:
                    self.err("E013", e.span, f"{e.text}: an integer is not a {t}")
            elif k == "real" and not b.is_real:
                self.err("E013", e.span, f"{e.text}: a real number is not a {t}")
            elif k == "bool" and not (b.is_bool or b.is_intlike):
                self.err("E013", e.span, f"{e.text}: a BOOL is not a {t}")
            elif k in ("string", "wstring") and not (b.is_string or b.kind == "char"):
                self.err("E013", e.span, f"{e.text}: a string is not a {t}")
            if k == "bool" and b.is_intlike:
                e.value = int(e.value)
            return t
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

    def _lookup(self, key: str, scope: Scope):
        sym = scope.vars.get(key)
        if sym is not None:
            return sym
        if scope.pou is not None and scope.pou.pou_kind == "FUNCTION" and key == scope.pou.name.lower():
            return "RESULT"
        if key in scope.steps:
            return "STEP"
        gs = self.p.global_names.get(key)
        if gs:
            return gs[0]
        return None

    def _name(self, e: A.Name, scope: Scope, expected):
        key = e.name.lower()
        sym = self._lookup(key, scope)
        if sym == "RESULT":
            pou = scope.pou
            e.sym = pou
            return pou.return_type
        if sym == "STEP":
            e.sym = STEP
            e.const = scope.steps[key]
            return STEP
        if isinstance(sym, T.VarSym) and expected is not None and isinstance(T.base_of(expected), T.EnumType) \
                and key in T.base_of(expected).members and not isinstance(T.base_of(sym.type), T.EnumType):
            sym = None      # an enum value of the expected type wins over a same-named variable
        if isinstance(sym, T.VarSym):
            sym.used = True
            e.sym = sym
            if sym.constant and sym.const_value is not None:
                e.const = sym.const_value
            return sym.type
        if key == "null":
            e.sym = _NULL
            return _NULL
        mems = self.p.enum_members.get(key)
        if mems:
            pick = None
            if expected is not None:
                et = T.base_of(expected)
                for m in mems:
                    if m[0] is et:
                        pick = m
            if pick is None:
                if len(mems) > 1:
                    self.err("E010", e.span, f"'{e.name}' is a value of several enumerations",
                             f"qualify it, e.g. {mems[0][0].name}#{e.name}")
                pick = mems[0]
            e.sym = pick[0]
            e.const = pick[2]
            return pick[0]
        if key in self.p.pous or self._native(key) is not None:
            self.err("E026", e.span, f"'{e.name}' is a POU, not a value")
            return None
        self.err("E010", e.span, f"undeclared identifier '{e.name}'", self._suggest(key, scope))
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

    def _native(self, key: str) -> Optional[FuncSig]:
        for lib in self.libraries:
            sig = lib.lookup(key)
            if sig is not None:
                return sig
        return None

    def _binary(self, e: A.Binary, scope: Scope, expected):
        op = e.op
        hint = expected if op not in _CMP and op not in ("MOD", "**") else None
        lt = self.expr(e.left, scope, hint)
        rt = self.expr(e.right, scope, lt if lt is not None and not isinstance(lt, T.LiteralType) else hint)
        if isinstance(lt, T.LiteralType) and rt is not None and not isinstance(rt, T.LiteralType):
            lt = self.expr(e.left, scope, rt)
        if lt is None or rt is None:
            return T.BOOL if op in _CMP else (lt or rt)
        a, b = T.base_of(lt), T.base_of(rt)
        if op in _LOGIC:
            if a.is_bool and b.is_bool:
                return T.BOOL
            if op in ("AND_THEN", "OR_ELSE"):
                return self._bad_operands(e, lt, rt)
            if (a.is_intlike or a is T.LIT_INT) and (b.is_intlike or b is T.LIT_INT):
                c = T.common_type(a, b)
                if c is None:
                    return self._bad_operands(e, lt, rt)
                return c if not isinstance(c, T.LiteralType) else T.default_type_for_literal(c)
            return self._bad_operands(e, lt, rt)
        if op in _CMP:
            if isinstance(a, T.EnumType) or isinstance(b, T.EnumType):
                if a is b:
                    return T.BOOL
                return self._bad_operands(e, lt, rt)
            if isinstance(a, T.StringType) and isinstance(b, T.StringType):
                return T.BOOL
            if a.kind == "char" and isinstance(b, (T.StringType,)) or b.kind == "char" and isinstance(a, T.StringType):
                return T.BOOL
            if isinstance(a, T.RefType) and (isinstance(b, T.RefType) or b is _NULL) or a is _NULL:
                return T.BOOL
            c = T.common_type(a, b)
            if c is None or isinstance(c, (T.ArrayType, T.StructType, T.POUType)):
                return self._bad_operands(e, lt, rt)
            return T.BOOL
        # arithmetic
        if op in ("+", "-", "*", "/"):
            tt = self._time_arith(op, a, b)
            if tt is not None:
                return tt
            if (a.is_num or isinstance(a, T.LiteralType)) and (b.is_num or isinstance(b, T.LiteralType)):
                c = T.common_type(a, b)
                if c is None:
                    return self._bad_operands(e, lt, rt)
                return c
            if a.is_bit and b.is_bit or a.is_bit and b is T.LIT_INT or b.is_bit and a is T.LIT_INT:
                # IEC has no arithmetic on bit strings, but every dialect allows it
                return T.common_type(a, b)
            return self._bad_operands(e, lt, rt)
        if op == "MOD":
            if (a.is_intlike or a is T.LIT_INT) and (b.is_intlike or b is T.LIT_INT):
                c = T.common_type(a, b)
                if c is not None:
                    return c
            return self._bad_operands(e, lt, rt)
        if op == "**":
            if (a.is_num or isinstance(a, T.LiteralType)) and (b.is_num or isinstance(b, T.LiteralType)):
                if a.is_real:
                    return a
                if a is T.LIT_REAL or a is T.LIT_INT:
                    return T.LIT_REAL if (b is T.LIT_INT or b is T.LIT_REAL) else T.LREAL
                return T.REAL if a.bits <= 16 else T.LREAL
            return self._bad_operands(e, lt, rt)
        raise AssertionError(op)

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
        self.err("E014", e.span, f"operator {e.op} cannot combine {lt} and {rt}",
                 self._conv_hint(lt, rt))
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
        else:
            if b.is_num or isinstance(b, T.LiteralType) or b.is_time:
                if e.op == "-" and b.is_int and not b.signed:
                    self.warn("W005", e.span, f"negating an unsigned {t} wraps around")
                return t
        self.err("E014", e.span, f"operator {e.op} cannot be applied to {t}")
        return t

    def _field(self, e: A.Field, scope: Scope):
        if isinstance(e.base, A.Name) and self._lookup(e.base.name.lower(), scope) is None:
            et = self._resolve_named_type(e.base.name.lower(), e.base.span)
            if isinstance(T.unalias(et) if et is not None else None, T.EnumType):
                # Color.Red: CODESYS's qualified enumeration value
                et = T.unalias(et)
                m = et.members.get(e.name.lower())
                if m is None:
                    self.err("E010", e.name_span, f"'{e.name}' is not a value of {et.name}")
                    return et
                e.const = m[1]
                e.sym = et
                return et
        bt = self.expr(e.base, scope)
        if bt is None:
            return None
        b = T.unalias(bt)
        key = e.name.lower()
        if b is STEP:
            up = e.name.upper()
            if up == "X":
                return T.BOOL
            if up == "T":
                return T.TIME
            self.err("E023", e.name_span, f"a step has only the flags .X and .T, not .{e.name}")
            return None
        if isinstance(b, T.StructType):
            m = b.members.get(key)
            if m is None:
                self.err("E023", e.name_span, f"'{bt}' has no field '{e.name}'")
                return None
            e.sym = m
            return m.type
        if isinstance(b, T.POUType) and b.pou_kind != "FUNCTION":
            self._resolve_interface(b)
            v = b.vars.get(key)
            if v is None:
                if key in b.actions:
                    self.err("E026", e.name_span, f"'{e.name}' is an action; call it: {e.name}()")
                    return None
                self.err("E023", e.name_span, f"{b.name} has no variable '{e.name}'")
                return None
            if v.section in ("VAR", "VAR_TEMP") and b.pou_kind == "FUNCTION_BLOCK" and not b.library and \
                    scope.pou is not b:
                # IEC hides an FB's internal variables; most dialects let you read them
                pass
            v.used = True
            e.sym = v
            return v.type
        if isinstance(b, T.ElemType) and b.is_intlike and e.name.isdigit():
            return T.BOOL
        self.err("E023", e.span, f"'{bt}' is not a structure or function block instance, it has no field '{e.name}'")
        return None

    def _index(self, e: A.Index, scope: Scope):
        bt = self.expr(e.base, scope)
        for i in e.indices:
            it = self.expr(i, scope, T.DINT)
            if it is not None and not (T.base_of(it).is_intlike or it is T.LIT_INT or isinstance(T.base_of(it), T.EnumType)):
                self.err("E013", i.span, f"an array index must be an integer, not {it}")
        if bt is None:
            return None
        b = T.unalias(bt)
        if isinstance(b, T.StringType):
            self.err("E023", e.span, "strings cannot be indexed; use MID()")
            return None
        if not isinstance(b, T.ArrayType):
            self.err("E023", e.span, f"'{bt}' is not an array")
            return None
        if len(e.indices) != len(b.dims):
            # ARRAY OF ARRAY written a[i, j] is not allowed; a[i][j] is
            self.err("E023", e.span, f"this array has {len(b.dims)} dimension(s), not {len(e.indices)}")
            return b.element
        for i, (lo, hi) in zip(e.indices, b.dims):
            c = self.const_value(i, scope)
            if isinstance(c, int) and hi >= lo and not (lo <= c <= hi):
                self.err("E022", i.span, f"index {c} is outside the bounds {lo}..{hi}")
        return b.element

    # ---------------------------------------------------------------- calls
    def call(self, c: A.Call, scope: Scope, statement: bool = False, expected=None) -> Optional[T.Type]:
        callee = c.callee
        if isinstance(callee, A.Name):
            key = callee.name.lower()
            sym = self._lookup(key, scope)
            if isinstance(sym, T.VarSym) and not isinstance(T.unalias(sym.type), T.POUType) and (
                    key in self.p.pous or self._native(key) is not None):
                sym = None      # LEN(x) is the function even where a variable is called len
            if isinstance(sym, T.VarSym):
                sym.used = True
                callee.sym = sym
                callee.ty = sym.type
                return self._fb_call(c, sym.type, scope, statement)
            if key == "ref" and sym is None and key not in self.p.pous:
                return self._ref_call(c, scope)
            if key in scope.actions or (scope.pou is not None and key in scope.pou.actions):
                if c.args:
                    self.err("E017", c.span, "an action takes no arguments")
                c.target = CallTarget("action", name=key)
                return None
            pou = self.p.pous.get(key)
            if pou is not None:
                if pou.pou_kind != "FUNCTION":
                    self.err("E020", c.span, f"'{callee.name}' is a {pou.pou_kind.replace('_', ' ')} type; "
                             f"declare an instance and call that",
                             f"VAR inst : {pou.name}; END_VAR ... inst(...);")
                    return None
                self._resolve_interface(pou)
                return self._function_call(c, pou, scope)
            sig = self._native(key)
            if sig is not None:
                return self._native_call(c, sig, scope, expected)
            if self.p.enum_members.get(key) or sym is not None:
                self.err("E020", c.span, f"'{callee.name}' is not callable")
                return None
            self.err("E010", c.span, f"undeclared function or function block '{callee.name}'")
            for a in c.args:
                if not a.output:
                    self.expr(a.value, scope)
            return None
        # a call through a path: inst.sub(...), arr[i](...)
        t = self.expr(callee, scope)
        if t is None:
            return None
        return self._fb_call(c, t, scope, statement)

    def _ref_call(self, c: A.Call, scope: Scope):
        """REF(x): a reference to a variable (IEC 61131-3 3rd edition)."""
        if len(c.args) != 1 or c.args[0].name:
            self.err("E017", c.span, "REF takes exactly one variable")
            return None
        arg = c.args[0].value
        if not isinstance(arg, (A.Name, A.Field, A.Index)):
            self.err("E031", arg.span, "REF needs a variable")
            return None
        t = self.lvalue(arg, scope)
        root = arg
        while isinstance(root, (A.Field, A.Index)):
            root = root.base
        if isinstance(root, A.Name) and isinstance(root.sym, T.VarSym):
            root.sym.address_taken = True
        c.target = CallTarget("ref", arg=arg)
        return T.RefType(t) if t is not None else None

    def _fb_call(self, c: A.Call, t: T.Type, scope: Scope, statement: bool):
        fb = T.unalias(t)
        if not isinstance(fb, T.POUType) or fb.pou_kind == "FUNCTION":
            self.err("E020", c.span, f"a {t} is not callable")
            return None
        self._resolve_interface(fb)
        if not statement:
            self.err("E020", c.span, "a function block call is a statement; it has no value",
                     "call it, then read its outputs, e.g. inst(...); x := inst.Q;")
        bind = self._bind_args(c, fb, scope, is_fb=True)
        c.target = CallTarget("fb", pou=fb, bind=bind)
        return None

    def _function_call(self, c: A.Call, pou: T.POUType, scope: Scope):
        if scope.pou is not None:
            self._calls.setdefault(scope.pou.name.lower(), []).append((pou.name.lower(), c.span))
        bind = self._bind_args(c, pou, scope, is_fb=False)
        c.target = CallTarget("function", pou=pou, bind=bind)
        return pou.return_type

    def _bind_args(self, c: A.Call, pou: T.POUType, scope: Scope, is_fb: bool):
        """Match arguments to parameters: {lower param: Arg} plus EN/ENO."""
        params = pou.params()
        pos_params = params
        bind: dict = {}
        extras: dict = {}
        npos = 0
        for a in c.args:
            key = a.name.lower()
            if not a.name:
                if npos >= len(pos_params):
                    self.err("E017", a.span, f"too many arguments for {pou.name} (it has {len(pos_params)} parameters)")
                    self.expr(a.value, scope)
                    continue
                p = pos_params[npos]
                npos += 1
                if p.section == "VAR_OUTPUT":
                    a.output = True
                bind[p.name.lower()] = a
            elif key in ("en", "eno"):
                extras[key] = a
                if key == "eno" and "eno" in pou.vars:
                    bind[key] = a       # the body sets ENO itself
            else:
                p = pou.vars.get(key)
                if p is None or p.section not in _SECTIONS_PARAM:
                    names = ", ".join(x.name for x in params) or "none"
                    self.err("E016", a.span, f"{pou.name} has no parameter '{a.name}' (parameters: {names})")
                    if not a.output:
                        self.expr(a.value, scope)
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
                vt = self.lvalue(a.value, scope)
                pt = p.type
                if vt is not None and pt is not None and not (T.base_of(pt) is T.base_of(vt) or T.widens_to(pt, vt)):
                    self.assignable(None, pt, vt, a.value.span, "assign output")
            elif p.section == "VAR_IN_OUT":
                if not isinstance(a.value, (A.Name, A.Field, A.Index, A.Bit, A.Deref, A.Direct)):
                    self.err("E031", a.value.span, f"VAR_IN_OUT '{p.name}' needs a variable, not an expression")
                    continue
                vt = self.lvalue(a.value, scope)
                if vt is not None and not self._same_type(vt, p.type) and not (
                        isinstance(T.unalias(p.type), T.ArrayType) and T.unalias(p.type).dims[0] == (0, -1)):
                    if not (isinstance(T.base_of(vt), T.StringType) and isinstance(T.base_of(p.type), T.StringType)):
                        self.err("E013", a.value.span, f"VAR_IN_OUT '{p.name}' is {p.type}; {vt} cannot be passed")
            else:
                vt = self.expr(a.value, scope, p.type)
                self.assignable(a.value, vt, p.type, a.value.span, "pass")
        if "en" in extras:
            et = self.expr(extras["en"].value, scope, T.BOOL)
            if et is not None and not T.base_of(et).is_bool:
                self.err("E013", extras["en"].span, "EN must be BOOL")
        if "eno" in extras:
            a = extras["eno"]
            if not a.output:
                self.err("E016", a.span, "ENO is an output; use 'ENO => var'")
            else:
                self.lvalue(a.value, scope)
        if not is_fb:
            if npos and not any(a.name and a.name.lower() not in ("en", "eno") for a in c.args):
                # a non-formal call gives every input and in-out, in order (IEC 61131-3 6.6.1.4.2)
                needed = [p for p in params if p.section != "VAR_OUTPUT"]
                if npos < len(needed):
                    self.err("E017", c.span, f"{pou.name} takes {len(needed)} argument(s), not {npos}",
                             "name the arguments (x := ...) to leave some out")
                    return {"params": bind, "en": extras.get("en"), "eno": extras.get("eno")}
            for p in pou.in_outs():
                if p.name.lower() not in bind:
                    self.err("E017", c.span, f"VAR_IN_OUT '{p.name}' of {pou.name} must be given")
        return {"params": bind, "en": extras.get("en"), "eno": extras.get("eno")}

    def _native_call(self, c: A.Call, sig: FuncSig, scope: Scope, expected=None):
        args = []
        en = eno = None
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
                named[a.name.lower()] = a
            args.append(a)
        # named arguments in declaration order
        if named:
            ordered = []
            names = [p.name.lower() for p in sig.params]
            for a in args:
                if a.name:
                    key = a.name.lower()
                    if key not in names:
                        m = re.fullmatch(r"in(\d+)", key)
                        if sig.extensible and m:
                            continue
                        self.err("E016", a.span, f"{sig.name} has no parameter '{a.name}' "
                                 f"(parameters: {', '.join(p.name for p in sig.params)})")
                        return None
            pos = [a for a in args if not a.name]
            for i, p in enumerate(sig.params):
                a = named.get(p.name.lower())
                if a is None and pos:
                    a = pos.pop(0)
                if a is not None:
                    ordered.append(a)
            if sig.extensible:
                extra = sorted(((int(k[2:]), a) for k, a in named.items()
                                if re.fullmatch(r"in\d+", k) and k not in names), key=lambda x: x[0])
                ordered.extend(a for _, a in extra)
            ordered.extend(pos)
            args = ordered
        n = len(args)
        nmin = sig.min_args or len(sig.params)
        if n < nmin or (not sig.extensible and n > len(sig.params)):
            want = f"at least {nmin}" if sig.extensible else str(len(sig.params))
            self.err("E017", c.span, f"{sig.name} takes {want} argument(s), not {n}")
            for a in args:
                self.expr(a.value, scope)
            return None
        # types
        arg_types = []
        groups: dict = {}
        for i, a in enumerate(args):
            p = sig.params[min(i, len(sig.params) - 1)]
            want = T.ELEMENTARY.get(p.constraint)
            t = self.expr(a.value, scope, want)
            arg_types.append(t)
            if t is None:
                continue
            if not _satisfies(t, p.constraint):
                self.err("E013", a.value.span, f"argument {i + 1} of {sig.name} must be {p.constraint}, not {t}")
                arg_types[-1] = None
                continue
            if p.group:
                prev = groups.get(p.group)
                if prev is None:
                    groups[p.group] = t
                else:
                    ct = T.common_type(prev, t)
                    if ct is None and isinstance(T.base_of(prev), T.StringType) and isinstance(T.base_of(t), T.StringType):
                        ct = prev
                    if ct is None and isinstance(T.base_of(prev), T.EnumType) and T.base_of(prev) is T.base_of(t):
                        ct = prev
                    if ct is None:
                        self.err("E013", a.value.span, f"arguments of {sig.name} have incompatible types {prev} and {t}")
                    else:
                        groups[p.group] = ct
            elif want is not None:
                self.assignable(a.value, t, want, a.value.span, "pass")
        if any(t is None for t in arg_types):
            return None
        for g, t in list(groups.items()):
            if isinstance(t, T.LiteralType):
                # all-literal arguments take the type the context expects (IEC: ANY_NUM literals)
                eb = T.base_of(expected) if expected is not None else None
                if sig.result == g and eb is not None and isinstance(eb, T.ElemType) and \
                        (eb.is_num or (eb.is_bit and t is T.LIT_INT)) and not (t is T.LIT_REAL and not eb.is_real):
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
        if callable(res) and arg_types and all(isinstance(t, T.LiteralType) for t in arg_types) \
                and isinstance(eb, T.ElemType) and eb.is_real:
            # SQRT(2.0) in a REAL context computes in REAL
            for a in args:
                a.value.ty = eb
            arg_types = [eb] * len(arg_types)
        if getattr(sig, "result_from_context", False) and isinstance(eb, T.ElemType) and eb.is_int:
            rt = eb             # TRUNC: ANY_REAL → the integer type the context wants
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
            self.expr(en.value, scope, T.BOOL)
        if eno is not None:
            self.lvalue(eno.value, scope)
        c.target = CallTarget("native", sig=sig, args=args, arg_types=arg_types, en=en, eno=eno)
        return rt

    # ================================================================ configuration
    def _check_configuration(self, cfg: A.Configuration) -> None:
        cm = ConfigModel(cfg.name)
        scope = Scope(None, {})
        for res in cfg.resources:
            for td in res.tasks:
                tm = TaskModel(td.name, span=td.span)
                for k, v in td.params.items():
                    if k == "INTERVAL":
                        tt = self.expr(v, scope, T.TIME)
                        c = self.const_value(v, scope)
                        if tt is None or not T.base_of(tt).is_time or not isinstance(c, int):
                            self.err("E013", v.span, "INTERVAL must be a TIME constant, e.g. T#20ms")
                        elif c <= 0:
                            self.err("E029", v.span, "INTERVAL must be positive")
                        else:
                            tm.interval = c
                    elif k == "PRIORITY":
                        c = self.const_value(v, scope)
                        if not isinstance(c, int):
                            self.err("E029", v.span, "PRIORITY must be an integer constant")
                        else:
                            tm.priority = c
                    elif k == "SINGLE":
                        if isinstance(v, A.Name):
                            gs = self.p.global_names.get(v.name.lower())
                            if not gs:
                                self.err("E010", v.span, f"SINGLE refers to unknown variable '{v.name}'")
                            else:
                                tm.single = gs[0].pyname
                        else:
                            self.err("E013", v.span, "SINGLE must name a BOOL variable")
                    else:
                        self.err("E016", v.span, f"unknown task parameter '{k}' (INTERVAL, SINGLE, PRIORITY)")
                if any(t.name.lower() == td.name.lower() for t in cm.tasks):
                    self.err("E011", td.span, f"task '{td.name}' is declared twice")
                cm.tasks.append(tm)
            for pc in res.programs:
                pou = self.p.pous.get(pc.type_name.lower())
                if pou is None or pou.pou_kind != "PROGRAM":
                    self.err("E028", pc.span, f"'{pc.type_name}' is not a PROGRAM")
                    continue
                if pc.task and not any(t.name.lower() == pc.task.lower() for t in cm.tasks):
                    self.err("E028", pc.span, f"unknown task '{pc.task}'")
                    continue
                if any(i.name.lower() == pc.instance.lower() for i in cm.instances):
                    self.err("E011", pc.span, f"program instance '{pc.instance}' is declared twice")
                    continue
                im = InstanceModel(pc.instance, pou, pc.task, res.name, [], pc.span)
                for a in pc.args:
                    p = pou.vars.get(a.name.lower())
                    if p is None or p.section not in _SECTIONS_PARAM:
                        self.err("E016", a.span, f"{pou.name} has no parameter '{a.name}'")
                        continue
                    if a.output:
                        self.expr(a.value, scope)
                    else:
                        vt = self.expr(a.value, scope, p.type)
                        self.assignable(a.value, vt, p.type, a.value.span, "pass")
                    im.args.append((p, a.value, a.output))
                cm.instances.append(im)
        for b in cfg.var_blocks:
            if b.kind == "VAR_CONFIG":
                for d in b.decls:
                    if self._config_path_type(cm, d) is not None:
                        cm.var_config.append((d.path or [], d.location, d.init, d.type, d.span))
        self.p.configs.append(cm)

    def _config_path_type(self, cm: ConfigModel, d: A.VarDecl):
        """Check a VAR_CONFIG entry `inst.fb.var AT %QX0.0 : T := v;`; its variable's type or None."""
        path = d.path or []
        inst = next((i for i in cm.instances if path and i.name.lower() == path[0].lower()), None)
        if inst is None:
            self.err("E010", d.span, f"VAR_CONFIG: no program instance named '{path[0] if path else ''}'")
            return None
        t: T.Type = inst.type
        for name in path[1:]:
            ut = T.unalias(t)
            sym = ut.vars.get(name.lower()) if isinstance(ut, T.POUType) else None
            if sym is None:
                self.err("E010", d.span, f"VAR_CONFIG: {'.'.join(path)}: '{name}' is not a variable of {ut}")
                return None
            t = sym.type
        want = self.resolve_type(d.type, None)
        if not self._same_type(want, t):
            self.err("E013", d.type.span, f"VAR_CONFIG: {'.'.join(path)} is {t}, not {want}")
            return None
        if d.location:
            self._check_location(d.location, t, d.span)
        if d.init is not None:
            self.check_initializer(d.init, t, None)
        return t

    def _implicit_configuration(self) -> None:
        progs = [p for p in self.p.pous.values() if p.pou_kind == "PROGRAM" and not p.library]
        cm = ConfigModel("", implicit=True)
        cm.tasks.append(TaskModel("main", 0, 0))
        for p in progs:
            cm.instances.append(InstanceModel(p.name, p, "main", "", [], p.decl.span if p.decl else None))
        self.p.configs.append(cm)

    # ================================================================ cycles
    def _check_cycles(self) -> None:
        """A type may not contain itself, and POUs may not call themselves (IEC forbids recursion)."""
        def members(t):
            t = T.unalias(t)
            if isinstance(t, T.ArrayType):
                return members(t.element)
            if isinstance(t, T.StructType):
                return [m.type for m in t.members.values()]
            if isinstance(t, T.POUType) and t.pou_kind != "FUNCTION":
                return [v.type for v in t.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_IN_OUT")]
            return []

        def leaf(t):
            t = T.unalias(t)
            while isinstance(t, T.ArrayType):
                t = T.unalias(t.element)
            return t if isinstance(t, (T.StructType, T.POUType)) else None

        for t in list(self.p.types.values()) + list(self.p.pous.values()):
            start = leaf(t)
            if start is None:
                continue
            seen, stack = set(), [leaf(m) for m in members(start)]
            while stack:
                x = stack.pop()
                if x is None or id(x) in seen:
                    continue
                if x is start:
                    span = self._decl_span.get(start.name.lower())
                    self.err("E012", span or Span("<types>", 0, 0), f"'{start.name}' contains itself")
                    break
                seen.add(id(x))
                stack.extend(leaf(m) for m in members(x))
        # calls
        for pou in self.p.pous.values():
            seen, stack = set(), list(self._calls.get(pou.name.lower(), ()))
            while stack:
                name, span = stack.pop()
                if name == pou.name.lower():
                    self.err("E032", span, f"{pou.name} calls itself (recursion is not allowed in IEC 61131-3)")
                    break
                if name in seen:
                    continue
                seen.add(name)
                stack.extend(self._calls.get(name, ()))

    # ================================================================ warnings
    def _warn_unused(self) -> None:
        for pou in self.p.pous.values():
            if pou.library:
                continue
            for sym in pou.vars.values():
                if sym.section in ("VAR", "VAR_TEMP") and not sym.used and not sym.location:
                    self.warn("W002", sym.span, f"variable '{sym.name}' is never used")


def _names_in(body):
    """Every Name node in a statement list."""
    stack = list(body)
    while stack:
        x = stack.pop()
        if isinstance(x, A.Name):
            yield x
            continue
        if isinstance(x, list):
            stack.extend(x)
        elif isinstance(x, tuple):
            stack.extend(x)
        elif hasattr(x, "__dataclass_fields__"):
            for f in x.__dataclass_fields__:
                if f in ("span", "ty", "const", "sym"):
                    continue
                v = getattr(x, f, None)
                if isinstance(v, CallTarget):
                    continue
                if isinstance(v, (list, tuple)) or hasattr(v, "__dataclass_fields__"):
                    stack.append(v)


class _NullType(T.Type):
    kind = "null"
    name = "NULL"


_NULL = _NullType()


def _satisfies(t: T.Type, constraint: str) -> bool:
    b = T.base_of(t)
    if constraint == "ANY":
        return True
    if isinstance(b, T.LiteralType):
        if constraint in ("ANY_NUM", "ANY_MAGNITUDE", "ANY_ELEMENTARY"):
            return True
        if constraint in ("ANY_INT", "ANY_BIT", "ANY_INTLIKE"):
            return b is T.LIT_INT
        if constraint == "ANY_REAL":
            return True
        c = T.ELEMENTARY.get(constraint)
        if c is not None:
            return c.is_num or (c.is_bit and b is T.LIT_INT)
        return False
    k = b.kind
    if constraint == "ANY_NUM":
        return k in ("int", "real")
    if constraint == "ANY_REAL":
        return k in ("int", "real")     # integers are accepted and computed as LREAL
    if constraint == "ANY_INT":
        return k == "int" or k == "bit"
    if constraint == "ANY_BIT":
        return k in ("bit", "int", "bool")
    if constraint == "ANY_INTLIKE":
        return k in ("bit", "int")
    if constraint == "ANY_MAGNITUDE":
        return k in ("int", "real", "time")
    if constraint == "ANY_STRING":
        return k == "string"
    if constraint == "ANY_DATE":
        return k in ("date", "tod", "dt")
    if constraint == "ANY_ELEMENTARY":
        return b.is_elementary or isinstance(b, T.EnumType)
    if constraint == "ANY_CHARS":
        return k in ("string", "char")
    c = T.ELEMENTARY.get(constraint)
    if c is None:
        return False
    return b is c or T.widens_to(b, c)
