"""Shared pieces of the checker: scopes, the STEP and NULL pseudo-types, generic constraints (call
targets: targets.py)."""

from __future__ import annotations

import re

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


_WORD_WITH_BIT = re.compile(r"(%[IQM][BWDL][0-9]+)((?:\.[0-9]+)+)", re.I)


def openplc_address(ctx, addr: str, span) -> str:
    """OpenPLC binds a byte, word, double or long address by its first number only (its glue
    generator drops the rest: %IW0.0 is %IW0); under openplc and the default the address is read so,
    with a warning; the other presets keep it as written (and refuse it)."""
    m = _WORD_WITH_BIT.fullmatch(addr.strip())
    if m is None or not (ctx.dialect is None or ctx.dialect.name == "openplc"):
        return addr
    ctx.warn(
        "W011",
        span,
        f"'{addr}': OpenPLC binds it to {m.group(1).upper()} and ignores '{m.group(2)}'",
        f"write {m.group(1).upper()}; only bit addresses (X) have a '.'",
    )
    return m.group(1)


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
    def __init__(self, pou: T.POUType | None, vars: dict, *, library: str = ""):
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


def method_of(fb, key: str):
    """The METHOD `key` of a function block (None when it has none by that name)."""
    return fb.methods.get(key) if fb is not None else None


# the generic type names a user POU's input may be declared with (CODESYS, TwinCAT)
ANY_FAMILIES = frozenset(
    {"ANY", "ANY_NUM", "ANY_REAL", "ANY_INT", "ANY_BIT", "ANY_STRING", "ANY_DATE", "ANY_ELEMENTARY", "ANY_MAGNITUDE"}
)


def _satisfies(t: T.Type, constraint: str) -> bool:
    b = T.base_of(t)
    if constraint == "ANY":
        return True
    if constraint == "ANY_POINTER":  # a POINTER, REF_TO or ADR(...) (the vendor memory functions)
        return isinstance(T.unalias(t), T.RefType)
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
        return k in ("int", "real")  # integers are accepted and computed as LREAL
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
