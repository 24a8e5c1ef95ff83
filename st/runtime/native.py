"""Binding a program's native module (st/compiler/native) to one PLC's namespace.

The extension module is imported once per process (CPython cannot import one twice) and its
`make(ns)` called for every namespace: each PLC, restart and online change gets its own bodies,
bound to its own helpers, watchdog and globals. When the module cannot be loaded (its file
was removed from the cache, another Python), the program runs on the Python tier and the PLC's
log says why.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import threading
import types
from typing import Any

from ..model.compiled import NativeModule
from .faults import NATIVE_LINES

_loaded: dict[str, types.ModuleType] = {}
_lock = threading.Lock()


def install_native(ns: dict[str, Any], modules: list[NativeModule]) -> list[str]:
    """Replace the `_body` of each class a native module compiled; the problems, as text."""
    problems = []
    for m in modules:
        try:
            mod = _load(m)
            bodies = mod.make(ns)
        except Exception as e:  # noqa: BLE001 - any failure leaves the Python bodies in place
            problems.append(f"native module {m.name} not used ({type(e).__name__}: {e}); running as Python")
            continue
        for cls, body in bodies.items():
            ns[cls]._body = body
    return problems


def _load(m: NativeModule) -> types.ModuleType:
    with _lock:
        mod = _loaded.get(m.path)
        if mod is None:
            loader = importlib.machinery.ExtensionFileLoader(m.name, m.path)
            spec = importlib.util.spec_from_file_location(m.name, m.path, loader=loader)
            if spec is None:
                raise ImportError(f"cannot load {m.path}")
            mod = importlib.util.module_from_spec(spec)
            loader.exec_module(mod)
            _loaded[m.path] = mod
            NATIVE_LINES[m.pyx] = m.lines
        return mod
