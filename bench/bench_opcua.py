"""The OPC UA server's cost to the scan, and what it serves (issue 37): `st run --opcua` under 11 clients.

Generates a program publishing over 1,000 scalar variables that change every scan (`main.c0` …
counters, VAR_OUTPUTs of one PROGRAM, read-only by the map file) and 50 writable inputs
(`main.w0` …, readwrite by the map file), a 1 ms task, and runs it with `st run` in real time
three ways, each for N seconds of measurement (plus the clients' connecting):

- `plain`:   without --opcua;
- `opcua`:   with --opcua (security none,sign,encrypt; anonymous readers and one operate user), no client;
- `clients`: with --opcua and 11 clients, each its own process (asyncua): 10 readers, each with one
  subscription at a 100 ms publishing interval monitoring 100 different counters (1,000 in all),
  counting data change notifications; one writer signed in as a user of role operate, writing the
  writable inputs at a steady rate (--write-rate, 20/s), counting Good results and timing each
  write's round trip (the PLC applies it at a scan boundary, the server answers with its status).

All clients connect with security None (the writer's password goes encrypted with the server's
certificate, as the endpoint's user token policy asks). The client processes are started (asyncua
imported) before `st run`; they connect --lead seconds before the measurement window, and `st run`
is stopped (SIGINT) at its end, so the task's figures cover lead + window in every phase.

Prints a markdown table, per phase: the task's wake-up latency (p99, p99.9, max, µs), execution
time and overruns from `--stats-json`; the notifications/s; the writes/s, Good results and their
round trip (median, p99, max, ms); the RSS of the PLC process and of the server process (`python
-m st.opcua`, the PLC's child; VmRSS at the window's end, VmHWM the peak); the CPU used in the
window by the PLC, the server and the clients (% of one CPU); then the ratio p99.9(clients) /
p99.9(plain) against issue 37's goal ≤ 1.2, and the overruns inside the window alone (the task's
Jobs and Overruns nodes, read by the writer at the window's start and end).

    python bench/bench_opcua.py                   # 15 s window per phase (~1.5 min)
    python bench/bench_opcua.py --seconds 8 --rounds 3 --port 14841 --json out.json --keep-stderr logs/

The Python tier by default (--python: no C build in the background during a phase); --native
waits for the C build first (minutes on a first run, cached after).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
USER, PASSWORD = "bench", "bench-operate-pw"
READERS, PER_READER, PUBLISH_MS = 10, 100, 100.0


# ---------------------------------------------------------------------------- the program
def write_program(d: Path, counters: int, writables: int, cycle: str) -> tuple[Path, Path]:
    """main: `counters` DINT outputs counting up every scan, `writables` DINT inputs summed into total."""
    lines = ["PROGRAM main", "  VAR_INPUT"]
    lines += [f"    w{i} : DINT;" for i in range(writables)]
    lines += ["  END_VAR", "  VAR_OUTPUT"]
    lines += [f"    c{i} : DINT;" for i in range(counters)]
    lines += ["    total : DINT;", "  END_VAR"]
    lines += [f"  c{i} := c{i} + 1;" for i in range(counters)]
    lines += ["  total := " + " + ".join(f"w{i}" for i in range(writables)) + ";", "END_PROGRAM", ""]
    lines += [
        "CONFIGURATION cfg",
        "  RESOURCE res ON PLC",
        f"    TASK fast (INTERVAL := T#{cycle}, PRIORITY := 1);",
        "    PROGRAM main WITH fast : main;",
        "  END_RESOURCE",
        "END_CONFIGURATION",
    ]
    prog = d / "opcua_bench.st"
    prog.write_text("\n".join(lines) + "\n")
    mapping = d / "opcua_bench.map.toml"
    mapping.write_text('[symbols]\n"main.*" = "read"\n"main.w*" = "readwrite"\n')
    return prog, mapping


def make_users(d: Path) -> Path:
    users = d / "users.txt"
    subprocess.run(
        [sys.executable, "-m", "st.cli", "opcua", "user", str(users), USER, "--role", "operate", "--password-stdin"],
        input=PASSWORD + "\n",
        text=True,
        cwd=ROOT,
        check=True,
        capture_output=True,
    )
    return users


# ---------------------------------------------------------------------------- the clients
def _client(key: int, go, out, user: bool, body) -> None:
    """A client process: say ready (asyncua imported), wait for (url, t0, t1, watchdog), connect,
    run `body(client, ua, t0, t1)`, put its result (before disconnecting: the PLC is stopped at t1)
    with the connection losses asyncua's watchdog saw (its probe of the server's state unanswered
    within `watchdog` s)."""
    import asyncio
    import logging

    from asyncua import Client, ua

    logging.getLogger("asyncua").setLevel(logging.CRITICAL)
    out.put((key, "ready", None))
    job = go.get()
    if job is None:
        return
    url, t0, t1, watchdog = job
    sent = False
    lost: list[str] = []

    async def on_lost(exc: Exception) -> None:
        lost.append(f"{time.monotonic() - t0:+.1f} s: {type(exc).__name__}: {exc}"[:200])

    async def main() -> None:
        nonlocal sent
        client = Client(url, timeout=30, watchdog_intervall=watchdog)
        client.connection_lost_callback = on_lost
        if user:
            client.set_user(USER)
            client.set_password(PASSWORD)
        await client.connect()
        try:
            result = await body(client, ua, t0, t1)
            result["lost"] = lost
            out.put((key, "done", result))
            sent = True
        finally:
            try:
                await asyncio.wait_for(client.disconnect(), 3)
            except Exception:  # noqa: BLE001, S110 - the server may be gone already
                pass

    try:
        asyncio.run(main())
    except Exception as e:  # noqa: BLE001 - reported in the table's notes
        if not sent:
            out.put((key, "error", f"{type(e).__name__}: {e}" + (f" (connection lost at {lost[0]})" if lost else "")))


def reader(key: int, first: int, counters: int, go, out) -> None:
    """One subscription (100 ms) over 100 counters; the notifications counted in [t0, t1]."""
    import asyncio

    class Count:
        n = 0

        def datachange_notification(self, node, val, data) -> None:
            self.n += 1

        def status_change_notification(self, status) -> None:
            pass

    async def body(client, ua, t0: float, t1: float) -> dict:
        handler = Count()
        sub = await client.create_subscription(PUBLISH_MS, handler)
        nodes = [client.get_node(f"ns=2;s=main.c{(first + i) % counters}") for i in range(PER_READER)]
        handles = await sub.subscribe_data_change(nodes)
        bad = sum(1 for h in handles if not isinstance(h, int))
        ready = time.monotonic()
        await asyncio.sleep(max(0.0, t0 - time.monotonic()))
        n0, c0 = handler.n, time.process_time()
        await asyncio.sleep(max(0.0, t1 - time.monotonic()))
        n1, c1 = handler.n, time.process_time()
        return {"notifications": n1 - n0, "ready": ready - t0, "bad_items": bad, "cpu": c1 - c0}

    _client(key, go, out, False, body)


def writer(key: int, writables: int, rate: float, task: str, go, out) -> None:
    """`rate` writes/s of an Int32 to main.w0 … on an absolute schedule in [t0, t1], each awaited
    (one at a time, as an HMI does: a slow answer delays the next, the schedule catches up);
    and the task's jobs and overruns at t0 and t1 (the PLC's own nodes)."""
    import asyncio

    async def body(client, ua, t0: float, t1: float) -> dict:
        ids = [ua.NodeId.from_string(f"ns=2;s=main.w{i}") for i in range(writables)]
        figures = [client.get_node(f"ns=2;s=PLC.Tasks.{task}.{x}") for x in ("Jobs", "Overruns")]
        ready = time.monotonic()
        await asyncio.sleep(max(0.0, t0 - time.monotonic()))
        before = await client.read_values(figures)
        rtt: list[float] = []
        statuses: dict[str, int] = {}
        k, t_next, c0 = 0, t0, time.process_time()
        while True:
            t_next += 1.0 / rate
            if t_next > t1:
                break
            await asyncio.sleep(max(0.0, t_next - time.monotonic()))
            if time.monotonic() > t1:
                break  # behind schedule: the writes not sent are counted as missed
            k += 1
            wv = ua.WriteValue(
                NodeId=ids[k % writables],
                AttributeId=ua.AttributeIds.Value,
                Value=ua.DataValue(ua.Variant(k, ua.VariantType.Int32)),
            )
            t = time.perf_counter()
            try:
                (status,) = await client.uaclient.write(ua.WriteParameters(NodesToWrite=[wv]))
                name = status.name
            except Exception as e:  # noqa: BLE001 - counted as not Good
                name = type(e).__name__
            rtt.append(time.perf_counter() - t)
            statuses[name] = statuses.get(name, 0) + 1
        cpu = time.process_time() - c0
        after = await client.read_values(figures)
        return {
            "writes": len(rtt),
            "missed": int(rate * (t1 - t0)) - len(rtt),
            "statuses": statuses,
            "rtt": rtt,
            "ready": ready - t0,
            "cpu": cpu,
            "window_jobs": after[0] - before[0],
            "window_overruns": after[1] - before[1],
        }

    _client(key, go, out, True, body)


# ---------------------------------------------------------------------------- processes
def rss_kb(pid: int) -> dict[str, int]:
    """VmRSS and VmHWM (peak) of `pid`, kB."""
    out = {}
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(("VmRSS:", "VmHWM:")):
                out[line.split(":")[0]] = int(line.split()[1])
    except OSError:
        pass
    return out


def cpu_s(pid: int | None) -> float | None:
    """User + system CPU time of `pid` so far, s."""
    if not pid:
        return None
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def server_pid(plc_pid: int) -> int | None:
    """The `python -m st.opcua` child of the PLC process."""
    kids: list[int] = []
    for task in Path(f"/proc/{plc_pid}/task").glob("*"):
        try:
            kids += [int(p) for p in (task / "children").read_text().split()]
        except OSError:
            continue
    for pid in kids:
        try:
            if b"st.opcua" in Path(f"/proc/{pid}/cmdline").read_bytes():
                return pid
        except OSError:
            continue
    return None


def phase(mode: str, a, d: Path, prog: Path, mapping: Path, users: Path) -> dict:
    stats = d / f"{mode}.json"
    stats.unlink(missing_ok=True)
    port = a.port
    cmd = [sys.executable, "-m", "st", "run", str(prog), "--duration", f"{a.seconds + a.lead + 60:g}s"]
    cmd += ["--stats-json", str(stats), "--no-retain", "--rt-priority", str(a.rt_priority)]
    cmd += ["--native"] if a.native else ["--python"]
    if mode != "plain":
        cmd += ["--opcua", f"127.0.0.1:{port}", "--opcua-map", str(mapping), "--opcua-users", str(users)]
        cmd += ["--opcua-anonymous", "--opcua-security", "none,sign,encrypt", "--opcua-pki", str(d / "pki")]

    # the clients' processes start (and import asyncua) before the PLC, not during the measurement
    ctx = mp.get_context("spawn")
    out = ctx.Queue()
    procs, gos = [], []
    if mode == "clients":
        for k in range(READERS + 1):
            go = ctx.Queue()
            if k < READERS:
                p = ctx.Process(target=reader, args=(k, k * PER_READER, a.counters, go, out), daemon=True)
            else:
                p = ctx.Process(target=writer, args=(k, a.writables, a.write_rate, "fast", go, out), daemon=True)
            p.start()
            procs.append(p)
            gos.append(go)
        for _ in procs:
            out.get(timeout=120)  # (key, "ready", None)

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    plc = subprocess.Popen(cmd, cwd=d, env=env, stderr=subprocess.PIPE, text=True)
    assert plc.stderr is not None
    lines: list[str] = []
    running = threading.Event()

    def read_stderr() -> None:
        for line in plc.stderr:  # type: ignore[union-attr]
            lines.append(line.rstrip("\n"))
            if line.startswith("running in real time"):
                running.set()

    threading.Thread(target=read_stderr, daemon=True).start()
    if not running.wait(300) or plc.poll() is not None:
        plc.kill()
        raise SystemExit(f"{mode}: st run did not start:\n" + "\n".join(lines))
    endpoint = next((m.group(1) for line in lines if (m := re.match(r"opcua: (opc\.tcp://\S+)", line))), None)
    if mode != "plain" and endpoint is None:
        endpoint = f"opc.tcp://127.0.0.1:{port}/st/"
    start = time.monotonic()
    t0 = start + a.lead
    t1 = t0 + a.seconds
    for go in gos:
        go.put((endpoint, t0, t1, a.watchdog))
    results: dict[int, tuple[str, object]] = {}
    mem: dict[str, dict[str, int]] = {}
    spid = server_pid(plc.pid) if mode != "plain" else None
    # CPU over the window; the RSS in its middle and at its end
    time.sleep(max(0.0, t0 - time.monotonic()))
    cpu0 = (cpu_s(plc.pid), cpu_s(spid))
    time.sleep(max(0.0, t0 + a.seconds / 2 - time.monotonic()))
    mem["plc_mid"] = rss_kb(plc.pid)
    if spid:
        mem["server_mid"] = rss_kb(spid)
    time.sleep(max(0.0, t1 - time.monotonic()))
    cpu1 = (cpu_s(plc.pid), cpu_s(spid))
    mem["plc"] = rss_kb(plc.pid)
    if spid:
        mem["server"] = rss_kb(spid)
    cpu = {
        who: (b - a_) / a.seconds * 100 if a_ is not None and b is not None else None
        for who, a_, b in (("plc", cpu0[0], cpu1[0]), ("server", cpu0[1], cpu1[1]))
    }
    while len(results) < len(procs):  # (the clients put their results before disconnecting)
        try:
            key, kind, value = out.get(timeout=30)
        except Exception:  # noqa: BLE001 - queue.Empty: a client hung
            break
        results[key] = (kind, value)
    plc.send_signal(signal.SIGINT)
    run_s = time.monotonic() - start
    try:
        plc.wait(30)
    except subprocess.TimeoutExpired:
        plc.kill()
        plc.wait()
    for p in procs:
        p.join(10)
        if p.is_alive():
            p.kill()
    if not stats.exists():
        raise SystemExit(f"{mode}: no --stats-json from st run:\n" + "\n".join(lines[-20:]))
    task = json.loads(stats.read_text())["tasks"][0]
    if a.keep_stderr:
        Path(a.keep_stderr).mkdir(parents=True, exist_ok=True)
        (Path(a.keep_stderr) / f"{mode}.stderr.txt").write_text("\n".join(lines) + "\n")

    logged_writes = sum(1 for line in lines if re.match(r"\[[\d.]+ ms\] \w+: opcua .*: write ", line))
    notes = [
        line
        for line in lines
        if line.startswith(("[", "warning", "error", "st opcua", "Traceback")) and " write " not in line
    ][:10]
    if logged_writes:
        notes.append(f"the PLC's log printed {logged_writes} write line(s) on st run's stderr")
    notifications = 0
    client_cpu = 0.0
    ready = -a.lead
    bad_items = 0
    wr: dict = {}
    for key, (kind, value) in sorted(results.items()):
        if kind == "error":
            notes.append(f"client {key}: {value}")
            continue
        assert isinstance(value, dict)
        ready = max(ready, value["ready"])
        for what in value.get("lost", []):
            notes.append(f"client {key}: connection lost at t0{what}")
        client_cpu += value.get("cpu", 0.0)
        if key < READERS:
            notifications += value["notifications"]
            bad_items += value["bad_items"]
        else:
            wr = value
    if len(results) < len(procs):
        notes.append(f"{len(procs) - len(results)} client(s) reported nothing")
    if ready > 0:
        notes.append(f"the last client was ready {ready:.1f} s into the window (--lead is {a.lead:g} s): raise --lead")
    if bad_items:
        notes.append(f"{bad_items} monitored item(s) refused")
    rtt = sorted(wr.get("rtt", []))
    if wr.get("missed"):
        notes.append(f"the writer fell {wr['missed']} write(s) behind its schedule (slow answers)")
    return {
        "mode": mode,
        "lat": task["latency_us"],
        "exec": task["exec_us"],
        "jobs": task["jobs"],
        "overruns": task["overruns"] + task["skipped"],
        "run_s": run_s,
        "clients_ready_s": a.lead + ready if procs else None,  # after the PLC's start
        "window_jobs": wr.get("window_jobs"),
        "window_overruns": wr.get("window_overruns"),
        "notif_s": notifications / a.seconds if procs else None,
        "writes_s": wr["writes"] / a.seconds if wr else None,
        "good": wr.get("statuses", {}).get("Good", 0) if wr else None,
        "writes": wr.get("writes", 0) if wr else None,
        "statuses": wr.get("statuses", {}),
        "rtt_med": statistics.median(rtt) * 1e3 if rtt else None,
        "rtt_p99": rtt[min(len(rtt) - 1, int(0.99 * len(rtt)))] * 1e3 if rtt else None,
        "rtt_max": rtt[-1] * 1e3 if rtt else None,
        "rtt_ms": [round(x * 1e3, 2) for x in wr.get("rtt", [])],
        "cpu_plc": cpu["plc"],
        "cpu_server": cpu["server"],
        "cpu_clients": client_cpu / a.seconds * 100 if procs else None,
        "mem": mem,
        "notes": notes,
    }


# ---------------------------------------------------------------------------- report
def _f(x, fmt: str = ".1f") -> str:
    return "-" if x is None else format(x, fmt)


def _mb(kb: dict, key: str = "VmRSS") -> str:
    return f"{kb[key] / 1024:.0f}" if kb and key in kb else "-"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=15.0, help="the measurement window of each phase")
    ap.add_argument("--lead", type=float, default=6.0, help="seconds from the PLC's start to the window (connecting)")
    ap.add_argument("--rounds", type=int, default=1, help="rounds of the three phases (medians shown)")
    ap.add_argument("--cycle", default="1ms")
    ap.add_argument("--counters", type=int, default=1000, help="published counters (>= 1000 for issue 37)")
    ap.add_argument("--writables", type=int, default=50)
    ap.add_argument("--write-rate", type=float, default=20.0, help="the writer's writes per second")
    ap.add_argument("--port", type=int, default=14840)
    ap.add_argument("--rt-priority", type=int, default=80)
    ap.add_argument("--native", action="store_true", help="the C tier (--native) instead of --python")
    ap.add_argument(
        "--watchdog",
        type=float,
        default=5.0,
        help="the clients' asyncua watchdog: a connection is given up when a probe of the server's state "
        "waits longer (asyncua's default 1 s drops clients of a busy server)",
    )
    ap.add_argument("--json", help="also write the results to this file")
    ap.add_argument("--keep-stderr", metavar="DIR", help="save each st run's stderr in DIR")
    a = ap.parse_args()
    modes = ("plain", "opcua", "clients")
    runs: dict[str, list[dict]] = {m: [] for m in modes}
    with tempfile.TemporaryDirectory(prefix="bench_opcua") as t:
        d = Path(t)
        prog, mapping = write_program(d, a.counters, a.writables, a.cycle)
        users = make_users(d)
        for _ in range(a.rounds):
            for mode in modes:
                r = phase(mode, a, d, prog, mapping, users)
                runs[mode].append(r)
                print(
                    f"  {mode}: p99.9 {r['lat']['p99.9']:.1f} µs, max {r['lat']['max']:.1f} µs, "
                    f"{r['overruns']} overruns, {r['jobs']} jobs",
                    file=sys.stderr,
                )

    def med(mode: str, get) -> float | None:
        xs = [get(r) for r in runs[mode]]
        xs = [x for x in xs if x is not None]
        return statistics.median(xs) if xs else None

    published = a.counters + a.writables + 1
    print(
        f"OPC UA server under load (issue 37): {published} published scalars ({a.counters} counters changing "
        f"every scan, {a.writables} writable), task {a.cycle}, {'C tier' if a.native else 'Python tier'}, "
        f"{a.seconds:g} s window per phase (+{a.lead:g} s lead), {a.rounds} round(s), {os.cpu_count()} CPUs, "
        f"{'SCHED_FIFO ' + str(a.rt_priority) if os.geteuid() == 0 else 'not root: SCHED_OTHER'}"
    )
    print(
        f"clients: {READERS} readers × 1 subscription ({PUBLISH_MS:g} ms) × {PER_READER} counters, 1 writer "
        f"({a.write_rate:g}/s, user of role operate); all with security None (server offers none,sign,encrypt); "
        f"client watchdog {a.watchdog:g} s\n"
    )
    print(
        "| phase | lat p99 µs | p99.9 µs | max µs | exec avg µs | overruns | notif/s | writes/s | Good | "
        "write med ms | write p99 ms | write max ms | PLC RSS MB | server RSS MB (peak) | CPU % PLC/server/clients |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    p999 = {}
    for mode in modes:
        rs = runs[mode]
        p999[mode] = med(mode, lambda r: r["lat"]["p99.9"])
        good = med(mode, lambda r: r["good"])
        writes = med(mode, lambda r: r["writes"])
        last = rs[-1]["mem"]
        server = last.get("server", {})
        print(
            f"| {mode} | {_f(med(mode, lambda r: r['lat']['p99']))} | {_f(p999[mode])} "
            f"| {_f(med(mode, lambda r: r['lat']['max']))} | {_f(med(mode, lambda r: r['exec']['avg']))} "
            f"| {_f(med(mode, lambda r: r['overruns']), 'g')} | {_f(med(mode, lambda r: r['notif_s']), '.0f')} "
            f"| {_f(med(mode, lambda r: r['writes_s']))} "
            f"| {'-' if good is None else f'{good:g}/{writes:g}'} "
            f"| {_f(med(mode, lambda r: r['rtt_med']), '.2f')} | {_f(med(mode, lambda r: r['rtt_p99']), '.2f')} "
            f"| {_f(med(mode, lambda r: r['rtt_max']), '.1f')} "
            f"| {_mb(last.get('plc', {}))} | {_mb(server)} ({_mb(server, 'VmHWM')}) "
            f"| {_f(med(mode, lambda r: r['cpu_plc']), '.0f')}/{_f(med(mode, lambda r: r['cpu_server']), '.0f')}"
            f"/{_f(med(mode, lambda r: r['cpu_clients']), '.0f')} |"
        )
    ratio = p999["clients"] / p999["plain"] if p999["plain"] else float("nan")
    print(f"\np99.9 clients / plain: {ratio:.2f} (goal ≤ 1.2: {'met' if ratio <= 1.2 else 'NOT met'})")
    if p999["opcua"]:
        print(f"p99.9 opcua / plain:   {p999['opcua'] / p999['plain']:.2f}")
        print(f"p99.9 clients / opcua: {p999['clients'] / p999['opcua']:.2f}")
    expected = READERS * PER_READER * 1000 / PUBLISH_MS
    span = ", ".join(f"{m} {med(m, lambda r: r['run_s']):.1f} s" for m in modes)
    print(f"the latency figures cover each st run whole ({span}): lead + window, clients connecting included")
    for k, r in enumerate(runs["clients"]):
        if r["window_jobs"] is not None:
            print(
                f"clients (round {k + 1}): all connected and subscribed {r['clients_ready_s']:.1f} s after the PLC "
                f"started; in the window alone {r['window_overruns']} overruns in {r['window_jobs']} jobs "
                "(PLC.Tasks.fast read over OPC UA)"
            )
    print(f"notifications: at most ≈ {expected:.0f}/s (one per monitored counter per publish, queue size 1)")
    for mode in modes:
        for k, r in enumerate(runs[mode]):
            bad = {s: n for s, n in r["statuses"].items() if s != "Good"}
            extra = ([f"write statuses not Good: {bad}"] if bad else []) + r["notes"]
            for note in extra:
                print(f"note ({mode}, round {k + 1}): {note}")
    if a.json:
        Path(a.json).write_text(json.dumps(runs, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
