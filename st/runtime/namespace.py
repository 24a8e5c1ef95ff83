"""The namespace compiled ST runs in: helpers, then every generated module executed into it.

One namespace per PLC (and per unit test, which is what isolates tests from one
another: globals, FB classes and mocks are all fresh).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..model.compiled import CompiledProgram
from .helpers import BASE_NAMESPACE, make_f32
from .messages import MessageLog
from .native import install_native
from .pointers import POINTER_HELPERS
from .sfc import SfcDesc, SfcState


def build_namespace(
    compiled: CompiledProgram, install: Callable[[dict[str, Any]], None] | None = None
) -> dict[str, Any]:
    """`install(ns)` adds what must exist before module code runs (watchdog, test helpers)."""
    ns: dict[str, Any] = dict(BASE_NAMESPACE)
    ns.update(POINTER_HELPERS)
    ns.update(compiled.helpers)
    ns.update({"_SfcDesc": SfcDesc, "_SfcState": SfcState, "_now": 0, "_st_namespace": True, "_f32": make_f32()})
    ns["_plc_log"] = MessageLog()  # the PLC's own replaces it when the program is installed
    ns["_ns"] = ns
    if compiled.coverage_hits is not None:
        ns["_cov"] = compiled.coverage_hits
    if install is not None:
        install(ns)
    for _path, code in compiled.modules:
        exec(code, ns)
    for name in sorted(k for k in ns if k.startswith("_post_exec_")):
        ns[name](ns)  # libraries with native parts finish their classes here
    if compiled.native:
        for problem in install_native(ns, compiled.native):
            ns["_plc_log"].add(0, 2, problem)
    return ns
