"""Testing PLC logic: ST TEST blocks (runner), the pytest plugin, Python-side helpers, coverage."""
from .runner import Report, TestCase, TestResult, TestSuite, resolve_sources

__all__ = ["Report", "TestCase", "TestResult", "TestSuite", "resolve_sources"]
