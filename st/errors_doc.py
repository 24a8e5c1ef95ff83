"""Diagnostic codes and what they mean (`st explain CODE`, docs/diagnostics.md)."""

EXPLANATIONS = {
    "E000": "A source file could not be read.",
    "E001": "Syntax error: the parser met a token it did not expect. The hint names the usual slips: "
            "a missing ';', '=' written for ':=', 'ELSE IF' (a nested IF that needs its own END_IF) "
            "instead of ELSIF, a missing END_*.",
    "E002": "A comment '(*', '/*' or a pragma '{' is never closed.",
    "E003": "A declaration section is in a place where it is not allowed (e.g. VAR_INPUT outside a POU).",
    "E004": "A literal or address is malformed (e.g. T#5x, D#2024-13-01, %QX0.), an integer literal has more than 128 digits, or an address is outside the process image (1024 entries per table and size; bits %IX0.0..%IX1023.7).",
    "E010": "An identifier is used but never declared (or a VAR_EXTERNAL has no VAR_GLOBAL).",
    "E011": "A name is declared twice in the same scope.",
    "E012": "A type name is unknown, a type is used where it cannot be, or a type contains itself.",
    "E013": "Type mismatch: the value's type cannot be assigned or passed to the target's type.",
    "E014": "The operands of an operator have types it cannot combine; convert one side explicitly.",
    "E015": "A condition (IF, ELSIF, WHILE, UNTIL, transition) is not BOOL.",
    "E016": "A call names a parameter the POU does not have, or uses ':=' for an output / '=>' for an input.",
    "E017": "A call has too many or too few arguments.",
    "E018": "A write to a CONSTANT, or to a VAR_INPUT inside its own POU.",
    "E019": "A CASE label has the wrong type, or repeats / overlaps an earlier label.",
    "E020": "Something that is not callable is called (e.g. an FB type instead of an instance).",
    "E021": "A literal does not fit the range of its type.",
    "E022": "A constant array index (or bit number) is outside the bounds.",
    "E023": "A field, index or bit access on a value that has no such field, is not an array, ...",
    "E024": "EXIT or CONTINUE outside a loop.",
    "E025": "A FOR loop variable must be an integer.",
    "E026": "A POU name is used where a value is expected.",
    "E027": "An implicit narrowing conversion (e.g. INT := DINT, REAL := LREAL): IEC allows only widening; "
            "convert explicitly with *_TO_*.",
    "E028": "A configuration names an unknown PROGRAM type or task.",
    "E029": "A constant expression is required (array bounds, CASE labels, string lengths, ...).",
    "E030": "An SFC error: unknown step or action, missing INITIAL_STEP, a bad qualifier.",
    "E031": "An output (=>) or VAR_IN_OUT argument must be a variable.",
    "E032": "A POU calls itself, directly or through others: IEC 61131-3 does not allow recursion.",
    "E033": "A unit-test statement (ASSERT_*, ADVANCE_TIME, MOCK, MOCK_FUNCTION, MOCK_VERIFY_*) outside a "
            "TEST, SETUP or TEARDOWN block. Move it into a test, or rename the POU or variable it was meant to be.",
    "E040": "A construct the code generator does not support yet.",
    "E041": "Code or data nested too deeply: an expression of tens of thousands of terms, more than about 20 nested loops, or types and function blocks nested more than 100 levels inside each other.",
    "E042": "An array is too large (more than 50,000,000 elements), or one declaration holds more than 50,000,000 values (arrays of arrays or of structures).",
    "E043": "An object-oriented rule is broken: a PRIVATE or PROTECTED method, property or variable used from outside, an ABSTRACT function block instantiated or an ABSTRACT method or property called or left unimplemented, an OVERRIDE that overrides nothing.",
    "E044": "A construct is not part of the chosen dialect preset (--dialect or a {dialect '…'} pragma): object-oriented ST in openplc, vendor extensions (POINTER TO, REFERENCE TO, REF=, ADR, SIZEOF, __QUERYINTERFACE, __ISVALIDREF, __NEW, __DELETE, VAR_INST, VAR_STAT, STRUCT EXTENDS, methods of programs, FB_init arguments) in iec or openplc.",
    "E045": "A {dialect '…'} pragma names a preset st does not know (the presets: openplc, iec, codesys, twincat).",
    "E099": "An internal compiler error (a bug in st): please report it with the source file.",
    "W001": "A pragma { ... } is ignored.",
    "W002": "A variable is declared but never used.",
    "W003": "A string literal is longer than the variable and will be truncated.",
    "W004": "A user POU replaces a standard library POU of the same name.",
    "W005": "Negating an unsigned value wraps around.",
    "W006": "A variable of a METHOD has the name of a variable of its function block and hides it inside the method.",
    "W007": "A call without an instance inside a function block reaches one of its METHODs although a standard or global function of the same name would take the same arguments (write THIS^.M() to say so, or rename the method).",
}


def markdown() -> str:
    """docs/diagnostics.md (regenerate with `python -m st.errors_doc > docs/diagnostics.md`)."""
    lines = ["# Diagnostic codes", "",
             "Every diagnostic is printed as `file:line:col: severity[CODE]: message`, then the source",
             "line with a caret under the spot and, for the usual slips, a `hint`. `st explain CODE` prints",
             "the explanation below. Codes are stable.", "", "| code | meaning |", "|---|---|"]
    lines += [f"| {k} | {EXPLANATIONS[k]} |" for k in sorted(EXPLANATIONS)]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
