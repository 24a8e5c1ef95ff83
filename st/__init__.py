"""st: an IEC 61131-3 Structured Text toolchain and soft PLC."""

from .api import PLC
from .diagnostics import CompileError
from .runtime.faults import PLCFaultError, PLCStartError
from .runtime.online_change import OnlineChangeRefused

__version__ = "0.1.0"
__all__ = ["PLC", "PLCFaultError", "PLCStartError", "OnlineChangeRefused", "CompileError", "__version__"]
