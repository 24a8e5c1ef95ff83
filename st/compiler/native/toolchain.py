"""Cython and the C compiler: a .pyx text to a loadable extension module, built once.

The module is named after the hash of everything that decides its bytes (its text, Cython's
version, this Python's ABI, the C flags and compiler), so a build is found again by any later
compile of the same program, a compiled program finds it by that name alone (NativeModule.file),
and two processes building it at once both end with the same file: each builds in its own
directory and renames the result into place.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

from ...model.compiled import native_dir, native_file

# -ffp-contract=off: no fused multiply-add (x * x - 0.01 must round twice, as Python does)
CFLAGS = ["-O2", "-fwrapv", "-fno-strict-aliasing", "-ffp-contract=off", "-fPIC", "-shared", "-w"]
TIMEOUT_S = 600


class ToolchainError(Exception):
    """Cython or the C compiler is missing or refused the module (the message says which and why)."""


def cython_version() -> str | None:
    try:
        import Cython  # noqa: PLC0415 - optional: only the native tier needs it
    except ImportError:
        return None
    return str(Cython.__version__)


def c_compiler() -> list[str] | None:
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    argv = shlex.split(cc)
    if not argv or shutil.which(argv[0]) is None:
        argv = ["cc"] if shutil.which("cc") else (["gcc"] if shutil.which("gcc") else [])
    return argv or None


def missing() -> str | None:
    """Why no native module can be built here, or None when everything is present."""
    if cython_version() is None:
        return "Cython is not installed (pip install 'st[native]' or pip install cython)"
    if c_compiler() is None:
        return "no C compiler found (install gcc, or set CC)"
    include = sysconfig.get_paths()["include"]
    if not Path(include, "Python.h").exists():
        return f"Python's C headers are missing ({include}/Python.h; install python3-dev)"
    return None


def build_dir() -> Path:
    """The native build directory (st.model.compiled.native_dir: where the runtime looks too)."""
    d = native_dir()
    d.mkdir(parents=True, exist_ok=True)
    return d


def module_name(text: str) -> str:
    cc = " ".join(c_compiler() or [])  # another compiler (or CC) builds another module
    key = "\0".join([text, cython_version() or "", sysconfig.get_config_var("EXT_SUFFIX") or "", " ".join(CFLAGS), cc])
    return "st_k_" + hashlib.sha256(key.encode()).hexdigest()[:20]


def build(text: str) -> tuple[str, Path, bool]:
    """(module name, path of the built module, whether it was built now rather than found)."""
    why = missing()
    if why is not None:
        raise ToolchainError(why)
    name = module_name(text)
    try:
        d = build_dir()
    except OSError as e:
        raise ToolchainError(f"the native build directory cannot be made: {e}") from None
    so = native_file(name)
    pyx = d / (name + ".pyx")
    if so.exists() and pyx.exists():
        return name, so, False
    with tempfile.TemporaryDirectory(dir=d, prefix=name + ".") as tmp:
        t_pyx = Path(tmp, name + ".pyx")
        t_pyx.write_text(text)
        c_file = Path(tmp, name + ".c")
        t_so = Path(tmp, so.name)
        cc = c_compiler() or ["cc"]
        try:
            _run([sys.executable, "-m", "cython", "-3", "--fast-fail", str(t_pyx), "-o", str(c_file)], "Cython")
            _run([*cc, *CFLAGS, "-I", sysconfig.get_paths()["include"], str(c_file), "-o", str(t_so)], "the C compiler")
        except ToolchainError as e:
            kept = _keep_failed(t_pyx, str(e))
            raise ToolchainError(f"{e} (the module's source is kept in {kept} for a bug report)") from None
        os.replace(t_pyx, pyx)
        os.replace(t_so, so)
    return name, so, True


def _keep_failed(pyx: Path, why: str) -> Path:
    """A module that did not build is a bug of the tier: its source and the tool's words stay."""
    failed = pyx.parent.parent / "failed"
    failed.mkdir(exist_ok=True)
    kept = failed / pyx.name
    os.replace(pyx, kept)
    kept.with_suffix(".txt").write_text(why + "\n")
    return kept


def _run(argv: list[str], what: str) -> None:
    try:
        r = subprocess.run(argv, capture_output=True, text=True, timeout=TIMEOUT_S)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise ToolchainError(f"{what} could not run: {e}") from None
    if r.returncode != 0:
        lines = (r.stderr or r.stdout).strip().splitlines()
        raise ToolchainError(f"{what} failed: " + " | ".join(lines[-6:]))
