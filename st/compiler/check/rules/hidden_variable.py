"""A METHOD's variable with the name of a variable of its function block hides that variable
inside the method: a warning, under every preset with methods (not in library sources).

Codes: W006.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ..context import CheckContext


def check_hidden_variable(ctx: CheckContext, fb: T.POUType, method: str, v: T.VarSym) -> None:
    """The variable `v` of the method `method` of `fb`."""
    if v.name.lower() in fb.vars and v.section != "VAR_EXTERNAL":
        ctx.warn(Code.HIDDEN_VARIABLE, v.span, f"'{v.name}' in method {method} hides the variable of {fb.name}")
