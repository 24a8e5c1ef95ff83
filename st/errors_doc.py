"""docs/diagnostics.md, generated from the `Code` enum (the one place codes are explained);
`python -m st.errors_doc > docs/diagnostics.md` regenerates it, a test checks it is current."""

from __future__ import annotations

from .diagnostics import Code


def explain(code: str) -> str | None:
    """The explanation of a code (any case), or None for an unknown one."""
    try:
        # Code(value) looks a member up (Enum's metaclass), it does not call Code.__new__
        return Code(code.upper()).explanation  # type: ignore[call-arg]
    except ValueError:
        return None


def markdown() -> str:
    """docs/diagnostics.md."""
    lines = [
        "# Diagnostic codes",
        "",
        "Every diagnostic is printed as `file:line:col: severity[CODE]: message`, then the source",
        "line with a caret under the spot and, for the usual slips, a `hint`. `st explain CODE` prints",
        "the explanation below. Codes are stable. This table is generated from `st.diagnostics.Code`",
        "(`python -m st.errors_doc > docs/diagnostics.md`).",
        "",
        "| code | meaning |",
        "|---|---|",
    ]
    lines += [f"| {c.value} | {c.explanation} |" for c in sorted(Code, key=lambda c: c.value)]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
