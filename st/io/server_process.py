"""A server in its own interpreter beside the PLC (the Modbus slave, the web page's server).

A fresh interpreter, not a fork: the PLC's heap and real-time settings stay in the PLC's
process. Not multiprocessing's spawn either: it would run the user's main module again. The
server reads its configuration, pickled, on stdin, and reports through the shared memory.
"""

from __future__ import annotations

import pickle
import subprocess
import sys
from typing import Any


def spawn(module: str, config: Any, log_path: str | None = None) -> subprocess.Popen[bytes]:
    """`python -m module` with `config` pickled on its stdin; its stderr to `log_path` (appended)
    or to the PLC's."""
    log = open(log_path, "ab") if log_path else None
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", module], stdin=subprocess.PIPE, stderr=log, start_new_session=True
        )
    finally:
        if log is not None:
            log.close()
    assert proc.stdin is not None  # stdin=PIPE
    proc.stdin.write(pickle.dumps(config))
    proc.stdin.close()
    return proc


def stop(proc: subprocess.Popen[bytes] | None) -> None:
    """SIGTERM, then SIGKILL after 5 s."""
    if proc is None:
        return
    if proc.poll() is None:
        proc.terminate()
    try:
        proc.wait(5)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(1)
