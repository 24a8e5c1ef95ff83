"""A CASE selects on an integer or an enumeration, by labels of its type that are constants and
neither repeat nor overlap one another, under every preset (codesys and twincat, whose
enumerations read as integers, also take a non-strict enumeration value as an integer label).

Codes: E019, E029.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ..context import CheckContext


class CaseLabels:
    """The labels of one CASE, checked as the statement is walked."""

    def __init__(self, ctx: CheckContext, selector: A.Expr, t: T.Type | None) -> None:
        self.ctx = ctx
        self.t = t
        self.base = T.base_of(t) if t is not None else None
        if self.base is not None and not (self.base.is_intlike or isinstance(self.base, T.EnumType)):
            ctx.err(Code.BAD_CASE_LABEL, selector.span, f"a CASE selector must be an integer or enumeration, not {t}")
            self.base = None  # no label can be of a wrong type for it
        self.seen: list[tuple[int, int]] = []

    def check_type(self, e: A.Expr, et: T.Type | None) -> None:
        """The label `e`, of type `et` (None: reported already)."""
        b = self.base
        if b is None or et is None:
            return
        if isinstance(b, T.EnumType):
            fits = T.base_of(et) is b
        else:  # CODESYS: a non-strict enumeration value labels an integer selector
            fits = T.base_of(et).is_intlike or et is T.LIT_INT or self.ctx.enum_as_int(T.base_of(et))
        if not fits:
            self.ctx.err(Code.BAD_CASE_LABEL, e.span, f"CASE label of type {et} for a selector of type {self.t}")

    def check_constant(self, e: A.Expr, value):
        """The label `e`, whose constant value is `value` (None: not a constant); returns `value`."""
        if value is None:
            self.ctx.err(Code.NOT_CONSTANT, e.span, "a CASE label must be a constant")
        return value

    def add(self, span: Span, values: list) -> None:
        """A label (one value, or a range's two) at `span`: it may not meet an earlier one."""
        if not all(isinstance(v, int) for v in values):
            return  # a wrong label type was reported already
        if len(values) == 2:
            lo, hi = values
            if any(lo <= d and c <= hi for c, d in self.seen):
                self.ctx.err(Code.BAD_CASE_LABEL, span, f"CASE label {lo}..{hi} overlaps an earlier label")
            self.seen.append((lo, hi))
        elif len(values) == 1:
            v = values[0]
            if any(c <= v <= d for c, d in self.seen):
                self.ctx.err(Code.BAD_CASE_LABEL, span, f"duplicate CASE label {v}")
            self.seen.append((v, v))
