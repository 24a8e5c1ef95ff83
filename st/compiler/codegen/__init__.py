"""Code generation: lowered AST (compiler/lower) → Python `ast` → code objects.

A printer: the lowering has made the semantic decisions (inheritance, properties, FB_init,
loop forms and their watchdog guards); what is left here is how to say it in Python.

One Python module per ST source file, all executed into one namespace per PLC.
Every generated statement carries its ST line, and each module is compiled
with the ST file name, so tracebacks, profilers and coverage speak ST.

Shapes (see docs/ARCHITECTURE.md): a FUNCTION becomes a Python function
(`_fn_Name`), a FUNCTION_BLOCK or PROGRAM a slotted class (`_fb_Name`,
`_prg_Name`) whose `_body()` runs one call, a STRUCT a slotted class
(`_st_Name`). Inside `_body()` the instance's variables are read into Python
locals once and written back on exit (locals are the fastest thing CPython
has); variables that something else may reach while the body runs (through a
reference, an action or an SFC) stay attributes.

Libraries emit code through the public API of `emit.py` (`call`, `const`, `wrap`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .pyast import f32

if TYPE_CHECKING:
    from .module import ModuleGen

__all__ = ["ModuleGen", "f32"]


def __getattr__(name: str) -> Any:
    """ModuleGen, imported when code is generated (a library's `emit` helpers need only emit.py)."""
    if name == "ModuleGen":
        from .module import ModuleGen

        return ModuleGen
    raise AttributeError(f"module 'st.compiler.codegen' has no attribute {name!r}")
