"""The abstract syntax tree: small slotted dataclasses, each with a source span.

Expression nodes carry a `ty` slot that the checker fills in (the resolved
IEC type) and a `const` slot for folded constant values; everything else is
what the source said.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..model.syntax import Syntax
from ..source import Span

# --------------------------------------------------------------------------- expressions


@dataclass(slots=True, eq=False)
class Expr(Syntax):
    span: Span
    ty: Any = field(default=None, init=False, repr=False)
    const: Any = field(default=None, init=False, repr=False)


@dataclass(slots=True, eq=False)
class Literal(Expr):
    kind: str = ""  # int real bool string wstring time date tod dt
    value: Any = None
    type_name: str = ""  # the typed prefix (INT#5 → "INT"), or "" when untyped
    text: str = ""  # the source text, for messages


@dataclass(slots=True, eq=False)
class EnumLit(Expr):
    type_name: str = ""
    member: str = ""


@dataclass(slots=True, eq=False)
class Name(Expr):
    name: str = ""
    sym: Any = field(default=None, repr=False)  # resolved by the checker


@dataclass(slots=True, eq=False)
class Direct(Expr):
    address: str = ""  # "%IX0.0"
    sym: Any = field(default=None, repr=False)  # the variable declared AT this address, if any (checker)


@dataclass(slots=True, eq=False)
class Field(Expr):
    base: Expr
    name: str
    name_span: Span
    sym: Any = field(default=None, repr=False)


@dataclass(slots=True, eq=False)
class Bit(Expr):
    base: Expr
    index: int = 0
    size: str = "X"  # X (bit), B, W, D, L for partial access x.%B1


@dataclass(slots=True, eq=False)
class Index(Expr):
    base: Expr
    indices: list[Expr]


@dataclass(slots=True, eq=False)
class Deref(Expr):
    base: Expr


@dataclass(slots=True, eq=False)
class Arg(Syntax):
    span: Span
    name: str  # "" for a positional argument
    value: Expr
    output: bool = False  # name => variable
    negated: bool = False  # NOT name => variable
    # the checker: a VAR_IN_OUT CONSTANT's argument that is no variable (a literal, an expression,
    # a constant), passed through a temporary (CODESYS)
    temporary: bool = False


@dataclass(slots=True, eq=False)
class Call(Expr):
    callee: Expr
    args: list[Arg]
    # filled by the checker: what is being called
    target: Any = field(default=None, repr=False)
    deref: bool = False  # the checker: a REFERENCE TO result used as the variable it refers to


@dataclass(slots=True, eq=False)
class Unary(Expr):
    op: str  # "-", "+", "NOT"
    operand: Expr


@dataclass(slots=True, eq=False)
class Binary(Expr):
    op: str  # + - * / MOD ** = <> < > <= >= AND OR XOR AND_THEN OR_ELSE
    left: Expr
    right: Expr
    single: bool = False  # the checker, openplc: a REAL operation MatIEC's C does in single precision


# --------------------------------------------------------------------------- initializers


@dataclass(slots=True, eq=False)
class AccessorCall(Expr):
    """A property read or written, after lowering (compiler/lower/properties.py): a call of
    `accessor` (its GET; its SET as an assignment's target) on `obj`, None for this instance.
    `nonvirtual`: SUPER^.Prop, the base block's accessor on this instance (obj is the SUPER^)."""

    obj: Expr | None = None
    accessor: Any = field(default=None, repr=False)
    nonvirtual: bool = False


@dataclass(slots=True, eq=False)
class ArrayInit(Syntax):
    span: Span
    items: list  # of initializers or RepeatInit


@dataclass(slots=True, eq=False)
class RepeatInit(Syntax):
    span: Span
    count: int
    items: list


@dataclass(slots=True, eq=False)
class StructInit(Syntax):
    span: Span
    fields: list  # of (name, span, initializer)


@dataclass(slots=True, eq=False)
class CtorInit(Syntax):
    """`inst : FB(a := 1)` (CODESYS): arguments for the block's FB_init, plus an ordinary
    initializer (`:= (x := 2)`) if one is given too."""

    span: Span
    args: list  # of (name, span, expression)
    inner: Any = None


@dataclass(slots=True, eq=False)
class ArrayCtorInit(Syntax):
    """`a : ARRAY[1..2] OF FB(x := 1)` (`each`: every element's FB_init arguments) or
    `ARRAY[1..2] OF FB[(x := 1), (x := 2)]` (`elements`: element by element), plus an ordinary
    array initializer (`inner`) if one is given too. The checker expands it into an ArrayInit of
    CtorInits, one per element (check/declarations.py)."""

    span: Span
    each: list | None
    elements: list | None
    inner: Any = None


# --------------------------------------------------------------------------- statements


@dataclass(slots=True, eq=False)
class Stmt(Syntax):
    span: Span


@dataclass(slots=True, eq=False)
class Assign(Stmt):
    target: Expr
    value: Expr
    kind: str = ":="  # ":=", "S=", "R=", "?=", "REF="
    chained: bool = False  # the leftmost of `a := b := c` (a vendor extension), for the dialect check
    in_condition: bool = False  # from `IF b := f() THEN` (a vendor extension), for the dialect check
    attempt: tuple[str, bool, bool] | None = (
        None  # for "?=": (kind name, source is a reference, destination is a reference)
    )


@dataclass(slots=True, eq=False)
class CallStmt(Stmt):
    call: Call


@dataclass(slots=True, eq=False)
class Mock(Stmt):
    """MOCK inst; (unit tests): the instance's body is skipped from now on, calls are counted."""

    target: Expr


@dataclass(slots=True, eq=False)
class MockFunction(Stmt):
    """MOCK_FUNCTION f RETURNS v; (unit tests)."""

    name: str
    value: Expr
    pou: Any = field(default=None, repr=False)  # filled by the checker


@dataclass(slots=True, eq=False)
class If(Stmt):
    branches: list[tuple[Expr, list[Stmt]]]
    orelse: list[Stmt] | None = None


@dataclass(slots=True, eq=False)
class CaseBranch(Syntax):
    span: Span
    labels: list[tuple[Expr, Expr | None]]
    body: list[Stmt]


@dataclass(slots=True, eq=False)
class Case(Stmt):
    selector: Expr
    branches: list[CaseBranch]
    orelse: list[Stmt] | None = None


@dataclass(slots=True, eq=False)
class For(Stmt):
    var: Expr
    start: Expr
    end: Expr
    step: Expr | None
    body: list[Stmt]


@dataclass(slots=True, eq=False)
class While(Stmt):
    cond: Expr
    body: list[Stmt]


@dataclass(slots=True, eq=False)
class Repeat(Stmt):
    body: list[Stmt]
    cond: Expr


@dataclass(slots=True, eq=False)
class Try(Stmt):
    """`__TRY body __CATCH(var) handler __FINALLY final __ENDTRY` (CODESYS, TwinCAT): a fault in the
    body that a __CATCH handles ends the body, gives `var` its __SYSTEM.ExceptionCode and runs the
    handler; the final statements run in every case. No __CATCH: None; no __FINALLY: None."""

    body: list[Stmt]
    catch_var: Expr | None = None
    handler: list[Stmt] | None = None
    final: list[Stmt] | None = None


@dataclass(slots=True, eq=False)
class CountedFor(Stmt):
    """A FOR after lowering (compiler/lower/loops.py): how the counter runs is decided.

    form "range": the body never writes the counter, which steps from start to end;
    "while": the body writes it, so the loop tests it each round and steps it (wrapping
    to its type) before every round but the first. `step_value` is the step as a constant
    (1 without BY), or None when only known at run time.
    """

    var: Expr
    start: Expr
    end: Expr
    step: Expr | None
    step_value: int | None
    form: str
    body: list[Stmt]


@dataclass(slots=True, eq=False)
class LoopGuard(Stmt):
    """The watchdog's check (compiler/lower/loops.py puts it first in every ST loop's body):
    while the flag is down it costs one test; when a job overran, it ends the job here."""


@dataclass(slots=True, eq=False)
class Exit(Stmt):
    pass


@dataclass(slots=True, eq=False)
class Continue(Stmt):
    pass


@dataclass(slots=True, eq=False)
class Return(Stmt):
    pass


@dataclass(slots=True, eq=False)
class Empty(Stmt):
    pass


# --------------------------------------------------------------------------- type specs


@dataclass(slots=True, eq=False)
class TypeSpec(Syntax):
    span: Span


@dataclass(slots=True, eq=False)
class NamedType(TypeSpec):
    name: str = ""
    ctor_args: list[tuple[str, Span, Expr]] | None = (
        None  # `FB(a := 1)`: FB_init arguments, moved to the declaration's CtorInit
    )


@dataclass(slots=True, eq=False)
class StringType(TypeSpec):
    wide: bool = False
    length: Expr | None = None


@dataclass(slots=True, eq=False)
class ArrayType(TypeSpec):
    ranges: list[tuple[Expr, Expr] | None]  # [None] for [*]
    element: TypeSpec


@dataclass(slots=True, eq=False)
class RefType(TypeSpec):
    target: TypeSpec
    kind: str = "REF_TO"  # REF_TO, POINTER, REFERENCE


@dataclass(slots=True, eq=False)
class SubrangeType(TypeSpec):
    base: str
    lo: Expr
    hi: Expr


@dataclass(slots=True, eq=False)
class EnumValue(Syntax):
    span: Span
    name: str
    value: Expr | None = None


@dataclass(slots=True, eq=False)
class EnumType(TypeSpec):
    values: list[EnumValue]
    base: str = ""  # "" → INT
    default: str = ""


@dataclass(slots=True, eq=False)
class StructType(TypeSpec):
    members: list[VarDecl]
    extends: Any = None  # NamedType of the base structure (CODESYS `TYPE B EXTENDS A : STRUCT`)
    union: bool = False  # UNION … END_UNION: the members share their bytes (CODESYS, TwinCAT)


# --------------------------------------------------------------------------- declarations


@dataclass(slots=True, eq=False)
class VarDecl(Syntax):
    span: Span
    names: list  # [(name, span)]
    type: TypeSpec
    init: Any = None  # Expr, ArrayInit, StructInit or None
    location: str = ""  # "%IX0.0"
    edge: str = ""  # R_EDGE / F_EDGE
    path: list[str] | None = None  # VAR_CONFIG: instance path [names]
    written_location: str = ""  # the address as written, when the checker reads it otherwise (W011)


@dataclass(slots=True, eq=False)
class AccessDecl(Syntax):
    """`name : R.inst.x : INT READ_WRITE;` in a configuration's or resource's VAR_ACCESS: a name
    under which the variable at `path` (names, or a resource's name and a %address) is reached from
    outside the program (an HMI, a client, plc["name"])."""

    span: Span
    names: list  # [(name, span)]: one (as a VarDecl's, so that code walking declarations reads it)
    path: list[str]  # ["R", "inst", "x"], ["%IX1.1"], ["R", "%IX1.1"]
    type: TypeSpec
    read_only: bool = True  # IEC: READ_ONLY unless READ_WRITE is written
    init: Any = None  # (none: an access path has no initial value)


@dataclass(slots=True, eq=False)
class VarBlock(Syntax):
    span: Span
    kind: str  # VAR, VAR_INPUT, ... (upper case)
    qualifiers: list  # CONSTANT, RETAIN, NON_RETAIN, PERSISTENT, PUBLIC, PRIVATE, PROTECTED, INTERNAL
    decls: list


@dataclass(slots=True, eq=False)
class TypeDecl(Syntax):
    span: Span
    name: str
    spec: TypeSpec
    init: Any = None


@dataclass(slots=True, eq=False)
class TypeBlock(Syntax):
    span: Span
    types: list


@dataclass(slots=True, eq=False)
class ActionAssoc(Syntax):
    span: Span
    action: str
    qualifier: str
    time: Expr | None = None


@dataclass(slots=True, eq=False)
class Step(Syntax):
    span: Span
    name: str
    initial: bool
    actions: list


@dataclass(slots=True, eq=False)
class Transition(Syntax):
    span: Span
    name: str
    priority: Expr | None
    sources: list  # [(name, span)]
    targets: list
    cond: Expr | None = None
    body: list | None = None  # transition given as statements assigning the transition name


@dataclass(slots=True, eq=False)
class ActionDecl(Syntax):
    span: Span
    name: str
    body: list


@dataclass(slots=True, eq=False)
class Method(Syntax):
    span: Span
    name: str
    modifiers: list = field(default_factory=list)
    return_type: TypeSpec | None = None
    var_blocks: list = field(default_factory=list)
    body: list = field(default_factory=list)
    end_span: Span | None = None
    kind: str = "FUNCTION"  # checked and generated as a function with the instance as `self`
    steps: list = field(default_factory=list)
    transitions: list = field(default_factory=list)
    actions: list = field(default_factory=list)


@dataclass(slots=True, eq=False)
class Property(Syntax):
    span: Span
    name: str
    modifiers: list = field(default_factory=list)
    type: TypeSpec | None = None
    get: Method | None = None  # the accessors, as methods (GET: result = the property's name;
    set: Method | None = None  # SET: an input with the property's name)
    end_span: Span | None = None


@dataclass(slots=True, eq=False)
class Interface(Syntax):
    span: Span
    name: str
    extends: list = field(default_factory=list)
    methods: list = field(default_factory=list)  # Method prototypes (no body)
    end_span: Span | None = None
    kind: str = "INTERFACE"
    properties: list = field(default_factory=list)
    var_blocks: list = field(default_factory=list)
    body: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    transitions: list = field(default_factory=list)
    actions: list = field(default_factory=list)
    modifiers: list = field(default_factory=list)
    implements: list = field(default_factory=list)
    return_type: TypeSpec | None = None


@dataclass(slots=True, eq=False)
class POU(Syntax):
    span: Span
    kind: str  # FUNCTION, FUNCTION_BLOCK, PROGRAM
    name: str
    return_type: TypeSpec | None = None
    var_blocks: list = field(default_factory=list)
    body: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    transitions: list = field(default_factory=list)
    actions: list = field(default_factory=list)
    modifiers: list = field(default_factory=list)
    extends: str = ""
    implements: list = field(default_factory=list)
    end_span: Span | None = None
    methods: list = field(default_factory=list)
    properties: list = field(default_factory=list)


@dataclass(slots=True, eq=False)
class TaskDecl(Syntax):
    span: Span
    name: str
    params: dict  # upper-case name → Expr


@dataclass(slots=True, eq=False)
class ProgramConfig(Syntax):
    span: Span
    instance: str
    task: str
    type_name: str
    args: list  # [Arg]
    retain: str = ""


@dataclass(slots=True, eq=False)
class Resource(Syntax):
    span: Span
    name: str
    target: str
    var_blocks: list
    tasks: list
    programs: list


@dataclass(slots=True, eq=False)
class Configuration(Syntax):
    span: Span
    name: str
    var_blocks: list
    resources: list


@dataclass(slots=True, eq=False)
class TestBlock(Syntax):
    span: Span
    kind: str  # TEST, SETUP, TEARDOWN
    name: str
    var_blocks: list
    body: list


@dataclass(slots=True, eq=False)
class Unit(Syntax):
    """Everything declared in one source file."""

    path: str
    items: list  # TypeBlock, POU, Configuration, VarBlock, TestBlock
    pragmas: list = field(default_factory=list)
    unqualified_for: frozenset = (
        frozenset()
    )  # the namespaces whose qualifiers were dropped (check/passes/namespaces.py)


_NOT_CHILDREN = frozenset(("span", "name_span", "end_span", "ty", "const", "sym", "pou"))


_CHILD_FIELDS: dict[type, tuple[str, ...]] = {}
_LEAVES = (str, int, float, bool, type(None))


def walk_nodes(body):
    """Every node (statement, expression, argument, CASE branch) under a statement list or a node,
    depth first, each once; not into what the checker attached (types, symbols, Call.target)."""
    stack = [body]
    seen: set = set()
    module = __name__
    fields_of = _CHILD_FIELDS
    while stack:
        x = stack.pop()
        if isinstance(x, (list, tuple)):
            stack.extend(reversed(x))
            continue
        cls = type(x)
        if cls.__module__ != module or id(x) in seen:  # a syntax node, not a type or symbol
            continue
        seen.add(id(x))
        yield x
        fields = fields_of.get(cls)
        if fields is None:
            fields = fields_of[cls] = tuple(f for f in cls.__dataclass_fields__ if f not in _NOT_CHILDREN)
        kids = []
        for f in fields:
            k = getattr(x, f, None)
            if isinstance(k, _LEAVES):
                continue
            if isinstance(k, (list, tuple)) or type(k).__module__ == module:
                kids.append(k)
        stack.extend(reversed(kids))
