"""Lark callbacks → AST. One method per grammar rule (Lark's Transformer style).

The builder runs inside the LALR parser (no intermediate parse tree), which is
what makes parsing large libraries fast.
"""

from __future__ import annotations

import copy

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
EDGE_NAMES = frozenset({"R_EDGE", "F_EDGE"})
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


class BuildError(Exception):
    def __init__(self, span: Span, message: str, code: str = Code.MISPLACED_SECTION):
        self.span = span
        self.message = message
        self.code = code


class _Chain(list):
    """Several statements from one piece of text (a chained assignment), spliced into the
    statement list around it by `_flat`."""


def _flat(items):
    for x in items:
        if isinstance(x, _Chain):
            yield from x
        else:
            yield x


class AstBuilder(Transformer):
    """Builds AST nodes for one file; literal errors are collected in `errors`."""

    __visit_tokens__ = False

    def __init__(self, path: str):
        super().__init__(visit_tokens=False)
        self.path = path
        self.errors: list[BuildError] = []
        # keywords the chosen dialect lets a program use as names (CODESYS: R_EDGE, F_EDGE)
        self.names_allowed: frozenset[str] = frozenset()

    # ---------------------------------------------------------------- helpers
    def sp(self, x) -> Span:
        if isinstance(x, Token):
            # the lexer gives every token its position, and the parser's repaired ";" copies one
            return Span(self.path, x.line, x.column, x.end_line, x.end_column)  # type: ignore[arg-type]
        span = getattr(x, "span", None)
        if span is not None:
            return span
        if isinstance(x, (list, tuple)) and x:
            return self.sp(x[0])
        return Span(self.path, 0, 0)

    def _lit(self, fn, tok, *args, at=None, shown: str = ""):
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
    def start(self, items):
        out = []
        for i in items:
            if isinstance(i, (A.Method, A.Property, A.ActionDecl)):
                self._attach(i, out)
            elif i is not None:
                out.append(i)
        return A.Unit(self.path, out)

    def _attach(self, part, items) -> None:
        """A METHOD, PROPERTY or ACTION after END_FUNCTION_BLOCK / END_PROGRAM (the layout of TwinCAT
        and CODESYS text exports) belongs to the block just before it in the file."""
        owner = (
            items[-1]
            if items and isinstance(items[-1], A.POU) and items[-1].kind in ("FUNCTION_BLOCK", "PROGRAM")
            else None
        )
        what = {A.Method: "METHOD", A.Property: "PROPERTY", A.ActionDecl: "ACTION"}[type(part)]
        if owner is None:
            self.errors.append(
                BuildError(
                    part.span,
                    f"this {what} is outside any FUNCTION_BLOCK or PROGRAM: "
                    f"declare it inside the block, or right after its END_FUNCTION_BLOCK",
                )
            )
            return
        {A.Method: owner.methods, A.Property: owner.properties, A.ActionDecl: owner.actions}[type(part)].append(part)

    def name(self, c):
        return c[0]

    def _not_reserved(self, tok):
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
    def type_decl(self, c):
        return A.TypeBlock(self.sp(c[0]), [x for x in c if isinstance(x, A.TypeDecl)])

    def type_item(self, c):
        name, (spec, init) = c
        self._not_reserved(name)
        return A.TypeDecl(self.sp(name), str(name), spec, init)

    def struct_extends_item(self, c):
        name, base, (spec, init) = c[0], c[2], c[3]
        self._not_reserved(name)
        spec.extends = A.NamedType(self.sp(base), str(base))
        return A.TypeDecl(self.sp(name), str(name), spec, init)

    def alias_type(self, c):
        return (c[0], c[1] if len(c) > 1 else None)

    def enum_type(self, c):
        values = [x for x in c if isinstance(x, A.EnumValue)]
        names = [x for x in c if isinstance(x, Token)]
        base = str(names[0]) if names else ""
        default = str(names[1]) if len(names) > 1 else ""
        return (A.EnumType(values[0].span, values, base, default), None)

    def typed_enum_type(self, c):
        base = c[0]
        values = [x for x in c[1:] if isinstance(x, A.EnumValue)]
        rest = [x for x in c[1:] if isinstance(x, Token)]
        return (A.EnumType(self.sp(base), values, str(base), str(rest[0]) if rest else ""), None)

    def struct_type(self, c):
        return (A.StructType(self.sp(c[0]), [x for x in c if isinstance(x, A.VarDecl)]), None)

    def union_type(self, c):
        return (A.StructType(self.sp(c[0]), [x for x in c if isinstance(x, A.VarDecl)], union=True), None)

    def enum_value(self, c):
        self._not_reserved(c[0])
        return A.EnumValue(self.sp(c[0]), str(c[0]), c[1] if len(c) > 1 else None)

    def struct_member(self, c):
        return self._var_decl(c)

    def named_type(self, c):
        return A.NamedType(self.sp(c[0]), str(c[0]))

    def ctor_type(self, c):
        return A.NamedType(self.sp(c[0]), str(c[0]), [(n, sp, v) for n, sp, v in c[1:]])

    def ctor_positional(self, c):
        return ("", c[0].span, c[0])  # the checker names it: the n-th input of FB_init

    def string_type(self, c):
        kw = str(c[0]).upper()
        return A.StringType(self.sp(c[0]), kw == "WSTRING", c[1] if len(c) > 1 else None)

    def array_type(self, c):
        ranges = [x for x in c[1:-1] if not isinstance(x, Token)]
        return A.ArrayType(self.sp(c[0]), ranges, c[-1])

    def ref_type(self, c):
        return A.RefType(self.sp(c[0]), c[-1], "REF_TO")

    def pointer_type(self, c):
        return A.RefType(self.sp(c[0]), c[-1], "POINTER")

    def reference_type(self, c):
        return A.RefType(self.sp(c[0]), c[-1], "REFERENCE")

    def subrange_type(self, c):
        lo, hi = c[1]
        return A.SubrangeType(self.sp(c[0]), str(c[0]), lo, hi)

    def inline_enum_type(self, c):
        return A.EnumType(c[0].span, list(c), "", "")

    def subrange(self, c):
        return (c[0], c[1])

    def star_range(self, c):
        return None

    # ---------------------------------------------------------------- variables
    def var_block(self, c):
        kind = str(c[0]).upper()
        quals = [q for q in c[1:] if isinstance(q, Token) and q.type in _QUALIFIERS]
        decls = [d for d in c if isinstance(d, A.VarDecl)]
        return A.VarBlock(self.sp(c[0]), kind, [str(q).upper() for q in quals], decls)

    def var_qualifier(self, c):
        return c[0]

    def _var_decl(self, c):
        names = c[0]
        location = ""
        edge = ""
        init = None
        spec = None
        for x in c[1:]:
            if isinstance(x, A.TypeSpec) and spec is None:
                spec = x
            elif isinstance(x, tuple) and x and x[0] == "loc":
                location = x[1]
            elif isinstance(x, tuple) and x and x[0] == "edge":
                edge = x[1]
            else:
                init = x
        if isinstance(spec, A.NamedType) and spec.ctor_args:
            init = A.CtorInit(spec.span, spec.ctor_args, init)
            spec.ctor_args = None
        return A.VarDecl(self.sp(names[0]), [(str(n), self.sp(n)) for n in names], spec, init, location, edge)

    def var_decl(self, c):
        return self._var_decl(c)

    def anonymous_located_decl(self, c):
        """`AT %IX1.1 : BOOL;` (IEC): a variable reached only by its address. Its name joins two
        words with '__', which no ST identifier may contain, so it names nothing else."""
        loc = c[0]
        at = Token("IDENT", "AT__" + loc[1].lstrip("%").replace(".", "_"))
        first = next((t for t in c if isinstance(t, Token)), None)
        if first is not None:
            at = Token.new_borrow_pos("IDENT", str(at), first)
        return self._var_decl([[at]] + list(c))

    def config_decl(self, c):
        path = c[0]
        d = self._var_decl([[path[-1]]] + list(c[1:]))
        d.span = self.sp(path[0])
        d.path = [str(p) for p in path]
        return d

    def edge(self, c):
        return ("edge", str(c[0]).upper())

    def config_path(self, c):
        return list(c)

    def name_list(self, c):
        for t in c:
            self._not_reserved(t)
        return list(c)

    def location(self, c):
        return ("loc", str(c[1]).upper())

    def array_init(self, c):
        return A.ArrayInit(self.sp(c[0]), list(c))

    def repeat_init(self, c):
        return A.RepeatInit(self.sp(c[0]), self._lit(int_literal, c[0]), list(c[1:]))

    def struct_init(self, c):
        return A.StructInit(c[0][1], list(c))

    def field_init(self, c):
        return (str(c[0]), self.sp(c[0]), c[1])

    # ---------------------------------------------------------------- POUs
    def _pou(self, kind, kw, name, parts, end):
        self._not_reserved(name)
        pou = A.POU(self.sp(name), kind, str(name))
        pou.end_span = self.sp(end)
        for p in _flat(parts):
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

    def function_decl(self, c):
        mods, i = self._modifiers(c, 1)
        name = c[i]
        rest = c[i + 1 : -1]
        ret = None
        if rest and isinstance(rest[0], A.TypeSpec):
            ret, rest = rest[0], rest[1:]
        pou = self._pou("FUNCTION", c[0], name, rest, c[-1])
        pou.return_type = ret
        self._top_level_access(pou, mods)
        return pou

    @staticmethod
    def _modifiers(c, i):
        """The ("mod", X) items from c[i] on, and the index after them."""
        mods = []
        while isinstance(c[i], tuple) and c[i][0] == "mod":
            mods.append(c[i][1])
            i += 1
        return mods, i

    def _top_level_access(self, pou, mods):
        """FUNCTION/PROGRAM/INTERFACE PUBLIC or INTERNAL (CODESYS, TwinCAT): read; with no
        namespaces (one project, its libraries) both mean visible everywhere."""
        for m in mods:
            if m not in ("PUBLIC", "INTERNAL"):
                self.errors.append(BuildError(pou.span, f"{m} is not allowed on a {pou.kind}", Code.SYNTAX))

    def fb_decl(self, c):
        mods = []
        i = 1
        while isinstance(c[i], tuple) and c[i][0] == "mod":
            mods.append(c[i][1])
            i += 1
        name = c[i]
        i += 1
        extends = ""
        implements = []
        rest = []
        for x in c[i:-1]:
            if isinstance(x, tuple) and x[0] == "extends":
                extends = x[1]
            elif isinstance(x, tuple) and x[0] == "implements":
                implements = x[1]
            else:
                rest.append(x)
        pou = self._pou("FUNCTION_BLOCK", c[0], name, rest, c[-1])
        pou.modifiers = mods
        pou.extends = extends
        pou.implements = implements
        return pou

    def method_decl(self, c):
        mods = []
        i = 1
        while isinstance(c[i], tuple) and c[i][0] == "mod":
            mods.append(c[i][1])
            i += 1
        name = c[i]
        self._not_reserved(name)
        rest = c[i + 1 : -1]
        m = A.Method(self.sp(name), str(name), mods)
        if rest and isinstance(rest[0], A.TypeSpec):
            m.return_type, rest = rest[0], rest[1:]
        for p in _flat(rest):
            if isinstance(p, A.VarBlock):
                m.var_blocks.append(p)
            elif isinstance(p, A.Stmt):
                m.body.append(p)
        m.end_span = self.sp(c[-1])
        return m

    def itf_name(self, c):
        return Token.new_borrow_pos("IDENT", ".".join(str(x) for x in c), c[0])

    def interface_decl(self, c):
        mods, i = self._modifiers(c, 1)
        name = c[i]
        self._not_reserved(name)
        itf = A.Interface(self.sp(name), str(name))
        itf.end_span = self.sp(c[-1])
        for m in mods:
            if m not in ("PUBLIC", "INTERNAL"):
                self.errors.append(BuildError(itf.span, f"{m} is not allowed on an INTERFACE", Code.SYNTAX))
        after_extends = False
        for x in c[i + 1 : -1]:
            if isinstance(x, A.Method):
                itf.methods.append(x)
            elif isinstance(x, A.Property):
                itf.properties.append(x)
            elif hasattr(x, "type") and str(getattr(x, "type", "")) == "EXTENDS":
                after_extends = True
            elif after_extends and not isinstance(x, (A.Method, A.Property)):
                itf.extends.append(str(x))
        return itf

    def property_decl(self, c):
        mods = []
        i = 1
        while isinstance(c[i], tuple) and c[i][0] == "mod":
            mods.append(c[i][1])
            i += 1
        name = c[i]
        self._not_reserved(name)
        prop = A.Property(self.sp(name), str(name), mods, c[i + 1])
        for acc in c[i + 2 : -1]:
            if isinstance(acc, Token):  # TwinCAT writes PROPERTY P : T; with a ';'
                continue
            kind, span, parts = acc
            own = [p[1] for p in parts if isinstance(p, tuple) and p[0] == "mod"]
            # GET PRIVATE / SET PROTECTED: the accessor's own access replaces the property's
            access = {"PUBLIC", "PRIVATE", "PROTECTED", "INTERNAL"}
            m = A.Method(span, str(name), [x for x in mods if not (own and x in access)] + own)
            for p in _flat(parts):
                if isinstance(p, A.VarBlock):
                    m.var_blocks.append(p)
                elif isinstance(p, A.Stmt):
                    m.body.append(p)
            if kind == "GET":
                m.return_type = prop.type
                prop.get = m
            else:
                prop.set = m
        prop.end_span = self.sp(c[-1])
        return prop

    def property_get(self, c):
        return ("GET", self.sp(c[0]), c[1:-1])

    def property_set(self, c):
        return ("SET", self.sp(c[0]), c[1:-1])

    def method_modifier(self, c):
        return ("mod", str(c[0]).upper())

    def class_decl(self, c):
        """CLASS: a function block without a body of its own (methods and properties only)."""
        pou = self.fb_decl(c)
        pou.modifiers = pou.modifiers + ["CLASS"]
        return pou

    def program_decl(self, c):
        mods, i = self._modifiers(c, 1)
        pou = self._pou("PROGRAM", c[0], c[i], c[i + 1 : -1], c[-1])
        self._top_level_access(pou, mods)
        return pou

    def pou_modifier(self, c):
        return ("mod", str(c[0]).upper())

    def extends(self, c):
        return ("extends", str(c[1]))

    def implements(self, c):
        return ("implements", [str(x) for x in c[1:]])

    # ---------------------------------------------------------------- SFC
    def step_decl(self, c):
        initial = str(c[0]).upper() == "INITIAL_STEP"
        return A.Step(self.sp(c[1]), str(c[1]), initial, [x for x in c if isinstance(x, A.ActionAssoc)])

    def action_assoc(self, c):
        args = c[2:]
        return A.ActionAssoc(self.sp(c[0]), str(c[0]), str(c[1]).upper(), args[0] if args else None)

    def transition_decl(self, c):
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
        sources = c[i_from + 1]
        targets = c[i_from + 3]
        kind, val = c[i_from + 4]
        t = A.Transition(self.sp(c[0]), name, prio, sources, targets)
        if kind == "cond":
            t.cond = val
        else:
            t.body = val
        return t

    def step_set(self, c):
        return [(str(x), self.sp(x)) for x in c]

    def transition_cond(self, c):
        return ("cond", c[0])

    def transition_body(self, c):
        return ("body", self._stmts(c))

    def action_decl(self, c):
        return A.ActionDecl(self.sp(c[1]), str(c[1]), self._stmts(c[2:-1]))

    # ---------------------------------------------------------------- configuration
    def configuration_decl(self, c):
        name = c[1]
        blocks = [x for x in c if isinstance(x, A.VarBlock)]
        resources = [x for x in c if isinstance(x, A.Resource)]
        tasks = [x for x in c if isinstance(x, A.TaskDecl)]
        progs = [x for x in c if isinstance(x, A.ProgramConfig)]
        if tasks or progs:
            resources.insert(0, A.Resource(self.sp(name), "", "", [], tasks, progs))
        return A.Configuration(self.sp(name), str(name), blocks, resources)

    def resource_decl(self, c):
        name, target = c[1], c[3]
        return A.Resource(
            self.sp(name),
            str(name),
            str(target),
            [x for x in c if isinstance(x, A.VarBlock)],
            [x for x in c if isinstance(x, A.TaskDecl)],
            [x for x in c if isinstance(x, A.ProgramConfig)],
        )

    def task_decl(self, c):
        params = {}
        for x in c[2:]:
            if isinstance(x, tuple):
                params[x[0].upper()] = x[1]
        return A.TaskDecl(self.sp(c[1]), str(c[1]), params)

    def task_param(self, c):
        return (str(c[0]), c[1])

    def program_config(self, c):
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
    def test_decl(self, c):
        wide = c[1].type == "WSTRING_LIT"
        name = self._lit(parse_string, c[1], wide)
        return self._test("TEST", c[0], name, c[2:-1])

    def setup_decl(self, c):
        return self._test("SETUP", c[0], "", c[1:-1])

    def teardown_decl(self, c):
        return self._test("TEARDOWN", c[0], "", c[1:-1])

    def _test(self, kind, kw, name, parts):
        return A.TestBlock(
            self.sp(kw),
            kind,
            name,
            [p for p in parts if isinstance(p, A.VarBlock)],
            self._stmts(parts),
        )

    # ---------------------------------------------------------------- statements
    def assignment(self, c):
        return A.Assign(c[0].span, c[0], c[2], ":=")

    def chained_assignment(self, c):
        """`a := b := c;` (CODESYS): the rightmost assignment first, each target then given the
        one to its right, so `c` is evaluated once and `a` gets `b`'s value."""
        targets = c[0:-1:2]
        out = _Chain()
        value = c[-1]
        for t in reversed(targets):
            out.append(A.Assign(t.span, t, value, ":="))
            value = copy.deepcopy(t)
        out[-1].chained = True
        return out

    def set_assignment(self, c):
        return A.Assign(c[0].span, c[0], c[2], "S=")

    def reset_assignment(self, c):
        return A.Assign(c[0].span, c[0], c[2], "R=")

    def attempt_assignment(self, c):
        return A.Assign(c[0].span, c[0], c[2], "?=")

    def ref_assignment(self, c):
        return A.Assign(c[0].span, c[0], c[2], "REF=")

    def call_stmt(self, c):
        return A.CallStmt(c[0].span, c[0])

    def mock_stmt(self, c):
        return A.Mock(self.sp(c[0]), c[1])

    def mock_function_stmt(self, c):
        return A.MockFunction(self.sp(c[0]), str(c[1]), c[3])

    def empty_stmt(self, c):
        return None

    @staticmethod
    def _stmts(items):
        return [s for s in _flat(items) if isinstance(s, A.Stmt)]

    def if_stmt(self, c):
        branches = [(c[1], self._stmts(c[3:]))]
        orelse = None
        for x in c[3:]:
            if isinstance(x, tuple) and x[0] == "elsif":
                branches.append((x[1], x[2]))
            elif isinstance(x, tuple) and x[0] == "else":
                orelse = x[1]
        return A.If(self.sp(c[0]), branches, orelse)

    def elsif_clause(self, c):
        return ("elsif", c[1], self._stmts(c[3:]))

    def else_clause(self, c):
        return ("else", self._stmts(c[1:]))

    def case_stmt(self, c):
        branches = []
        orelse = None
        for x in _flat(c[3:]):
            if isinstance(x, tuple) and x[0] == "labels":
                branches.append(A.CaseBranch(x[1][0][0].span, x[1], []))
            elif isinstance(x, tuple) and x[0] == "else":
                orelse = x[1]
            elif isinstance(x, A.Stmt):
                if not branches:  # reported, the statement dropped: parsing goes on
                    self.errors.append(BuildError(x.span, "a statement in a CASE needs a label before it", Code.SYNTAX))
                    continue
                branches[-1].body.append(x)
        return A.Case(self.sp(c[0]), c[1], branches, orelse)

    def case_labels(self, c):
        return ("labels", [(lo, hi) for _, lo, hi in c])

    def case_else(self, c):
        return ("else", self._stmts(c[1:]))

    def case_label(self, c):
        return ("label", c[0], None)

    def case_range(self, c):
        return ("label", c[0], c[1])

    def signed_int(self, c):
        neg = len(c) == 2
        tok = c[-1]
        v = self._lit(int_literal, tok)
        return A.Literal(self.sp(c[0]), "int", -v if neg else v, "", ("-" if neg else "") + str(tok))

    def case_real(self, c):
        neg = len(c) == 2
        v = self._lit(real_literal, c[-1])
        return A.Literal(self.sp(c[0]), "real", -v if neg else v, "", str(c[-1]))

    def case_other(self, c):
        t = c[0]
        if t.type == "TIME_LIT":
            return self._prefixed("time", time_literal, t)
        if t.type in ("TRUE", "FALSE"):
            return A.Literal(self.sp(t), "bool", t.type == "TRUE", "", str(t))
        wide = t.type == "WSTRING_LIT"
        return A.Literal(self.sp(t), "wstring" if wide else "string", self._lit(parse_string, t, wide), "", str(t))

    def for_stmt(self, c):
        var, start, end = c[1], c[3], c[5]
        i = 6
        step = None
        if isinstance(c[i], Token) and c[i].type == "BY":
            step = c[i + 1]
            i += 2
        return A.For(self.sp(c[0]), var, start, end, step, self._stmts(c[i + 1 :]))

    def while_stmt(self, c):
        return A.While(self.sp(c[0]), c[1], self._stmts(c[3:]))

    def repeat_stmt(self, c):
        i_until = next(i for i, x in enumerate(c) if isinstance(x, Token) and x.type == "UNTIL")
        return A.Repeat(self.sp(c[0]), self._stmts(c[1:i_until]), c[i_until + 1])

    def exit_stmt(self, c):
        return A.Exit(self.sp(c[0]))

    def continue_stmt(self, c):
        return A.Continue(self.sp(c[0]))

    def return_stmt(self, c):
        return A.Return(self.sp(c[0]))

    # ---------------------------------------------------------------- expressions
    def _bin(self, op, left, right):
        return A.Binary(left.span, op, left, right)

    def expression(self, c):
        """c = [operand, op, operand, op, ...]: precedence climbing, all left-associative."""
        ops = [str(t).upper() for t in c[1::2]]
        operands = c[0::2]
        pos = 0

        def climb(min_prec):
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

    def unary_expr(self, c):
        op = str(c[0]).upper()
        operand = c[1]
        if op == "-" and isinstance(operand, A.Literal) and operand.kind in ("int", "real") and not operand.type_name:
            # fold negative literals so that e.g. -32768 fits an INT
            return A.Literal(self.sp(c[0]), operand.kind, -operand.value, "", "-" + operand.text)
        return A.Unary(self.sp(c[0]), op, operand)

    def call(self, c):
        start, end = c[0].span, c[-1]
        span = Span(start.file, start.line, start.col, end.end_line, end.end_column)
        return A.Call(span, c[0], [a for a in c[1:] if isinstance(a, A.Arg)])

    def pos_arg(self, c):
        return A.Arg(c[0].span, "", c[0])

    def named_arg(self, c):
        return A.Arg(self.sp(c[0]), str(c[0]), c[2])

    def out_arg(self, c):
        neg = isinstance(c[0], Token) and c[0].type == "NOT"
        name = c[1] if neg else c[0]
        return A.Arg(self.sp(c[0]), str(name), c[-1], True, neg)

    def var_name(self, c):
        return A.Name(self.sp(c[0]), str(c[0]))

    def var_direct(self, c):
        return A.Direct(self.sp(c[0]), str(c[0]).upper())

    def var_field(self, c):
        return A.Field(c[0].span, c[0], str(c[1]), self.sp(c[1]))

    def var_bit(self, c):
        return A.Bit(c[0].span, c[0], self._lit(int_literal, c[1]), "X")

    def var_partial(self, c):
        t = str(c[1]).upper()
        return A.Bit(c[0].span, c[0], int(t[2:]), t[1])

    def var_index(self, c):
        return A.Index(c[0].span, c[0], list(c[1:]))

    def var_deref(self, c):
        return A.Deref(c[0].span, c[0])

    # ---------------------------------------------------------------- literals
    def lit_int(self, c):
        t = c[0]
        return A.Literal(self.sp(t), "int", self._lit(int_literal, t), "", str(t))

    def lit_real(self, c):
        t = c[0]
        return A.Literal(self.sp(t), "real", self._lit(real_literal, t), "", str(t))

    def lit_true(self, c):
        return A.Literal(self.sp(c[0]), "bool", True, "", "TRUE")

    def lit_false(self, c):
        return A.Literal(self.sp(c[0]), "bool", False, "", "FALSE")

    def lit_string(self, c):
        return A.Literal(self.sp(c[0]), "string", self._lit(parse_string, c[0], False), "", str(c[0]))

    def lit_wstring(self, c):
        return A.Literal(self.sp(c[0]), "wstring", self._lit(parse_string, c[0], True), "", str(c[0]))

    def _prefixed(self, kind, fn, tok):
        t = str(tok)
        prefix = t.split("#", 1)[0].upper()
        return A.Literal(self.sp(tok), kind, self._lit(fn, tok), prefix, t)

    def lit_time(self, c):
        return self._prefixed("time", time_literal, c[0])

    def lit_date(self, c):
        return self._prefixed("date", date_literal, c[0])

    def lit_tod(self, c):
        return self._prefixed("tod", tod_literal, c[0])

    def lit_dt(self, c):
        return self._prefixed("dt", dt_literal, c[0])

    def lit_typed_num(self, c):
        prefix = str(c[0])[:-1]
        neg = len(c) == 3
        tok = c[-1]
        text = str(c[0]) + ("-" if neg else "") + str(tok)
        if tok.type == "REAL_LIT":
            bits = 32 if prefix.upper() == "REAL" else 64
            kind, v = "real", self._lit(real_literal, tok, bits, at=c[0], shown=text)
        else:
            kind, v = "int", self._lit(int_literal, tok, at=c[0], shown=text)
        return A.Literal(self.sp(c[0]), kind, -v if neg else v, prefix.upper(), text)

    def lit_typed_bool(self, c):
        prefix = str(c[0])[:-1]
        return A.Literal(self.sp(c[0]), "bool", str(c[1]).upper() == "TRUE", prefix.upper(), str(c[0]) + str(c[1]))

    def lit_typed_string(self, c):
        prefix = str(c[0])[:-1]
        wide = c[1].type == "WSTRING_LIT"
        return A.Literal(
            self.sp(c[0]),
            "wstring" if wide else "string",
            self._lit(parse_string, c[1], wide),
            prefix.upper(),
            str(c[0]) + str(c[1]),
        )

    def lit_enum(self, c):
        prefix = str(c[0])[:-1]
        return A.EnumLit(self.sp(c[0]), prefix, str(c[1]))
