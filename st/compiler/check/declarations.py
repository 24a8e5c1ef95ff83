"""Declarations: named types resolved, POU interfaces (variables, methods, properties, bases, interfaces)
declared, variable blocks declared, initial values checked. Resolution is on demand: a type or a POU
is resolved when first met, so declarations may come in any order."""

from __future__ import annotations

from collections import ChainMap
from collections.abc import Callable, Mapping
from typing import cast

from ...diagnostics import Code
from ...model import types as T
from ...model.addresses import AddressError, UnplacedAddress, parse_address
from ...source import Span
from .. import ast as A
from ..names import mangle, qualified
from ..syntax import block_decl, decl_of, declared, interface_decl
from .common import (
    _DIRECT,
    _DIRECT_TYPES,
    ANY_FAMILIES,
    CONSTRUCTION,
    THIS,
    Scope,
    _names_in,
    take_address,
)
from .expressions import _zero_pointer
from .memo import remembered
from .part import Part
from .passes.namespaces import unknown_namespace
from .rules import (
    abstract,
    array_bounds,
    hidden_variable,
    inheritance,
    initializers,
    located_type,
    reference_binding,
    self_containment,
    storage_limits,
)
from .rules.openplc_address import openplc_address
from .targets import SizeofCall

# the sections each kind of POU may declare
_SECTIONS = {
    "FUNCTION": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL", "VAR_STAT"},
    "FUNCTION_BLOCK": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL", "VAR_STAT"},
    "PROGRAM": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL", "VAR_GLOBAL"},
    "TEST": {"VAR", "VAR_TEMP"},
}


