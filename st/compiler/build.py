"""Lark callbacks → AST. One method per grammar rule (Lark's Transformer style).

The builder runs inside the LALR parser (no intermediate parse tree), which is
what makes parsing large libraries fast. A callback gets its rule's children (`c`: tokens,
AST nodes, and the pieces of build_parts.py that a parent rule takes apart) and returns an
AST node or such a piece.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable
from typing import Any, cast

from lark import Token, Transformer

from ..diagnostics import Code
from ..model.literals import (
    LiteralError,
    LiteralRangeError,
    date_literal,
    dt_literal,
    int_literal,
    parse_string,
    real_literal,
    time_literal,
    tod_literal,
)
from ..source import Span
from . import ast as A
from .build_parts import (
    Accessor,
    ArrayCtor,
    AssignCondition,
    CaseLabel,
    CaseLabels,
    Catch,
    Chain,
    CtorArgs,
    Edge,
    Else,
    ElsIf,
    Extends,
    FieldValue,
    Finally,
    Implements,
    Location,
    Modifier,
    Range,
    TaskParam,
    TransitionBody,
    TransitionCond,
    TypeBody,
    flat,
)

_PREC = {
    "OR": 1,
    "OR_ELSE": 1,
    "XOR": 2,
    "AND": 3,
    "&": 3,
    "AND_THEN": 3,
    "=": 4,
    "<>": 4,
    "<": 5,
    ">": 5,
    "<=": 5,
    ">=": 5,
    "+": 6,
    "-": 6,
    "*": 7,
    "/": 7,
    "MOD": 7,
    "**": 8,
}
_OPNAME = {"&": "AND"}
# Words that may never be declared as a name (contextual lexing would otherwise let 'THEN' be an
# identifier where no keyword is expected). Soft keywords (ON, STEP, BY, ...) and type names (DT is
# a common name for a time step) are not here: the grammar tells them apart by context.
# CODESYS and TwinCAT let a program name a variable R_EDGE or F_EDGE (IEC and MatIEC do not)
# keywords CODESYS and TwinCAT do not have, so their code uses them as names (a property
# `Configuration`, TcLog): names there, keywords under iec and openplc
VENDOR_NAMES = frozenset({"R_EDGE", "F_EDGE", "CONFIGURATION", "RESOURCE"})
RESERVED = frozenset(
    """
