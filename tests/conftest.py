"""The suite runs on every core by default (`addopts` in pyproject.toml: pytest-xdist's
`--numprocesses=auto --dist=worksteal`). With `-p no:xdist` those options would be unknown
and pytest would refuse to start: accept them then, and ignore them (the run is in-process)."""


def pytest_addoption(parser, pluginmanager):
    if not pluginmanager.has_plugin("xdist"):
        parser.addoption("--numprocesses", default=None, help="ignored: pytest-xdist is off (-p no:xdist)")
        parser.addoption("--dist", default="no", help="ignored: pytest-xdist is off (-p no:xdist)")
