"""The command line's value types: one click ParamType per kind of value, shared by every command.

Each checks its value when the command line is read, before anything is compiled or started, and
refuses a bad one with `error: OPTION VALUE: what is wrong` on stderr and exit status 2 (cli.py
prints click's usage errors that way). A duration needs a unit and is greater than 0, a count is
a whole number greater than 0, a file to read exists and can be read, a file to write can be
created where it is asked for (nothing is created here: a probe file is made and removed).
"""

from __future__ import annotations

import os
import re
from typing import Any, NoReturn

import click

from ..model.addresses import AddressError, parse_address

_NUMBER = re.compile(r"[+-]?(\d[\d_]*)?(\.\d*)?([eE][+-]?\d+)?$")


class OptionValueError(click.BadParameter):
    """A refused value; its message starts with the value itself (`10: a duration needs a unit`)."""


class _Type(click.ParamType):
    def refuse(self, value: Any, why: str) -> NoReturn:
        raise OptionValueError(f"{value}: {why}")


class Duration(_Type):
    """'10s', '250ms', '1m30s', 'T#2s' → ns, greater than 0. A bare number is refused: which unit
    it meant cannot be guessed."""

    name = "duration"

    def convert(self, value: Any, param: Any, ctx: Any) -> int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value  # already converted (a default given in ns)
        text = str(value).strip()
        if text and _NUMBER.match(text) and any(c.isdigit() for c in text):
            self.refuse(value, f"a duration needs a unit, e.g. {text.lstrip('+')}s or {text.lstrip('+')}ms")
        from ..runtime.values import parse_duration_arg  # (when used: `st --help` loads no runtime)

        try:
            ns = parse_duration_arg(text)
        except ValueError:
            self.refuse(value, "not a duration (e.g. 10s, 250ms, 1m30s, T#2s)")
        if ns <= 0:
            self.refuse(value, "must be greater than 0")
        return ns


class Count(_Type):
    """A whole number greater than 0 (`lo`, and at most `hi` when given)."""

    name = "count"

    def __init__(self, lo: int = 1, hi: int | None = None):
        self.lo, self.hi = lo, hi

    def convert(self, value: Any, param: Any, ctx: Any) -> int:
        if isinstance(value, int) and not isinstance(value, bool):
            n = value
        else:
            try:
                n = int(str(value).strip(), 10)
            except ValueError:
                n = None
        if n is None or n < self.lo or (self.hi is not None and n > self.hi):
            if self.hi is not None:
                self.refuse(value, f"must be a whole number from {self.lo} to {self.hi}")
            if self.lo == 1:
                self.refuse(value, "must be a whole number greater than 0")
            self.refuse(value, f"must be a whole number, at least {self.lo}")
        return n


class Integer(_Type):
    """Any whole number (a seed)."""

    name = "integer"

    def convert(self, value: Any, param: Any, ctx: Any) -> int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        try:
            return int(str(value).strip(), 10)
        except ValueError:
            self.refuse(value, "must be a whole number")


class Number(_Type):
    """A real number greater than 0 (or at least 0 with zero=True: `--modbus-rate 0` is unbounded)."""

    name = "number"

    def __init__(self, zero: bool = False):
        self.zero = zero

    def convert(self, value: Any, param: Any, ctx: Any) -> float:
        try:
            x = float(value)
        except (TypeError, ValueError):
            x = float("nan")
        if not x == x or x in (float("inf"), float("-inf")) or x < 0 or (x == 0 and not self.zero):
            self.refuse(value, "must be a number, at least 0" if self.zero else "must be a number greater than 0")
        return x


class CPU(_Type):
    """A CPU this process may run on."""

    name = "cpu"

    def convert(self, value: Any, param: Any, ctx: Any) -> int:
        try:
            n = int(str(value).strip(), 10)
        except ValueError:
            self.refuse(value, "must be a CPU number, e.g. 1")
        allowed = (
            sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else list(range(os.cpu_count() or 1))
        )
        if n not in allowed:
            self.refuse(value, f"no such CPU here (CPUs: {_spans(allowed)})")
        return n


def _spans(ns: list[int]) -> str:
    """[0, 1, 2, 5] → '0-2, 5'."""
    out: list[str] = []
    for n in ns:
        if out and out[-1].split("-")[-1] == str(n - 1):
            out[-1] = f"{out[-1].split('-')[0]}-{n}"
        else:
            out.append(str(n))
    return ", ".join(out)


class Endpoint(_Type):
    """'[HOST:]PORT' (an IPv6 host in brackets: '[::1]:5020') → 'HOST:PORT', host 127.0.0.1 when left out."""

    name = "[HOST:]PORT"

    def convert(self, value: Any, param: Any, ctx: Any) -> str:
        text = str(value).strip()
        host, sep, port = text.rpartition(":")
        host = host.strip()
        if host.startswith("[") and host.endswith("]"):
            host = host[1:-1]
        if not port.isdigit():
            self.refuse(value, "expected [HOST:]PORT, e.g. 127.0.0.1:5020")
        if int(port) > 65535:
            self.refuse(value, f"port {int(port)} is not 0..65535")
        if any(c.isspace() for c in host):
            self.refuse(value, "expected [HOST:]PORT, e.g. 127.0.0.1:5020")
        return f"{host or '127.0.0.1'}:{int(port)}"


def is_loopback(host: str) -> bool:
    """True for an address only this machine reaches (127.0.0.0/8, ::1, localhost)."""
    h = host.strip().strip("[]").lower()
    if h == "localhost":
        return True
    try:
        import ipaddress

        return ipaddress.ip_address(h).is_loopback
    except ValueError:
        return False


