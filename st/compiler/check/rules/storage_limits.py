"""Resource limits of a program's storage: how deeply types nest, how many elements one array has
and how many values one declaration holds. A program within them can always be built at
start-up; one beyond them is a located error here rather than a RecursionError or MemoryError
when `st run` builds it. Under every preset (not in library sources).

Depth: an elementary type is 0; a STRUCT, an ARRAY or a function block instance is one more than
its deepest part. Values: an elementary value (or a reference) is 1; an array holds its size
times its element's; a STRUCT or block the sum of its parts.

Codes: E041, E042.
"""

from __future__ import annotations

from collections.abc import Iterator

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ..context import CheckContext

MAX_NESTING = 100  # real programs nest types and blocks a handful of levels deep
MAX_VALUES = 50_000_000  # the same bound as one array's elements (E042)
MAX_ARRAY_ELEMENTS = 50_000_000
_STORED = ("VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_STAT", "VAR_INST", "VAR_TEMP", "VAR_GLOBAL")


def _parts(t) -> Iterator[tuple]:
    """(declaration span, type) of what a type is made of, one level down."""
    u = T.unalias(t)
    if isinstance(u, T.ArrayType):
        yield None, u.element
    elif isinstance(u, T.StructType):
        for m in u.members.values():
            yield m.span, m.type
    elif isinstance(u, T.POUType) and u.pou_kind in ("FUNCTION_BLOCK", "PROGRAM"):
        for v in u.vars.values():
            if v.section in _STORED:
                yield v.span, v.type


class _Measure:
    """(depth, values) of types, memoised; an explicit stack, so that a chain of thousands of
    nested types is measured (and reported) without recursion."""

    def __init__(self):
        self.memo: dict = {}

    def measure(self, t) -> tuple:
        memo = self.memo
        stack = [(t, False)]
        while stack:
            cur, expanded = stack.pop()
            key = id(cur)
            if key in memo and memo[key] is not None:
                continue
            parts = [pt for _, pt in _parts(cur)]
            if not expanded:
                memo[key] = None  # in progress: a cycle (reported elsewhere) is a leaf
                stack.append((cur, True))
                stack.extend((pt, False) for pt in parts if id(pt) not in memo)
                continue
            u = T.unalias(cur)
            got = [memo.get(id(pt)) or (0, 1) for pt in parts]
            if isinstance(u, T.ArrayType):
                d, v = got[0]
                memo[key] = (d + 1, u.size * v)
            elif got:
                memo[key] = (1 + max(d for d, _ in got), sum(v for _, v in got))
            else:
                memo[key] = (1 if isinstance(u, T.StructType) else 0, 1)
        return memo[id(t)]


def check_array_size(ctx: CheckContext, at: T.ArrayType, span: Span) -> None:
    """An array type of more than MAX_ARRAY_ELEMENTS elements (E042), where it is written."""
    if at.size > MAX_ARRAY_ELEMENTS:
        ctx.err(
            Code.TOO_LARGE,
            span,
            f"an array of {at.size:,} elements is too large (at most {MAX_ARRAY_ELEMENTS:,})",
        )


def check_storage_limits(ctx: CheckContext) -> None:
    """Report E041 where nesting crosses MAX_NESTING and E042 at the innermost declaration that
    holds more than MAX_VALUES values (each problem once, where it starts)."""
    project, err = ctx.project, ctx.err
    m = _Measure()
    decls: list = []  # (span, type) of every declaration with storage
    seen_types: set = set()
    for pou in project.pous.values():
        for v in pou.vars.values():
            if v.section in _STORED:
                decls.append((v.span, v.type))
    for g in project.globals.values():
        decls.append((g.span, g.type))
    for t in project.types.values():
        if id(t) not in seen_types and isinstance(T.unalias(t), T.StructType):
            seen_types.add(id(t))
            decls.extend(_parts(t))
    reported: set = set()
    for span, t in decls:
        if span is None or span.file in ctx.library_units or (span, id(t)) in reported:
            continue
        reported.add((span, id(t)))
        depth, values = m.measure(t)
        if depth == MAX_NESTING + 1:
            err(
                Code.TOO_DEEP,
                span,
                f"this declaration's type nests {MAX_NESTING + 1} levels deep "
                f"(structures, arrays and function blocks inside each other; at most {MAX_NESTING})",
                "flatten the data: keep a few levels of structure and use arrays of them",
            )
        if values > MAX_VALUES and not _too_large_inside(t, m):
            u = T.unalias(t)
            if isinstance(u, T.ArrayType) and u.size > MAX_VALUES:
                continue  # the array itself is already E042 (its elements)
            err(
                Code.TOO_LARGE,
                span,
                f"this declaration holds {values:,} values (at most {MAX_VALUES:,})",
                "make the arrays smaller",
            )


def _too_large_inside(t, m: _Measure) -> bool:
    """Does a part of this type (a member or block variable) already hold too many values?"""
    u = T.unalias(t)
    if isinstance(u, T.ArrayType):
        return m.measure(u.element)[1] > MAX_VALUES
    return any(s is not None and m.measure(pt)[1] > MAX_VALUES for s, pt in _parts(u))