class Declarations(Part):
    _pending_inits: list | None = None
    """The initial values of the POU whose variables are being declared, checked once all are."""
    _at_run_time = False
    """FB_init arguments of __NEW are being checked: any variable of the code may be read."""

    # ================================================================ types
    def resolve_named_type(self, key: str, span: Span) -> T.Type | None:
        if key in self.p.types:
            return self.p.types[key]
        if key not in self.ctx.pending_types:
            return None
        if key in self.ctx.resolving:
            self_containment.report_named_type(self.ctx, key, span)
            return None
        td, lib = self.ctx.pending_types[key]
        self.ctx.resolving.add(key)
        try:
            t = self._type_from_decl(td)
        finally:
            self.ctx.resolving.discard(key)
        self.p.types[key] = t
        return t

    def _union_member(self, d: A.VarDecl, t: T.Type) -> None:
        """A UNION member is bytes another member also is: an elementary value (a number, bit
        string, BOOL, time, date or string) or an array of them; and it has no initial value of its own."""
        spec = T.byte_layout(t)
        if spec is None or spec[0] in ("r", "u") or (spec[0] == "a" and spec[2][0] in ("a", "r", "u", "s")):
            self.err(
                Code.BAD_TYPE,
                d.type.span,
                f"a UNION member must be an elementary value or a one-dimensional array of numbers, not {t}",
            )
        initializers.check_union_member(self.ctx, d)

    def _type_from_decl(self, td: A.TypeDecl) -> T.Type:
        spec = td.spec
        if isinstance(spec, A.EnumType):
            if isinstance(td.init, A.Name) and not spec.default:
                spec.default = td.init.name  # TYPE E : (A, B) := B;
            elif td.init is not None:
                initializers.check_enum_default(self.ctx, td.init, spec)
            return self._enum(td.name, spec)
        if isinstance(spec, A.StructType):
            return self._struct(td, spec)
        if isinstance(spec, A.SubrangeType):
            t = self.resolve_type(spec, None)
            if isinstance(t, T.SubrangeType):
                t = T.SubrangeType(td.name, t.base, t.lo, t.hi, t.outside)
            if td.init is not None:
                self.check_initializer(td.init, t, None)
                return T.AliasType(td.name, t, td.init)
            return t
        target = self.resolve_type(spec, None)
        if td.init is not None:
            self.check_initializer(td.init, target, None)
        return T.AliasType(td.name, target, td.init)

    def _struct(self, td: A.TypeDecl, spec: A.StructType) -> T.StructType:
        st = T.StructType(td.name, pyname="_st_" + mangle(td.name), kind="union" if spec.union else "struct")
        self.p.types[td.name.lower()] = st  # allow references to itself through REF_TO
        if spec.extends is not None:  # the base's fields come first, as declared there
            self.feature("vendor", spec.extends.span, "STRUCT EXTENDS")
            bt = T.unalias(self.resolve_type(spec.extends, None))
            if isinstance(bt, T.StructType):
                st.members.update(bt.members)
            else:
                self.err(Code.BAD_TYPE, spec.extends.span, f"a structure can only extend a structure, not {bt}")
        for d in spec.members:
            mt = self.resolve_type(d.type, None)
            for n, sp in d.names:
                if n.lower() in st.members:
                    self.err(Code.DECLARED_TWICE, sp, f"field '{n}' is declared twice in {td.name}")
                    continue
                st.members[n.lower()] = T.Member(n, mt, sp, d.init, mangle(n))
                if spec.union:
                    self._union_member(d, mt)
                elif d.init is not None:
                    self.check_initializer(d.init, mt, None)
        if spec.union:
            self.feature("vendor", spec.span, "UNION")
        st.resolved = True
        return st

    def _enum(self, name: str, spec: A.EnumType) -> T.EnumType:
        base = T.INT
        if spec.base:
            b = T.ELEMENTARY.get(spec.base.upper())
            if not isinstance(b, T.ElemType) or not b.is_intlike:  # (only an ElemType is int-like)
                self.err(
                    Code.BAD_TYPE, spec.span, f"an enumeration's base type must be an integer type, not '{spec.base}'"
                )
            else:
                base = b
        et = T.EnumType(name or "enum", base=base)
        nxt = 0
        for v in spec.values:
            if v.value is not None:
                c = self.consts.value(v.value, None)
                if not isinstance(c, int):
                    self.err(Code.NOT_CONSTANT, v.span, f"the value of '{v.name}' must be an integer constant")
                    c = nxt
                nxt = c
            if v.name.lower() in et.members:
                self.err(Code.DECLARED_TWICE, v.span, f"'{v.name}' appears twice in the enumeration")
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
                self.err(Code.UNDECLARED, spec.span, f"'{spec.default}' is not a value of this enumeration")
            else:
                et.default_value = m[1]
        return et

    def resolve_type(self, spec: A.TypeSpec, scope: Scope | None) -> T.Type:
        resolve = _TYPE_SPECS.get(type(spec))
        if resolve is None:
            raise AssertionError(spec)
        return resolve(self, spec, scope)

    def _named_type(self, spec: A.NamedType, scope: Scope | None) -> T.Type:
        initializers.check_type_has_no_arguments(self.ctx, spec)
        key = spec.name.lower()
        up = spec.name.upper()
        if up in T.ELEMENTARY:
            return T.ELEMENTARY[up]
        t = self.resolve_named_type(key, spec.span)
        if t is not None:
            return t
        if up == "BIT" and key not in self.p.pous and self.ctx.feature_quiet("vendor"):
            return T.BOOL  # CODESYS's BIT (structures, blocks): one BOOL; st does not pack bits
        pou = self.p.pous.get(key)
        if pou is not None:
            if pou.pou_kind == "FUNCTION":
                self.err(Code.BAD_TYPE, spec.span, f"'{spec.name}' is a FUNCTION, not a type")
                return T.INT
            return pou
        self.err(
            Code.BAD_TYPE, spec.span, unknown_namespace(spec.name, self.ctx.namespaces) or f"unknown type '{spec.name}'"
        )
        return T.INT

    def _string_type(self, spec: A.StringType, scope: Scope | None) -> T.Type:
        n = 80
        if spec.length is not None:
            c = self.consts.value(spec.length, scope)
            if not isinstance(c, int) or c < 1:
                self.err(Code.NOT_CONSTANT, spec.span, "a string length must be a positive integer constant")
            else:
                n = c
        return T.StringType(n, spec.wide)

    def _array_type(self, spec: A.ArrayType, scope: Scope | None) -> T.Type:
        dims = []
        for r in spec.ranges:
            if r is None:
                dims.append((0, -1))  # ARRAY[*]: bounds come from the argument
                continue
            lo, hi = self.consts.value(r[0], scope), self.consts.value(r[1], scope)
            if not isinstance(lo, int) or not isinstance(hi, int):
                self.err(Code.NOT_CONSTANT, spec.span, "array bounds must be integer constants")
                lo, hi = 0, 0
            elif hi < lo:
                self.err(Code.NOT_CONSTANT, spec.span, f"empty array range {lo}..{hi}")
                hi = lo
            dims.append((lo, hi))
        elem = self.resolve_type(spec.element, scope)
        at = T.ArrayType(dims, elem)
        storage_limits.check_array_size(self.ctx, at, spec.span)
        return at

    def _ref_type(self, spec: A.RefType, scope: Scope | None) -> T.Type:
        if spec.kind != "REF_TO":
            self.feature("vendor", spec.span, f"{spec.kind} TO")
        return T.RefType(self.resolve_type(spec.target, scope), spec.kind)

    def _subrange_type(self, spec: A.SubrangeType, scope: Scope | None) -> T.Type:
        base = cast(T.ElemType | None, T.ELEMENTARY.get(spec.base.upper()))
        if base is None or not base.is_intlike:
            self.err(Code.BAD_TYPE, spec.span, f"a subrange needs an integer base type, not '{spec.base}'")
            base = T.INT
        lo, hi = self.consts.value(spec.lo, scope), self.consts.value(spec.hi, scope)
        if not isinstance(lo, int) or not isinstance(hi, int):
            self.err(Code.NOT_CONSTANT, spec.span, "subrange bounds must be integer constants")
            lo, hi = base.lo, base.hi
        outside = self.ctx.dialect.subranges if self.ctx.dialect is not None else "fault"
        return T.SubrangeType(f"{base.name}({lo}..{hi})", base, lo, hi, outside)

    def _enum_type(self, spec: A.EnumType, scope: Scope | None) -> T.Type:
        return self._enum("", spec)

    def _struct_type(self, spec: A.StructType, scope: Scope | None) -> T.Type:
        self.err(Code.BAD_TYPE, spec.span, "STRUCT is only allowed in a TYPE declaration")
        return T.INT

    def check_ctor_args(self, init: A.CtorInit, t: T.Type, scope: Scope, at_run_time: bool) -> None:
        """FB_init arguments outside a declaration: `__NEW(FB(a := v))`, where `at_run_time` they
        may be any expressions of the code around them."""
        outer, self._at_run_time = self._at_run_time, at_run_time
        try:
            self._check_ctor_args(init, t, scope, True)
        finally:
            self._at_run_time = outer

    def _check_ctor_args(self, init: A.CtorInit, t: T.Type, scope: Scope | None, variables: bool = False) -> None:
        """`inst : FB(a := 1)`: the arguments go to the inputs of FB's FB_init (CODESYS)."""
        if not self._at_run_time:
            self.feature("vendor", init.span, "FB_init arguments in a declaration")
        if not initializers.check_constructed(self.ctx, init, t):
            return
        bt = cast(T.POUType, T.unalias(t))
        self.resolve_interface(bt)
        mt = bt.methods.get("fb_init")
        if mt is None:
            self.err(Code.ARGUMENT_COUNT, init.span, f"{bt.name} has no FB_init method to take these arguments")
            return
        inputs = {p.name.lower(): p for p in mt.params() if p.section == "VAR_INPUT"}
        own = [p.name for p in inputs.values() if p.name.lower() not in ("binitretains", "bincopycode")]
        seen = set()
        named = False
        for i, (name, sp, val) in enumerate(init.args):
            named = named or bool(name)
            if not name:  # positional: the inputs FB_init declares after bInitRetains, bInCopyCode
                if named:
                    self.err(Code.ARGUMENT_COUNT, sp, "a positional argument cannot follow named ones")
                    continue
                if i >= len(own):
                    self.err(
                        Code.ARGUMENT_COUNT,
                        sp,
                        f"FB_init of {bt.name} takes {len(own)} argument(s) here, not {len(init.args)}",
                    )
                    continue
                name = own[i]
                init.args[i] = (name, sp, val)
            p = inputs.get(name.lower())
            if p is None or name.lower() in ("binitretains", "bincopycode"):
                self.err(Code.BAD_PARAMETER, sp, f"FB_init of {bt.name} has no input '{name}' to set here")
                continue
            if name.lower() in seen:
                self.err(Code.BAD_PARAMETER, sp, f"'{name}' is given twice")
            seen.add(name.lower())
            self.check_initializer(val, p.type, scope, variables)
        if init.inner is not None:
            self.check_initializer(init.inner, t, scope, variables)

    def _bound_initializer(self, init: A.Expr, t: T.Type, bt: T.Type, scope: Scope | None, variables: bool) -> bool:
        """An initial value that names another variable of the instance (or a global) rather than
        a value (CODESYS): `p : POINTER TO INT := ADR(x)`, `r : REF_TO INT := REF(x)`, an interface
        variable `itf : I_X := inst`, a REFERENCE TO input of FB_init `fs : FB_S(other := a)`.
        Only in a function block or program, where the variable outlives the initial value; the
        instance or interface must be declared above (initial values are set in declaration order)
        unless `variables` (CODESYS: rules/initialization_order.py orders them). Returns False when `init` is not such a value (the constant rule applies)."""
        if scope is None or scope.pou is None or scope.pou.pou_kind not in ("FUNCTION_BLOCK", "PROGRAM"):
            return False
        is_ref = T.is_reference(t)
        is_itf = isinstance(bt, T.POUType) and bt.pou_kind == "INTERFACE"
        target: A.Expr = init
        if isinstance(init, A.Call) and isinstance(init.callee, A.Name) and len(init.args) == 1:
            if init.callee.name.upper() not in ("REF", "ADR") or init.args[0].name:
                return False
            target = init.args[0].value
        elif not (is_ref or is_itf):
            return False
        root = target
        while isinstance(root, (A.Field, A.Index)):
            root = root.base
        if not isinstance(root, A.Name):
            return False
        sym = self.exprs.lookup(root.name.lower(), scope)
        if isinstance(sym, T.VarSym) and sym.owner is scope.pou and _below(sym.span, init.span) and not variables:
            sym = None  # declared below the variable it initialises: not set yet
        if sym is None and _declared_in(scope.pou, root.name):
            self.err(
                Code.NOT_CONSTANT,
                root.span,
                f"'{root.name}' is declared below; initial values are set in declaration order",
                f"declare '{root.name}' above the variable it initialises",
            )
            return True
        if not isinstance(sym, T.VarSym) or sym.section in ("VAR_TEMP", "VAR_IN_OUT") or sym.constant:
            return False
        if target is init and is_ref:  # bound like REF=: the variable itself, of the referenced type
            self.feature("vendor", init.span, "a REFERENCE TO initialised with a variable")
            vt = self.exprs.expr(init, scope)
            want = cast(T.RefType, T.unalias(t)).target
            reference_binding.check_initial_reference(self.ctx, init, want, vt)
        else:
            vt = self.exprs.expr(init, scope, t)
            if vt is not None:
                self.stmts.assignable(init, vt, t, init.span)
        take_address(target)
        for n in _names_in([target]):  # indices must still be constants
            if (
                n is not root
                and isinstance(n.sym, T.VarSym)
                and not (n.sym.global_ref or n.sym).constant
                and not (variables and _readable_at_init(n.sym, scope))
            ):
                self.err(
                    Code.NOT_CONSTANT,
                    n.span,
                    f"an index in an initial value must be a constant; '{n.name}' is a variable",
                )
        return True

    # ================================================================ interfaces
    def resolve_interface(self, pou: T.POUType) -> None:
        if pou.resolved or pou.decl is None:
            return
        pou.resolved = True
        d = decl_of(pou)
        scope = Scope(pou, pou.vars)
        if d.kind == "FUNCTION_BLOCK":
            scope.fb = pou  # THIS in an initial value (`fbState : FB_Off(THIS);`, CODESYS)
        if d.kind == "INTERFACE":
            return self._resolve_itf(pou)
        if d.kind == "FUNCTION":
            if d.return_type is not None:
                pou.return_type = self.resolve_type(d.return_type, scope)
        base = self._base_of(pou) if isinstance(d, A.POU) and d.kind == "FUNCTION_BLOCK" and d.extends else None
        if base is not None:  # inherited variables come first, as declared there
            pou.base = base
            for k, v in base.vars.items():
                if k not in ("en", "eno"):
                    pou.vars[k] = v
        self.declare_blocks(d.var_blocks, pou.vars, scope, pou)
        if d.kind in ("FUNCTION", "FUNCTION_BLOCK"):
            self._implicit_en_eno(pou)
        self._declare_members(pou)
        if base is not None:
            _inherit(pou, base)
        if isinstance(d, A.POU) and d.kind == "FUNCTION_BLOCK" and d.implements:
            self._link_interfaces(pou)

    def _implicit_en_eno(self, pou: T.POUType) -> None:
        """EN and ENO are implicit in every function and FB; declared when the body uses them."""
        d = decl_of(pou)
        mentioned = remembered(self.ctx.memo, "names", (d.body,), lambda: {n.name.lower() for n in _names_in(d.body)})
        for key, section in (("en", "VAR_INPUT"), ("eno", "VAR_OUTPUT")):
            if key in mentioned and key not in pou.vars:
                true = A.Literal(d.span, "bool", True, "", "TRUE")
                pou.vars[key] = T.VarSym(
                    key.upper(), T.BOOL, section, d.span, true, pyname=key.upper(), owner=pou, used=True
                )

    def _declare_members(self, pou: T.POUType) -> None:
        """A POU's actions, methods and properties."""
        d = decl_of(pou)
        for act in d.actions:
            if act.name.lower() in pou.actions:
                self.err(Code.DECLARED_TWICE, act.span, f"action '{act.name}' is declared twice")
            pou.actions[act.name.lower()] = act
        for m in getattr(d, "methods", ()):
            self._declare_method(pou, m)
        for pr in getattr(d, "properties", ()):
            self._declare_property(pou, pr)

    def _link_interfaces(self, fb: T.POUType) -> None:
        """FUNCTION_BLOCK … IMPLEMENTS I1, I2: the interfaces it provides (whether it implements them
        fully is an object-oriented rule, checked later)."""
        for name in block_decl(fb).implements:
            itf = self._interface_named(name, decl_of(fb).span, f"{fb.name} IMPLEMENTS")
            if itf is not None:
                fb.interfaces.append(itf)

    def _interface_named(self, name: str, span, who: str):
        if name.lower() == "__system.iqueryinterface":
            # CODESYS's root interface for __QUERYINTERFACE: every interface here can be queried
            self.feature("vendor", span, "__SYSTEM.IQueryInterface")
            return None
        itf = self.p.pous.get(name.lower())
        if itf is None or itf.pou_kind != "INTERFACE":
            what = "not declared" if itf is None else f"a {itf.pou_kind.replace('_', ' ')}, not an INTERFACE"
            msg = unknown_namespace(name, self.ctx.namespaces) if itf is None else ""
            self.err(
                Code.BAD_TYPE if itf is not None else Code.UNDECLARED,
                span,
                f"{who}: {msg or repr(name) + ' is ' + what}",
            )
            return None
        self.resolve_interface(itf)
        return itf

    def _resolve_itf(self, itf: T.POUType) -> None:
        """An INTERFACE: its method prototypes and those of the interfaces it EXTENDS."""
        d = interface_decl(itf)
        for name in d.extends:
            base = self._interface_named(name, d.span, f"INTERFACE {itf.name} EXTENDS")
            if base is None:
                continue
            if not self_containment.check_interface_extends(self.ctx, itf, base):
                continue
            itf.interfaces.append(base)
        for m in d.methods:
            inheritance.check_interface_method_body(self.ctx, itf, m)
            self._declare_method(itf, m)
        for pr in d.properties:
            bare = pr.get is None and pr.set is None
            if bare:  # a bare prototype: both accessors
                pr.get = A.Method(pr.span, pr.name, [], pr.type)
                pr.set = A.Method(pr.span, pr.name, [])
            self._declare_property(itf, pr)
            if bare and pr.name.lower() in itf.properties:
                itf.properties[pr.name.lower()].bare = True
        for base in itf.interfaces:
            for k, bp in base.properties.items():
                itf.properties.setdefault(k, bp)
            for k, bm in base.methods.items():
                mine = itf.methods.get(k)
                if mine is None:
                    itf.methods[k] = bm
                else:
                    inheritance.check_interface_extension(self.ctx, itf, base, mine, bm)

    def _declare_property(self, owner: T.POUType, pr) -> None:
        """PROPERTY: GET is a method returning the property's type under its name; SET a method whose
        input has the property's name."""
        key = pr.name.lower()
        if (
            key in owner.vars
            or key in owner.methods
            or (key in owner.properties and owner.properties[key].owner is owner)
        ):
            self.err(Code.DECLARED_TWICE, pr.span, f"'{pr.name}' is declared twice in {owner.name}")
            return
        t = self.resolve_type(pr.type, Scope(owner, owner.vars))
        ps = T.PropSym(pr.name, t, owner=owner, span=pr.span)
        if pr.get is not None:
            pr.get.return_type = pr.type
            ps.get = self._accessor(owner, pr.get, "_pg_")
        if pr.set is not None:
            blocks = pr.set.var_blocks
            if not (blocks and blocks[0].span is pr.span):  # (added by an earlier check of this tree)
                value = A.VarDecl(pr.span, [(pr.name, pr.span)], pr.type)
                blocks.insert(0, A.VarBlock(pr.span, "VAR_INPUT", [], [value]))
            ps.set = self._accessor(owner, pr.set, "_ps_")
        if ps.get is None and ps.set is None:
            self.err(Code.BAD_TYPE, pr.span, f"property {pr.name} has neither GET nor SET")
        owner.properties[key] = ps

    def _accessor(self, owner: T.POUType, m, prefix: str) -> T.POUType:
        # the getter is named like the property (its result); the setter's input carries that name
        mt = T.POUType(m.name if prefix == "_pg_" else f"{m.name}.SET", "FUNCTION", decl=m, library=owner.library)
        mt.pyname = prefix + mangle(m.name)
        mt.owner_fb = owner
        mt.resolved = True
        scope = Scope(mt, mt.vars)
        if m.return_type is not None:
            mt.return_type = self.resolve_type(m.return_type, scope)
        self.declare_blocks(m.var_blocks, mt.vars, scope, mt)
        return mt

    def _base_of(self, pou: T.POUType):
        """The function block `pou` EXTENDS, resolved and checked (None after an error)."""
        d = block_decl(pou)
        base = self.p.pous.get(d.extends.lower())
        if base is None:
            msg = unknown_namespace(d.extends, self.ctx.namespaces)
            self.err(Code.UNDECLARED, d.span, msg or f"{pou.name} extends '{d.extends}', which is not declared")
            return None
        if base.pou_kind != "FUNCTION_BLOCK":
            kind = base.pou_kind.replace("_", " ")
            self.err(
                Code.BAD_TYPE,
                d.span,
                f"{pou.name} can only extend a FUNCTION_BLOCK; '{base.name}' is "
                f"{'an' if kind[0] in 'AEIOU' else 'a'} {kind}",
            )
            return None
        if not self_containment.check_extends_chain(self.ctx, pou, base):
            return None
        if not inheritance.check_extensible(self.ctx, pou, base):
            return None
        self.resolve_interface(base)
        return base

    def _declare_method(self, fb: T.POUType, m) -> None:
        """A METHOD: a function whose body also sees the instance's variables (and THIS)."""
        key = m.name.lower()
        if (key in fb.methods and fb.methods[key].owner_fb is fb) or key in fb.vars or key in fb.actions:
            self.err(Code.DECLARED_TWICE, m.span, f"'{m.name}' is declared twice in {fb.name}")
            return
        if fb.pou_kind == "PROGRAM":
            self.feature("vendor", m.span, "a METHOD of a PROGRAM")
        mt = T.POUType(m.name, "FUNCTION", decl=m, library=fb.library)
        mt.pyname = "_m_" + mangle(m.name)
        mt.owner_fb = fb
        mt.resolved = True
        # its initial values see its own variables, then the instance's (CODESYS: a VAR_INST
        # `p : Randomizer(_positionDist);` names a variable of the block)
        scope = Scope(mt, ChainMap(mt.vars, fb.vars))
        scope.fb = fb
        if m.return_type is not None:
            mt.return_type = self.resolve_type(m.return_type, scope)
        self.declare_blocks(m.var_blocks, mt.vars, scope, mt)
        for v in mt.vars.values():
            hidden_variable.check_hidden_variable(self.ctx, fb, m.name, v)
            if v.section == "VAR_INST":  # kept in the instance between calls
                self.feature("vendor", v.span, "VAR_INST")
                v.pyname = "_mi_" + qualified(m.name, v.name)
            if key in CONSTRUCTION and v.section in ("VAR_IN_OUT", "VAR_OUTPUT"):
                self.err(
                    Code.MISPLACED_SECTION, v.span, f"{m.name} runs when the instance is created: it takes inputs only"
                )
        fb.methods[key] = mt

    def declare_block(self, block: A.VarBlock, table: dict, scope: Scope | None, owner) -> None:
        kind = self._section_kind(block, owner)
        if kind is None:
            return
        access = self._access(block, kind, owner)
        for decl in block.decls:
            t, family = self._decl_type(decl, kind, scope, owner)
            if decl.location:
                # the address as written stays beside the one read (a tree checked again, as the
                # language server does, reads the written one again, and warns again)
                decl.written_location = decl.written_location or decl.location
                where = decl.names[0][1] if decl.names else decl.span
                decl.location = openplc_address(self.ctx, decl.written_location, where)
            for n, sp in decl.names:
                self._declare_name(n, sp, decl, t, kind, block, access, family, table, owner)
            self._declare_init(decl, t, kind, block, table, scope, owner)
            if kind in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and owner is None:
                self.err(Code.MISPLACED_SECTION, decl.span, f"{kind} is only allowed in a POU")

    def _section_kind(self, block: A.VarBlock, owner) -> str | None:
        """The section the block's variables are declared in (VAR for one the POU may not have, so
        that its names are still known), None when there is nothing to declare here."""
        kind = block.kind
        if owner is None:
            return kind
        allowed = _SECTIONS[owner.pou_kind]
        if getattr(owner, "owner_fb", None) is not None:
            allowed = allowed | {"VAR_INST"}  # a METHOD's variables that live in the instance
        if kind not in allowed:
            self.err(Code.MISPLACED_SECTION, block.span, f"{kind} is not allowed in a {owner.pou_kind}")
            if kind in ("VAR_GLOBAL", "VAR_ACCESS", "VAR_CONFIG"):
                return None
            kind = "VAR"  # still declare the names: no cascade of 'undeclared' errors
        if kind == "VAR_GLOBAL":
            self.ctx.global_blocks.append((owner.name, block))
            return None
        return kind

    def _access(self, block: A.VarBlock, kind: str, owner) -> list[str]:
        """The block's access specifiers (PRIVATE, PROTECTED, ...): for the VARs of a function block."""
        access = [q for q in block.qualifiers if q in ("PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL")]
        if not access:
            return access
        if (
            owner is None
            or owner.pou_kind != "FUNCTION_BLOCK"
            or kind != "VAR"
            or getattr(owner, "owner_fb", None) is not None
        ):
            self.err(
                Code.MISPLACED_SECTION,
                block.span,
                f"{access[0]} applies to the VAR sections of function blocks and "
                f"classes (inputs and outputs are always public)",
            )
        else:
            self.feature("oop", block.span, f"VAR {access[0]}")
        if len(access) > 1:
            self.err(
                Code.MISPLACED_SECTION,
                block.span,
                f"a VAR section has one access specifier, not {' and '.join(access)}",
            )
        return access

    def _decl_type(self, decl: A.VarDecl, kind: str, scope: Scope | None, owner) -> tuple[T.Type, str]:
        """The declared type and, for an ANY input, its family."""
        family = self._any_input(decl, kind, owner)
        t = self.resolve_type(A.NamedType(decl.type.span, "AnyType"), scope) if family else None
        if t is None:
            family = ""
            t = self.resolve_type(decl.type, scope)
        if T.is_conformant(t) and kind != "VAR_IN_OUT":
            self.err(
                Code.BAD_TYPE,
                decl.type.span,
                "ARRAY[*] takes its bounds from an argument: it is only allowed for a VAR_IN_OUT",
            )
        abstract.check_declared_instance(self.ctx, t, kind, decl.type.span)
        if isinstance(t, T.POUType) and t.pou_kind == "PROGRAM" and owner is not None and owner.pou_kind != "TEST":
            self.err(Code.BAD_TYPE, decl.type.span, f"a PROGRAM ('{t.name}') cannot be instantiated inside a POU")
        return t, family

    def _declare_name(self, n: str, sp: Span, decl: A.VarDecl, t, kind, block, access, family, table, owner) -> None:
        key = n.lower()
        if key in table:
            self.err(Code.DECLARED_TWICE, sp, f"'{n}' is declared twice")
            return
        if (
            owner is not None
            and owner.pou_kind == "FUNCTION"
            and key == owner.name.lower()
            and (owner.return_type is not None or getattr(owner.decl, "return_type", None) is not None)
        ):  # a FUNCTION without a result type has no variable of its name (TwinCAT)
            self.err(Code.DECLARED_TWICE, sp, f"'{n}' is the function's own name (its return value)")
            return
        quals = block.qualifiers
        sym = T.VarSym(
            n,
            t,
            kind,
            sp,
            decl.init,
            decl.location,
            constant="CONSTANT" in quals,
            retain="RETAIN" in quals,
            persistent="PERSISTENT" in quals,
            edge=decl.edge,
            pyname=mangle(n),
            owner=owner,
        )
        if kind == "VAR_EXTERNAL":
            sym.is_global = True
        sym.any_input = family
        if access:
            sym.access = access[0]
        if kind == "VAR_STAT" and owner is not None:
            # static: one variable shared by every instance and call, kept as a module global
            self.feature("vendor", sp, "VAR_STAT")
            sym.is_global = True
            where = [owner.name] if getattr(owner, "owner_fb", None) is None else [owner.owner_fb.name, owner.name]
            sym.pyname = "_gs_" + qualified(*where, n)
            self.p.globals[sym.pyname] = sym
        table[key] = sym
        if decl.location:
            self.check_location(decl.location, t, sp)

    def _declare_init(self, decl: A.VarDecl, t: T.Type, kind: str, block, table, scope: Scope | None, owner) -> None:
        """The initial value: a global's once every global is declared, a POU variable's now (or
        once the globals are, if they are not yet: it may name a global constant)."""
        if decl.init is None or kind == "VAR_EXTERNAL":
            return
        if isinstance(decl.init, A.ArrayCtorInit):  # FB_init arguments element by element
            decl.init = initializers.expand_array_ctor(self.ctx, decl.init, t)
            for n, _ in decl.names:
                if n.lower() in table:
                    table[n.lower()].init = decl.init
            if decl.init is None:
                return
        if owner is None:
            self.ctx.deferred_inits.append((decl, t))
            return
        variables = "CONSTANT" not in block.qualifiers and _evaluated_in_place(kind, owner)
        if not self.ctx.globals_declared:
            self.ctx.deferred_pou_inits.append((decl, t, scope, variables))
        elif self._pending_inits is not None:  # once every variable of the POU is declared
            self._pending_inits.append((decl, t, scope, variables))
        else:
            self.check_initializer(decl.init, t, scope, variables)
        if "CONSTANT" in block.qualifiers:
            cv = self.consts.value(decl.init, scope) if isinstance(decl.init, A.Expr) else None
            if cv is not None:
                for n, _ in decl.names:
                    table[n.lower()].const_value = cv

    def declare_blocks(self, blocks: list[A.VarBlock], table: dict, scope: Scope, owner) -> None:
        """A POU's VAR sections: its VAR CONSTANT sections first, since CODESYS lets an initial value
        name a constant declared below (`t : TON := (PT := GAP);` above `GAP : TIME := T#10MS;`);
        `table` keeps the order of declaration."""
        before = list(table)
        constants_first = sorted(blocks, key=lambda b: 0 if b.kind == "VAR" and "CONSTANT" in b.qualifiers else 1)
        outer, self._pending_inits = self._pending_inits, []
        try:
            for block in constants_first:
                self.declare_block(block, table, scope, owner)
        finally:
            pending, self._pending_inits = self._pending_inits, outer
        for decl, t, sc, variables in pending:  # an initial value may name a variable declared below it
            self.check_initializer(decl.init, t, sc, variables)
        order = before + [n.lower() for b in blocks for d in b.decls for n, _ in d.names]
        declared = {k: table[k] for k in order if k in table}
        declared.update(table)
        table.clear()
        table.update(declared)

    def _any_input(self, decl: A.VarDecl, kind: str, owner) -> str:
        """`x : ANY` (or ANY_NUM, ...) as an input of a function, block or method (CODESYS,
        TwinCAT): the family, the argument then arriving as an AnyType (TypeClass, pValue, diSize);
        "" for any other declaration. A vendor extension; elsewhere the generic names stay unknown
        types, as IEC leaves them to the standard functions."""
        spec = decl.type
        if not (isinstance(spec, A.NamedType) and spec.name.upper() in ANY_FAMILIES):
            return ""
        if kind != "VAR_INPUT" or owner is None or owner.pou_kind not in ("FUNCTION", "FUNCTION_BLOCK"):
            self.err(
                Code.BAD_TYPE, spec.span, f"{spec.name.upper()} is for the inputs of functions, blocks and methods only"
            )
            return ""
        if not self.feature("vendor", spec.span, f"an {spec.name.upper()} input"):
            return ""
        if self.resolve_named_type("anytype", spec.span) is None:
            return ""
        return spec.name.upper()

    def check_location(self, loc: str, t: T.Type, span: Span) -> None:
        """A variable of type `t` declared AT `loc` (at `span`): the address is well formed, in the
        process image (st/model/addresses.py) and as wide as the type. A hierarchical address
        (`%QX0.4.2`, `%IW2.5`) that reaches here (not read the OpenPLC way: openplc_address) is
        accepted where the preset's compiler accepts it (iec, codesys, twincat: its place is the I/O
        configuration's; `st run` refuses it, located), refused under openplc and the default."""
        m = _DIRECT.fullmatch(loc.upper())
        if not m:
            self.err(Code.MALFORMED_LITERAL, span, f"malformed address '{loc}'")
            return
        size = m.group(2)
        if m.group(3) == "*":
            return
        try:
            parse_address(loc)
        except UnplacedAddress as e:
            if self.ctx.dialect is None or self.ctx.dialect.dotted_word_addresses:
                self.err(Code.MALFORMED_LITERAL, span, str(e))
                return
        except AddressError as e:
            self.err(Code.MALFORMED_LITERAL, span, str(e))
            return
        located_type.check_located_type(self.ctx, loc, t, size, _DIRECT_TYPES[size], span)

    # ================================================================ initializers
    def check_initializer(self, init, t: T.Type, scope: Scope | None, variables: bool = False) -> None:
        """The initial value `init` of a `t`; `variables`: it is evaluated where the variables it may
        name have their values (a block's instance variable, a FUNCTION's or METHOD's local), so
        CODESYS lets it name them (rules/initialization_order.py orders them)."""
        if isinstance(init, A.CtorInit):
            return self._check_ctor_args(init, t, scope, variables)
        if isinstance(init, A.ArrayInit):
            return self._array_initializer(init, t, scope, variables)
        if isinstance(init, A.StructInit):
            return self._struct_initializer(init, t, scope, variables)
        if isinstance(init, A.Expr):
            self._value_initializer(init, t, scope, variables)
        return None

    def _array_initializer(self, init: A.ArrayInit, t: T.Type, scope: Scope | None, variables: bool) -> None:
        if not initializers.check_array_form(self.ctx, init, t):
            return
        bt = cast(T.ArrayType, T.unalias(t))
        count = 0
        for item in init.items:
            if isinstance(item, A.RepeatInit):
                for sub in item.items:
                    self.check_initializer(sub, bt.element, scope, variables)
                count += item.count * max(1, len(item.items))
            else:
                self.check_initializer(item, bt.element, scope, variables)
                count += 1
        array_bounds.check_initializer_count(self.ctx, init, count, bt.size)

    def _struct_initializer(self, init: A.StructInit, t: T.Type, scope: Scope | None, variables: bool) -> None:
        bt = T.unalias(t)
        fields: Mapping[str, T.Member | T.VarSym]
        if isinstance(bt, T.StructType):
            fields, what = bt.members, "field"
        elif isinstance(bt, T.POUType) and bt.pou_kind != "FUNCTION":
            self.resolve_interface(bt)
            fields, what = bt.vars, "variable"
        else:
            initializers.check_structure_form(self.ctx, init, t)
            return
        for name, sp, val in init.fields:
            m = fields.get(name.lower())
            if m is None and isinstance(bt, T.POUType) and name.lower() in bt.properties:
                ps = bt.properties[name.lower()]  # TwinCAT: a property given its value through SET
                if ps.set is None:
                    self.err(Code.BAD_ACCESS, sp, f"property {ps.name} of {bt.name} has no SET to give it a value")
                    continue
                self.feature("oop", sp, "a property's initial value")
                self.check_initializer(val, ps.type, scope, variables)
                continue
            if m is None:
                self.err(Code.BAD_ACCESS, sp, f"'{t}' has no {what} '{name}'")
                continue
            self.check_initializer(val, m.type, scope, variables)

    def _value_initializer(self, init: A.Expr, t: T.Type, scope: Scope | None, variables: bool) -> None:
        if not initializers.check_single_value(self.ctx, init, t):
            return
        variables = variables and self.ctx.feature_quiet("vendor")
        if self._bound_initializer(init, t, T.unalias(t), scope, variables):
            return
        if _zero_pointer(self.ctx, init, t):
            return  # a literal 0 for a POINTER, a REF_TO or an interface (CODESYS): NULL
        st = self.exprs.expr(init, scope or Scope(None, {}), t)
        sized = {
            id(n)
            for c in A.walk_nodes(init)
            if isinstance(c, A.Call) and isinstance(c.target, SizeofCall)
            for n in _names_in(c.args)
        }  # SIZEOF(buffer): its size, a constant, not its value
        for n in _names_in([init]):
            if id(n) in sized:
                continue
            if n.sym is THIS and not variables:
                self.err(Code.NOT_CONSTANT, n.span, "an initial value must be a constant; THIS is the instance")
                return
            if (
                isinstance(n.sym, T.VarSym)
                and not (n.sym.global_ref or n.sym).constant
                and not (variables and (self._at_run_time or _readable_at_init(n.sym, scope)))
            ):
                self.err(
                    Code.NOT_CONSTANT,
                    n.span,
                    f"an initial value must be a constant; '{n.name}' is a variable",
                    "assign it in the code instead, or declare it CONSTANT",
                )
                return
        self.stmts.assignable(init, st, t, init.span)


