"""Per-task real-time statistics, as cyclictest and the thesis report them.

For every job (one execution of a task): its release a (the ideal start), its start t and its
end e. Wake-up latency = t − a (the thesis's jitter J); execution time = e − t; response time
R = e − a; period = t − previous t. A job overruns when it ends after its next release
(R ≥ period); a release that finds the previous job not yet started is skipped (counted apart
from overruns). The (m,k)-firm time utility U(T_i) = (1/k) Σ u over the last k jobs, u = 1 when R < C
(thesis eq. 3.4); a skipped job counts u = 0.

Samples are kept in bounded deques (the latest `keep`), so percentiles describe the recent
window while min/avg/max and counts cover the whole run. Recording is a few list operations.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any


class TaskStats:
    def __init__(self, name: str, period_ns: int, k: int = 10, m: int = 0, keep: int = 200_000):
        self.name = name
        self.period = period_ns
        self.k = k
        self.m = m or k
        self.keep = keep
        self.jobs = 0
        self.overruns = 0  # jobs that ended after their next release
        self.skipped = 0  # releases dropped because the previous job had not started
        self.lat_min = math.inf
        self.lat_max = 0
        self.lat_sum = 0
        self.exec_min = math.inf
        self.exec_max = 0
        self.exec_sum = 0
        self.last_exec = 0
        self.latencies: deque[int] = deque(maxlen=keep)  # the latest `keep` samples (ns)
        # execution times of the same jobs (ns), kept once someone asks (keep_execs: the web page)
        self.execs: deque[int] | None = None
        self.periods: deque[int] = deque(maxlen=keep)  # start-to-start intervals (ns)
        self._last_start: int | None = None
        # the (m,k) window as the entries (jobs and skipped releases, numbered from 1) that missed:
        # an on-time job with no miss in the window, the common case, costs nothing more
        self._skip_entries = 0  # entries of skipped releases (entries = jobs + these)
        self._miss_at: deque[int] = deque()
        self.mk_violations = 0  # windows (after the first k jobs) with U < m/k

    def keep_execs(self) -> deque[int]:
        """From now on, keep each job's execution time beside its latency (`execs`)."""
        if self.execs is None:
            self.execs = deque(maxlen=self.keep)
        return self.execs

    def record(self, release: int, start: int, end: int) -> None:
        lat = start - release
        ex = end - start
        self.jobs += 1
        if lat < self.lat_min:
            self.lat_min = lat
        if lat > self.lat_max:
            self.lat_max = lat
        self.lat_sum += lat
        if ex < self.exec_min:
            self.exec_min = ex
        if ex > self.exec_max:
            self.exec_max = ex
        self.exec_sum += ex
        self.last_exec = ex
        self.latencies.append(lat)
        if self.execs is not None:
            self.execs.append(ex)
        last = self._last_start
        if last is not None:
            self.periods.append(start - last)
        self._last_start = start
        if end - release >= self.period > 0:
            self.overruns += 1
            self._miss_at.append(self.jobs + self._skip_entries)
            self._slide()
            return
        if self._miss_at:
            self._slide()

    def record_skip(self, n: int = 1) -> None:
        self.skipped += n
        for _ in range(min(n, self.k)):
            self._skip_entries += 1
            self._miss_at.append(self.jobs + self._skip_entries)
            self._slide()

    @property
    def _entries(self) -> int:
        return self.jobs + self._skip_entries

    def _slide(self) -> None:
        """Misses older than the last k entries leave the window; a full window below m/k counts."""
        miss_at, k = self._miss_at, self.k
        oldest = self.jobs + self._skip_entries - k
        while miss_at and miss_at[0] <= oldest:
            miss_at.popleft()
        if oldest >= 0 and k - len(miss_at) < self.m:
            self.mk_violations += 1

    @property
    def utility_window(self) -> list[int]:
        """The last k entries' utilities, oldest first (1 on time, 0 missed)."""
        n = min(self._entries, self.k)
        first = self._entries - n + 1
        missed = set(self._miss_at)
        return [0 if i in missed else 1 for i in range(first, self._entries + 1)]

    @property
    def utility(self) -> float:
        n = min(self._entries, self.k)
        return (n - len(self._miss_at)) / n if n else 1.0

    def summary(self) -> dict[str, Any]:
        """Everything as plain numbers (µs for times), for JSON and the status line."""
        lats = sorted(self.latencies)
        jitter = [p - self.period for p in self.periods] if self.period > 0 else []
        return {
            "task": self.name,
            "period_us": self.period / 1e3,
            "jobs": self.jobs,
            "overruns": self.overruns,
            "skipped": self.skipped,
            "latency_us": {
                "min": _us(self.lat_min if self.jobs else 0),
                "avg": _us(self.lat_sum / self.jobs if self.jobs else 0),
                "max": _us(self.lat_max),
                "p50": _us(_pct(lats, 50)),
                "p99": _us(_pct(lats, 99)),
                "p99.9": _us(_pct(lats, 99.9)),
            },
            "exec_us": {
                "min": _us(self.exec_min if self.jobs else 0),
                "avg": _us(self.exec_sum / self.jobs if self.jobs else 0),
                "max": _us(self.exec_max),
            },
            "jitter_us": {"max_abs": _us(max((abs(j) for j in jitter), default=0)), "stdev": _us(_stdev(jitter))},
            "period_histogram": self.period_histogram(),
            "utility": {
                "k": self.k,
                "m": self.m,
                "U": round(self.utility, 4),
                "windows_below_m_over_k": self.mk_violations,
            },
        }

    def period_histogram(self, bins: int = 20) -> dict[str, Any]:
        """Start-to-start intervals in `bins` equal bins around the nominal period (µs edges)."""
        ps = self.periods
        if not ps:
            return {"edges_us": [], "counts": []}
        lo, hi = min(ps), max(ps)
        if hi == lo:
            return {"edges_us": [_us(lo), _us(hi)], "counts": [len(ps)]}
        width = (hi - lo) / bins
        counts = [0] * bins
        for p in ps:
            counts[min(int((p - lo) / width), bins - 1)] += 1
        return {"edges_us": [_us(lo + i * width) for i in range(bins + 1)], "counts": counts}

    def latency_histogram(self, bin_us: float = 10.0) -> tuple[list[float], list[int]]:
        """(bin edges in µs, counts) of the recent wake-up latencies."""
        if not self.latencies:
            return [], []
        step = bin_us * 1e3
        top = max(self.latencies)
        n = int(top // step) + 1
        counts = [0] * n
        for v in self.latencies:
            counts[int(max(v, 0) // step)] += 1
        return [i * bin_us for i in range(n + 1)], counts


def _nice_bin(raw_us: float) -> float:
    """The smallest of 1, 2, 5, 10, 20, 50, … µs that is at least raw_us."""
    step = 1.0
    while True:
        for m in (1, 2, 5):
            if m * step >= raw_us:
                return m * step
        step *= 10


def _us(v: float) -> float:
    return round(v / 1e3, 3)


def _pct(sorted_vals: list[int], p: float) -> int:
    if not sorted_vals:
        return 0
    i = min(len(sorted_vals) - 1, max(0, math.ceil(p / 100 * len(sorted_vals)) - 1))
    return sorted_vals[i]


def _stdev(vals: list[int]) -> float:
    if len(vals) < 2:
        return 0.0
    mean = sum(vals) / len(vals)
    return math.sqrt(sum((v - mean) ** 2 for v in vals) / (len(vals) - 1))


def plot_latency(stats: list[TaskStats], path: str) -> None:
    """A PNG of each task's wake-up latency histogram (log scale), as cyclictest users draw it."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise RuntimeError("--stats-plot needs matplotlib: pip install 'st-plc[plot]'") from None
    fig, ax = plt.subplots(figsize=(8, 4.5))
    top_us = max((max(s.latencies) for s in stats if s.latencies), default=0) / 1e3
    bin_us = _nice_bin(top_us / 100)
    for s in stats:
        edges, counts = s.latency_histogram(bin_us)
        if counts:
            ax.stairs(counts, edges, label=f"{s.name} ({s.period / 1e6:g} ms): max {max(s.latencies) / 1e3:.0f} µs")
    ax.set_yscale("log")
    ax.set_xlabel(f"wake-up latency (µs, {bin_us:g} µs bins)")
    ax.set_ylabel("jobs")
    ax.set_title("st run: wake-up latency per task")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
