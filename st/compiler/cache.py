"""The compile cache: a compiled program's bytes (`CompiledProgram.to_bytes`) under a digest of
everything that decides them (the compiler's own code, Python, the libraries, the options, the
sources).

It stores bytes and returns fresh objects: it never changes the program it is given or one it
returned. An entry it cannot read (another format, another Python, a damaged file) is a miss,
and the program is compiled again.
"""

from __future__ import annotations

import hashlib
import os
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..model.compiled import CompiledProgram, FormatError, cache_root
from ..source import SourceFile
from .library import Library
from .options import CompileOptions

COMPILER_VERSION = "0.1.0-9"
_toolchain_digest: str | None = None


def cache_dir() -> Path | None:
    """The directory of cached programs ($ST_CACHE_DIR, else ~/.cache/st), or None: ST_NO_CACHE is
    set or the directory cannot be made."""
    if os.environ.get("ST_NO_CACHE"):
        return None
    p = cache_root() / "compiled"
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return p


def _toolchain() -> str:
    """A digest of the compiler's own code: a new compiler never reuses old cached output."""
    global _toolchain_digest
    if _toolchain_digest is None:
        h = hashlib.sha256(COMPILER_VERSION.encode())
        root = Path(__file__).resolve().parents[1]
        for sub in ("grammar", "compiler", "model", "stdlib", "runtime"):
            for f in sorted((root / sub).rglob("*")):
                if f.suffix in (".py", ".lark", ".st"):
                    h.update(f.read_bytes())
        _toolchain_digest = h.hexdigest()
    return _toolchain_digest


def cache_key(sources: list[SourceFile], libraries: list[Library], options: CompileOptions) -> str:
    h = hashlib.sha256()
    h.update(_toolchain().encode())
    h.update(sys.version.encode())
    h.update(options.cache_token().encode() + b"\0")
    for lib in libraries:
        h.update(lib.name.encode() + lib.version.encode())
        for _path, text in lib.sources:
            h.update(text.encode())
    for s in sources:
        h.update(s.path.encode() + b"\0" + s.text.encode() + b"\0")
    return h.hexdigest()


def load(
    directory: Path, key: str, *, sources: dict[str, SourceFile], helpers: dict[str, Any]
) -> CompiledProgram | None:
    """The program stored under `key`, with the caller's sources and helpers, or None. A program
    whose native module (found by its content hash) is no longer in the build directory is a miss
    too: compiled again, the module is built again."""
    try:
        data = (directory / key).read_bytes()
    except OSError:
        return None
    try:
        compiled = CompiledProgram.from_bytes(data, sources=sources, helpers=helpers)
    except FormatError:
        return None
    if any(not m.file.exists() for m in compiled.native):
        return None
    return replace(compiled, from_cache=True)


def store(directory: Path, key: str, compiled: CompiledProgram) -> None:
    """Write the program's bytes under `key` (atomically); the cache is an optimisation, so a
    failure to write is silent."""
    try:
        path = directory / key
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_bytes(compiled.to_bytes())
        os.replace(tmp, path)
    except Exception:  # noqa: BLE001 - never fail a compile for the cache
        pass
