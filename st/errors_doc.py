"""Diagnostic codes and what they mean (`st explain CODE`, docs/diagnostics.md)."""

EXPLANATIONS = {
    "E000": "A source file could not be read.",
    "E001": "Syntax error: the parser met a token it did not expect. The hint names the usual slips: "
            "a missing ';', '=' written for ':=', 'ELSE IF' (a nested IF that needs its own END_IF) "
            "instead of ELSIF, a missing END_*.",
    "E002": "A comment '(*', '/*' or a pragma '{' is never closed.",
    "E003": "A declaration section is in a place where it is not allowed (e.g. VAR_INPUT outside a POU).",
    "E004": "A literal or address is malformed (e.g. T#5x, D#2024-13-01, %QX0.).",
    "E101": "An identifier is used but never declared (or a VAR_EXTERNAL has no VAR_GLOBAL).",
    "E102": "A name is declared twice in the same scope.",
    "E103": "A type name is unknown, a type is used where it cannot be, or a type contains itself.",
    "E104": "Type mismatch: the value's type cannot be assigned or passed to the target's type.",
    "E105": "The operands of an operator have types it cannot combine; convert one side explicitly.",
    "E106": "A condition (IF, ELSIF, WHILE, UNTIL, transition) is not BOOL.",
    "E107": "A call names a parameter the POU does not have, or uses ':=' for an output / '=>' for an input.",
    "E108": "A call has too many or too few arguments.",
    "E109": "A write to a CONSTANT, or to a VAR_INPUT inside its own POU.",
    "E110": "A CASE label has the wrong type, or repeats / overlaps an earlier label.",
    "E111": "Something that is not callable is called (e.g. an FB type instead of an instance).",
    "E112": "A literal does not fit the range of its type.",
    "E113": "A constant array index (or bit number) is outside the bounds.",
    "E114": "A field, index or bit access on a value that has no such field, is not an array, ...",
    "E115": "EXIT or CONTINUE outside a loop.",
    "E116": "A FOR loop variable must be an integer.",
    "E117": "A POU name is used where a value is expected.",
    "E118": "An implicit narrowing conversion (e.g. INT := DINT, REAL := LREAL): IEC allows only widening; "
            "convert explicitly with *_TO_*.",
    "E119": "A configuration names an unknown PROGRAM type or task.",
    "E120": "A constant expression is required (array bounds, CASE labels, string lengths, ...).",
    "E121": "An SFC error: unknown step or action, missing INITIAL_STEP, a bad qualifier.",
    "E122": "An output (=>) or VAR_IN_OUT argument must be a variable.",
    "E123": "A POU calls itself, directly or through others: IEC 61131-3 does not allow recursion.",
    "E130": "A construct the code generator does not support yet.",
    "E999": "An internal compiler error (a bug in st): please report it with the source file.",
    "W101": "A pragma { ... } is ignored.",
    "W201": "A variable is declared but never used.",
    "W202": "A string literal is longer than the variable and will be truncated.",
    "W203": "A user POU replaces a standard library POU of the same name.",
    "W204": "Negating an unsigned value wraps around.",
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