TYPE END_TYPE STRUCT END_STRUCT ARRAY OF STRING WSTRING REF_TO POINTER REFERENCE TO END_VAR CONSTANT RETAIN
NON_RETAIN PERSISTENT R_EDGE F_EDGE AT FUNCTION END_FUNCTION FUNCTION_BLOCK END_FUNCTION_BLOCK PROGRAM
END_PROGRAM EXTENDS IMPLEMENTS INITIAL_STEP END_STEP END_TRANSITION END_ACTION CONFIGURATION
END_CONFIGURATION RESOURCE END_RESOURCE IF THEN ELSIF ELSE END_IF CASE END_CASE FOR DO END_FOR WHILE
END_WHILE REPEAT UNTIL END_REPEAT EXIT CONTINUE RETURN OR XOR AND NOT MOD TRUE FALSE VAR VAR_INPUT
VAR_OUTPUT VAR_IN_OUT VAR_TEMP VAR_GLOBAL VAR_EXTERNAL VAR_CONFIG VAR_ACCESS END_TEST END_SETUP
END_TEARDOWN PUBLIC PRIVATE PROTECTED INTERNAL ABSTRACT FINAL END_METHOD END_INTERFACE END_PROPERTY END_GET END_SET END_CLASS
""".split()
)
_QUALIFIERS = frozenset(
    ("CONSTANT", "RETAIN", "NON_RETAIN", "PERSISTENT", "PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL")
)
# an accessor's own access (GET PRIVATE) replaces these of its property's
_ACCESS = frozenset(("PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL"))


class BuildError(Exception):
    def __init__(self, span: Span, message: str, code: str = Code.MISPLACED_SECTION) -> None:
        self.span = span
        self.message = message
        self.code = code


class AstBuilder(Transformer[Token, A.Unit]):
    """Builds AST nodes for one file; literal errors are collected in `errors`."""

    __visit_tokens__ = False

    def __init__(self, path: str) -> None:
        super().__init__(visit_tokens=False)
        self.path = path
        self.errors: list[BuildError] = []
        # keywords the chosen dialect lets a program use as names (CODESYS: R_EDGE, F_EDGE)
        self.names_allowed: frozenset[str] = frozenset()

    # ---------------------------------------------------------------- helpers
    def sp(self, x: object) -> Span:
        if isinstance(x, Token):
            # the lexer gives every token its position, and the parser's repaired ";" copies one
            return Span(self.path, x.line, x.column, x.end_line, x.end_column)  # type: ignore[arg-type]
        span: Span | None = getattr(x, "span", None)
        if span is not None:
            return span
        if isinstance(x, (list, tuple)) and x:
            return self.sp(x[0])
        return Span(self.path, 0, 0)

    def _lit(self, fn: Callable[..., Any], tok: Token, *args: Any, at: Token | None = None, shown: str = "") -> Any:
        """The value of a literal token, or "" / 0 after a located error: E004 for a malformed
        literal, E021 for one its type cannot hold. `at`: where the whole literal starts (a typed
        literal's prefix) and `shown`: its whole text, when they differ from the token's."""
        try:
            return fn(str(tok), *args)
        except LiteralRangeError as e:
            self.errors.append(
                BuildError(self.sp(at if at is not None else tok), f"{shown or tok} {e}", Code.OUT_OF_RANGE)
            )
            return 0
        except (LiteralError, ValueError, OverflowError) as e:
            full = shown or str(tok)
            text = full if len(full) <= 60 else f"{full[:40]}…"
            self.errors.append(
                BuildError(
                    self.sp(at if at is not None else tok), f"invalid literal {text!r}: {e}", Code.MALFORMED_LITERAL
                )
            )
            return "" if fn is parse_string else 0

    # ---------------------------------------------------------------- file
    def start(self, items: list[Any]) -> A.Unit:
        out: list[Any] = []
        for i in items:
            if isinstance(i, (A.Method, A.Property, A.ActionDecl)):
                self._attach(i, out)
            elif i is not None:
                out.append(i)
        return A.Unit(self.path, out)

    def _attach(self, part: A.Method | A.Property | A.ActionDecl, items: list[Any]) -> None:
        """A METHOD, PROPERTY or ACTION after END_FUNCTION_BLOCK / END_PROGRAM (the layout of TwinCAT
        and CODESYS text exports) belongs to the block just before it in the file."""
        owner = (
            items[-1]
            if items and isinstance(items[-1], A.POU) and items[-1].kind in ("FUNCTION_BLOCK", "PROGRAM")
            else None
        )
        if owner is None:
            what = {A.Method: "METHOD", A.Property: "PROPERTY", A.ActionDecl: "ACTION"}[type(part)]
            self.errors.append(
                BuildError(
                    part.span,
                    f"this {what} is outside any FUNCTION_BLOCK or PROGRAM: "
                    f"declare it inside the block, or right after its END_FUNCTION_BLOCK",
                )
            )
            return
        match part:
            case A.Method():
                owner.methods.append(part)
            case A.Property():
                owner.properties.append(part)
            case A.ActionDecl():
                owner.actions.append(part)

    def name(self, c: list[Token]) -> Token:
        return c[0]

    def _not_reserved(self, tok: Token) -> Token:
        if (
            isinstance(tok, Token)
            and tok.type == "IDENT"
            and tok.upper() in RESERVED
            and tok.upper() not in self.names_allowed
        ):
            self.errors.append(
                BuildError(self.sp(tok), f"'{tok}' is a reserved keyword and cannot be a name", Code.SYNTAX)
            )
        return tok

    # ---------------------------------------------------------------- types
    def type_decl(self, c: list[Any]) -> A.TypeBlock:
        return A.TypeBlock(self.sp(c[0]), [x for x in c if isinstance(x, A.TypeDecl)])

    def type_item(self, c: list[Any]) -> A.TypeDecl:
        name: Token
        body: TypeBody
        name, body = c
        self._not_reserved(name)
        return A.TypeDecl(self.sp(name), str(name), body.spec, body.init)

    def struct_extends_item(self, c: list[Any]) -> A.TypeDecl:
        name: Token
        base: Token
        body: TypeBody
        name, _, base, body = c
        self._not_reserved(name)
        spec = body.spec
        assert isinstance(spec, A.StructType)  # the grammar: STRUCT or UNION
        spec.extends = A.NamedType(self.sp(base), str(base))
        return A.TypeDecl(self.sp(name), str(name), spec, body.init)

    def alias_type(self, c: list[Any]) -> TypeBody:
        return TypeBody(c[0], c[1] if len(c) > 1 else None)

    def enum_type(self, c: list[Any]) -> TypeBody:
        values = [x for x in c if isinstance(x, A.EnumValue)]
        names = [x for x in c if isinstance(x, Token)]
        base = str(names[0]) if names else ""
        default = str(names[1]) if len(names) > 1 else ""
        return TypeBody(A.EnumType(values[0].span, values, base, default), None)

    def typed_enum_type(self, c: list[Any]) -> TypeBody:
        base: Token = c[0]
        values = [x for x in c[1:] if isinstance(x, A.EnumValue)]
        rest = [x for x in c[1:] if isinstance(x, Token)]
        return TypeBody(A.EnumType(self.sp(base), values, str(base), str(rest[0]) if rest else ""), None)

    def struct_type(self, c: list[Any]) -> TypeBody:
        return TypeBody(A.StructType(self.sp(c[0]), [x for x in c if isinstance(x, A.VarDecl)]), None)

    def union_type(self, c: list[Any]) -> TypeBody:
        return TypeBody(A.StructType(self.sp(c[0]), [x for x in c if isinstance(x, A.VarDecl)], union=True), None)

    def enum_value(self, c: list[Any]) -> A.EnumValue:
        name: Token = c[0]
        self._not_reserved(name)
        return A.EnumValue(self.sp(name), str(name), c[1] if len(c) > 1 else None)

    def struct_member(self, c: list[Any]) -> A.VarDecl:
        return self._var_decl(c)

    def named_type(self, c: list[Token]) -> A.NamedType:
        return A.NamedType(self.sp(c[0]), str(c[0]))

    def ctor_type(self, c: list[Any]) -> A.NamedType:
        parts = [x for x in c if isinstance(x, Token)]  # Lib.FB: the (qualified) type's name
        args: list[FieldValue] = [x for x in c if not isinstance(x, Token)]
        name = ".".join(str(p) for p in parts)
        return A.NamedType(self.sp(parts[0]), name, [(n, sp, v) for n, sp, v in args])

    def array_ctor(self, c: list[Any]) -> ArrayCtor:
        kw: Token = c[0]
        last = c[-1]
        ranges: list[Range | None] = [x for x in c[1:-1] if not isinstance(x, Token)]  # without OF
        if isinstance(last, A.NamedType):  # OF FB(args): the same for every element
            args, last.ctor_args = last.ctor_args, None
            return ArrayCtor(A.ArrayType(self.sp(kw), ranges, last), args, None)
        spec, lists = last
        return ArrayCtor(A.ArrayType(self.sp(kw), ranges, spec), None, lists)

    def ctor_elements(self, c: list[Any]) -> tuple[A.NamedType, list[list[FieldValue]]]:
        name: Token = c[0]
        return A.NamedType(self.sp(name), str(name)), [x.args for x in c[1:]]

    def ctor_args(self, c: list[Any]) -> CtorArgs:
        return CtorArgs(list(c))

    def ctor_positional(self, c: list[A.Expr]) -> FieldValue:
        return ("", c[0].span, c[0])  # the checker names it: the n-th input of FB_init

    def string_type(self, c: list[Any]) -> A.StringType:
        kw: Token = c[0]
        return A.StringType(self.sp(kw), str(kw).upper() == "WSTRING", c[1] if len(c) > 1 else None)

    def array_type(self, c: list[Any]) -> A.ArrayType:
        kw: Token
        element: A.TypeSpec
        kw, *rest, element = c
        ranges: list[Range | None] = [x for x in rest if not isinstance(x, Token)]  # without OF
        return A.ArrayType(self.sp(kw), ranges, element)

    def ref_type(self, c: list[Any]) -> A.RefType:
        return A.RefType(self.sp(c[0]), c[-1], "REF_TO")

    def pointer_type(self, c: list[Any]) -> A.RefType:
        return A.RefType(self.sp(c[0]), c[-1], "POINTER")

    def reference_type(self, c: list[Any]) -> A.RefType:
        return A.RefType(self.sp(c[0]), c[-1], "REFERENCE")

    def subrange_type(self, c: list[Any]) -> A.SubrangeType | A.NamedType:
        base: Token
        bounds: Range | None
        base, bounds = c
        if bounds is None:  # INT(*): `*` is an array's bound, not a subrange's
            self.errors.append(
                BuildError(self.sp(base), f"a subrange of {base} needs its bounds: {base}(lo..hi)", Code.SYNTAX)
            )
            return A.NamedType(self.sp(base), str(base))
        lo, hi = bounds
        return A.SubrangeType(self.sp(base), str(base), lo, hi)

    def inline_enum_type(self, c: list[A.EnumValue]) -> A.EnumType:
        return A.EnumType(c[0].span, list(c), "", "")

    def subrange(self, c: list[A.Expr]) -> Range:
        lo, hi = c
        return (lo, hi)

    def star_range(self, c: list[Any]) -> None:
        return None

    # ---------------------------------------------------------------- variables
    def var_block(self, c: list[Any]) -> A.VarBlock:
        kw: Token = c[0]
        quals = [q for q in c[1:] if isinstance(q, Token) and q.type in _QUALIFIERS]
        decls = [d for d in c if isinstance(d, (A.VarDecl, A.AccessDecl))]
        if str(kw).upper() != "VAR_ACCESS":
            for d in decls:
                if isinstance(d, A.AccessDecl):
                    self.errors.append(BuildError(d.span, "an access path is declared in VAR_ACCESS", Code.SYNTAX))
            decls = [d for d in decls if isinstance(d, A.VarDecl)]
        else:
            for d in decls:
                if isinstance(d, A.VarDecl):
                    self.errors.append(
                        BuildError(d.span, "VAR_ACCESS declares access paths: name : path : type;", Code.SYNTAX)
                    )
            decls = [d for d in decls if isinstance(d, A.AccessDecl)]
        return A.VarBlock(self.sp(kw), str(kw).upper(), [str(q).upper() for q in quals], decls)

    def var_qualifier(self, c: list[Token]) -> Token:
        return c[0]

    def _var_decl(self, c: list[Any]) -> A.VarDecl:
        """c: the names, then those of a location, the type, an edge and the initial value that
        the declaration has, in that order."""
        names: list[Token] = c[0]
        location = ""
        edge = ""
        init = None
        spec: A.TypeSpec | None = None
        array_ctor: ArrayCtor | None = None
        for x in c[1:]:
            match x:
                case A.TypeSpec() if spec is None:
                    spec = x
                case ArrayCtor() if spec is None:
                    spec, array_ctor = x.spec, x
                case Location(address):
                    location = address
                case Edge(kind):
                    edge = kind
                case _:
                    init = x
        if isinstance(spec, A.NamedType) and spec.ctor_args:
            init = A.CtorInit(spec.span, spec.ctor_args, init)
            spec.ctor_args = None
        assert spec is not None  # the grammar gives every declaration a type
        if array_ctor is not None:
            init = A.ArrayCtorInit(spec.span, array_ctor.each, array_ctor.elements, init)
        return A.VarDecl(self.sp(names[0]), [(str(n), self.sp(n)) for n in names], spec, init, location, edge)

    def var_decl(self, c: list[Any]) -> A.VarDecl:
        return self._var_decl(c)

    def anonymous_located_decl(self, c: list[Any]) -> A.VarDecl:
        """`AT %IX1.1 : BOOL;` (IEC): a variable reached only by its address. Its name joins two
        words with '__', which no ST identifier may contain, so it names nothing else."""
        loc: Location = c[0]
        at = Token("IDENT", "AT__" + loc.address.lstrip("%").replace(".", "_"))
        first = next((t for t in c if isinstance(t, Token)), None)
        if first is not None:
            at = Token.new_borrow_pos("IDENT", str(at), first)
        return self._var_decl([[at]] + list(c))

    def config_decl(self, c: list[Any]) -> A.VarDecl:
        path: list[Token] = c[0]
        d = self._var_decl([[path[-1]]] + list(c[1:]))
        d.span = self.sp(path[0])
        d.path = [str(p) for p in path]
        return d

    def access_decl(self, c: list[Any]) -> A.AccessDecl:
        names: list[Token] = c[0]
        path: list[str] = c[1]
        spec: A.TypeSpec = c[2]
        direction = str(c[3]).upper() if len(c) > 3 and c[3] is not None else "READ_ONLY"
        if len(names) > 1:
            self.errors.append(BuildError(self.sp(names[1]), "an access path has one name", Code.SYNTAX))
        return A.AccessDecl(
            self.sp(names[0]), [(str(names[0]), self.sp(names[0]))], path, spec, direction == "READ_ONLY"
        )

    def access_path(self, c: list[Any]) -> list[str]:
        out: list[str] = []
        for x in c:
            if isinstance(x, Token) and x.type == "DIRECT_VAR":
                out.append(str(x).upper())
            elif x is not None:
                out.extend(str(x).split("."))  # itf_name: one dotted token
        return out

    def edge(self, c: list[Token]) -> Edge:
        return Edge(str(c[0]).upper())

    def config_path(self, c: list[Token]) -> list[Token]:
        return list(c)

    def name_list(self, c: list[Token]) -> list[Token]:
        for t in c:
            self._not_reserved(t)
        return list(c)

    def location(self, c: list[Token]) -> Location:
        _, address = c
        return Location(str(address).upper())

    def array_init(self, c: list[Any]) -> A.ArrayInit:
        return A.ArrayInit(self.sp(c[0]), list(c))

    def repeat_init(self, c: list[Any]) -> A.RepeatInit:
        count: Token
        count, *items = c
        return A.RepeatInit(self.sp(count), self._lit(int_literal, count), items)

    def struct_init(self, c: list[FieldValue]) -> A.StructInit:
        _, first_span, _ = c[0]
        return A.StructInit(first_span, list(c))

    def field_init(self, c: list[Any]) -> FieldValue:
        name: Token
        name, value = c
        return (str(name), self.sp(name), value)

    # ---------------------------------------------------------------- POUs
    def _pou(self, kind: str, kw: Token, name: Token, parts: list[Any], end: Token) -> A.POU:
        self._not_reserved(name)
        pou = A.POU(self.sp(name), kind, str(name))
        pou.end_span = self.sp(end)
        for p in flat(parts):
            if isinstance(p, A.VarBlock):
                pou.var_blocks.append(p)
            elif isinstance(p, A.Step):
                pou.steps.append(p)
            elif isinstance(p, A.Transition):
                pou.transitions.append(p)
            elif isinstance(p, A.ActionDecl):
                pou.actions.append(p)
            elif isinstance(p, A.Method):
                pou.methods.append(p)
            elif isinstance(p, A.Property):
                pou.properties.append(p)
            elif isinstance(p, A.Stmt):
                pou.body.append(p)
        return pou

    @staticmethod
    def _modifiers(c: list[Any], i: int) -> tuple[list[str], int]:
        """The modifiers from c[i] on, and the index after them."""
        mods = []
        while isinstance(c[i], Modifier):
            mods.append(c[i].name)
            i += 1
        return mods, i

    def _top_level_access(self, pou: A.POU, mods: list[str]) -> None:
        """FUNCTION/PROGRAM/INTERFACE PUBLIC or INTERNAL (CODESYS, TwinCAT): read; with no
        namespaces (one project, its libraries) both mean visible everywhere."""
        for m in mods:
            if m not in ("PUBLIC", "INTERNAL"):
                self.errors.append(BuildError(pou.span, f"{m} is not allowed on a {pou.kind}", Code.SYNTAX))

    def function_decl(self, c: list[Any]) -> A.POU:
        mods, i = self._modifiers(c, 1)
        kw, name, end = c[0], c[i], c[-1]
        rest = c[i + 1 : -1]
        ret = None
        if rest and isinstance(rest[0], A.TypeSpec):
            ret, rest = rest[0], rest[1:]
        pou = self._pou("FUNCTION", kw, name, rest, end)
        pou.return_type = ret
        self._top_level_access(pou, mods)
        return pou

    def fb_decl(self, c: list[Any]) -> A.POU:
        mods, i = self._modifiers(c, 1)
        kw, name, end = c[0], c[i], c[-1]
        extends = ""
        implements: list[str] = []
        rest = []
        for x in c[i + 1 : -1]:
            match x:
                case Extends(base):
                    extends = base
                case Implements(names):
                    implements = names
                case _:
                    rest.append(x)
        pou = self._pou("FUNCTION_BLOCK", kw, name, rest, end)
        pou.modifiers = mods
        pou.extends = extends
        pou.implements = implements
        return pou

    def method_decl(self, c: list[Any]) -> A.Method:
        mods, i = self._modifiers(c, 1)
        name: Token = c[i]
        end: Token = c[-1]
        self._not_reserved(name)
        rest = c[i + 1 : -1]
        m = A.Method(self.sp(name), str(name), mods)
        if rest and isinstance(rest[0], A.TypeSpec):
            m.return_type, rest = rest[0], rest[1:]
        for p in flat(rest):
            if isinstance(p, A.VarBlock):
                m.var_blocks.append(p)
            elif isinstance(p, A.Stmt):
                m.body.append(p)
        m.end_span = self.sp(end)
        return m

    def itf_name(self, c: list[Token]) -> Token:
        return Token.new_borrow_pos("IDENT", ".".join(str(x) for x in c), c[0])

    def interface_decl(self, c: list[Any]) -> A.Interface:
        mods, i = self._modifiers(c, 1)
        name: Token = c[i]
        end: Token = c[-1]
        self._not_reserved(name)
        itf = A.Interface(self.sp(name), str(name))
        itf.end_span = self.sp(end)
        for m in mods:
            if m not in ("PUBLIC", "INTERNAL"):
                self.errors.append(BuildError(itf.span, f"{m} is not allowed on an INTERFACE", Code.SYNTAX))
        after_extends = False
        for x in c[i + 1 : -1]:
            if isinstance(x, A.Method):
                itf.methods.append(x)
            elif isinstance(x, A.Property):
                itf.properties.append(x)
            elif isinstance(x, Token) and x.type == "EXTENDS":
                after_extends = True
            elif after_extends:  # the names of the interfaces extended
                itf.extends.append(str(x))
        return itf

    def property_decl(self, c: list[Any]) -> A.Property:
        mods, i = self._modifiers(c, 1)
        name: Token = c[i]
        end: Token = c[-1]
        self._not_reserved(name)
        prop = A.Property(self.sp(name), str(name), mods, c[i + 1])
        acc: Accessor | Token
        for acc in c[i + 2 : -1]:
            if isinstance(acc, Token):  # TwinCAT writes PROPERTY P : T; with a ';'
                continue
            own = [p.name for p in acc.parts if isinstance(p, Modifier)]
            # GET PRIVATE / SET PROTECTED: the accessor's own access replaces the property's
            m = A.Method(acc.span, str(name), [x for x in mods if not (own and x in _ACCESS)] + own)
            for p in flat(acc.parts):
                if isinstance(p, A.VarBlock):
                    m.var_blocks.append(p)
                elif isinstance(p, A.Stmt):
                    m.body.append(p)
            if acc.kind == "GET":
                m.return_type = prop.type
                prop.get = m
            else:
                prop.set = m
        prop.end_span = self.sp(end)
        return prop

    def property_get(self, c: list[Any]) -> Accessor:
        return Accessor("GET", self.sp(c[0]), c[1:-1])

    def property_set(self, c: list[Any]) -> Accessor:
        return Accessor("SET", self.sp(c[0]), c[1:-1])

    def method_modifier(self, c: list[Token]) -> Modifier:
        return Modifier(str(c[0]).upper())

    def class_decl(self, c: list[Any]) -> A.POU:
        """CLASS: a function block without a body of its own (methods and properties only)."""
        pou = self.fb_decl(c)
        pou.modifiers = pou.modifiers + ["CLASS"]
        return pou

    def program_decl(self, c: list[Any]) -> A.POU:
        mods, i = self._modifiers(c, 1)
        pou = self._pou("PROGRAM", c[0], c[i], c[i + 1 : -1], c[-1])
        self._top_level_access(pou, mods)
        return pou

    def pou_modifier(self, c: list[Token]) -> Modifier:
        return Modifier(str(c[0]).upper())

    def extends(self, c: list[Token]) -> Extends:
        _, base = c
        return Extends(str(base))

    def implements(self, c: list[Token]) -> Implements:
        _, *names = c
        return Implements([str(x) for x in names])

    # ---------------------------------------------------------------- SFC
    def step_decl(self, c: list[Any]) -> A.Step:
        kw: Token
        name: Token
        kw, name, *rest = c
        initial = str(kw).upper() == "INITIAL_STEP"
        return A.Step(self.sp(name), str(name), initial, [x for x in rest if isinstance(x, A.ActionAssoc)])

    def action_assoc(self, c: list[Any]) -> A.ActionAssoc:
        action: Token
        qualifier: Token
        action, qualifier, *args = c
        return A.ActionAssoc(self.sp(action), str(action), str(qualifier).upper(), args[0] if args else None)

    def transition_decl(self, c: list[Any]) -> A.Transition:
        i_from = next(i for i, x in enumerate(c) if isinstance(x, Token) and x.type == "FROM")
        head = c[1:i_from]
        name = ""
        prio = None
        if len(head) == 1:
            name = str(head[0])
        elif len(head) == 2:
            prio = head[1]
        elif len(head) == 3:
            name, prio = str(head[0]), head[2]
        sources: list[tuple[str, Span]] = c[i_from + 1]
        targets: list[tuple[str, Span]] = c[i_from + 3]
        t = A.Transition(self.sp(c[0]), name, prio, sources, targets)
        match c[i_from + 4]:
            case TransitionCond(cond):
                t.cond = cond
            case TransitionBody(body):
                t.body = body
        return t

    def step_set(self, c: list[Token]) -> list[tuple[str, Span]]:
        return [(str(x), self.sp(x)) for x in c]

    def transition_cond(self, c: list[A.Expr]) -> TransitionCond:
        return TransitionCond(c[0])

    def transition_body(self, c: list[Any]) -> TransitionBody:
        return TransitionBody(self._stmts(c))

    def action_decl(self, c: list[Any]) -> A.ActionDecl:
        name: Token
        _, name, *body, _ = c
        return A.ActionDecl(self.sp(name), str(name), self._stmts(body))

    # ---------------------------------------------------------------- configuration
    def configuration_decl(self, c: list[Any]) -> A.Configuration:
        name: Token = c[1]
        blocks = [x for x in c if isinstance(x, A.VarBlock)]
        resources = [x for x in c if isinstance(x, A.Resource)]
        tasks = [x for x in c if isinstance(x, A.TaskDecl)]
        progs = [x for x in c if isinstance(x, A.ProgramConfig)]
        if tasks or progs:
            resources.insert(0, A.Resource(self.sp(name), "", "", [], tasks, progs))
        return A.Configuration(self.sp(name), str(name), blocks, resources)

    def resource_decl(self, c: list[Any]) -> A.Resource:
        name: Token
        target: Token
        _, name, _, target, *parts = c
        return A.Resource(
            self.sp(name),
            str(name),
            str(target),
            [x for x in parts if isinstance(x, A.VarBlock)],
            [x for x in parts if isinstance(x, A.TaskDecl)],
            [x for x in parts if isinstance(x, A.ProgramConfig)],
        )

    def task_decl(self, c: list[Any]) -> A.TaskDecl:
        name: Token
        _, name, *rest = c
        params: dict[str, A.Expr] = {}
        for x in rest:
            if isinstance(x, TaskParam):
                params[x.name.upper()] = x.value
        return A.TaskDecl(self.sp(name), str(name), params)

    def task_param(self, c: list[Any]) -> TaskParam:
        name, value = c
        return TaskParam(str(name), value)

    def program_config(self, c: list[Any]) -> A.ProgramConfig:
        items = list(c[1:])
        retain = ""
        if (
            items
            and isinstance(items[0], Token)
            and items[0].type in ("RETAIN", "NON_RETAIN", "CONSTANT", "PERSISTENT")
        ):
            retain = str(items.pop(0)).upper()
        inst = items.pop(0)
        task = ""
        if items and isinstance(items[0], Token) and items[0].type == "WITH":
            items.pop(0)
            task = str(items.pop(0))
        type_name = items.pop(0)
        args = [a for a in items if isinstance(a, A.Arg)]
        return A.ProgramConfig(self.sp(inst), str(inst), task, str(type_name), args, retain)

    # ---------------------------------------------------------------- tests
    def test_decl(self, c: list[Any]) -> A.TestBlock:
        kw: Token
        title: Token
        kw, title, *parts, _ = c
        wide = title.type == "WSTRING_LIT"
        name = self._lit(parse_string, title, wide)
        return self._test("TEST", kw, name, parts)

    def setup_decl(self, c: list[Any]) -> A.TestBlock:
        return self._test("SETUP", c[0], "", c[1:-1])

    def teardown_decl(self, c: list[Any]) -> A.TestBlock:
        return self._test("TEARDOWN", c[0], "", c[1:-1])

    def _test(self, kind: str, kw: Token, name: str, parts: list[Any]) -> A.TestBlock:
        return A.TestBlock(
            self.sp(kw),
            kind,
            name,
            [p for p in parts if isinstance(p, A.VarBlock)],
            self._stmts(parts),
        )

    # ---------------------------------------------------------------- statements
    def assignment(self, c: list[Any]) -> A.Assign:
        target: A.Expr
        value: A.Expr
        target, _, value = c
        return A.Assign(target.span, target, value, ":=")

    def chained_assignment(self, c: list[Any]) -> Chain:
        """`a := b := c;` (CODESYS): the rightmost assignment first, each target then given the
        one to its right, so `c` is evaluated once and `a` gets `b`'s value."""
        targets: list[A.Expr] = c[0:-1:2]
        out = Chain()
        value: A.Expr = c[-1]
        for t in reversed(targets):
            out.append(A.Assign(t.span, t, value, ":="))
            value = copy.deepcopy(t)
        out[-1].chained = True
        return out

    def set_assignment(self, c: list[Any]) -> A.Assign:
        target: A.Expr
        target, _, value = c
        return A.Assign(target.span, target, value, "S=")

    def reset_assignment(self, c: list[Any]) -> A.Assign:
        target: A.Expr
        target, _, value = c
        return A.Assign(target.span, target, value, "R=")

    def attempt_assignment(self, c: list[Any]) -> A.Assign:
        target: A.Expr
        target, _, value = c
        return A.Assign(target.span, target, value, "?=")

    def ref_assignment(self, c: list[Any]) -> A.Assign:
        target: A.Expr
        target, _, value = c
        return A.Assign(target.span, target, value, "REF=")

    def call_stmt(self, c: list[A.Call]) -> A.CallStmt:
        return A.CallStmt(c[0].span, c[0])

    def mock_stmt(self, c: list[Any]) -> A.Mock:
        kw, target = c
        return A.Mock(self.sp(kw), target)

    def mock_function_stmt(self, c: list[Any]) -> A.MockFunction:
        kw, name, _, value = c
        return A.MockFunction(self.sp(kw), str(name), value)

    def empty_stmt(self, c: list[Any]) -> None:
        return None

    @staticmethod
    def _stmts(items: Iterable[Any]) -> list[A.Stmt]:
        return [s for s in flat(items) if isinstance(s, A.Stmt)]

    def if_stmt(self, c: list[Any]) -> A.If | Chain:
        kw: Token
        cond: A.Expr | AssignCondition
        kw, cond, _, *rest = c
        branches: list[tuple[A.Expr | AssignCondition, list[A.Stmt]]] = [(cond, self._stmts(rest))]
        orelse = None
        for x in rest:
            match x:
                case ElsIf(elsif_cond, body):
                    branches.append((elsif_cond, body))
                case Else(body):
                    orelse = body
        return self._if_chain(self.sp(kw), branches, orelse)

    def _if_chain(
        self, span: Span, branches: list[tuple[A.Expr | AssignCondition, list[A.Stmt]]], orelse: list[A.Stmt] | None
    ) -> A.If | Chain:
        """An IF whose conditions may assign (`IF b := f() THEN`): the branches before the first such
        condition, then, in their ELSE, the assignment and an IF of the rest testing `b` (so it is
        made only where TwinCAT evaluates that condition)."""
        k = next((i for i, (cnd, _) in enumerate(branches) if isinstance(cnd, AssignCondition)), None)
        if k is None:
            return A.If(span, cast(list[tuple[A.Expr, list[A.Stmt]]], branches), orelse)
        first = cast(AssignCondition, branches[k][0])
        rest = self._if_chain(first.span, [(first.test(), branches[k][1])] + branches[k + 1 :], orelse)
        tail: list[A.Stmt] = [first.assign(), *(rest if isinstance(rest, Chain) else [rest])]
        if k == 0:
            return Chain(cast(list[A.Assign], tail))
        return A.If(span, cast(list[tuple[A.Expr, list[A.Stmt]]], branches[:k]), tail)

    def assign_condition(self, c: list[Any]) -> AssignCondition:
        target, _, value = c
        return AssignCondition(target.span, target, value)

    def elsif_clause(self, c: list[Any]) -> ElsIf:
        _, cond, _, *body = c
        return ElsIf(cond, self._stmts(body))

    def else_clause(self, c: list[Any]) -> Else:
        return Else(self._stmts(c[1:]))

    def case_stmt(self, c: list[Any]) -> A.Case:
        kw: Token
        selector: A.Expr
        kw, selector, _, *rest = c
        branches: list[A.CaseBranch] = []
        orelse = None
        for x in flat(rest):
            match x:
                case CaseLabels(labels):
                    branches.append(A.CaseBranch(labels[0][0].span, labels, []))
                case Else(body):
                    orelse = body
                case A.Stmt():
                    if not branches:  # reported, the statement dropped: parsing goes on
                        self.errors.append(
                            BuildError(x.span, "a statement in a CASE needs a label before it", Code.SYNTAX)
                        )
                        continue
                    branches[-1].body.append(x)
        return A.Case(self.sp(kw), selector, branches, orelse)

    def case_labels(self, c: list[CaseLabel]) -> CaseLabels:
        return CaseLabels([(x.lo, x.hi) for x in c])

    def case_else(self, c: list[Any]) -> Else:
        return Else(self._stmts(c[1:]))

    def case_label(self, c: list[A.Expr]) -> CaseLabel:
        return CaseLabel(c[0], None)

    def case_range(self, c: list[A.Expr]) -> CaseLabel:
        lo, hi = c
        return CaseLabel(lo, hi)

    def signed_int(self, c: list[Token]) -> A.Literal:
        neg = len(c) == 2
        tok = c[-1]
        v = self._lit(int_literal, tok)
        return A.Literal(self.sp(c[0]), "int", -v if neg else v, "", ("-" if neg else "") + str(tok))

    def case_real(self, c: list[Token]) -> A.Literal:
        neg = len(c) == 2
        v = self._lit(real_literal, c[-1])
        return A.Literal(self.sp(c[0]), "real", -v if neg else v, "", str(c[-1]))

    def case_other(self, c: list[Token]) -> A.Literal:
        t = c[0]
        if t.type == "TIME_LIT":
            return self._prefixed("time", time_literal, t)
        if t.type in ("TRUE", "FALSE"):
            return A.Literal(self.sp(t), "bool", t.type == "TRUE", "", str(t))
        wide = t.type == "WSTRING_LIT"
        return A.Literal(self.sp(t), "wstring" if wide else "string", self._lit(parse_string, t, wide), "", str(t))

    def for_stmt(self, c: list[Any]) -> A.For:
        kw: Token
        var: A.Expr
        start: A.Expr
        end: A.Expr
        kw, var, _, start, _, end, *rest = c
        step = None
        if isinstance(rest[0], Token) and rest[0].type == "BY":
            _, step, *rest = rest
        _, *body = rest  # after DO
        return A.For(self.sp(kw), var, start, end, step, self._stmts(body))

    def while_stmt(self, c: list[Any]) -> A.While:
        kw: Token
        cond: A.Expr | AssignCondition
        kw, cond, _, *body = c
        if isinstance(cond, AssignCondition):  # WHILE b := f() DO: assigned and tested before each round
            test = A.If(cond.span, [(A.Unary(cond.span, "NOT", cond.test()), [A.Exit(cond.span)])])
            true = A.Literal(cond.span, "bool", True, "", "TRUE")
            return A.While(self.sp(kw), true, [cond.assign(), test, *self._stmts(body)])
        return A.While(self.sp(kw), cond, self._stmts(body))

    def repeat_stmt(self, c: list[Any]) -> A.Repeat:
        i_until = next(i for i, x in enumerate(c) if isinstance(x, Token) and x.type == "UNTIL")
        cond = c[i_until + 1]
        body = self._stmts(c[1:i_until])
        if isinstance(cond, AssignCondition):  # UNTIL b := f(): assigned after each round, then tested
            return A.Repeat(self.sp(c[0]), [*body, cond.assign()], cond.test())
        return A.Repeat(self.sp(c[0]), body, cond)

    def try_stmt(self, c: list[Any]) -> A.Try:
        kw: Token = c[0]
        out = A.Try(self.sp(kw), self._stmts(c[1:]))
        for x in c[1:]:
            match x:
                case Catch(var, body):
                    out.catch_var, out.handler = var, body
                case Finally(body):
                    out.final = body
        return out

    def catch_clause(self, c: list[Any]) -> Catch:
        _, var, *body = c
        return Catch(var, self._stmts(body))

    def finally_clause(self, c: list[Any]) -> Finally:
        return Finally(self._stmts(c[1:]))

    def exit_stmt(self, c: list[Token]) -> A.Exit:
        return A.Exit(self.sp(c[0]))

    def continue_stmt(self, c: list[Token]) -> A.Continue:
        return A.Continue(self.sp(c[0]))

    def return_stmt(self, c: list[Token]) -> A.Return:
        return A.Return(self.sp(c[0]))

    # ---------------------------------------------------------------- expressions
    def _bin(self, op: str, left: A.Expr, right: A.Expr) -> A.Binary:
        return A.Binary(left.span, op, left, right)

    def expression(self, c: list[Any]) -> A.Expr:
        """c = [operand, op, operand, op, ...]: precedence climbing, all left-associative."""
        ops = [str(t).upper() for t in c[1::2]]
        operands: list[A.Expr] = c[0::2]
        pos = 0

        def climb(min_prec: int) -> A.Expr:
            nonlocal pos
            left = operands[pos]
            while pos < len(ops):
                op = ops[pos]
                prec = _PREC[op]
                if prec < min_prec:
                    break
                pos += 1
                # left-associative: the right side only takes tighter operators
                right = climb(prec + 1)
                left = A.Binary(left.span, _OPNAME.get(op, op), left, right)
            return left

        return climb(0)

    def unary_expr(self, c: list[Any]) -> A.Expr:
        op_tok: Token
        operand: A.Expr
        op_tok, operand = c
        op = str(op_tok).upper()
        if op == "-" and isinstance(operand, A.Literal) and operand.kind in ("int", "real") and not operand.type_name:
            # fold negative literals so that e.g. -32768 fits an INT
            return A.Literal(self.sp(op_tok), operand.kind, -operand.value, "", "-" + operand.text)
        return A.Unary(self.sp(op_tok), op, operand)

    def call(self, c: list[Any]) -> A.Call:
        callee: A.Expr
        rpar: Token
        callee, *args, rpar = c
        start, end = callee.span, self.sp(rpar)
        span = Span(start.file, start.line, start.col, end.end_line, end.end_col)
        return A.Call(span, callee, [a for a in args if isinstance(a, A.Arg)])

    def pos_arg(self, c: list[A.Expr]) -> A.Arg:
        return A.Arg(c[0].span, "", c[0])

    def named_arg(self, c: list[Any]) -> A.Arg:
        name: Token
        value: A.Expr
        name, _, value = c
        return A.Arg(self.sp(name), str(name), value)

    def out_arg(self, c: list[Any]) -> A.Arg:
        neg = isinstance(c[0], Token) and c[0].type == "NOT"
        name = c[1] if neg else c[0]
        return A.Arg(self.sp(c[0]), str(name), c[-1], True, neg)

    def var_name(self, c: list[Token]) -> A.Name:
        return A.Name(self.sp(c[0]), str(c[0]))

    def var_direct(self, c: list[Token]) -> A.Direct:
        return A.Direct(self.sp(c[0]), str(c[0]).upper())

    def var_field(self, c: list[Any]) -> A.Field:
        base: A.Expr
        name: Token
        base, name = c
        return A.Field(base.span, base, str(name), self.sp(name))

    def var_bit(self, c: list[Any]) -> A.Bit:
        base: A.Expr
        base, index = c
        return A.Bit(base.span, base, self._lit(int_literal, index), "X")

    def var_partial(self, c: list[Any]) -> A.Bit:
        base: A.Expr
        base, access = c
        t = str(access).upper()  # %X1, %B0, ...
        return A.Bit(base.span, base, int(t[2:]), t[1])

    def var_index(self, c: list[Any]) -> A.Index:
        base: A.Expr
        base, *indices = c
        return A.Index(base.span, base, indices)

    def var_deref(self, c: list[Any]) -> A.Deref:
        base: A.Expr = c[0]
        return A.Deref(base.span, base)

    # ---------------------------------------------------------------- literals
    def lit_int(self, c: list[Token]) -> A.Literal:
        t = c[0]
        return A.Literal(self.sp(t), "int", self._lit(int_literal, t), "", str(t))

    def lit_real(self, c: list[Token]) -> A.Literal:
        t = c[0]
        return A.Literal(self.sp(t), "real", self._lit(real_literal, t), "", str(t))

    def lit_true(self, c: list[Token]) -> A.Literal:
        return A.Literal(self.sp(c[0]), "bool", True, "", "TRUE")

    def lit_false(self, c: list[Token]) -> A.Literal:
        return A.Literal(self.sp(c[0]), "bool", False, "", "FALSE")

    def lit_string(self, c: list[Token]) -> A.Literal:
        return A.Literal(self.sp(c[0]), "string", self._lit(parse_string, c[0], False), "", str(c[0]))

    def lit_wstring(self, c: list[Token]) -> A.Literal:
        return A.Literal(self.sp(c[0]), "wstring", self._lit(parse_string, c[0], True), "", str(c[0]))

    def _prefixed(self, kind: str, fn: Callable[[str], int], tok: Token) -> A.Literal:
        t = str(tok)
        prefix = t.split("#", 1)[0].upper()
        return A.Literal(self.sp(tok), kind, self._lit(fn, tok), prefix, t)

    def lit_time(self, c: list[Token]) -> A.Literal:
        return self._prefixed("time", time_literal, c[0])

    def lit_date(self, c: list[Token]) -> A.Literal:
        return self._prefixed("date", date_literal, c[0])

    def lit_tod(self, c: list[Token]) -> A.Literal:
        return self._prefixed("tod", tod_literal, c[0])

    def lit_dt(self, c: list[Token]) -> A.Literal:
        return self._prefixed("dt", dt_literal, c[0])

    def lit_typed_num(self, c: list[Token]) -> A.Literal:
        typed = c[0]  # INT#, REAL#, ...
        prefix = str(typed)[:-1]
        neg = len(c) == 3
        tok = c[-1]
        text = str(typed) + ("-" if neg else "") + str(tok)
        if tok.type == "REAL_LIT":
            bits = 32 if prefix.upper() == "REAL" else 64
            kind, v = "real", self._lit(real_literal, tok, bits, at=typed, shown=text)
        else:
            kind, v = "int", self._lit(int_literal, tok, at=typed, shown=text)
        return A.Literal(self.sp(typed), kind, -v if neg else v, prefix.upper(), text)

    def lit_typed_bool(self, c: list[Token]) -> A.Literal:
        typed, value = c
        prefix = str(typed)[:-1]
        return A.Literal(self.sp(typed), "bool", str(value).upper() == "TRUE", prefix.upper(), str(typed) + str(value))

    def lit_typed_string(self, c: list[Token]) -> A.Literal:
        typed, value = c
        prefix = str(typed)[:-1]
        wide = value.type == "WSTRING_LIT"
        return A.Literal(
            self.sp(typed),
            "wstring" if wide else "string",
            self._lit(parse_string, value, wide),
            prefix.upper(),
            str(typed) + str(value),
        )

    def lit_enum(self, c: list[Token]) -> A.EnumLit:
        typed, member = c
        prefix = str(typed)[:-1]
        return A.EnumLit(self.sp(typed), prefix, str(member))
