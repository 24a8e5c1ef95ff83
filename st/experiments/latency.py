"""Thesis 6.1/6.2, Tables 6.2, 6.3 and 6.4: wake-up latency and CPU usage of the scan with 1, 2, 3
and 10 PLCopen axes on a 1 ms task, in real time on this machine, beside cyclictest.

For N axes an ST program with N × (AXIS_REF (AxisNo := i), MC_Power, MC_MoveVelocity at 1 rev/s)
runs under `st run --duration S --stats-json F` (SCHED_FIFO when root), by default with an
emulated EtherCAT segment (`--ethercat`, sim backend) of N CiA 402 drives bound to axes 1..N.
Just before each run, cyclictest (rt-tests) measures the machine's own timer wake-up latency for
as long, at the same interval and priority. Both are real time: the numbers change from run to run
and machine to machine; only the comparison with cyclictest next to it is meaningful.

The helpers (`run_cyclictest`, `run_st`, `start_load`) are shared with bench/bench_latency.py.
"""

from __future__ import annotations

import json
import math
import os
import platform
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from statistics import mean, pstdev
from typing import Any

from .report import Report

PKG_PARENT = Path(__file__).resolve().parents[2]  # the directory holding the `st` package
PRIORITY = 80  # SCHED_FIFO priority of both tools (as bench_latency.py)

# (average, std) over the thesis's runs; Xenomai, 1 µs timer resolution. 6.2/6.3: real drives, 6.4: simulation.
THESIS_HW = {
    1: {"table": "6.2", "min": (1.2802, 0.0079), "max": (533.034, 596.82), "cpu": (23.47, 0.12)},
    2: {"table": "6.3", "min": (1.6401, 0.0120), "max": (713.859, 137.50), "cpu": (29.6, 0.4)},
}
THESIS_SIM = {
    1: {"min": (1.2583, 0.0095), "max": (567.92, 130.55)},
    2: {"min": (1.8374, 0.0098), "max": (611.21, 95.34)},
    3: {"min": (1.742, 0.0147), "max": (674.12, 154.28)},
    10: {"min": (1.877, 0.0230), "max": (709.78, 120.51)},
}


# ---------------------------------------------------------------- the program and segment for N axes
def axes_program(n: int, cycle: str = "1ms") -> str:
    """An ST program that powers N axes and turns each at 360 units/s (1 rev/s of a drive)."""
    decl = "\n".join(
        f"    ax{i} : AXIS_REF := (AxisNo := {i});\n    power{i} : MC_Power;\n    move{i} : MC_MoveVelocity;"
        for i in range(1, n + 1)
    )
    body = "\n".join(
        f"  power{i}(Axis := ax{i}, Enable := TRUE);\n"
        f"  move{i}(Axis := ax{i}, Execute := power{i}.Status, Velocity := 360.0, Acceleration := 360.0,"
        f" Deceleration := 360.0);"
        for i in range(1, n + 1)
    )
    return f"""(* {n} PLCopen axes on a {cycle} task: the scan of thesis Tables 6.2-6.4 *)
PROGRAM Axes
  VAR
{decl}
  END_VAR
{body}
END_PROGRAM

CONFIGURATION Cell
  RESOURCE Cpu ON PLC
    TASK Motion (INTERVAL := T#{cycle}, PRIORITY := 1);
    PROGRAM axes WITH Motion : Axes;
  END_RESOURCE
END_CONFIGURATION
"""


def segment_toml(n: int, cycle: str = "1ms") -> str:
    """An emulated EtherCAT segment of N CiA 402 drives (MINAS A6 model) bound to axes 1..N."""
    out = [f"# {n} CiA 402 drives for the latency experiment", "[segment]", f'cycle = "{cycle}"', "dc = true"]
    for i in range(1, n + 1):
        out += ["", "[[slave]]", f'name = "d{i}"', 'type = "cia402"', f"axis = {i}", "encoder_bits = 23"]
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------- cyclictest
def percentile_from_histogram(hist: dict, total: int, q: float, overflow_max: float) -> float:
    """The q-quantile (µs) of a cyclictest histogram {µs: count}; overflows sit at the max."""
    need = q * total
    seen = 0
    for us in sorted(hist):
        seen += hist[us]
        if seen >= need:
            return float(us)
    return float(overflow_max)