_TYPE_SPECS: dict[type, Callable[..., T.Type]] = {
    A.NamedType: Declarations._named_type,
    A.StringType: Declarations._string_type,
    A.ArrayType: Declarations._array_type,
    A.RefType: Declarations._ref_type,
    A.SubrangeType: Declarations._subrange_type,
    A.EnumType: Declarations._enum_type,
    A.StructType: Declarations._struct_type,
}


def _evaluated_in_place(kind: str, owner) -> bool:
    """Is the initial value of a variable of section `kind` of `owner` evaluated where the variables
    it may name have values: an instance variable of a block or program (when the instance is
    created), a local or an input's default of a FUNCTION or METHOD (at every call)?"""
    if owner is None or getattr(owner, "owner_fb", None) is not None or owner.pou_kind == "FUNCTION":
        # (a METHOD's VAR_INST: when the instance is created, after the block's own variables)
        return owner is not None and (
            kind in ("VAR", "VAR_TEMP", "VAR_INPUT") or kind == "VAR_INST" and owner.owner_fb is not None
        )
    return owner.pou_kind in ("FUNCTION_BLOCK", "PROGRAM") and kind in ("VAR", "VAR_INPUT", "VAR_OUTPUT")


def _readable_at_init(sym: T.VarSym, scope: Scope | None) -> bool:
    """May an initial value in `scope` read the variable `sym` (CODESYS)? A global; in a block or
    program, its instance variables (not a VAR_TEMP or VAR_IN_OUT, unset then); in a FUNCTION or
    METHOD, its own parameters and locals and a method's instance variables."""
    if sym.is_global or sym.section == "VAR_EXTERNAL":
        return True
    if scope is None or scope.pou is None:
        return False
    inst = scope.pou.owner_fb
    if scope.pou.pou_kind == "FUNCTION" and sym.owner is scope.pou:
        return True
    block = inst if inst is not None else scope.pou if scope.pou.pou_kind != "FUNCTION" else None
    return (
        block is not None
        and any(v is sym for v in block.vars.values())
        and sym.section not in ("VAR_TEMP", "VAR_IN_OUT")
    )


def _below(a: Span | None, b: Span | None) -> bool:
    """Is position a after position b in the same file?"""
    return a is not None and b is not None and a.file == b.file and (a.line, a.col) > (b.line, b.col)


def _declared_in(pou: T.POUType, name: str) -> bool:
    """Is `name` declared anywhere in the POU's own declaration (above or below)?"""
    key = name.lower()
    d = declared(pou)
    return d is not None and any(n.lower() == key for vb in d.var_blocks for vd in vb.decls for n, _ in vd.names)


def _inherit(pou: T.POUType, base: T.POUType) -> None:
    """What a block inherits from its base besides its variables."""
    for k, ba in base.actions.items():
        pou.actions.setdefault(k, ba)  # actions are inherited; a same-named one replaces it
    for k, bp in base.properties.items():
        pou.properties.setdefault(k, bp)  # an own property of that name overrides it
    for k, bm in base.methods.items():
        pou.methods.setdefault(k, bm)  # an own method of that name overrides it
