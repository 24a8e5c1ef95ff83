"""The suite runs on every core by default (`addopts` in pyproject.toml: pytest-xdist's
`--numprocesses=auto --dist=worksteal`). With `-p no:xdist` those options would be unknown and
pytest would refuse to start: accept them then, and ignore them (the run is in-process). At the
root, so that it serves both testpaths (tests/ and programs/).

The suite starts many Python processes (`st run`, the Modbus and web servers, pytest in pytest,
the fuzzer's workers): where the environment says PYTHONDONTWRITEBYTECODE, each of them would
compile st's modules again. The suite writes bytecode caches (__pycache__, ignored by git), so
that only the first one does."""

import os
import sys

os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False


def pytest_addoption(parser, pluginmanager):
    if pluginmanager.has_plugin("xdist"):
        return
    parser.addoption("--numprocesses", default=None, help="ignored: pytest-xdist is off (-p no:xdist)")
    parser.addoption("--dist", default="no", help="ignored: pytest-xdist is off (-p no:xdist)")
