"""The Template record shared by the tpl_*.py modules of the library generator."""

from collections.abc import Callable
from dataclasses import dataclass


@dataclass
class Template:
    key: str  # short name, e.g. "filter_pt1"
    text: str  # ST text with str.format placeholders
    params: Callable = None  # rng -> dict of constants (optional)
    # For function blocks the program may call: the FB's name prefix and a call
    # snippet with {inst} (instance name) and {b}, {r}, {i} (a BOOL, a REAL and an
    # INT expression of the program).
    fb: str | None = None
    call: str | None = None

    def render(self, rng, ctx: dict) -> str:
        values = dict(ctx)
        if self.params is not None:
            values.update(self.params(rng))
        return self.text.format(**values)


def fnum(x: float) -> str:
    """A REAL literal with a few digits (always with a decimal point)."""
    s = f"{x:.4f}".rstrip("0")
    return s + "0" if s.endswith(".") else s
