"""PLC runtime faults, how a Python exception maps to an ST location, and the errors the PLC raises."""

from __future__ import annotations

import types
from dataclasses import dataclass


class PLCFault(Exception):
    """Raised by generated code or its helpers for an IEC runtime error."""

    def __init__(self, message: str, kind: str = "FAULT"):
        super().__init__(message)
        self.message = message
        self.kind = kind


@dataclass
class FaultInfo:
    kind: str  # DIV0, INDEX, RANGE, NULL, LOOP, WATCHDOG, CONVERSION, ...
    message: str
    file: str = ""
    line: int = 0
    pou: str = ""
    task: str = ""

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}: " if self.file else ""
        ctx = f" (in {self.pou}" + (f", task {self.task}" if self.task else "") + ")" if self.pou else ""
        return f"{where}PLC fault [{self.kind}]: {self.message}{ctx}"


class PLCFaultError(RuntimeError):
    """A scan ended in a PLC fault; `.fault` says where and why."""

    def __init__(self, fault: FaultInfo):
        super().__init__(str(fault))
        self.fault = fault


class PLCStartError(ValueError):
    """The program cannot start: a located address outside the process image, a VAR_CONFIG value
    that does not fit, or a fault while creating the instances (FB_init, an initial value): then
    `.fault` names it and its ST line, as for a fault in a scan."""

    def __init__(self, message: str, fault: FaultInfo | None = None):
        super().__init__(message)
        self.fault = fault


_PY_KINDS = {
    ZeroDivisionError: ("DIV0", "division by zero"),
    IndexError: ("INDEX", "array index out of range"),
    RecursionError: ("RECURSION", "call depth exceeded (recursion)"),
    OverflowError: ("OVERFLOW", "numeric overflow"),
    AttributeError: ("NULL", "invalid reference"),
}


# __TRY/__CATCH (CODESYS, TwinCAT): the fault kinds a __CATCH handles and the __SYSTEM.ExceptionCode
# each gives (st/stdlib/vendor/vendor.st: CODESYS's runtime codes). The others are not caught: a
# WATCHDOG (a runaway loop still stops the PLC), LOOP (a FOR that never ends), TEST (the test runner's).
EXCEPTION_CODES = {
    "DIV0": 0x102,  # RTSEXCPT_DIVIDEBYZERO
    "INDEX": 0x101,  # RTSEXCPT_ARRAYBOUNDS
    "RANGE": 0x101,  # RTSEXCPT_ARRAYBOUNDS: a subrange or a string position outside its bounds
    "NULL": 0x51,  # RTSEXCPT_ACCESS_VIOLATION
    "MEMORY": 0x51,  # RTSEXCPT_ACCESS_VIOLATION: bytes beyond a variable
    "RECURSION": 0x54,  # RTSEXCPT_STACK_OVERFLOW
    "OVERFLOW": 0x155,  # RTSEXCPT_FPU_OVERFLOW
    "CONVERSION": 0x154,  # RTSEXCPT_FPU_INVALID_OPERATION: NaN or infinity to an integer, a value out of range
}

# what a __CATCH's Python `except` names: the exceptions that may carry a fault it handles
CATCHABLE: tuple[type[BaseException], ...] = (PLCFault, *_PY_KINDS)


def exception_code(exc: BaseException) -> int | None:
    """The __SYSTEM.ExceptionCode a __CATCH gives for `exc`, or None: not handled (the PLC faults)."""
    if isinstance(exc, PLCFault):
        return EXCEPTION_CODES.get(exc.kind)
    for cls, (kind, _) in _PY_KINDS.items():
        if isinstance(exc, cls):
            return EXCEPTION_CODES.get(kind)
    return None


# the native tier's modules: their source file's name → {line: (ST file, ST line, POU)}
NATIVE_LINES: dict[str, dict[int, tuple[str, int, str]]] = {}


def fault_from_exception(exc: BaseException, task: str = "") -> FaultInfo:
    """Describe an exception raised while running generated code, at its ST line."""
    if isinstance(exc, PLCFault):
        kind, msg = exc.kind, exc.message
    else:
        kind, msg = "FAULT", f"{type(exc).__name__}: {exc}"
        for cls, (k, m) in _PY_KINDS.items():
            if isinstance(exc, cls):
                kind, msg = k, m
                break
    file, line, pou = "", 0, ""
    tb: types.TracebackType | None = exc.__traceback__
    while tb is not None:
        code = tb.tb_frame.f_code
        if tb.tb_frame.f_globals.get("_st_namespace"):
            file, line = code.co_filename, tb.tb_lineno
            pou = _pou_name(tb.tb_frame)
        elif NATIVE_LINES:
            where = NATIVE_LINES.get(code.co_filename.rpartition("/")[2], {}).get(tb.tb_lineno)
            if where is not None:
                file, line, pou = where
        tb = tb.tb_next
    return FaultInfo(kind, msg, file, line, pou, task)


def _pou_name(frame: types.FrameType) -> str:
    name: str = frame.f_code.co_name
    self = frame.f_locals.get("self")
    if self is not None:
        cls = type(self).__name__
        for p in ("_fb_", "_prg_"):
            if cls.startswith(p):
                return str(cls[len(p) :])
    if name.startswith("_fn_"):
        return name[4:]
    return name
