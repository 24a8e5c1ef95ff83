"""The IEC type model: elementary types, strings, arrays, structs, enums, refs, POUs.

Runtime representation (what generated code stores), decided here once:
BOOL → bool; integers and bit strings → int; REAL/LREAL → float;
TIME/DATE/TOD/DT (and L-variants) → int nanoseconds; STRING/WSTRING/CHAR → str;
enums → int; arrays → list (multi-dimensional: flat, row-major); structs and
FB/program instances → instances of generated slotted classes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..source import Span
from .summaries import InitialValue, PouInfo
from .syntax import Syntax


class Type:
    name: str = "?"
    kind: str = "?"

    def __str__(self) -> str:
        return self.name

    @property
    def is_int(self) -> bool:
        return self.kind == "int"

    @property
    def is_bit(self) -> bool:
        return self.kind == "bit"

    @property
    def is_intlike(self) -> bool:
        return self.kind in ("int", "bit")

    @property
    def is_real(self) -> bool:
        return self.kind == "real"

    @property
    def is_num(self) -> bool:
        return self.kind in ("int", "real")

    @property
    def is_bool(self) -> bool:
        return self.kind == "bool"

    @property
    def is_string(self) -> bool:
        return self.kind == "string"

    @property
    def is_time(self) -> bool:
        return self.kind == "time"

    @property
    def is_datetime(self) -> bool:
        return self.kind in ("date", "tod", "dt")

    @property
    def is_elementary(self) -> bool:
        return self.kind in ("bool", "int", "bit", "real", "time", "date", "tod", "dt", "string", "char")

    @property
    def is_aggregate(self) -> bool:
        return self.kind in ("array", "struct", "union", "fb")


@dataclass(eq=False)
class ElemType(Type):
    name: str
    kind: str
    bits: int = 0
    signed: bool = False
    lo: Any = None
    hi: Any = None
    default: Any = 0
    long: bool = False  # LTIME, LDATE, ... (64-bit variants)

    def __repr__(self) -> str:
        return self.name

    def __reduce__(self) -> tuple[Any, ...]:
        # keep the canonical instances canonical across pickling (the compile cache)
        if ELEMENTARY.get(self.name) is self or ELEMENTARY.get({"TIME_OF_DAY": "TOD"}.get(self.name, "")) is self:
            return (_elementary, (self.name,))
        return (_rebuild, (type(self), dict(self.__dict__)))


def _elementary(name: str) -> Type:
    return ELEMENTARY[name]


def _rebuild(cls: type[Type], state: dict[str, Any]) -> Type:
    obj = cls.__new__(cls)
    obj.__dict__.update(state)
    return obj


def _int(name: str, bits: int, signed: bool) -> ElemType:
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    return ElemType(name, "int", bits, signed, lo, hi, 0)


def _bit(name: str, bits: int) -> ElemType:
    return ElemType(name, "bit", bits, False, 0, (1 << bits) - 1, 0)


BOOL = ElemType("BOOL", "bool", 1, False, 0, 1, False)
SINT, INT, DINT, LINT = _int("SINT", 8, True), _int("INT", 16, True), _int("DINT", 32, True), _int("LINT", 64, True)
USINT, UINT, UDINT, ULINT = (
    _int("USINT", 8, False),
    _int("UINT", 16, False),
    _int("UDINT", 32, False),
    _int("ULINT", 64, False),
)
BYTE, WORD, DWORD, LWORD = _bit("BYTE", 8), _bit("WORD", 16), _bit("DWORD", 32), _bit("LWORD", 64)
REAL = ElemType("REAL", "real", 32, True, -3.4028234663852886e38, 3.4028234663852886e38, 0.0)
LREAL = ElemType("LREAL", "real", 64, True, -1.7976931348623157e308, 1.7976931348623157e308, 0.0)
_T64 = (-(1 << 63), (1 << 63) - 1)
TIME = ElemType("TIME", "time", 64, True, *_T64, 0)
LTIME = ElemType("LTIME", "time", 64, True, *_T64, 0, long=True)
DATE = ElemType("DATE", "date", 64, True, *_T64, 0)
LDATE = ElemType("LDATE", "date", 64, True, *_T64, 0, long=True)
TOD = ElemType("TIME_OF_DAY", "tod", 64, True, *_T64, 0)
LTOD = ElemType("LTIME_OF_DAY", "tod", 64, True, *_T64, 0, long=True)
DT = ElemType("DATE_AND_TIME", "dt", 64, True, *_T64, 0)
LDT = ElemType("LDATE_AND_TIME", "dt", 64, True, *_T64, 0, long=True)
CHAR = ElemType("CHAR", "char", 8, False, 0, 255, "\0")
WCHAR = ElemType("WCHAR", "char", 16, False, 0, 65535, "\0")


@dataclass(eq=False)
class StringType(Type):
    length: int = 80
    wide: bool = False
    kind: str = "string"
    default: str = ""

    @property
    def name(self) -> str:  # type: ignore[override]
        base = "WSTRING" if self.wide else "STRING"
        return base if self.length == 80 else f"{base}[{self.length}]"


STRING = StringType(80, False)
WSTRING = StringType(80, True)

ELEMENTARY: dict[str, Type] = {
    "BOOL": BOOL,
    "SINT": SINT,
    "INT": INT,
    "DINT": DINT,
    "LINT": LINT,
    "USINT": USINT,
    "UINT": UINT,
    "UDINT": UDINT,
    "ULINT": ULINT,
    "BYTE": BYTE,
    "WORD": WORD,
    "DWORD": DWORD,
    "LWORD": LWORD,
    "REAL": REAL,
    "LREAL": LREAL,
    "TIME": TIME,
    "LTIME": LTIME,
    "DATE": DATE,
    "LDATE": LDATE,
    "TIME_OF_DAY": TOD,
    "TOD": TOD,
    "LTIME_OF_DAY": LTOD,
    "LTOD": LTOD,
    "DATE_AND_TIME": DT,
    "DT": DT,
    "LDATE_AND_TIME": LDT,
    "LDT": LDT,
    "STRING": STRING,
    "WSTRING": WSTRING,
    "CHAR": CHAR,
    "WCHAR": WCHAR,
}


@dataclass(eq=False)
class LiteralType(Type):
    """An untyped numeric literal (or constant expression of literals): fits any numeric context."""

    name: str
    kind: str  # "lit_int" or "lit_real"


LIT_INT = LiteralType("integer literal", "lit_int")
LIT_REAL = LiteralType("real literal", "lit_real")


@dataclass(eq=False)
class ArrayType(Type):
    dims: list[tuple[int, int]] = field(default_factory=list)  # [(lo, hi)]; hi < lo: ARRAY[*]
    element: Type = None  # type: ignore[assignment]  # always given
    kind: str = "array"

    @property
    def name(self) -> str:  # type: ignore[override]
        return "ARRAY[" + ", ".join("*" if hi < lo else f"{lo}..{hi}" for lo, hi in self.dims) + f"] OF {self.element}"

    @property
    def size(self) -> int:
        n = 1
        for lo, hi in self.dims:
            n *= hi - lo + 1
        return n


@dataclass(eq=False)
class Member:
    name: str
    type: Type
    span: Span
    init: Syntax | InitialValue | None = None  # the initializer (compiler: its syntax; artefact: a value or None)
    pyname: str = ""


@dataclass(eq=False)
class StructType(Type):
    name: str
    members: dict[str, Member] = field(default_factory=dict)  # lower name → Member
    kind: str = "struct"
    pyname: str = ""
    resolved: bool = False


@dataclass(eq=False)
class EnumType(Type):
    name: str
    members: dict[str, tuple[str, int]] = field(default_factory=dict)  # lower name → (name, value)
    base: ElemType = INT
    default_value: int = 0
    kind: str = "enum"
    names_by_value: dict[int, str] = field(default_factory=dict)


@dataclass(eq=False)
class SubrangeType(Type):
    name: str = "?"
    base: ElemType = None  # type: ignore[assignment]  # always given
    lo: int = 0
    hi: int = 0
    outside: str = "fault"  # a value outside lo..hi: fault, clamp or store (the dialect's rule)

    @property
    def kind(self) -> str:  # type: ignore[override]
        return self.base.kind

    @property
    def bits(self) -> int:
        return self.base.bits

    @property
    def signed(self) -> bool:
        return self.base.signed


@dataclass(eq=False)
class RefType(Type):
    target: Type = None  # type: ignore[assignment]  # always given
    ref_kind: str = "REF_TO"
    kind: str = "ref"

    @property
    def name(self) -> str:  # type: ignore[override]
        return f"{'REF_TO' if self.ref_kind == 'REF_TO' else self.ref_kind + ' TO'} {self.target}"


def is_reference(t: Type | None) -> bool:
    """REFERENCE TO: a reference used as the variable it refers to (bound with REF=)."""
    u = unalias(t) if t is not None else None
    return isinstance(u, RefType) and u.ref_kind == "REFERENCE"


@dataclass(eq=False)
class AliasType(Type):
    """A named alias whose only difference from its target is a default value."""

    name: str = "?"
    target: Type = None  # type: ignore[assignment]  # always given
    init: Syntax | InitialValue | None = None  # the default value (compiler: its syntax; artefact: a value or None)


@dataclass(eq=False)
class VarSym:
    name: str
    type: Type
    section: str  # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_GLOBAL, VAR_EXTERNAL
    span: Span
    init: Syntax | InitialValue | None = None  # the initial value (compiler: its syntax; artefact: a value or None)
    location: str = ""
    constant: bool = False
    retain: bool = False
    persistent: bool = False
    edge: str = ""
    pyname: str = ""
    owner: POUType | None = None  # None for globals
    used: bool = False
    written: bool = False
    address_taken: bool = False
    const_value: Any = None
    is_global: bool = False
    global_ref: VarSym | None = None  # VAR_EXTERNAL → the VAR_GLOBAL symbol
    access: str = ""  # PUBLIC, PRIVATE, PROTECTED or INTERNAL from `VAR PRIVATE`; "" = unrestricted
    any_input: str = ""  # an input declared ANY / ANY_NUM / ...: the generic family (its type is AnyType)


@dataclass(eq=False)
class POUType(Type):
    name: str = "?"
    pou_kind: str = "FUNCTION_BLOCK"  # FUNCTION, FUNCTION_BLOCK, PROGRAM (TEST: a unit test's variables)
    decl: Syntax | PouInfo | None = None  # compiler: ast.POU / ast.Method; artefact: PouInfo; None for native
    vars: dict[str, VarSym] = field(default_factory=dict)  # lower → VarSym, declaration order
    return_type: Type | None = None
    pyname: str = ""
    library: str = ""  # "" for user code, else the library name
    native: Any = None  # a native implementation (Python) for library POUs
    actions: dict[str, Syntax | PouInfo] = field(
        default_factory=dict
    )  # lower → compiler: ast.ActionDecl; artefact: PouInfo
    resolved: bool = False
    result_address_taken: bool = False  # ADR(F) inside F: its result lives in a box (codegen)
    methods: dict[str, POUType] = field(default_factory=dict)  # lower → POUType (pou_kind FUNCTION, owner_fb set)
    owner_fb: POUType | None = None  # a METHOD: the function block it belongs to
    base: POUType | None = None  # FUNCTION_BLOCK … EXTENDS base
    interfaces: list[POUType] = field(default_factory=list)  # INTERFACEs implemented (FB) or extended (INTERFACE)
    properties: dict[str, PropSym] = field(default_factory=dict)  # lower → PropSym
    modifiers: tuple[str, ...] = ()  # ABSTRACT, FINAL, OVERRIDE, PUBLIC, …

    @property
    def block(self) -> POUType:
        """The function block (or interface) a METHOD or property accessor belongs to."""
        if self.owner_fb is None:
            raise TypeError(f"{self.name} is not a method")
        return self.owner_fb

    @property
    def kind(self) -> str:  # type: ignore[override]
        return {
            "FUNCTION": "function",
            "FUNCTION_BLOCK": "fb",
            "PROGRAM": "fb",
            "TEST": "test",
            "INTERFACE": "interface",
        }[self.pou_kind]

    def inputs(self) -> list[VarSym]:
        return [v for v in self.vars.values() if v.section == "VAR_INPUT"]

    def outputs(self) -> list[VarSym]:
        return [v for v in self.vars.values() if v.section == "VAR_OUTPUT"]

    def in_outs(self) -> list[VarSym]:
        return [v for v in self.vars.values() if v.section == "VAR_IN_OUT"]

    def params(self) -> list[VarSym]:
        return [v for v in self.vars.values() if v.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")]


@dataclass(eq=False)
class PropSym:
    """A PROPERTY of a function block or interface: its type and accessor methods (None if absent)."""

    name: str
    type: Type
    owner: POUType  # the block or interface that declares it
    span: Span
    get: POUType | None = None  # POUType (FUNCTION returning `type`), pyname _pg_<name>
    set: POUType | None = None  # POUType with one VAR_INPUT named like the property, pyname _ps_<name>
    bare: bool = False  # an interface prototype without accessors: GET, SET or both satisfy it


def is_conformant(t: Type | None) -> bool:
    """ARRAY[*] (a VAR_IN_OUT whose bounds come from the argument: a runtime `_Conf`)."""
    u = unalias(t) if t is not None else None
    return isinstance(u, ArrayType) and any(hi < lo for lo, hi in u.dims)


def extends(t: Type, base: Type) -> bool:
    """Is `t` a function block that EXTENDS `base` (directly or further up)? A derived instance
    may stand where its base is expected: VAR_IN_OUT, REFERENCE TO, REF_TO."""
    t, base = unalias(t), unalias(base)
    if not (isinstance(t, POUType) and isinstance(base, POUType) and base.pou_kind == "FUNCTION_BLOCK"):
        return False
    x = t.base
    while isinstance(x, POUType):
        if x is base:
            return True
        x = x.base
    return False


def fb_init_chain(pou: POUType) -> list[POUType]:
    """The FB_init methods that construct an instance of `pou` (CODESYS): its bases' first, then
    its own; each block's own one only (an inherited entry is its base's)."""
    chain: list[POUType] = []
    x: POUType | None = pou
    while x is not None:
        own = x.methods.get("fb_init")
        if own is not None and own.owner_fb is x:
            chain.append(own)
        x = x.base
    return chain[::-1]


def implements(t: Type, itf: POUType) -> bool:
    """Does a function block or interface type provide interface `itf` (directly, through its
    base blocks, or through interfaces that extend it)?"""
    seen = set()
    todo: list[Type | None] = [t]
    while todo:
        x = todo.pop()
        if x is None or id(x) in seen:
            continue
        seen.add(id(x))
        if x is itf:
            return True
        if isinstance(x, POUType):
            todo.extend(x.interfaces)
            todo.append(x.base)
    return False


def unalias(t: Type) -> Type:
    while isinstance(t, AliasType):
        t = t.target
    return t


def base_of(t: Type) -> Type:
    """The type a value is computed in (subranges → base, aliases → target)."""
    t = unalias(t)
    if isinstance(t, SubrangeType):
        return t.base
    return t


# --------------------------------------------------------------------------- conversions

# IEC 61131-3 3rd edition, implicit (widening) conversions.
_WIDEN: dict[str, set[str]] = {
    "SINT": {"INT", "DINT", "LINT", "REAL", "LREAL"},
    "INT": {"DINT", "LINT", "REAL", "LREAL"},
    "DINT": {"LINT", "LREAL"},
    "LINT": set(),
    "USINT": {"UINT", "UDINT", "ULINT", "INT", "DINT", "LINT", "REAL", "LREAL"},
    "UINT": {"UDINT", "ULINT", "DINT", "LINT", "REAL", "LREAL"},
    "UDINT": {"ULINT", "LINT", "LREAL"},
    "ULINT": set(),
    "REAL": {"LREAL"},
    "LREAL": set(),
    "BOOL": {"BYTE", "WORD", "DWORD", "LWORD"},
    "BYTE": {"WORD", "DWORD", "LWORD"},
    "WORD": {"DWORD", "LWORD"},
    "DWORD": {"LWORD"},
    "LWORD": set(),
    "TIME": {"LTIME"},
    "LTIME": set(),
    "DATE": {"LDATE"},
    "LDATE": set(),
    "TIME_OF_DAY": {"LTIME_OF_DAY"},
    "LTIME_OF_DAY": set(),
    "DATE_AND_TIME": {"LDATE_AND_TIME"},
    "LDATE_AND_TIME": set(),
    "CHAR": {"STRING"},
    "WCHAR": {"WSTRING"},
}


def widens_to(src: Type, dst: Type) -> bool:
    s, d = base_of(src), base_of(dst)
    if s is d:
        return True
    if isinstance(s, ElemType) and isinstance(d, ElemType):
        return d.name in _WIDEN.get(s.name, ())
    if isinstance(s, ElemType) and isinstance(d, StringType):
        return s.kind == "char" and d.wide == (s.name == "WCHAR")
    return False


_RANK = ["SINT", "USINT", "INT", "UINT", "DINT", "UDINT", "LINT", "ULINT", "REAL", "LREAL"]


def _holds_bits(bits: int, d: ElemType) -> bool:
    """Does number type `d` hold every value of an unsigned bit string of `bits` bits?"""
    if d.is_real:
        return bits <= (16 if d.bits == 32 else 32)  # exactly, within the mantissa
    return d.is_int and (d.bits > bits if d.signed else d.bits >= bits)


def bits_numbers_convert(src: Type, dst: Type) -> bool:
    """CODESYS's and TwinCAT's implicit conversions between bit strings and numbers that keep the
    value (IEC 61131-3 converts between ANY_BIT and ANY_NUM only explicitly): a bit string into a
    number that holds all its values (BYTE into INT, UINT or REAL; WORD into DINT or REAL; DWORD into
    LINT or LREAL), an integer into a bit string at least as wide (INT into WORD: its bit pattern)."""
    s, d = base_of(src), base_of(dst)
    if not (isinstance(s, ElemType) and isinstance(d, ElemType)) or s.is_bool or d.is_bool:
        return False
    if s.is_bit and d.is_num:
        return _holds_bits(s.bits, d)
    return s.is_int and d.is_bit and s.bits <= d.bits


def lossy_number_conversion(src: Type, dst: Type) -> bool:
    """An implicit conversion CODESYS and TwinCAT make with a warning ("possible loss of
    information", "possible change of sign"): between integers and bit strings of any sizes, and
    from those or a REAL into a REAL type. Never from a REAL into an integer."""
    s, d = base_of(src), base_of(dst)
    if not (isinstance(s, ElemType) and isinstance(d, ElemType)) or s.is_bool or d.is_bool:
        return False
    if d.is_int or d.is_bit:
        return s.is_int or s.is_bit
    return d.is_real and (s.is_int or s.is_bit or s.is_real)


def bits_numbers_common(a: Type, b: Type) -> Type | None:
    """The type of arithmetic or a comparison between a bit string and a number under those rules:
    the number's type if it holds the bit string's values, else the smallest integer type that
    holds both; None when no type does."""
    a, b = base_of(a), base_of(b)
    if not (isinstance(a, ElemType) and isinstance(b, ElemType)):
        return None
    bit, num = (a, b) if a.is_bit and b.is_num else (b, a) if b.is_bit and a.is_num else (None, None)
    if bit is None or num is None or bit.is_bool:
        return None
    if bits_numbers_convert(bit, num):
        return num
    if num.is_real:
        return LREAL if bit.bits <= 32 else None
    for name in _RANK[:8]:
        t = ELEMENTARY[name]
        if isinstance(t, ElemType) and _holds_bits(bit.bits, t) and widens_to(num, t):
            return t
    return None


def common_type(a: Type, b: Type) -> Type | None:
    """The smallest type both operands widen to, or None."""
    a, b = base_of(a), base_of(b)
    if a is b:
        return a
    if isinstance(a, LiteralType) or isinstance(b, LiteralType):
        if isinstance(a, LiteralType) and isinstance(b, LiteralType):
            return LIT_REAL if LIT_REAL in (a, b) else LIT_INT
        lit, other = (a, b) if isinstance(a, LiteralType) else (b, a)
        if lit is LIT_INT and (other.is_num or other.is_bit):
            return other
        if lit is LIT_REAL:
            if other.is_real:
                return other
            if isinstance(other, ElemType) and other.is_int:
                return REAL if other.bits <= 16 else LREAL
        return None
    if widens_to(a, b):
        return b
    if widens_to(b, a):
        return a
    if isinstance(a, StringType) and isinstance(b, StringType) and a.wide == b.wide:
        return a if a.length >= b.length else b
    if isinstance(a, ElemType) and isinstance(b, ElemType):
        if a.is_num and b.is_num:
            for name in _RANK:
                t = ELEMENTARY[name]
                if widens_to(a, t) and widens_to(b, t):
                    return t
        if a.is_bit and b.is_bit:
            return a if a.bits >= b.bits else b
    return None


def literal_fits(value: Any, t: Type) -> bool:
    u = unalias(t)
    if isinstance(u, SubrangeType):
        return bool(u.lo <= value <= u.hi)
    t = base_of(t)
    if isinstance(t, ElemType) and t.kind in ("int", "bit"):
        return bool(t.lo <= value <= t.hi)
    return True


def default_type_for_literal(t: Type, value: Any = None) -> Type:
    if t is LIT_INT:
        if value is not None and not (DINT.lo <= value <= DINT.hi):
            return LINT
        return DINT
    if t is LIT_REAL:
        return LREAL
    return t


def size_of(t: Type) -> tuple[int, int]:
    """(bytes, alignment) of a value of type t, laid out as a C compiler does on a 64-bit target."""
    u = unalias(t)
    if isinstance(u, SubrangeType):
        u = u.base
    if isinstance(u, EnumType):
        u = u.base if getattr(u, "base", None) is not None else INT
    if isinstance(u, StringType):
        n = (u.length + 1) * (2 if u.wide else 1)
        return n, 2 if u.wide else 1
    if isinstance(u, ArrayType):
        es, ea = size_of(u.element)
        return es * u.size, ea
    if isinstance(u, (RefType, POUType)) and not (isinstance(u, POUType) and u.pou_kind != "INTERFACE"):
        return 8, 8
    if isinstance(u, (StructType, POUType)):
        members = (
            [m.type for m in u.members.values()]
            if isinstance(u, StructType)
            else [v.type for v in u.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_TEMP")]
        )
        if isinstance(u, StructType) and u.kind == "union":  # the members share their bytes
            sizes = [size_of(mt) for mt in members] or [(1, 1)]
            align = max(a for _, a in sizes)
            return (max(s for s, _ in sizes) + align - 1) // align * align, align
        off, align = 0, 1
        for mt in members:
            ms, ma = size_of(mt)
            off = (off + ma - 1) // ma * ma + ms
            align = max(align, ma)
        return max(1, (off + align - 1) // align * align), align
    bits = getattr(u, "bits", 0) or 8
    if u is BOOL:
        bits = 8
    if getattr(u, "kind", "") in ("time", "date", "tod", "dt"):
        bits = 64 if getattr(u, "long", False) else 32
    n = max(1, bits // 8)
    return n, n


# struct formats of the values a POINTER TO may view as bytes (little-endian, as the PLCs st imitates)
_BYTE_FORMATS = {
    "BOOL": "?",
    "SINT": "b",
    "USINT": "B",
    "BYTE": "B",
    "INT": "h",
    "UINT": "H",
    "WORD": "H",
    "DINT": "i",
    "UDINT": "I",
    "DWORD": "I",
    "LINT": "q",
    "ULINT": "Q",
    "LWORD": "Q",
    "REAL": "f",
    "LREAL": "d",
}


# the unit a time or date is stored in, in its byte image (ns per unit): TIME/TOD in ms, DATE/DT in s,
# the long variants in ns, as TwinCAT and CODESYS store them
_TIME_UNIT = {"time": 1_000_000, "tod": 1_000_000, "date": 1_000_000_000, "dt": 1_000_000_000}


def byte_layout(t: Type) -> tuple[Any, ...] | None:
    """The spec of the byte image of a value of type t (runtime/byteimage.py), or None for what has
    no bytes a program may read (references, pointers, instances, interfaces)."""
    u = unalias(t)
    if isinstance(u, SubrangeType):
        u = u.base
    if isinstance(u, EnumType):
        u = u.base if getattr(u, "base", None) is not None else INT
    if isinstance(u, StringType):
        return ("s", u.length, u.wide)
    if isinstance(u, ArrayType):
        elem = byte_layout(u.element)
        return None if elem is None else ("a", u.size, elem)
    if isinstance(u, StructType):
        if u.kind == "union":
            return ("u", size_of(u)[0])
        members = []
        off = 0
        for m in u.members.values():
            ms = byte_layout(m.type)
            if ms is None:
                return None
            n, a = size_of(m.type)
            off = (off + a - 1) // a * a
            members.append((m.pyname or m.name, off, ms))
            off += n
        return ("r", size_of(u)[0], tuple(members))
    if not isinstance(u, ElemType):
        return None
    if u.kind == "bool":
        return ("b",)
    if u.kind == "real":
        return ("f", u.bits // 8)
    if u.kind in _TIME_UNIT:
        # TIME in 32 bits is an unsigned count of ms (CODESYS, TwinCAT: T#49d17h2m47s295ms is the
        # largest); LTIME's 64 bits are read as st's signed ns
        return ("i", 8, True, 1) if u.long else ("i", 4, False, _TIME_UNIT[u.kind])
    if u.kind in ("int", "bit", "char"):
        return ("i", u.bits // 8, u.signed and u.kind == "int", 1)
    return None


# CODESYS's __SYSTEM.TYPE_CLASS numbering (the vendor library's TYPE_CLASS enumeration)
_TYPE_CLASS = {
    "BOOL": 0, "BYTE": 2, "WORD": 3, "DWORD": 4, "LWORD": 5, "SINT": 6, "INT": 7, "DINT": 8, "LINT": 9,
    "USINT": 10, "UINT": 11, "UDINT": 12, "ULINT": 13, "REAL": 14, "LREAL": 15, "TIME": 18, "DATE": 19,
    "DATE_AND_TIME": 20, "TIME_OF_DAY": 21, "LTIME": 37, "LDATE": 46, "LDATE_AND_TIME": 47, "LTIME_OF_DAY": 48,
}  # fmt: skip


def type_class(t: Type) -> int:
    """The TYPE_CLASS an ANY input reports for a value of type t."""
    u = unalias(t)
    if isinstance(u, StringType):
        return 17 if u.wide else 16
    if isinstance(u, ArrayType):
        return 26
    if isinstance(u, EnumType):
        return 25
    if isinstance(u, SubrangeType):
        return 24
    if isinstance(u, RefType):
        return 22 if u.ref_kind == "POINTER" else 23
    if isinstance(u, (StructType, POUType)):
        return 28
    return _TYPE_CLASS.get(getattr(u, "name", ""), 29)


def pointer_view(src: Type, dst: Type) -> tuple[tuple[Any, ...], tuple[Any, ...]] | None:
    """A POINTER TO `src` seen as a POINTER TO `dst` (CODESYS: `pb : POINTER TO BYTE := ADR(x)`):
    the image specs (of what is pointed into, of what the pointer reads), or None if st cannot.
    An array on either side counts by its element; the pointer reads an elementary value."""
    us, ud = unalias(src), unalias(dst)
    sl = byte_layout(us.element if isinstance(us, ArrayType) else us)
    dl = byte_layout(ud.element if isinstance(ud, ArrayType) else ud)
    if sl is None or dl is None or dl[0] not in ("b", "i", "f", "s"):
        return None
    return sl, dl


def byte_format(t: Type) -> str | None:
    """The struct format of a value whose bytes a pointer of another type may read and write
    (an elementary number, bit string or BOOL, or an array of one), else None."""
    u = unalias(t)
    if isinstance(u, ArrayType):
        u = unalias(u.element)
    if isinstance(u, SubrangeType):
        u = u.base
    if isinstance(u, EnumType):
        u = u.base
    return _BYTE_FORMATS.get(getattr(u, "name", "")) if isinstance(u, ElemType) else None
