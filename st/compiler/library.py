"""What a library gives the compiler: ST sources, native functions and runtime helpers.

The compiler knows no standard function by itself; `st.stdlib` (and later
`st.stdlib.plcopen`) describe theirs with `FuncSig`, so every library plugs in
the same way.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass
class Param:
    name: str
    constraint: str  # a type name (INT, TIME, ...) or a generic (ANY_NUM, ANY_INT, ...)
    group: str = ""  # params of the same group unify to one type ("T")


@dataclass
class FuncSig:
    """A native (Python-implemented) function callable from ST.

    `result` is a type name, the name of a group ("T": the unified type of
    that group's arguments), or a callable(arg_types) → Type.
    `emit(ctx, args, arg_types, result_type)` returns a Python `ast.expr`;
    by default the call is `helper(*args, *extra(arg_types, result_type))`.
    """

    name: str
    params: list
    result: Any
    extensible: bool = False
    helper: str = ""
    extra: Callable | None = None
    emit: Callable | None = None
    min_args: int = 0
    doc: str = ""
    aliases: dict = field(default_factory=dict)  # another name of a parameter (lower) → its name (lower)
    # ENO after a call that ran, from the argument count: (n_args) → callable(arg expressions) → expr;
    # None: TRUE (MatIEC's MUX: FALSE for a selector out of range)
    eno_ok: Callable | None = None
    # (argument index, its integer type) → True: that argument, when it may leave its type (an exact
    # intermediate, `u - w`), is wrapped to its type first, as a user FUNCTION's input is stored (a
    # conversion converts a value of its source type); None: arguments are exact, as operands are
    typed_args: Callable | None = None


@dataclass
class Library:
    name: str
    sources: list = field(default_factory=list)  # [(path, text)]
    functions: dict = field(default_factory=dict)  # upper name → FuncSig
    helpers: dict = field(default_factory=dict)  # python name → object (module namespace)
    conversion: Callable | None = None  # name → FuncSig | None (X_TO_Y family)
    version: str = "1"
    namespaces: tuple[str, ...] = ()  # the names code may qualify this library's names with (Tc2_Standard.TON)
    # left out of a compilation whose own code declares a TYPE of one of its type names: the project
    # brings its own library of that kind (its own PLCopen motion library: AXIS_REF, MC_DIRECTION, ...)
    # and the library's blocks, built on its own types, cannot be mixed with it
    yields_to_own_types: bool = False
    # its blocks' ST bodies are what runs (no native body replaces them at run time), so code
    # generation may copy a small one into its callers (codegen/inline.py)
    inline_blocks: bool = False

    def add(self, sig: FuncSig) -> None:
        self.functions[sig.name.upper()] = sig

    def lookup(self, name: str) -> FuncSig | None:
        sig = self.functions.get(name.upper())
        if sig is None and self.conversion is not None:
            sig = self.conversion(name.upper())
        return sig
