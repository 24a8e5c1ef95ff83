"""st: an IEC 61131-3 Structured Text toolchain and soft PLC."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"
__all__ = ["PLC", "PLCFaultError", "PLCStartError", "OnlineChangeRefused", "CompileError", "__version__"]

# imported when first used (PEP 562): `st --version` and `st --help` need none of the compiler
_LAZY = {
    "PLC": ("st.facade", "PLC"),
    "CompileError": ("st.diagnostics", "CompileError"),
    "PLCFaultError": ("st.runtime.faults", "PLCFaultError"),
    "PLCStartError": ("st.runtime.faults", "PLCStartError"),
    "OnlineChangeRefused": ("st.runtime.online_change", "OnlineChangeRefused"),
}

if TYPE_CHECKING:
    from .diagnostics import CompileError
    from .facade import PLC
    from .runtime.faults import PLCFaultError, PLCStartError
    from .runtime.online_change import OnlineChangeRefused


def __getattr__(name: str) -> Any:
    where = _LAZY.get(name)
    if where is None:
        raise AttributeError(f"module 'st' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(where[0]), where[1])
    globals()[name] = value
    return value
