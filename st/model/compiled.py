"""The compiled program: code objects and the checked model, with a versioned serialisation.

`to_bytes()` writes what the compiler produced (code objects, the model, diagnostics, emitted
Python); the inputs (sources), the libraries' runtime helpers and coverage probes are the
caller's and are given back to `from_bytes()`. A payload of another format version or another
Python (marshalled code is version-specific) is refused with FormatError, never half-loaded.
The serialiser also refuses any object of st outside this package, st.source and
st.diagnostics: a compiled program loads without importing the compiler.
"""

from __future__ import annotations

import copyreg
import importlib.util
import io
import marshal
import os
import pickle
import sysconfig
import tempfile
import types
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..diagnostics import Diagnostic
from ..source import SourceFile
from .program import Project

FORMAT = 4  # 4: a NativeModule names its module by content hash, not by path
_MAGIC = b"st-compiled\n"
_HEADER = _MAGIC + FORMAT.to_bytes(2, "big") + importlib.util.MAGIC_NUMBER
_LEAF = ("st.model.", "st.source", "st.diagnostics")
# Code objects in marshal's version 2: without object references, whose use depends on reference
# counts, so that the same program always gives the same bytes.
_MARSHAL = 2

# An object's state in the payload instead of its own (`substitute`), or None to keep the object.
Substitute = Callable[[Any], dict[str, Any] | None]
# pickle writes a NEWOBJ for this function (as for any object it pickles by its state)
_NEWOBJ: Callable[..., Any] = copyreg.__newobj__  # type: ignore[attr-defined]  # not in typeshed


class FormatError(ValueError):
    """A payload that is not a compiled program of this format and this Python."""


def cache_root() -> Path:
    """The directory of st's caches: $ST_CACHE_DIR, else $XDG_CACHE_HOME/st or ~/.cache/st."""
    base = os.environ.get("ST_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "st"
    )
    return Path(base)


def native_dir() -> Path:
    """Where the native tier's modules are built and found: the compile cache's native/ directory
    (without a cache, ST_NO_CACHE, a directory of this user's under the system's temporary one)."""
    if os.environ.get("ST_NO_CACHE"):
        return Path(tempfile.gettempdir()) / f"st-cache-{os.getuid()}" / "native"
    return cache_root() / "compiled" / "native"


def native_file(name: str) -> Path:
    """The extension module called `name` in the native build directory (it may not exist)."""
    return native_dir() / (name + (sysconfig.get_config_var("EXT_SUFFIX") or ".so"))


@dataclass(frozen=True)
class NativeModule:
    """A program's bodies compiled by the native tier (st/compiler/native): an extension module
    whose `make(ns)` gives {class name: body}; `lines` maps its lines to (ST file, line, POU).

    The module is named after the hash of its contents (its text, Cython, the ABI, the C flags and
    compiler) and is found by that name in the native build directory (`native_dir()`), wherever
    the cache is when the program runs: an artefact holds no path."""

    name: str  # the module's import name: "st_k_" and the content hash
    pyx: str  # its source file's name, as its tracebacks name it
    classes: tuple[str, ...]  # the classes whose `_body` it replaces
    lines: dict[int, tuple[str, int, str]]
    functions: tuple[str, ...] = ()  # the FUNCTIONs it compiles (called in C by its bodies)

    @property
    def file(self) -> Path:
        """The built extension module, where it is looked for now (it may not exist)."""
        return native_file(self.name)


