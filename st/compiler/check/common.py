"""Shared pieces of the checker: scopes, the STEP and NULL pseudo-types, generic constraints (call
targets: targets.py)."""

from __future__ import annotations

import re
from collections.abc import Callable, MutableMapping

from ...model import types as T
from ...model.addresses import AddressError, parse_address
from .. import ast as A
from .targets import CallTarget

_SECTIONS_PARAM = ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")
_LOGIC = {"AND", "OR", "XOR", "AND_THEN", "OR_ELSE"}
_CMP = {"=", "<>", "<", ">", "<=", ">="}
_DIRECT = re.compile(r"%([IQM])([XBWDL]?)(\*|[0-9]+(?:\.[0-9]+)*)")
# CODESYS's implicit methods: FB_init runs when an instance is created (before the first scan)
CONSTRUCTION = ("fb_init", "fb_reinit", "fb_exit")
_DIRECT_TYPES = {"X": T.BOOL, "": T.BOOL, "B": T.BYTE, "W": T.WORD, "D": T.DWORD, "L": T.LWORD}


def image_problem(addr: str):
    """Why the process image cannot hold this address (the runtime's own rule), or None."""
    try:
        parse_address(addr)
    except AddressError as e:
        return str(e)
    return None


class StepType(T.Type):
    kind = "step"
    name = "STEP"


STEP = StepType()


class Scope:
    def __init__(self, pou: T.POUType | None, vars: MutableMapping, *, library: str = ""):
        self.pou = pou
        self.vars = vars
        self.loop_depth = 0
        self.steps: dict = {}
        self.actions: dict = {}
        self.library = library
        self.test = False  # inside TEST/SETUP/TEARDOWN: test statements allowed
        self.fb: T.POUType | None = None  # the function block whose body or METHOD this is (THIS, implicit calls)


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


class _ThisSym:
    """The symbol of THIS: a reference to the instance a function block body or method runs on."""

    kind = "this"
    name = "THIS"


THIS = _ThisSym()


class _SuperSym:
    """SUPER: the instance seen as its base function block (calls are not virtual)."""

    kind = "super"
    name = "SUPER"


SUPER = _SuperSym()


def take_address(e) -> None:
    """The variable under `e` (x, x.f, x[i]) is referred to: it must stay reachable (not a cached
    local) while a reference to it exists."""
    root = e
    while isinstance(root, (A.Field, A.Index)):
        root = root.base
    if isinstance(root, A.Name) and isinstance(root.sym, T.VarSym):
        root.sym.address_taken = True


def names_constant(part, e, scope: Scope) -> bool:
    """Does the variable path `e` (x, x.f, x[i], GVL.x), not typed yet, name a CONSTANT or a part
    of one? (`part`: the checker's Part, for its look-ups.)"""
    root = e
    while isinstance(root, (A.Field, A.Index)):
        if isinstance(root, A.Field) and isinstance(root.base, A.Name) and part.exprs.names_gvl(root.base, scope):
            g = part.ctx.gvls[root.base.name.lower()].get(root.name.lower())  # GVL.x
            return isinstance(g, T.VarSym) and g.constant
        root = root.base
    sym = part.exprs.lookup(root.name.lower(), scope) if isinstance(root, A.Name) else None
    return isinstance(sym, T.VarSym) and (sym.global_ref or sym).constant


def method_of(fb, key: str):
    """The METHOD `key` of a function block (None when it has none by that name)."""
    return fb.methods.get(key) if fb is not None else None


# the generic type names a user POU's input may be declared with (CODESYS, TwinCAT)
ANY_FAMILIES = frozenset(
    {"ANY", "ANY_NUM", "ANY_REAL", "ANY_INT", "ANY_BIT", "ANY_STRING", "ANY_DATE", "ANY_ELEMENTARY", "ANY_MAGNITUDE"}
)


def _satisfies(t: T.Type, constraint: str) -> bool:
    """Does a value of type `t` meet a library parameter's constraint (ANY_NUM, INT, ...)?"""
    b = T.base_of(t)
    if constraint == "ANY":
        return True
    if " or " in constraint:  # either family (SUB: "ANY_MAGNITUDE or ANY_DATE")
        return any(_satisfies(t, c) for c in constraint.split(" or "))
    if constraint == "ANY_POINTER":  # a POINTER, REF_TO or ADR(...) (the vendor memory functions)
        return isinstance(T.unalias(t), T.RefType)
    if isinstance(b, T.LiteralType):
        return _literal_satisfies(b, constraint)
    family = _FAMILIES.get(constraint)
    if family is not None:
        return family(b)
    c = T.ELEMENTARY.get(constraint)
    if c is None:
        return False
    return b is c or T.widens_to(b, c)


def _literal_satisfies(b: T.LiteralType, constraint: str) -> bool:
    if constraint in ("ANY_NUM", "ANY_MAGNITUDE", "ANY_ELEMENTARY", "ANY_REAL"):
        return True
    if constraint in ("ANY_INT", "ANY_BIT", "ANY_INTLIKE"):
        return b is T.LIT_INT
    c = T.ELEMENTARY.get(constraint)
    if c is not None:
        return c.is_num or (c.is_bit and b is T.LIT_INT)
    return False


# the generic families of the library's parameters, for a value of a declared type (by its base)
_FAMILIES: dict[str, Callable[[T.Type], bool]] = {
    "ANY_NUM": lambda b: b.kind in ("int", "real"),
    "ANY_REAL": lambda b: b.kind in ("int", "real"),  # integers are accepted and computed as LREAL
    "ANY_INT": lambda b: b.kind in ("int", "bit"),
    "ANY_BIT": lambda b: b.kind in ("bit", "int", "bool"),
    "ANY_INTLIKE": lambda b: b.kind in ("bit", "int"),
    "ANY_MAGNITUDE": lambda b: b.kind in ("int", "real", "time"),
    "ANY_STRING": lambda b: b.kind == "string",
    "ANY_DATE": lambda b: b.kind in ("date", "tod", "dt"),
    "ANY_ELEMENTARY": lambda b: b.is_elementary or isinstance(b, T.EnumType),
    "ANY_CHARS": lambda b: b.kind in ("string", "char"),
}


def same_type(a: T.Type, b: T.Type) -> bool:
    """Are these the same type (aliases seen through; strings of any length, subranges of one base)?"""
    a, b = T.unalias(a), T.unalias(b)
    if a is b:
        return True
    if isinstance(a, T.StringType) and isinstance(b, T.StringType):
        return a.wide == b.wide
    if isinstance(a, T.ArrayType) and isinstance(b, T.ArrayType):
        return a.dims == b.dims and same_type(a.element, b.element)
    if isinstance(a, T.SubrangeType) or isinstance(b, T.SubrangeType):
        return T.base_of(a) is T.base_of(b)
    if isinstance(a, T.RefType) and isinstance(b, T.RefType):
        return same_type(a.target, b.target)
    return False


def signature(mt: T.POUType) -> tuple:
    """A method's parameters and return type, as an override or an implementation must repeat them."""
    return (
        [(v.name.lower(), v.section, str(v.type)) for v in mt.params()],
        str(mt.return_type) if mt.return_type is not None else None,
    )