class UnitIds(_Type):
    """'1,255' → [1, 255]: Modbus unit ids, 0..255."""

    name = "IDS"

    def convert(self, value: Any, param: Any, ctx: Any) -> list[int]:
        if isinstance(value, list):
            return value
        out = []
        for part in str(value).split(","):
            p = part.strip()
            if not p.isdigit() or int(p) > 255:
                self.refuse(value, "expected unit ids 0..255 separated by commas, e.g. 1,255")
            out.append(int(p))
        return out


class ModbusRanges(_Type):
    """'holding:0-99,coil:0-15' → {table: [(first, end)]}."""

    name = "RANGES"

    def convert(self, value: Any, param: Any, ctx: Any) -> dict:
        if isinstance(value, dict):
            return value
        from ..io.modbus import parse_ranges

        try:
            ranges = parse_ranges(value)
        except ValueError as e:
            self.refuse(value, str(e))
        if not ranges:
            self.refuse(value, "expected TABLE:FIRST-LAST, e.g. holding:0-99")
        return ranges


class SafeOutput(_Type):
    """'%QX0.1=TRUE' / '%QW3=100' → (address, value): an output's value in STOP and FAULT."""

    name = "ADDR=VALUE"

    def convert(self, value: Any, param: Any, ctx: Any) -> tuple[str, bool | int]:
        if isinstance(value, tuple):
            return value
        addr, sep, text = str(value).partition("=")
        addr, text = addr.strip(), text.strip().upper()
        if not sep or not addr or not text:
            self.refuse(value, "expected ADDRESS=VALUE, e.g. %QX0.1=TRUE")
        try:
            area, size, _ = parse_address(addr)
        except AddressError as e:
            self.refuse(value, str(e))
        if area != "Q":
            self.refuse(value, "only outputs (%Q…) have safe values")
        if text in ("TRUE", "FALSE"):
            return addr, text == "TRUE"
        try:
            n = int(text, 0)
        except ValueError:
            self.refuse(value, "the value must be TRUE, FALSE or an integer")
        if size == "X" and n not in (0, 1):
            self.refuse(value, "a bit's value is TRUE, FALSE, 0 or 1")
        return addr, bool(n) if size == "X" else n


class TaskCost(_Type):
    """'TASK=4ms' → (task, ns)."""

    name = "TASK=DURATION"

    def convert(self, value: Any, param: Any, ctx: Any) -> tuple[str, int]:
        if isinstance(value, tuple):
            return value
        name, sep, cost = str(value).partition("=")
        if not sep or not name.strip() or not cost.strip():
            self.refuse(value, "expected TASK=DURATION, e.g. fast=4ms")
        try:
            ns = Duration().convert(cost.strip(), param, ctx)
        except OptionValueError as e:
            self.refuse(value, str(e.message))
        return name.strip(), ns


class InputFile(_Type):
    """A file that exists and can be read (a directory too with dirs=True: `st test tests/`)."""

    name = "file"

    def __init__(self, dirs: bool = False):
        self.dirs = dirs

    def convert(self, value: Any, param: Any, ctx: Any) -> str:
        path = os.fsdecode(value)
        if not os.path.exists(path):
            self.refuse(path, "no such file" + (" or directory" if self.dirs else ""))
        if os.path.isdir(path):
            if not self.dirs:
                self.refuse(path, "is a directory, not a file")
            return path
        try:
            with open(path, "rb"):
                pass
        except OSError as e:
            self.refuse(path, f"cannot be read ({(e.strerror or str(e)).lower()})")
        return path


class OutputFile(_Type):
    """A file the command writes: its folder exists and lets a file be created there; the file,
    when it exists, is not a directory and can be written. Nothing is left behind by the check."""

    name = "file"

    def convert(self, value: Any, param: Any, ctx: Any) -> str:
        path = os.fsdecode(value)
        problem = writable_file(path)
        if problem:
            self.refuse(path, problem)
        return path


class OutputDir(_Type):
    """A folder the command writes into, created (with its parents) when missing."""

    name = "DIR"

    def convert(self, value: Any, param: Any, ctx: Any) -> str:
        path = os.fsdecode(value)
        problem = writable_dir(path)
        if problem:
            self.refuse(path, problem)
        return path


def writable_file(path: str) -> str | None:
    """Why `path` cannot be written (None when it can)."""
    if not path:
        return "an empty file name"
    if os.path.isdir(path):
        return "is a directory"
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.exists(folder):
        return f"no such folder: {folder}"
    if not os.path.isdir(folder):
        return f"not a folder: {folder}"
    if os.path.exists(path):
        try:
            with open(path, "ab"):
                pass
        except OSError as e:
            return f"cannot be written ({(e.strerror or str(e)).lower()})"
        return None
    return _probe(folder)


def writable_dir(path: str) -> str | None:
    """Why files cannot be created in the folder `path`, created if missing (None when they can)."""
    if os.path.exists(path):
        if not os.path.isdir(path):
            return "is a file, not a folder"
        return _probe(path)
    parent = os.path.dirname(os.path.abspath(path))
    while not os.path.exists(parent):
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent):
        return f"not a folder: {parent}"
    return _probe(parent)


def _probe(folder: str) -> str | None:
    """Create and remove a file in `folder`: what permissions, a read-only file system or the
    root user's privileges really allow (os.access answers yes to root everywhere)."""
    try:
        import tempfile

        with tempfile.NamedTemporaryFile(dir=folder, prefix=".st-probe-"):
            pass
    except OSError as e:
        return f"cannot write in {folder} ({(e.strerror or str(e)).lower()})"
    return None


DURATION = Duration()
COUNT = Count()
INTEGER = Integer()
ENDPOINT = Endpoint()
INPUT_FILE = InputFile()
OUTPUT_FILE = OutputFile()
OUTPUT_DIR = OutputDir()
