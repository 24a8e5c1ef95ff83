"""What many test modules need: compile and run ST text, collect its diagnostics, catch its fault.

Import with `from helpers import ...` (pytest puts tests/ on sys.path). A module that names its
source file in assertions binds the name once: `run = partial(helpers.run, name="oop.st")`.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Iterable

import pytest

from st import PLC
from st.api import compile_text
from st.diagnostics import CompileError
from st.runtime.faults import FaultInfo, PLCFaultError


def program(body: str, decls: str = "", extra: str = "") -> str:
    """A PROGRAM main with `decls` in its VAR section and `body`, after `extra` (types, blocks)."""
    return f"{extra}\nPROGRAM main\nVAR\n{decls}\nEND_VAR\n{body}\nEND_PROGRAM\n"


def run(src: str, scans: int = 1, dialect: str | None = None, *, name: str = "t.st", **compile_kw) -> PLC:
    """Compile `src` (uncached unless asked), start a PLC on virtual time and run `scans` base ticks."""
    compile_kw.setdefault("use_cache", False)
    plc = PLC(compile_text(src, name, dialect=dialect, **compile_kw))
    plc.scan(scans)
    return plc


def compile_error(src: str, dialect: str | None = None, *, name: str = "t.st") -> CompileError:
    """The CompileError `src` must raise (the test fails if it compiles)."""
    with pytest.raises(CompileError) as info:
        compile_text(src, name, dialect=dialect, use_cache=False)
    return info.value


def errors(src: str, dialect: str | None = None, *, name: str = "t.st") -> str:
    """The rendered diagnostics of a program that must not compile (as `st check` prints them)."""
    return str(compile_error(src, name=name, dialect=dialect))


def fault(src: str, dialect: str | None = None, *, scans: int = 1, name: str = "t.st") -> tuple[PLC, FaultInfo]:
    """Run a program that must fault within `scans` ticks: (the PLC, its fault)."""
    plc = PLC(compile_text(src, name, dialect=dialect, use_cache=False))
    with pytest.raises(PLCFaultError) as info:
        plc.scan(scans)
    return plc, info.value.fault


def diagnostics(src: str, *, name: str = "t.st", dialect: str | None = None) -> list[tuple[str, int, int]]:
    """Every diagnostic (errors and warnings) of `src` in its own file, as (code, line, column)."""
    result = compile_text(src, name, dialect=dialect, use_cache=False, raise_on_error=False)
    return [(d.code, d.span.line, d.span.col) for d in result.diagnostics if d.span is not None and d.span.file == name]


def assert_diagnostics(
    src: str, expected: Iterable[tuple], *, allow: Iterable[str] = (), name: str = "t.st", dialect: str | None = None
) -> None:
    """Exactly the `expected` diagnostics, each (code, line) or (code, line, column), in any order:
    a missing one fails, and so does any other diagnostic unless its code is in `allow`."""
    got = diagnostics(src, name=name, dialect=dialect)
    want = [tuple(e) for e in expected]
    unmatched = list(got)
    missing = []
    for e in want:
        hit = next((g for g in unmatched if g[: len(e)] == e), None)
        if hit is None:
            missing.append(e)
        else:
            unmatched.remove(hit)
    allowed = set(allow)
    extra = [g for g in unmatched if g[0] not in allowed]
    assert not missing and not extra, f"missing {missing}, unexpected {extra}; all reported: {got}"


class StRun:
    """`st run ARGS` started as a user starts it, its stderr read line by line as it comes, so a
    test waits for what the PLC says (`wait_for("running in real time")`) instead of sleeping a
    guess at how long start-up takes on a loaded machine."""

    def __init__(self, *args: str, cwd: str | None = None):
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "st.cli", "run", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=cwd,
        )
        self.err_lines: list[str] = []
        self.out_lines: list[str] = []
        self._readers = [
            threading.Thread(target=self._read, args=(self.proc.stderr, self.err_lines), daemon=True),
            threading.Thread(target=self._read, args=(self.proc.stdout, self.out_lines), daemon=True),
        ]
        for t in self._readers:
            t.start()

    @staticmethod
    def _read(stream, into: list) -> None:
        for line in stream:
            into.append(line)

    @property
    def stderr(self) -> str:
        return "".join(self.err_lines)

    def wait_for(self, text: str, timeout: float = 60.0) -> None:
        """Until `text` appears on stderr; fails if the process ends or the time runs out first."""
        deadline = time.monotonic() + timeout
        while text not in self.stderr:
            if self.proc.poll() is not None:
                for t in self._readers:
                    t.join(5)
                if text in self.stderr:
                    return
                raise AssertionError(f"st run ended (exit {self.proc.returncode}) before {text!r}:\n{self.stderr}")
            if time.monotonic() > deadline:
                raise AssertionError(f"no {text!r} from st run within {timeout} s:\n{self.stderr}")
            time.sleep(0.02)

    def send_signal(self, sig: int) -> None:
        self.proc.send_signal(sig)

    def communicate(self, timeout: float = 60.0) -> tuple[str, str]:
        """Wait for the end: (stdout, stderr)."""
        self.proc.wait(timeout)
        for t in self._readers:
            t.join(10)
        return "".join(self.out_lines), self.stderr

    @property
    def returncode(self) -> int | None:
        return self.proc.returncode
