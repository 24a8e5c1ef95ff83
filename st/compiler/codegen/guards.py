"""The watchdog's hook in generated code: every loop tests one flag per iteration.

One pass over each generated module, after everything else, puts `if _wd_armed: _wd_check()`
first in the body of every Python `while` and `for` loop, whatever ST statement it came
from (WHILE, REPEAT, FOR in each of its forms, loops of the library's own ST code). First,
so that a CONTINUE cannot skip it. The flag is a module global that costs one load and one
jump while it is down; the runtime's watchdog raises it when a job runs past its budget or a
stop is forced (runtime/watchdog.py), and `_wd_check` then ends the job at the loop's ST line.
"""
from __future__ import annotations

import ast as py

from .pyast import _call, _name, _set_lines


def guard(line: int) -> py.stmt:
    return _set_lines(py.If(_name("_wd_armed"), [py.Expr(_call("_wd_check"))], []), line)


def guard_loops(tree: py.AST) -> int:
    """Insert the watchdog check into every loop of `tree`; returns how many loops were guarded."""
    loops = [n for n in py.walk(tree) if isinstance(n, (py.While, py.For))]
    for node in loops:
        node.body.insert(0, guard(getattr(node, "lineno", None) or 1))
    return len(loops)
