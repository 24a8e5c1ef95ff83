"""Binding a program's native module (st/compiler/native) to one PLC's namespace.

The extension module is found by its name, which is the hash of its contents, in the native
build directory where the cache is now (st.model.compiled.native_dir, so an artefact keeps
working when the cache moves), imported once per process (CPython cannot import one twice) and
its `make(ns)` called for every namespace: each PLC, restart and online change gets its own
bodies, bound to its own helpers, watchdog and globals. When the module cannot be loaded (its
file is not in the cache, another Python built it), the program runs on the Python tier and the
PLC's log says why.
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
        mod = _loaded.get(m.name)  # one name, one content: the same module wherever it was found
        if mod is None:
            path = m.file
            if not path.exists():
                raise FileNotFoundError(f"{path.name} is not in the native build directory {path.parent}")
            loader = importlib.machinery.ExtensionFileLoader(m.name, str(path))
            spec = importlib.util.spec_from_file_location(m.name, str(path), loader=loader)
            if spec is None:
                raise ImportError(f"cannot load {path}")
            mod = importlib.util.module_from_spec(spec)
            loader.exec_module(mod)
            _loaded[m.name] = mod
            NATIVE_LINES[m.pyx] = m.lines
        return mod