def run_cyclictest(interval_us: int, seconds: int, prio: int) -> dict:
    """cyclictest (mlockall, one thread) for `seconds`: min/avg/p99/p99.9/max µs, samples, overruns.
    Raises FileNotFoundError or subprocess.CalledProcessError when it cannot run."""
    limit = 20000
    cmd = [
        "cyclictest",
        "-m",
        "-p",
        str(prio),
        "-i",
        str(interval_us),
        "-D",
        str(int(seconds)),
        "-q",
        "-h",
        str(limit),
        "--policy=fifo" if prio else "--policy=other",
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    hist, total = {}, 0
    fields = {}
    for line in out.splitlines():
        m = re.match(r"^(\d+)\s+(\d+)\s*$", line)
        if m:
            us, n = int(m.group(1)), int(m.group(2))
            if n:
                hist[us] = n
                total += n
            continue
        m = re.match(r"^# (Min|Avg|Max) Latencies:\s+(\d+)", line)
        if m:
            fields[m.group(1).lower()] = float(m.group(2))
        m = re.match(r"^# Histogram Overflows:\s+(\d+)", line)
        if m:
            total += int(m.group(1))
    mx = fields.get("max", 0.0)
    return {
        "min": fields.get("min", 0.0),
        "avg": fields.get("avg", 0.0),
        "p99": percentile_from_histogram(hist, total, 0.99, mx),
        "p99.9": percentile_from_histogram(hist, total, 0.999, mx),
        "max": mx,
        "samples": total,
        # a wake-up later than the next period skips the missed periods: one sample per stall
        "overruns": max(0, int(seconds) * 1_000_000 // interval_us - total),
    }


# ---------------------------------------------------------------- st run
def _proc_cpu(pid: int):
    """CPU seconds (user + system, all threads) a live process has used so far, or None."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def run_st(program: Path, seconds: float, prio: int, cycle: str | None = None, ethercat: Path | None = None) -> dict:
    """`st run PROGRAM --duration S --stats-json F` in a child process (cycle: rewrite every task's
    INTERVAL). Returns the first task's wake-up latency (µs), jobs, overruns, execution time and CPU
    use: `cpu` is the share of one core used while scanning (from the moment the run reports its
    real-time setup, after compiling and start-up, to its exit); `cpu_total` also counts start-up,
    over the scan's duration (what bench_latency.py used to print). `rt` is what the OS granted."""
    program = Path(program)
    src = program.read_text()
    if cycle:
        src = re.sub(r"INTERVAL\s*:=\s*T#\w+", f"INTERVAL := T#{cycle}", src)
    env = dict(os.environ)
    env["PYTHONPATH"] = str(PKG_PARENT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    with tempfile.TemporaryDirectory() as d:
        prog = Path(d) / program.name
        prog.write_text(src)
        stats = Path(d) / "stats.json"
        cmd = [
            sys.executable,
            "-m",
            "st.cli",
            "run",
            str(prog),
            "--duration",
            f"{seconds:g}s",
            "--no-retain",
            "--rt-priority",
            str(prio or 30),
            "--stats-json",
            str(stats),
        ]
        if ethercat:
            cmd += ["--ethercat", str(Path(ethercat).resolve())]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=d, env=env)
        err: list[str] = []
        rt, cpu0, t0 = "", None, None
        assert proc.stderr is not None  # stderr=PIPE
        for line in proc.stderr:  # the line printed just before the first scan
            err.append(line)
            if line.startswith("real time:"):
                t0, cpu0, rt = time.monotonic(), _proc_cpu(proc.pid), line.split(":", 1)[1].strip()
                break
        err.append(proc.stderr.read())
        proc.wait()
        t1 = time.monotonic()
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if proc.returncode != 0 or not stats.exists():
            raise RuntimeError(f"st run exited with {proc.returncode}: {''.join(err).strip()[-600:]}")
        data = json.loads(stats.read_text())
    total = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    cpu = (total - cpu0) / (t1 - t0) if cpu0 is not None and t0 is not None and t1 > t0 else total / seconds
    t = data["tasks"][0]
    lat = t["latency_us"]
    ecat = data.get("io", {}).get("ethercat", {})
    return {
        "min": lat["min"],
        "avg": lat["avg"],
        "p99": lat["p99"],
        "p99.9": lat["p99.9"],
        "max": lat["max"],
        "samples": t["jobs"],
        "overruns": t["overruns"] + t["skipped"],
        "exec_avg": t["exec_us"]["avg"],
        "exec_max": t["exec_us"]["max"],
        "cpu": cpu,
        "cpu_total": total / seconds,
        "rt": rt,
        "fifo": rt.startswith("SCHED_FIFO priority"),
        "lost_frames": ecat.get("lost_frames", 0),
        "frames": ecat.get("frames", 0),
    }


def start_load() -> subprocess.Popen:
    """stress-ng on every CPU (arithmetic, memory, file system) at normal priority."""
    return subprocess.Popen(
        [
            "stress-ng",
            "--cpu",
            str(os.cpu_count() or 2),
            "--vm",
            "1",
            "--vm-bytes",
            "256M",
            "--hdd",
            "1",
            "--hdd-bytes",
            "64M",
            "--timeout",
            "3600s",
            "-q",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


# ---------------------------------------------------------------- the experiment
def _ms(vals: list, digits: int = 1) -> str:
    """'mean ± std' of a list (just the value when there is one)."""
    if not vals:
        return "–"
    if len(vals) == 1:
        return f"{vals[0]:.{digits}f}"
    return f"{mean(vals):.{digits}f} ± {pstdev(vals):.{digits}f}"


def _num(v: float, digits: int = 3) -> str:
    """A plain CSV number (Report.csv would format floats for reading, with thousands separators)."""
    return f"{v:.{digits}f}".rstrip("0").rstrip(".") or "0"


def _thesis(pair) -> str:
    return f"{pair[0]:g} ± {pair[1]:g}" if pair else "–"


def run(
    out_dir,
    quick: bool = False,
    seed: int = 1,
    axes=None,
    seconds: float | None = None,
    repeats: int | None = None,
    cyclictest: bool | None = None,
    ethercat: bool = True,
) -> Report:
    """Tables 6.2–6.4 on this machine. Full: N = 1, 2, 3, 10 axes, 3 runs of 10 s each (about 4 min
    with cyclictest); quick: N = 1, 2, one run of 2 s. cyclictest runs when it is installed unless
    `cyclictest=False`. `seed` is unused (real time cannot be seeded); it is accepted so that every
    experiment has the same signature."""
    axes = tuple(axes or ((1, 2) if quick else (1, 2, 3, 10)))
    seconds = seconds or (2 if quick else 10)
    repeats = repeats or (1 if quick else 3)
    root = hasattr(os, "geteuid") and os.geteuid() == 0
    prio = PRIORITY if root else 0
    have_ct = shutil.which("cyclictest") is not None
    use_ct = have_ct if cyclictest is None else (cyclictest and have_ct)
    rep = Report("latency", out_dir, "Wake-up latency and CPU usage with 1–10 axes (thesis 6.1/6.2, Tables 6.2–6.4)")
    d = Path(out_dir)

    results: dict[int, dict[str, Any]] = {}  # n → {"st": [dict], "ct": [dict], "ct_error": str}
    for n in axes:
        prog = d / f"axes_{n}.st"
        prog.write_text(axes_program(n))
        seg = None
        if ethercat:
            seg = d / f"axes_{n}.segment.toml"
            seg.write_text(segment_toml(n))
        r = results[n] = {"st": [], "ct": [], "ct_error": ""}
        for _ in range(repeats):
            if use_ct and not r["ct_error"]:
                try:
                    r["ct"].append(run_cyclictest(1000, max(1, int(math.ceil(seconds))), prio))
                except (OSError, subprocess.CalledProcessError) as e:
                    msg = (getattr(e, "stderr", None) or str(e)).strip()
                    r["ct_error"] = msg.splitlines()[-1] if msg else type(e).__name__
            r["st"].append(run_st(prog, seconds, prio, ethercat=seg))

    st_runs = [x for r in results.values() for x in r["st"]]
    granted = st_runs[0]["rt"] if st_runs else ""
    fifo = all(x["fifo"] for x in st_runs)
    ct_note = (
        "cyclictest (rt-tests) for the same duration just before each `st run`, at the same interval and "
        f"{'SCHED_FIFO ' + str(prio) if prio else 'SCHED_OTHER'}"
        if use_ct
        else (
            "cyclictest was not run (not installed: `apt-get install rt-tests`)"
            if not have_ct
            else "cyclictest was not run (switched off)"
        )
    )
    errors = {n: r["ct_error"] for n, r in results.items() if r["ct_error"]}
    if fifo:
        sched = f"`st run` got SCHED_FIFO {prio or 30}{'' if root else ' (without being root)'}."
    elif root:
        sched = "**SCHED_FIFO was refused** to `st run` although we are root, so it ran as a SCHED_OTHER process."
    else:
        sched = (
            "**Not root**: SCHED_FIFO (and mlockall, cpu_dma_latency) are refused, so both tools ran as "
            "ordinary SCHED_OTHER processes and the latencies include normal time-sharing."
        )
    rep.text(f"""
**Real time, not reproducible:** every number below is a measurement of this machine at the time of
the run; a rerun gives different values (the maximum most of all). Compare `st run` with cyclictest
measured just before it on the same machine, not with another run.

Setup: for N axes an ST program with N × (`AXIS_REF (AxisNo := i)`, `MC_Power`, `MC_MoveVelocity` at
1 rev/s) on a **1 ms** task ([axes_N.st](axes_1.st)), run by `st run --duration {seconds:g}s --stats-json`
{"with an emulated EtherCAT segment of N CiA 402 drives (`--ethercat axes_N.segment.toml`, sim backend: the drives and their motor models are simulated in the same process)" if ethercat else "with virtual axes (no EtherCAT segment)"};
{repeats} run(s) per N. Machine: {platform.system()} {platform.release()} ({platform.machine()}, {os.cpu_count()} CPUs),
Python {platform.python_version()}. {sched}
(`st run` reported: real time: {granted or "nothing"}). {ct_note}.
{"cyclictest failed: " + "; ".join(f"N={n}: {e}" for n, e in errors.items()) + "." if errors else ""}

Wake-up latency = actual start − release of each job of the 1 ms task (the thesis's J_i; cyclictest's
latency). CPU = share of one core the `st run` process used while scanning (start-up and compilation
excluded).
""")
    headers = [
        "axes",
        "runs × s",
        "min µs",
        "avg µs",
        "p99 µs",
        "p99.9 µs",
        "max µs",
        "overruns",
        "exec avg µs",
        "CPU % of a core",
        "cyclictest min / avg / max µs",
    ]
    rows = []
    for n, r in results.items():
        s, c = r["st"], r["ct"]
        rows.append(
            [
                n,
                f"{len(s)} × {seconds:g}",
                _ms([x["min"] for x in s], 2),
                _ms([x["avg"] for x in s], 2),
                _ms([x["p99"] for x in s]),
                _ms([x["p99.9"] for x in s]),
                _ms([x["max"] for x in s]),
                sum(x["overruns"] for x in s),
                _ms([x["exec_avg"] for x in s], 0),
                _ms([100 * x["cpu"] for x in s]),
                " / ".join(_ms([x[k] for x in c], 0) for k in ("min", "avg", "max")) if c else "not run",
            ]
        )
    rep.table("st run at 1 ms with N axes (mean ± std over the runs)", headers, rows)
    rows = []
    for n, r in results.items():
        s = r["st"]
        hw, sim = THESIS_HW.get(n), THESIS_SIM.get(n)
        rows.append(
            [
                n,
                _ms([x["min"] for x in s], 3),
                _thesis(hw and hw["min"]),
                _thesis(sim and sim["min"]),
                _ms([x["max"] for x in s]),
                _thesis(hw and hw["max"]),
                _thesis(sim and sim["max"]),
                _ms([100 * x["cpu"] for x in s]),
                _thesis(hw and hw["cpu"]),
                _ms([x["max"] for x in r["ct"]], 0) if r["ct"] else "–",
            ]
        )
    rep.table(
        "Beside the thesis (Tables 6.2 and 6.3: real drives; Table 6.4: simulated axes)",
        [
            "axes",
            "min µs (st)",
            "min µs (6.2/6.3)",
            "min µs (6.4)",
            "max µs (st)",
            "max µs (6.2/6.3)",
            "max µs (6.4)",
            "CPU % (st)",
            "CPU % (6.2/6.3)",
            "max µs (cyclictest)",
        ],
        rows,
        note="The thesis reports average ± std over its runs (their number and length are not given).",
    )
    st_min = min((x["min"] for x in st_runs), default=0)
    rep.text(f"""
### Why the numbers differ from the thesis's

- Platform: the thesis ran OpenPLC (C) on Xenomai with a 1 µs timer on an industrial PC with real
  drives (6.1/6.2) or load tasks standing for axes (6.4). Here a Python soft PLC runs on
  {platform.release()} (a general-purpose kernel{", in a container or VM" if _virtualised() else ""}), so
  the maximum is set by what the kernel and the host do, not by the program.
- Minimum: `st run` sleeps until 200 µs before a release and spins for the rest, so its wake-up is a
  spin loop's exit (lowest here {st_min:.2f} µs), the same order as the thesis's 1.3–1.9 µs, while
  cyclictest, which only sleeps, shows the kernel's timer wake-up ({"min " + _ms([x["min"] for r in results.values() for x in r["ct"]], 0) + " µs" if any(r["ct"] for r in results.values()) else "not measured"}).
- CPU: the spin costs a share of a core whatever the program does (up to 200 µs of every 1 ms, about
  20 %); on top, the
  emulated segment simulates every drive's slave controller and motor physics in the same process, so
  CPU and execution time grow with N far more than a real segment would cost the master. The thesis's
  23–30 % is of a different machine and possibly of all cores.
- Maximum: a maximum over a few seconds is one rare event; it depends on the run length, on the
  machine's other load and on luck (the thesis's own std of the 1-axis maximum is 597 µs). cyclictest,
  measured in the seconds before, shows how large the machine's own stalls are: compare the `max µs (st)`
  and `max µs (cyclictest)` columns, whose std is as large as their mean.
""")
    late = {n: sum(x["overruns"] for x in r["st"]) for n, r in results.items()}
    if any(late.values()):
        rep.text(f"""
- Overruns ({", ".join(f"N={n}: {v}" for n, v in late.items() if v)}): the emulated segment makes the job
  take a large part of the 1 ms period (exec avg in the first table), so after a stall some jobs end
  after their next release; the thesis's Table 6.4 has no such cost.
""")
    rows = []
    for n, r in results.items():
        for i, x in enumerate(r["st"]):
            rows.append(
                [n, i, "st run"]
                + [_num(x[k]) for k in ("min", "avg", "p99", "p99.9", "max")]
                + [x["samples"], x["overruns"], _num(x["exec_avg"], 2), _num(100 * x["cpu"], 2), x["rt"]]
            )
        for i, x in enumerate(r["ct"]):
            rows.append(
                [n, i, "cyclictest"]
                + [_num(x[k]) for k in ("min", "avg", "p99", "p99.9", "max")]
                + [x["samples"], x["overruns"], "", "", f"{'SCHED_FIFO ' + str(prio) if prio else 'SCHED_OTHER'}"]
            )
    rep.csv(
        "latency.csv",
        [
            "axes",
            "run",
            "tool",
            "min_us",
            "avg_us",
            "p99_us",
            "p99.9_us",
            "max_us",
            "samples",
            "overruns",
            "exec_avg_us",
            "cpu_percent",
            "scheduling",
        ],
        rows,
    )
    _plot(rep, results)
    rep.write()
    return rep


def _virtualised() -> bool:
    if os.path.exists("/.dockerenv") or os.path.exists("/run/.containerenv"):
        return True
    try:
        return "hypervisor" in Path("/proc/cpuinfo").read_text()
    except OSError:
        return False


def _plot(rep: Report, results: dict) -> None:
    fig, axs = rep.figure(1, 2, (13, 4.8))
    if fig is None:
        return
    ns = list(results)
    ax = axs[0][0]
    styles = {"min": "tab:green", "avg": "tab:blue", "p99": "tab:purple", "max": "tab:red"}
    for k, colour in styles.items():
        ax.plot(ns, [mean(x[k] for x in results[n]["st"]) for n in ns], "o-", color=colour, label=f"st {k}")
        if all(results[n]["ct"] for n in ns) and k != "p99":
            ax.plot(
                ns,
                [mean(x[k] for x in results[n]["ct"]) for n in ns],
                "s--",
                color=colour,
                alpha=0.6,
                mfc="none",
                label=f"cyclictest {k}",
            )
    sim = [n for n in ns if n in THESIS_SIM]
    for k in ("min", "max"):
        ax.errorbar(
            sim,
            [THESIS_SIM[n][k][0] for n in sim],
            [THESIS_SIM[n][k][1] for n in sim],
            fmt="k^",
            ms=6,
            capsize=3,
            label="thesis 6.4" if k == "min" else None,
        )
        hw = [n for n in ns if n in THESIS_HW]
        ax.scatter(
            hw,
            [THESIS_HW[n][k][0] for n in hw],
            marker="D",
            facecolors="none",
            edgecolors="black",
            label="thesis 6.2/6.3" if k == "min" else None,
            zorder=3,
        )
    ax.set_yscale("log")
    ax.set_xticks(ns)
    ax.set_xlabel("axes")
    ax.set_ylabel("wake-up latency (µs, log)")
    ax.set_title("Wake-up latency of the 1 ms task")
    ax.legend(fontsize=7, ncol=2)
    ax = axs[0][1]
    x = range(len(ns))
    cpu = [[100 * v["cpu"] for v in results[n]["st"]] for n in ns]
    ax.bar(
        x,
        [mean(c) for c in cpu],
        0.5,
        yerr=[pstdev(c) if len(c) > 1 else 0 for c in cpu],
        color="tab:blue",
        label="st run (one core)",
    )
    hw = [(i, n) for i, n in enumerate(ns) if n in THESIS_HW]
    ax.errorbar(
        [i for i, n in hw],
        [THESIS_HW[n]["cpu"][0] for i, n in hw],
        [THESIS_HW[n]["cpu"][1] for i, n in hw],
        fmt="kD",
        mfc="none",
        capsize=3,
        label="thesis 6.2/6.3",
    )
    ax.set_xticks(list(x), [str(n) for n in ns])
    ax.set_xlabel("axes")
    ax.set_ylabel("CPU %")
    ax.set_title("CPU usage while scanning")
    ax.legend(fontsize=8)
    rep.save_figure(fig, "latency.png")
