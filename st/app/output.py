"""Messages of `st run` go to stderr, flushed (stdout carries --dump-json)."""

from __future__ import annotations

import sys


def err(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)
