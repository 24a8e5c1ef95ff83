"""Modbus TCP slave: requests/s with 1 and 10 clients, and the scan's wake-up latency with and without them.

`st run` of an example program (its task at --cycle, default 1 ms, SCHED_FIFO when root) with
`--modbus`, for N seconds per phase: no client, 1 client, 10 clients. Each client is its own
process with a raw socket doing FC3 reads of 100 holding registers, back to back (the most the
server answers) and, in the last phase, 10 clients at a steady total rate (--paced, 3,000/s: far
busier than the thesis's VTScada polling every 0.1 s). Prints requests/s and the task's latency
statistics per phase, and the ratio of p99.9 under load to p99.9 without.

    python bench/bench_modbus.py [--seconds 15] [--cycle 1ms] [--clients 1,10]

Goal: at least 2,000 requests/s with 10 clients while p99.9 stays within 1.2× of the idle figure.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import re
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def client(port: int, stop_at: float, counter, rate: float = 0.0) -> None:
    """Back-to-back FC3 reads of 100 registers, or `rate` per second on an absolute schedule."""
    s = socket.create_connection(("127.0.0.1", port))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    n, tid = 0, 0
    want = 9 + 200
    t_next = time.monotonic()
    while time.monotonic() < stop_at:
        if rate:
            t_next += 1.0 / rate
            delay = t_next - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        tid = (tid + 1) & 0xFFFF
        s.sendall(struct.pack(">HHHBBHH", tid, 0, 6, 1, 3, 0, 100))
        got = 0
        while got < want:
            chunk = s.recv(want - got)
            if not chunk:
                raise ConnectionError("closed by the server")
            got += len(chunk)
        n += 1
    with counter.get_lock():
        counter.value += n
    s.close()


def phase(program: Path, cycle: str, seconds: int, clients: int, port: int, rate: float = 0.0) -> dict:
    with tempfile.TemporaryDirectory() as d:
        src = re.sub(r"INTERVAL\s*:=\s*T#\w+", f"INTERVAL := T#{cycle}", program.read_text())
        prog = Path(d) / program.name
        prog.write_text(src)
        stats = Path(d) / "stats.json"
        run = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "st.cli",
                "run",
                str(prog),
                "--duration",
                f"{seconds + 3}s",
                "--no-retain",
                "--rt-priority",
                "80",
                "--modbus",
                f"127.0.0.1:{port}",
                "--modbus-rate",
                "0",
                "--stats-json",
                str(stats),
                "-q",
            ],
            cwd=ROOT,
        )
        deadline = time.monotonic() + 20
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if time.monotonic() > deadline or run.poll() is not None:
                    raise RuntimeError("st run did not start its Modbus slave") from None
                time.sleep(0.1)
        time.sleep(1.0)
        counter = mp.Value("q", 0)
        t0 = time.monotonic()
        procs = [
            mp.Process(target=client, args=(port, t0 + seconds, counter, rate / clients if rate else 0.0))
            for _ in range(clients)
        ]
        for p in procs:
            p.start()
        for p in procs:
            p.join()
        elapsed = time.monotonic() - t0
        run.wait()
        task = json.loads(stats.read_text())["tasks"][0]
    return {
        "clients": clients,
        "rate": rate,
        "requests_per_s": counter.value / elapsed if clients else 0.0,
        "latency_us": task["latency_us"],
        "jobs": task["jobs"],
        "overruns": task["overruns"] + task["skipped"],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=int, default=15)
    ap.add_argument("--cycle", default="1ms")
    ap.add_argument("--clients", default="1,10")
    ap.add_argument("--program", default=str(ROOT / "programs" / "conveyor_sorter.st"))
    ap.add_argument("--port", type=int, default=15020)
    ap.add_argument(
        "--paced",
        type=float,
        default=3000.0,
        help="total requests/s of the last phase: 10 clients at an HMI-like steady rate",
    )
    a = ap.parse_args()
    phases = [(0, 0.0)] + [(int(c), 0.0) for c in a.clients.split(",")] + [(10, a.paced)]
    print(
        f"Modbus slave under load: {Path(a.program).name} at {a.cycle}, {a.seconds} s per phase, "
        f"{os.cpu_count()} CPUs, {'SCHED_FIFO 80' if os.geteuid() == 0 else 'not root: SCHED_OTHER'}"
    )
    print(
        f"{'clients':>7} {'offered':>8} {'req/s':>9} {'lat min':>8} {'avg':>7} {'p99':>7} {'p99.9':>8} {'max':>8} "
        f"{'jobs':>6} {'overruns':>8} {'p99.9 ratio':>11}"
    )
    base = None
    for n, rate in phases:
        r = phase(Path(a.program), a.cycle, a.seconds, n, a.port, rate)
        lat = r["latency_us"]
        base = lat["p99.9"] if base is None else base
        ratio = lat["p99.9"] / base if base else float("nan")
        offered = f"{rate:.0f}/s" if rate else ("max" if n else "-")
        print(
            f"{n:>7} {offered:>8} {r['requests_per_s']:>9.0f} {lat['min']:>8.1f} {lat['avg']:>7.1f} "
            f"{lat['p99']:>7.1f} {lat['p99.9']:>8.1f} {lat['max']:>8.1f} {r['jobs']:>6} {r['overruns']:>8} "
            f"{ratio:>11.2f}"
        )
    print("goal: >= 2000 req/s with 10 clients, p99.9 ratio <= 1.2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
