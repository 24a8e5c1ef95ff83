"""A call without an instance inside a function block reaches its METHOD of that name even where a
standard or global function of the name would take the same arguments: a warning (THIS^.M()
says it is meant), under every preset with methods.

Codes: W007.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def check_method_shadows_function(ctx: CheckContext, c: A.Call, callee: A.Name, mt: T.POUType) -> None:
    """`c`, written `callee(...)`, calls the method `mt` of the running instance."""
    key = callee.name.lower()
    fn = ctx.project.pous.get(key)
    sig = ctx.native(key)
    n = len([a for a in c.args if not a.name or a.name.lower() not in ("en", "eno")])
    fits = (sig is not None and (n == len(sig.params) or (sig.extensible and n >= len(sig.params)))) or (
        fn is not None and fn.pou_kind == "FUNCTION" and n == len([p for p in fn.params() if p.section != "VAR_OUTPUT"])
    )
    if fits:  # the call would fit the function too: say which runs
        ctx.warn(
            Code.METHOD_SHADOWS_FUNCTION,
            callee.span,
            f"'{callee.name}' calls the method {mt.name} of {mt.block.name}, not the function of that name",
            f"write THIS^.{mt.name}(...) to say so, or rename the method",
        )
