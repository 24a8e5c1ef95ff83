"""Diagnostics as data: a code, a severity, a span, a message and a hint.

They are collected, never raised one by one, so a run reports all its errors
together; `render` is the one place that turns them into text.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import Enum

from .source import NO_SPAN, SourceFile, Span


class Code(str, Enum):
    """Every diagnostic code, with its explanation (`st explain CODE`, docs/diagnostics.md is generated
    from it). A member equals its code's string, so `d.code == "E013"` holds either way."""

    explanation: str

    def __new__(cls, code: str, explanation: str) -> Code:
        member = str.__new__(cls, code)
        member._value_ = code
        member.explanation = explanation
        return member

    __str__ = str.__str__
    __format__ = str.__format__  # type: ignore[assignment]  # f"{code}" is the code, as for a str
    __hash__ = str.__hash__

    UNREADABLE_FILE = "E000", ("A source file could not be read.")
    SYNTAX = (
        "E001",
        (
            "Syntax error: the parser met a token it did not expect. The hint names the usual slips: a missing "
            "';', '=' written for ':=', 'ELSE IF' (a nested IF that needs its own END_IF) instead of ELSIF, a "
            "missing END_*."
        ),
    )
    UNCLOSED_COMMENT = "E002", ("A comment '(*', '/*' or a pragma '{' is never closed.")
    MISPLACED_SECTION = (
        "E003",
        (
            "A declaration section is in a place where it is not allowed (e.g. VAR_INPUT outside a POU, a "
            "VAR_OUTPUT or VAR_IN_OUT in FB_init, FB_reinit or FB_exit, which run when an instance is created "
            "and take inputs only)."
        ),
    )
    MALFORMED_LITERAL = (
        "E004",
        (
            "A literal or address is malformed (e.g. T#5x, D#2024-13-01, %QX0.; 1__0 or 1_: a '_' stands alone"
            " between two digits), an integer literal has more than 128 digits, or an address is outside the"
            " process image (1024 entries per table and size; bits %IX0.0..%IX1023.7)."
        ),
    )
    UNDECLARED = "E010", ("An identifier is used but never declared (or a VAR_EXTERNAL has no VAR_GLOBAL).")
    DECLARED_TWICE = (
        "E011",
        (
            "A name is declared twice in the same scope, or a user POU has the name of a standard library POU "
            "of another kind (the library's own code uses it as what it is)."
        ),
    )
    BAD_TYPE = (
        "E012",
        (
            "A type name is unknown, or a type is used where it cannot be (a FUNCTION as a type, a STRUCT outside "
            "a TYPE declaration, ARRAY[*] outside a VAR_IN_OUT, EXTENDS or IMPLEMENTS naming the wrong kind of "
            "POU, ...)."
        ),
    )
    TYPE_MISMATCH = (
        "E013",
        (
            "Type mismatch: a value of one type where another is needed: assigned, passed to a parameter, "
            "an array index, EN, a typed literal's value (INT#1.5), the operand of an intrinsic (LOWER_BOUND "
            "of an array, __DELETE of a POINTER) or of a test statement (ASSERT_TRUE of a BOOL)."
        ),
    )
    BAD_OPERANDS = "E014", ("The operands of an operator have types it cannot combine; convert one side explicitly.")
    CONDITION_NOT_BOOL = "E015", ("A condition (IF, ELSIF, WHILE, UNTIL, transition) is not BOOL.")
    BAD_PARAMETER = (
        "E016",
        (
            "A call (or the FB_init arguments of an instance's declaration) names a parameter the POU does not "
            "have or names one twice, or uses ':=' for an output / '=>' for an input."
        ),
    )
    ARGUMENT_COUNT = "E017", ("A call has too many or too few arguments.")
    WRITE_TO_CONSTANT = (
        "E018",
        ("A write to something that cannot be written: a CONSTANT, an enumeration value, a property without SET."),
    )
    BAD_CASE_LABEL = "E019", ("A CASE label has the wrong type, or repeats / overlaps an earlier label.")
    NOT_CALLABLE = "E020", ("Something that is not callable is called (e.g. an FB type instead of an instance).")
    OUT_OF_RANGE = (
        "E021",
        (
            "A literal does not fit the range of its type (an integer's; a REAL beyond ±3.4028235E38, an LREAL"
            " beyond ±1.7976931348623157E308; a TIME, LTIME, DATE or DT beyond 64-bit ns)."
        ),
    )
    INDEX_OUT_OF_BOUNDS = "E022", ("A constant array index (or bit number) is outside the bounds.")
    BAD_ACCESS = "E023", ("A field, index or bit access on a value that has no such field, is not an array, ...")
    EXIT_OUTSIDE_LOOP = "E024", ("EXIT or CONTINUE outside a loop.")
    FOR_NOT_INTEGER = "E025", ("A FOR loop variable must be an integer.")
    POU_AS_VALUE = "E026", ("A POU name is used where a value is expected.")
    NARROWING = (
        "E027",
        (
            "An implicit narrowing conversion (e.g. INT := DINT, REAL := LREAL): IEC allows only widening; "
            "convert explicitly with *_TO_*."
        ),
    )
    BAD_CONFIGURATION = "E028", ("A configuration names an unknown PROGRAM type or task.")
    NOT_CONSTANT = (
        "E029",
        (
            "A constant expression is required (array bounds, CASE labels, string lengths, ...), or a constant "
            "has a value it cannot have there (an empty array range, a FOR step of 0, a task INTERVAL that is "
            "not positive)."
        ),
    )
    SFC = "E030", ("An SFC error: unknown step or action, missing INITIAL_STEP, a bad qualifier.")
    NOT_A_VARIABLE = "E031", ("An output (=>) or VAR_IN_OUT argument must be a variable.")
    RECURSION = (
        "E032",
        (
            "A POU (a FUNCTION, METHOD, property accessor, ACTION or block body) calls itself, directly or through"
            " others, where the declarations show which body each call runs, under the iec or openplc dialect: "
            "IEC 61131-3 and MatIEC do not allow recursion. The codesys and twincat dialects and the default warn "
            "instead (W013)."
        ),
    )
    TEST_STATEMENT_OUTSIDE_TEST = (
        "E033",
        (
            "A unit-test statement (ASSERT_*, ADVANCE_TIME, MOCK, MOCK_FUNCTION, MOCK_VERIFY_*) outside a TEST, "
            "SETUP or TEARDOWN block. Move it into a test, or rename the POU or variable it was meant to be."
        ),
    )
    UNSUPPORTED = "E040", ("A construct the code generator does not support yet.")
    TOO_DEEP = (
        "E041",
        (
            "Code or data nested too deeply: an expression of tens of thousands of terms, more than about 20 "
            "nested loops, or types and function blocks nested more than 100 levels inside each other."
        ),
    )
    TOO_LARGE = (
        "E042",
        (
            "An array is too large (more than 50,000,000 elements), or one declaration holds more than 50,000,000"
            " values (arrays of arrays or of structures)."
        ),
    )
    NOT_ACCESSIBLE = (
        "E043",
        (
            "An access rule is broken: a PRIVATE or PROTECTED method, property or variable used from outside "
            "(PRIVATE: only its own block; PROTECTED: its block and the blocks that extend it), a method "
            "overridden with a narrower access than the base's, or an interface's method implemented by one "
            "that is not PUBLIC."
        ),
    )
    NOT_IN_DIALECT = (
        "E044",
        (
            "A construct is not part of the chosen dialect preset (--dialect or a {dialect '…'} pragma): object-"
            "oriented ST in openplc, vendor extensions (POINTER TO, REFERENCE TO, REF=, ADR, SIZEOF, "
            "__QUERYINTERFACE, __ISVALIDREF, __NEW, __DELETE, VAR_INST, VAR_STAT, STRUCT EXTENDS, methods of "
            "programs, FB_init arguments) in iec or openplc."
        ),
    )
    UNKNOWN_DIALECT = (
        "E045",
        ("A {dialect '…'} pragma names a preset st does not know (the presets: openplc, iec, codesys, twincat)."),
    )
    SELF_CONTAINING_TYPE = (
        "E046",
        (
            "A type is defined in terms of itself: a structure or function block contains itself (directly or "
            "through its members), a named type is defined through itself, or a function block or interface "
            "extends itself."
        ),
    )
    INHERITANCE_CONTRACT = (
        "E047",
        (
            "An inheritance or interface contract is broken: a FINAL function block extended or a FINAL method "
            "overridden, an override or an interface method implemented with other parameters or return type, "
            "a property overridden with another type, a method or property of an implemented interface missing, "
            "a method of an INTERFACE with a body, a method marked OVERRIDE that overrides nothing."
        ),
    )
    WRITE_TO_INPUT = (
        "E048",
        (
            "A VAR_INPUT is written inside its own POU under the iec dialect: IEC 61131-3 makes inputs read-only "
            "there (MatIEC, CODESYS and TwinCAT allow it, and so do the openplc, codesys and twincat dialects and "
            "the default). Copy it into a local variable first."
        ),
    )
    CALL_WITHOUT_VALUE = (
        "E049",
        (
            "A call that has no value (a function block call, __DELETE, a test statement such as ASSERT_EQ) is "
            "used inside an expression; call it as a statement."
        ),
    )
    XML_LANGUAGE = (
        "E050",
        (
            "A POU, action or transition of a PLCopen XML project (plc.xml) is written in FBD, LD or IL, or an "
            "SFC transition's condition is a graphical network: st reads ST and SFC bodies. The POU keeps its "
            "declarations, its body is left empty, and the file's other POUs are still checked."
        ),
    )
    XML_FILE = (
        "E051",
        (
            "An XML file st cannot read as a PLCopen XML project: malformed XML (at the XML parser's position), "
            "a root element other than <project> of the TC6 namespace (http://www.plcopen.org/xml/tc6_0201 or "
            "tc6_0200), or a part of the project st does not read (an SFC macro step, a type or value element "
            "it does not know, an SFC connection to nothing)."
        ),
    )
    FOR_COUNTER_WRITTEN = (
        "E052",
        (
            "A FOR loop's control variable is written inside its body (assigned, the counter of a nested FOR, "
            "an output or VAR_IN_OUT argument, its address or a reference taken) under the iec or openplc "
            "dialect: IEC 61131-3 and MatIEC forbid it. CODESYS and TwinCAT allow it, and so do their dialects "
            "and the default: the loop then tests the value the body left. Count in another variable, or use "
            "WHILE."
        ),
    )
    NOT_ASSIGNABLE = (
        "E053",
        (
            "Something that is not a variable is written: the target of an assignment (or of an output '=>', "
            "a VAR_IN_OUT argument, REF=, ...) is a literal, a call, an operator's result, a typed enumeration "
            "value or an SFC step."
        ),
    )
    REFERENCE_MISMATCH = (
        "E054",
        (
            "A reference is bound to something it cannot refer to: REF= whose left side is no REFERENCE TO "
            "variable, or whose right side is a variable (or the REFERENCE TO a call returns) of another type; "
            "a REFERENCE TO variable initialised with, or a REFERENCE TO input bound to, a variable of another "
            "type."
        ),
    )
    BAD_ASSIGNMENT_ATTEMPT = (
        "E055",
        (
            "An assignment attempt (dest ?= src) with an operand it cannot work on: dest must be an interface "
            "variable or a REF_TO a function block or interface, src an interface, a function block instance, "
            "a reference to one, or NULL."
        ),
    )
    SET_RESET_NOT_BOOL = (
        "E056",
        ("A set or reset assignment (x S= c, x R= c) whose variable or value is not BOOL: both must be."),
    )
    BAD_INITIALIZER = (
        "E057",
        (
            "An initial value of a form the declared type cannot take: an array initializer [...] for "
            "something that is not an array (or a single value for an array), a structure initializer (...) "
            "for something that is neither a structure nor a block, FB_init arguments for something that is "
            "not a function block (or in a TYPE), an initial value of a UNION member, an enumeration's default "
            "that is not one of its values."
        ),
    )
    LOCATED_TYPE = (
        "E058",
        (
            "A variable located AT an address of the process image has a type the address cannot hold: a "
            "string, a structure, an array or a block (a cell holds one elementary value), or a value of "
            "another width than the address's size (%IW is 16 bits, %QX one)."
        ),
    )
    RESULT_WITHOUT_TYPE = (
        "E059",
        (
            "A FUNCTION or METHOD declared without a return type is given a result: its name is assigned in "
            "its body, or a MOCK_FUNCTION gives it a RETURNS value. Declare the return type (FUNCTION F : INT)."
        ),
    )
    DECLARATION_MISMATCH = (
        "E060",
        (
            "Two declarations of one variable disagree on its type: a VAR_EXTERNAL and the VAR_GLOBAL it "
            "names, a VAR_CONFIG entry and the variable of the program instance it configures, or a "
            "VAR_ACCESS path and the variable it reaches."
        ),
    )
    ABSTRACT = (
        "E061",
        (
            "An ABSTRACT rule is broken: an ABSTRACT function block instantiated (declared, or made with "
            "__NEW), an ABSTRACT method or property in a block that is not ABSTRACT or with a body, one left "
            "unimplemented by a block that is not ABSTRACT, or an ABSTRACT method called through SUPER^ (it "
            "has no implementation)."
        ),
    )
    INTERNAL = "E099", ("An internal compiler error (a bug in st): please report it with the source file.")
    IGNORED_PRAGMA = "W001", ("A pragma { ... } is ignored.")
    UNUSED_VARIABLE = "W002", ("A variable is declared but never used.")
    TRUNCATED_STRING = "W003", ("A string literal is longer than the variable and will be truncated.")
    REPLACES_LIBRARY_POU = "W004", ("A user POU replaces a standard library POU of the same name and kind.")
    UNSIGNED_NEGATION = "W005", ("Negating an unsigned value wraps around.")
    HIDDEN_VARIABLE = (
        "W006",
        ("A variable of a METHOD has the name of a variable of its function block and hides it inside the method."),
    )
    METHOD_SHADOWS_FUNCTION = (
        "W007",
        (
            "A call without an instance inside a function block reaches one of its METHODs although a standard or"
            " global function of the same name would take the same arguments (write THIS^.M() to say so, or "
            "rename the method)."
        ),
    )
    LOSSY_CONVERSION = (
        "W008",
        (
            "An implicit conversion between numbers and bit strings may lose data (DINT into INT, WORD into "
            "INT, INT into UINT, LREAL into REAL): the codesys and twincat dialects and the default make it, "
            "as CODESYS and TwinCAT do with a warning; the value is wrapped to the target type (or rounded, "
            "for REAL). The iec and openplc dialects refuse it (E027). Convert explicitly to say it is meant."
        ),
    )
    EMBEDDED_CODE = (
        "W009",
        (
            "An embedded C block {{ ... }} (OpenPLC's python_eval and LogMessage blocks carry them) is read and "
            "skipped: st does not run C. Write what it does in ST to have it run."
        ),
    )
    OWN_MOTION_LIBRARY = (
        "W010",
        (
            "The project declares a type (or a block) named like one of the types of st's PLCopen motion "
            "library (AXIS_REF, MC_DIRECTION, ...): it brings its own motion library, so st's is left out of "
            "the compilation and the project's own blocks are used. A project block named like a library "
            "block (MC_Power) always keeps its own body."
        ),
    )
    ADDRESS_PART_IGNORED = (
        "W011",
        (
            "A hierarchical address, one with more numbers than its cell needs (%IW0.0, %QX0.4.2): OpenPLC's "
            "runtime binds it by its leading numbers (%IW0, %QX0.4) and ignores the rest, and so do the openplc "
            "preset and the default; iec, codesys and twincat accept the declaration as their compilers do "
            "(its place is the I/O configuration's) and `st run` refuses it, naming the declaration, since "
            "st's process image has no place for it."
        ),
    )
    NATIVE_UNAVAILABLE = (
        "W012",
        (
            "The native tier (--native) could not compile this program's loop bodies to C: Cython, a C compiler "
            "or Python's C headers is missing, or the build failed (the message gives the tool's last lines). "
            "The program compiles and runs on the Python tier, with the same results, only slower."
        ),
    )
    RECURSIVE_CALL = (
        "W013",
        (
            "A POU calls itself, directly or through others (as E032), under the codesys or twincat dialect or "
            "the default: CODESYS and TwinCAT allow it with a warning (C0561, C0298 for methods), IEC 61131-3 "
            "does not. It runs; a recursion that goes too deep faults with RECURSION at the call."
        ),
    )
    LIBRARY_NOT_FOUND = (
        "W014",
        (
            "A TwinCAT or CODESYS project references a library (<PlaceholderReference>, <LibraryReference> in its "
            ".plcproj) that is neither a project of the compilation nor a library project in the search path "
            "(--lib PATH, ST_LIBPATH, the API's lib_path=): its files are not compiled, so its names stay unknown "
            "where they are used. System libraries (Tc2_Standard, Tc2_System, Tc3_Module, SysFile, ...) are "
            "not searched for."
        ),
    )


