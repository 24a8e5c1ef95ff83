"""Testing PLC logic: ST TEST blocks (runner), the pytest plugin, Python-side helpers, coverage.

from st.testing import TestPLC, TestSuite
from st.testing import strategies as iec      # hypothesis strategies (needs hypothesis)
"""

from .harness import FBHandle, TestPLC
from .runner import Report, TestCase, TestResult, TestSuite, resolve_sources

__all__ = ["FBHandle", "Report", "TestCase", "TestPLC", "TestResult", "TestSuite", "resolve_sources"]
