"""Diagnostics as data: a code, a severity, a span, a message and a hint.

They are collected, never raised one by one, so a run reports all its errors
together; `render` is the one place that turns them into text.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .source import SourceFile, Span


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
    data: tuple[tuple[str, str], ...] = ()   # facts as (name, value) pairs, e.g. W001: (("pragma", "dialect"),)

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
                text = text[lo:lo + max_width]
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
        key = (d.code, d.span.file, d.span.line, d.span.col, d.message)
        if key not in self._seen:
            self._seen.add(key)
            self.items.append(d)

    @property
    def has_errors(self) -> bool:
        return any(d.is_error for d in self.items)

    def sorted(self) -> list[Diagnostic]:
        return sorted(self.items, key=lambda d: (d.span.file, d.span.line, d.span.col))
