"""The suite runs on every core by default (`addopts` in pyproject.toml: pytest-xdist's
`--numprocesses=auto --dist=worksteal`). With `-p no:xdist` those options would be unknown
and pytest would refuse to start: accept them then, and ignore them (the run is in-process)."""


def pytest_addoption(parser, pluginmanager):
    if pluginmanager.has_plugin("xdist"):
        return
    try:
        parser.addoption("--numprocesses", default=None, help="ignored: pytest-xdist is off (-p no:xdist)")
        parser.addoption("--dist", default="no", help="ignored: pytest-xdist is off (-p no:xdist)")
    except ValueError:  # the other conftest (tests/ or programs/) added them already
        pass
