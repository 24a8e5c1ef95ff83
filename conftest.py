"""The suite runs on every core by default (`addopts` in pyproject.toml: pytest-xdist's
`--numprocesses=auto --dist=worksteal`). With `-p no:xdist` those options would be unknown and
pytest would refuse to start: accept them then, and ignore them (the run is in-process). At the
root, so that it serves both testpaths (tests/ and programs/)."""


def pytest_addoption(parser, pluginmanager):
    if pluginmanager.has_plugin("xdist"):
        return
    parser.addoption("--numprocesses", default=None, help="ignored: pytest-xdist is off (-p no:xdist)")
    parser.addoption("--dist", default="no", help="ignored: pytest-xdist is off (-p no:xdist)")
