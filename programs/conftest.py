"""As tests/conftest.py: with `-p no:xdist`, accept and ignore pyproject.toml's xdist options
(this directory's tests can be run on their own: `python -m pytest -p no:xdist programs/`)."""


def pytest_addoption(parser, pluginmanager):
    if pluginmanager.has_plugin("xdist"):
        return
    try:
        parser.addoption("--numprocesses", default=None, help="ignored: pytest-xdist is off (-p no:xdist)")
        parser.addoption("--dist", default="no", help="ignored: pytest-xdist is off (-p no:xdist)")
    except ValueError:  # the other conftest (tests/ or programs/) added them already
        pass