class Severity(str, Enum):
    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


@dataclass(frozen=True, slots=True)
class Diagnostic:
    code: str
    severity: Severity
    span: Span
    message: str
    hint: str = ""
    data: tuple[tuple[str, str], ...] = ()  # facts as (name, value) pairs, e.g. W001: (("pragma", "dialect"),)

    def datum(self, name: str) -> str:
        """A fact about this diagnostic ("" if it has none of that name): what tools and filters
        read instead of the message text, which is for people and may change."""
        return next((v for k, v in self.data if k == name), "")

    @property
    def is_error(self) -> bool:
        return self.severity is Severity.ERROR

    def render(self, sources: dict[str, SourceFile] | None = None, *, max_width: int = 200) -> str:
        s = self.span
        head = f"{s.file}:{s.line}:{s.col}: {self.severity.value}[{self.code}]: {self.message}"
        lines = [head]
        src = (sources or {}).get(s.file)
        if src is not None and s.line > 0:
            text = src.line_text(s.line).rstrip("\r").expandtabs(1)
            col = max(s.col, 1)
            if len(text) > max_width:  # OpenPLC's debug lines can be megabytes long
                lo = max(0, col - max_width // 2)
                text = text[lo : lo + max_width]
                col -= lo
            width = 1
            if s.end_line == s.line and s.end_col > s.col:
                width = min(s.end_col - s.col, max(1, len(text) - col + 1))
            lines.append(f"  {s.line:>5} | {text}")
            lines.append(f"        | {' ' * (col - 1)}{'^' * width}")
        if self.hint:
            lines.append(f"        = hint: {self.hint}")
        return "\n".join(lines)


class CompileError(Exception):
    """Raised by the compiler driver when a run produced errors."""

    def __init__(self, diagnostics: list[Diagnostic], sources: dict[str, SourceFile]):
        self.diagnostics = diagnostics
        self.sources = sources
        super().__init__(self.render())

    @property
    def errors(self) -> list[Diagnostic]:
        return [d for d in self.diagnostics if d.is_error]

    def render(self) -> str:
        return render_all(self.diagnostics, self.sources)


def render_all(diags: list[Diagnostic], sources: dict[str, SourceFile]) -> str:
    parts = [d.render(sources) for d in diags]
    n_err = sum(1 for d in diags if d.is_error)
    n_warn = sum(1 for d in diags if d.severity is Severity.WARNING)
    if n_err or n_warn:
        parts.append(f"{n_err} error(s), {n_warn} warning(s)")
    return "\n".join(parts)


class DiagnosticSink:
    """Collects diagnostics for one compilation."""

    def __init__(self) -> None:
        self.items: list[Diagnostic] = []
        self._seen: set[tuple] = set()

    def error(self, code: str, span: Span, message: str, hint: str = "") -> None:
        self.add(Diagnostic(code, Severity.ERROR, span, message, hint))

    def warning(self, code: str, span: Span, message: str, hint: str = "") -> None:
        self.add(Diagnostic(code, Severity.WARNING, span, message, hint))

    def add(self, d: Diagnostic) -> None:
        if not isinstance(d.span, Span):  # every diagnostic is located; a bug must not hide the report
            d = replace(d, span=NO_SPAN)
        key = (d.code, d.span.file, d.span.line, d.span.col, d.message)
        if key not in self._seen:
            self._seen.add(key)
            self.items.append(d)

    @property
    def has_errors(self) -> bool:
        return any(d.is_error for d in self.items)

    def sorted(self) -> list[Diagnostic]:
        """By file, line and column (a field that is not what its type says sorts first)."""
        return sorted(self.items, key=_position)


def _position(d: Diagnostic) -> tuple[str, int, int]:
    s = d.span
    file, line, col = getattr(s, "file", ""), getattr(s, "line", 0), getattr(s, "col", 0)
    return (
        file if isinstance(file, str) else "",
        line if isinstance(line, int) else 0,
        col if isinstance(col, int) else 0,
    )
