"""ST identifiers → Python identifiers, injectively and safely.

An ST name keeps its spelling unless it is a Python keyword or begins or ends
with '_'; those get a marker ('def' → 'def_', '_x' → 'u_x0_'). So mangled ST
names never begin with '_' and the generated code's own names (helpers,
POU classes, globals) always do: no ST identifier can reach a Python builtin,
a helper or a dunder.

A name made of several ST names (a block's static variable, a method's instance
variable, a resource's global) joins them with `qualified`, which is injective too:
inside a part every '_' is written '_1' and parts are separated by '_0', so
`A_B` + `c` ('A_1B_0c') and `A` + `B_c` ('A_0B_1c') never meet.
"""

from __future__ import annotations

import keyword

_SOFT = {"match", "case", "type", "_", "self"}


def mangle(name: str) -> str:
    """Plain names stay as they are (and never end with '_'); the others end with '_': a name
    that begins with '_' as 'u' + name + '0_' (what precedes the last '_' ends with '0', so it
    cannot be the result of the next rule), any other as name + '_'."""
    if name.startswith("_"):
        return "u" + name + "0_"
    if keyword.iskeyword(name) or name in _SOFT or name.endswith("_"):
        return name + "_"
    return name


def qualified(*parts: str) -> str:
    """Several ST names as one Python identifier (no leading '_'): distinct part lists give
    distinct results."""
    return "_0".join(p.replace("_", "_1") for p in parts)