@dataclass
class CompiledProgram:
    """Everything the runtime needs: code objects and the checked model."""

    modules: list[tuple[str, types.CodeType]]  # [(filename, code object)]
    project: Project
    diagnostics: list[Diagnostic]
    sources: dict[str, SourceFile]  # path → SourceFile (for rendering diagnostics)
    helpers: dict[str, Any] = field(default_factory=dict)
    python_source: dict[str, str] = field(default_factory=dict)  # path → Python text (emit python)
    from_cache: bool = False
    coverage_points: list[tuple[Any, ...]] = field(default_factory=list)  # [(file, line, kind, label, target)]
    coverage_hits: bytearray | None = None  # one byte per point, shared by every PLC of this build
    test_modules: list[tuple[str, types.CodeType]] = field(default_factory=list)  # `_test_<n>` functions (TESTs)
    native: list[NativeModule] = field(default_factory=list)  # compiled bodies of the native tier
    native_skipped: dict[str, str] = field(default_factory=dict)  # POU → why its body stays Python

    def to_bytes(self, substitute: Substitute | None = None) -> bytes:
        """The compiler's output as bytes (FORMAT, this Python). `substitute(obj)` may give the
        state an object has in the payload (the compiler drops its syntax that way)."""
        payload = {
            "modules": [(p, marshal.dumps(c, _MARSHAL)) for p, c in self.modules],
            "test_modules": [(p, marshal.dumps(c, _MARSHAL)) for p, c in self.test_modules],
            "project": self.project,
            "diagnostics": list(self.diagnostics),
            "python": dict(self.python_source),
            "native": list(self.native),
            "native_skipped": dict(self.native_skipped),
        }
        buf = io.BytesIO()
        buf.write(_HEADER)
        _Writer(buf, substitute).dump(payload)
        return buf.getvalue()

    @classmethod
    def from_bytes(
        cls, data: bytes, *, sources: dict[str, SourceFile] | None = None, helpers: dict[str, Any] | None = None
    ) -> CompiledProgram:
        """A program from `to_bytes()` output, with the caller's sources and helpers."""
        if not data.startswith(_HEADER):
            raise FormatError(_why_refused(data))
        try:
            d = pickle.loads(memoryview(data)[len(_HEADER) :])
            modules = [(p, marshal.loads(c)) for p, c in d["modules"]]
            test_modules = [(p, marshal.loads(c)) for p, c in d["test_modules"]]
            project, diagnostics, python = d["project"], d["diagnostics"], d["python"]
            native, native_skipped = list(d["native"]), dict(d["native_skipped"])
        except Exception as exc:  # noqa: BLE001 - a damaged payload, whatever broke in it
            raise FormatError(f"damaged compiled program: {type(exc).__name__}: {exc}") from None
        if (
            not isinstance(project, Project)
            or not all(isinstance(x, Diagnostic) for x in diagnostics)
            or not all(isinstance(x, NativeModule) for x in native)
        ):
            raise FormatError("damaged compiled program: unexpected contents")
        return cls(
            modules,
            project,
            diagnostics,
            dict(sources or {}),
            dict(helpers or {}),
            python,
            test_modules=test_modules,
            native=native,
            native_skipped=native_skipped,
        )


def _why_refused(data: bytes) -> str:
    if not data.startswith(_MAGIC):
        return "not a compiled st program"
    version = int.from_bytes(data[len(_MAGIC) : len(_MAGIC) + 2], "big")
    if version != FORMAT:
        return f"compiled program format {version}, this st reads format {FORMAT}"
    return "compiled by another Python version"


class _Writer(pickle.Pickler):
    """A pickler that applies `substitute` and lets no object of the compiler into the payload."""

    def __init__(self, file: io.BytesIO, substitute: Substitute | None):
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self._substitute = substitute

    def reducer_override(self, obj: Any) -> Any:
        if self._substitute is not None:
            state = self._substitute(obj)
            if state is not None:
                return _NEWOBJ, (type(obj),), state
        owner = obj if isinstance(obj, (type, types.FunctionType, types.BuiltinFunctionType)) else type(obj)
        module = getattr(owner, "__module__", None) or ""
        if module.startswith("st.") and not module.startswith(_LEAF):
            raise TypeError(f"{module}.{owner.__qualname__} cannot be part of a compiled program")
        return NotImplemented
