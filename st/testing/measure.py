"""Coverage data from coverage builds (`compile_*(..., coverage=True)`): the probes' table and hits."""

from __future__ import annotations

from .covreport import CoverageData, Point


def coverage_data(builds) -> CoverageData:
    """Merge the hits of compiled programs (each `CompiledProgram` with probes) into one CoverageData."""
    total = CoverageData([], bytearray())
    for compiled in builds:
        if compiled.coverage_hits is None:
            continue
        points = [Point(*p) for p in compiled.coverage_points]
        total.merge(CoverageData(points, bytearray(compiled.coverage_hits)))
    return total
