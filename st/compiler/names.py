"""ST identifiers → Python identifiers, injectively and safely.

An ST name keeps its spelling unless it is a Python keyword or begins or ends
with '_'; those get a marker ('def' → 'def_', '_x' → 'u_x_'). So mangled ST
names never begin with '_' and the generated code's own names (helpers,
POU classes, globals) always do: no ST identifier can reach a Python builtin,
a helper or a dunder.
"""
from __future__ import annotations

import keyword

_SOFT = {"match", "case", "type", "_", "self"}


def mangle(name: str) -> str:
    if name.startswith("_"):
        return "u" + name + "_"
    if keyword.iskeyword(name) or name in _SOFT or name.endswith("_"):
        return name + "_"
    return name
