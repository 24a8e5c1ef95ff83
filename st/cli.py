"""The `st` command line: check, compile, run, test, explain."""

from __future__ import annotations

import functools
import os
import sys
import time

import click

from .diagnostics import Code, CompileError, render_all
from .errors_doc import explain as explanation_of

_DIALECT = None  # the --dialect of this command line (set by the @dialect decorator)


def _compile(
    files, emit_python=False, time_unit="ms", f_trig_first_scan=False, use_cache=True, native=False, coverage=False
):
    from .api import compile_paths

    return compile_paths(
        list(files),
        native=native,
        coverage=coverage,
        emit_python=emit_python,
        time_unit=time_unit,
        f_trig_first_scan=f_trig_first_scan,
        use_cache=use_cache,
        raise_on_error=False,
        dialect=_DIALECT,
    )


def _compile_or_exit(files, **kw):
    """Compile; on errors print every diagnostic and exit 1. Warnings are printed too."""
    try:
        result = _compile(files, **kw)
    except CompileError as e:
        click.echo(e.render(), err=True)
        sys.exit(1)
    if _report(result):
        sys.exit(1)
    return result


def _report(result) -> bool:
    """Print diagnostics; True when there were errors."""
    lib = {p for lib in result.project.libraries for p, _ in lib.sources}
    diags = [d for d in result.diagnostics if d.span.file not in lib]
    if diags:
        click.echo(render_all(diags, result.sources), err=True)
    return any(d.is_error for d in diags)


_dialect_options = [
    click.option(
        "--dialect",
        "dialect_name",
        type=click.Choice(["openplc", "iec", "codesys", "twincat"]),
        default=None,
        help="A preset of the switches below and of the accepted constructs "
        "(docs/semantics.md); default: everything accepted, or a {dialect '…'} pragma in a file.",
    ),
    click.option(
        "--time-unit",
        type=click.Choice(["ms", "s"]),
        default="ms",
        show_default=True,
        help="What TIME_TO_<int>/<int>_TO_TIME count: ms (IEC, CODESYS) or s (MatIEC).",
    ),
    click.option(
        "--f-trig-first-scan/--no-f-trig-first-scan",
        default=False,
        help="F_TRIG pulses on the first scan when CLK is FALSE (MatIEC).",
    ),
]


def dialect(f):
    @functools.wraps(f)
    def with_dialect(*args, dialect_name=None, **kw):
        global _DIALECT
        _DIALECT = dialect_name
        return f(*args, **kw)

    for opt in reversed(_dialect_options):
        with_dialect = opt(with_dialect)
    return with_dialect


@click.group()
@click.version_option(package_name="st-plc")
def main():
    """st: compile, check and run IEC 61131-3 Structured Text."""


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path())
@dialect
def check(files, time_unit, f_trig_first_scan):
    """Check ST files and report every error and warning."""
    result = _compile_or_exit(files, time_unit=time_unit, f_trig_first_scan=f_trig_first_scan)
    n = len(result.project.user_pous())
    click.echo(f"ok: {len(files)} file(s), {n} POU(s)")


_NATIVE = click.option(
    "--native",
    is_flag=True,
    help="Compile the program's block bodies to C (Cython and a C compiler needed; docs/native.md).",
)


def _native_summary(result) -> None:
    """Which bodies the native tier compiled, and why the others stay Python."""
    names = {p.pyname: p.name for p in result.project.pous.values()}
    done = [names.get(c, c) for m in result.native for c in (*m.functions, *m.classes)]
    click.echo("native: " + (", ".join(done) if done else "no body compiled"), err=True)
    for pou, why in sorted(result.native_skipped.items()):
        if pou not in {p.name for p in result.project.pous.values() if p.library}:
            click.echo(f"  {pou}: Python ({why})", err=True)


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path())
@click.option("--emit", type=click.Choice(["python"]), default=None, help="Print the generated code.")
@_NATIVE
@dialect
def compile(files, emit, native, time_unit, f_trig_first_scan):
    """Compile ST files (to Python bytecode, cached)."""
    result = _compile_or_exit(
        files,
        emit_python=emit == "python",
        time_unit=time_unit,
        f_trig_first_scan=f_trig_first_scan,
        use_cache=emit != "python",
        native=native,
    )
    if native:
        _native_summary(result)
    if emit == "python":
        for path, text in result.python_source.items():
            if path in {p for lib in result.project.libraries for p, _ in lib.sources}:
                continue
            click.echo(f"# ---- generated from {path}")
            click.echo(text)
    else:
        click.echo(f"ok: {len(result.modules)} module(s)" + (" (from cache)" if result.from_cache else ""))


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path())
@click.option("--scans", type=int, default=None, help="Stop after N base ticks.")
@click.option("--duration", default=None, help="Stop after this much PLC time (e.g. 5s).")
@click.option("--cycle", default=None, help="Task cycle for a program without CONFIGURATION (default 10ms).")
@click.option("--virtual", is_flag=True, help="Run on virtual time, as fast as the CPU allows (default: real time).")
@click.option(
    "--policy",
    type=click.Choice(["openplc", "priority", "edf", "frame"]),
    default="openplc",
    show_default=True,
    help="Scheduling policy (docs/runtime.md).",
)
@click.option("--dump-json", is_flag=True, help="After the run, print every variable as one JSON object.")
@click.option("--stats-json", type=click.Path(), default=None, help="Write per-task statistics to this JSON file.")
@click.option("--stats-plot", type=click.Path(), default=None, help="Draw the wake-up latency histogram (PNG).")
@click.option(
    "--on-fault",
    type=click.Choice(["stop", "restart"]),
    default="stop",
    show_default=True,
    help="After a fault: stay in FAULT with safe outputs, or restart warm.",
)
@click.option("--watchdog", default=None, help="Watchdog budget per task (default 10 x its interval).")
@click.option(
    "--retain",
    "retain_file",
    type=click.Path(),
    default=None,
    help="SQLite file for RETAIN/PERSISTENT variables (default: <program>.retain.db when there are any).",
)
@click.option("--no-retain", is_flag=True, help="Do not keep retained variables.")
@click.option("--retain-interval", default="1s", show_default=True, help="How often retained data is committed.")
@click.option("--cold", is_flag=True, help="Cold start: clear retained data first.")
@click.option("--watch", is_flag=True, help="Online change: recompile when a file changes and swap at a scan boundary.")
@click.option(
    "--rt/--no-rt", default=True, help="Real time: ask for SCHED_FIFO, mlockall, cpu_dma_latency (default on)."
)
@click.option("--rt-priority", type=int, default=30, show_default=True, help="SCHED_FIFO priority.")
@click.option("--cpu", type=int, default=None, help="Pin the scan to this CPU.")
@click.option(
    "--sim-cost",
    multiple=True,
    metavar="TASK=DURATION",
    help="Virtual time: simulated execution time of a task's job (overload studies).",
)
@click.option(
    "--safe-output",
    "safe_outputs",
    multiple=True,
    metavar="ADDR=VALUE",
    help="Value of an output in STOP and FAULT (default FALSE/0), e.g. %QX0.1=TRUE.",
)
@click.option(
    "--web",
    default=None,
    is_flag=False,
    flag_value="127.0.0.1:8080",
    metavar="[HOST:]PORT",
    help="Serve the online mode in a browser (default 127.0.0.1:8080; another address only when given). "
    "The URL with its access token is printed at start (docs/web.md).",
)
@click.option("--web-read-only", is_flag=True, help="The page shows the PLC but changes nothing.")
@click.option(
    "--web-password",
    default=None,
    envvar="ST_WEB_PASSWORD",
    help="A password that signs in too (besides the printed token); also $ST_WEB_PASSWORD.",
)
@click.option(
    "--modbus",
    default=None,
    metavar="[HOST:]PORT",
    help="Serve a Modbus TCP slave (OpenPLC's map), e.g. 127.0.0.1:5020; port 502 needs root.",
)
@click.option(
    "--modbus-map",
    type=click.Path(exists=True),
    default=None,
    help="TOML file mapping any variable to a Modbus table and address.",
)
@click.option("--modbus-read-only", is_flag=True, help="Refuse every Modbus write (exception 02).")
@click.option(
    "--modbus-writable",
    default=None,
    metavar="RANGES",
    help="Only these are writable, e.g. holding:0-99,coil:0-15 (a write elsewhere gets 02).",
)
@click.option(
    "--modbus-max-connections",
    type=int,
    default=16,
    show_default=True,
    help="Most simultaneous connections. When full, a new one closes one that is not regular (one "
    "without a request yet, else the newest of the busiest address); regular clients (requests "
    "at least 1 s apart) are never closed: the new connection is refused instead.",
)
@click.option("--modbus-idle-timeout", type=float, default=60.0, show_default=True, help="Seconds.")
@click.option(
    "--modbus-rate",
    type=float,
    default=1000.0,
    show_default=True,
    help="Requests per second per connection (0: unbounded).",
)
@click.option(
    "--modbus-unit-ids",
    default=None,
    metavar="IDS",
    help="Answer only these unit ids, e.g. 1,255 (others: exception 0x0B). Default: all.",
)
@click.option(
    "--axes",
    type=click.Path(exists=True),
    default=None,
    help="Axis configuration (TOML, [[axis]] tables by AxisNo): modulo, limits, …",
)
@click.option(
    "--trace",
    multiple=True,
    metavar="AXIS_REF",
    help="Record an axis every cycle, e.g. main.axis1 (repeatable); written as CSV at the end.",
)
@click.option("--trace-plot", type=click.Path(), default=None, help="Draw the traced axes (PNG).")
@click.option(
    "--trace-csv", type=click.Path(), default=None, help="Where the trace CSV goes (default beside the plot)."
)
@click.option(
    "--ethercat",
    type=click.Path(exists=True),
    default=None,
    metavar="SEGMENT.TOML",
    help="Exchange process data with an EtherCAT segment every scan; drives move their axes.",
)
@click.option(
    "--ethercat-backend",
    type=click.Choice(["sim", "soem"]),
    default="sim",
    show_default=True,
    help="sim: the emulated segment in process; soem: pysoem on --ethercat-iface.",
)
@click.option("--ethercat-iface", default=None, help="Network interface of the soem backend (root).")
@click.option(
    "--ethercat-capture",
    type=click.Path(),
    default=None,
    help="sim backend: write every frame to a pcap file (Wireshark/tshark).",
)
@click.option("--quiet", "-q", is_flag=True, help="No live status line and no summary.")
@_NATIVE
@dialect
def run(
    files,
    scans,
    duration,
    cycle,
    virtual,
    policy,
    dump_json,
    stats_json,
    stats_plot,
    on_fault,
    watchdog,
    retain_file,
    no_retain,
    retain_interval,
    cold,
    watch,
    rt,
    rt_priority,
    cpu,
    sim_cost,
    safe_outputs,
    web,
    web_read_only,
    web_password,
    modbus,
    modbus_map,
    modbus_read_only,
    modbus_writable,
    modbus_max_connections,
    modbus_idle_timeout,
    modbus_rate,
    modbus_unit_ids,
    axes,
    trace,
    trace_plot,
    trace_csv,
    ethercat,
    ethercat_backend,
    ethercat_iface,
    ethercat_capture,
    quiet,
    native,
    time_unit,
    f_trig_first_scan,
):
    """Run a program: its CONFIGURATION's tasks (or a lone PROGRAM as one cyclic task), in real time
    with a live status line until Ctrl-C, --duration or --scans; --virtual runs on virtual time."""
    from .app.options import RunOptions
    from .app.session import run_plc
    from .app.watch import source_mtimes

    seen = source_mtimes(files)  # --watch compares with the files as they were compiled
    # --web marks the lines that ran in the last scan: line probes, on the Python tier only
    flow = bool(web) and not native
    result = _compile_or_exit(
        files, time_unit=time_unit, f_trig_first_scan=f_trig_first_scan, native=native, coverage=flow
    )
    if native and not quiet:
        _native_summary(result)
    opts = RunOptions(
        files=list(files),
        scans=scans,
        duration=duration,
        cycle=cycle,
        virtual=virtual,
        policy=policy,
        dump_json=dump_json,
        stats_json=stats_json,
        stats_plot=stats_plot,
        on_fault=on_fault,
        watchdog=watchdog,
        retain_file=retain_file,
        no_retain=no_retain,
        retain_interval=retain_interval,
        cold=cold,
        watch=watch,
        rt=rt,
        rt_priority=rt_priority,
        cpu=cpu,
        sim_cost=list(sim_cost),
        safe_outputs=list(safe_outputs),
        web=web,
        web_read_only=web_read_only,
        web_password=web_password,
        modbus=modbus,
        modbus_map=modbus_map,
        modbus_read_only=modbus_read_only,
        modbus_writable=modbus_writable,
        modbus_max_connections=modbus_max_connections,
        modbus_idle_timeout=modbus_idle_timeout,
        modbus_rate=modbus_rate,
        modbus_unit_ids=modbus_unit_ids,
        axes=axes,
        trace=list(trace),
        trace_plot=trace_plot,
        trace_csv=trace_csv,
        ethercat=ethercat,
        ethercat_backend=ethercat_backend,
        ethercat_iface=ethercat_iface,
        ethercat_capture=ethercat_capture,
        quiet=quiet,
        native=native,
        time_unit=time_unit,
        f_trig_first_scan=f_trig_first_scan,
        compiled_mtimes=seen,
    )
    sys.exit(run_plc(result, opts))


@main.command("test")
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("-k", "keyword", default="", help="Run only tests whose name contains this text (or matches a glob).")
@click.option("-x", "--exitfirst", is_flag=True, help="Stop at the first failing test.")
@click.option("-q", "--quiet", is_flag=True, help="Print failing tests and the summary only.")
@click.option("--timeout", default="10s", show_default=True, help="Watchdog per test (an endless loop fails the test).")
@click.option("--cov", "cov", is_flag=True, help="Measure which ST lines and branches ran; print a table.")
@click.option("--cov-html", default=None, metavar="DIR", help="Also write the coverage report as HTML into DIR.")
@dialect
def test_cmd(files, keyword, exitfirst, quiet, timeout, cov, cov_html, time_unit, f_trig_first_scan):
    """Run the TEST blocks of ST files (STruC++ syntax). A file test_X.st is compiled with X.st beside it.

    Prints PASS/FAIL per test and ends with `N passed, M failed`; exit code 0 when all pass,
    1 when a test failed, 2 when the sources do not compile, 5 when there is no test to run."""
    from .testing.runner import TestSuite, resolve_sources

    paths = resolve_sources(files)
    measure = cov or cov_html is not None
    try:
        from .api import compile_paths

        result = compile_paths(
            paths,
            time_unit=time_unit,
            f_trig_first_scan=f_trig_first_scan,
            raise_on_error=False,
            coverage=measure,
            dialect=_DIALECT,
        )
    except CompileError as e:
        click.echo(e.render(), err=True)
        sys.exit(2)
    if _report(result):
        sys.exit(2)
    suite = TestSuite(result, timeout)
    cases = suite.select(keyword)
    if not cases:
        click.echo("no tests ran" + (f" (none matches -k {keyword!r})" if keyword else ""))
        sys.exit(5)

    def show(r):
        where = f"({r.case.file}:{r.case.line})"
        if r.passed:
            if not quiet:
                click.echo(f"{click.style('PASS', fg='green')}  {r.case.name}  {where}")
            return
        click.echo(f"{click.style('FAIL', fg='red')}  {r.case.name}  {where}")
        for line in str(r.report).splitlines():
            click.echo("      " + line)

    results = suite.run_all(cases, show, exitfirst)
    failed = sum(1 for r in results if not r.passed)
    if measure:
        from .testing.covreport import html_report, terminal_report
        from .testing.measure import coverage_data

        data = coverage_data([result])
        click.echo("")
        terminal_report(data, sys.stdout)
        if cov_html is not None:
            click.echo(f"HTML coverage report: {html_report(data, cov_html)}")
    click.echo(f"{len(results) - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


@main.command()
@click.argument("code")
def explain(code):
    """Explain a diagnostic code, e.g. `st explain E013`."""
    text = explanation_of(code)
    if text is None:
        click.echo(f"unknown code {code}; codes: {', '.join(sorted(c.value for c in Code))}", err=True)
        sys.exit(1)
    click.echo(f"{code.upper()}: {text}")


@main.group()
def modbus():
    """The Modbus TCP slave (see `st run --modbus`)."""


@modbus.command("map")
@click.argument("files", nargs=-1, required=True, type=click.Path())
@click.option("--map", "map_file", type=click.Path(exists=True), default=None, help="A TOML map file to add.")
@dialect
def modbus_map(files, map_file, time_unit, f_trig_first_scan):
    """Print the effective Modbus map of a program: OpenPLC's located variables plus the map file."""
    from .io.modbus import MapError, effective_map, load_map
    from .io.modbus.exchange import TABLE_NAMES
    from .runtime.plc import PLC

    result = _compile_or_exit(files, time_unit=time_unit, f_trig_first_scan=f_trig_first_scan)
    try:
        plc = PLC(result)
        entries = load_map(map_file, plc) if map_file else []
    except MapError as e:
        click.echo(str(e), err=True)
        sys.exit(2)
    except (ValueError, KeyError) as e:
        click.echo(f"error: {e}", err=True)
        sys.exit(2)
    rows = effective_map(plc, entries)
    head = ("table", "addresses", "variable", "type", "encoding", "access")
    body = [
        (
            TABLE_NAMES[r.table],
            str(r.first) if r.first == r.last else f"{r.first}-{r.last}",
            r.source,
            r.type_name,
            r.encoding,
            "read/write" if r.writable else "read",
        )
        for r in rows
    ]
    widths = [max(len(x[i]) for x in [head] + body) for i in range(len(head))]
    for line in [head] + body:
        click.echo("  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip())
    click.echo(
        "other addresses in OpenPLC's ranges (coils and discrete inputs 0-8191, input registers "
        "0-1023, holding registers 0-8191) read 0 and keep what is written; beyond them: exception 02"
    )


@main.command("experiment")
@click.argument("name", required=False)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(),
    default=None,
    help="Where the CSV, PNG and summary.md go (default: experiments/NAME).",
)
@click.option("--quick", is_flag=True, help="A shortened run (fewer cycles, shorter holds) for a first look.")
@click.option("--seed", type=int, default=1, show_default=True)
def experiment(name, out_dir, quick, seed):
    """Run one of the thesis's experiments (programs/thesis/README.md); without NAME, list them."""
    from .experiments import EXPERIMENTS
    from .experiments import run as run_experiment

    if not name:
        for key, (_mod, what) in EXPERIMENTS.items():
            click.echo(f"{key:<12}  {what}")
        return
    if name not in EXPERIMENTS:
        click.echo(f"error: unknown experiment '{name}' (known: {', '.join(EXPERIMENTS)})", err=True)
        sys.exit(2)
    out = out_dir or os.path.join("experiments", name)
    t0 = time.monotonic()
    try:
        rep = run_experiment(name, out, quick=quick, seed=seed)
    except FileNotFoundError as e:
        click.echo(f"error: {e}", err=True)
        sys.exit(2)
    summary = rep.dir / "summary.md"
    click.echo(summary.read_text())
    click.echo(
        f"{name}: {len(rep.files)} file(s) and summary.md in {rep.dir} ({time.monotonic() - t0:.0f} s)", err=True
    )


@main.group()
def ethercat():
    """EtherCAT: the emulated segment, scanning and timing plans (see `st run --ethercat`)."""


def _segment_config_or_exit(path):
    from .io.ethercat.config import ConfigError, load

    try:
        return load(path)
    except ConfigError as e:
        click.echo(str(e), err=True)
        sys.exit(2)


@ethercat.command("scan")
@click.option(
    "--config",
    "config_path",
    type=click.Path(exists=True),
    default=None,
    help="sim: the segment configuration to emulate.",
)
@click.option("--backend", type=click.Choice(["sim", "soem"]), default="sim", show_default=True)
@click.option("--iface", default=None, help="soem: the network interface.")
def ethercat_scan(config_path, backend, iface):
    """List the slaves a master finds, with their identity, state and process-data sizes."""
    from .io.ethercat.master import FrameMaster, MasterError

    try:
        if backend == "sim":
            if not config_path:
                click.echo("error: the sim backend needs --config segment.toml", err=True)
                sys.exit(2)
            from .io.ethercat.config import build_segment

            seg = build_segment(_segment_config_or_exit(config_path))
            clock = [0.0]

            def transport(frame):
                clock[0] += 20e-6
                return seg.exchange(frame, clock[0])

            m = FrameMaster(transport, pause=lambda s: clock.__setitem__(0, clock[0] + s))
        else:
            from .io.ethercat.soem import SoemMaster

            if not iface:
                click.echo("error: the soem backend needs --iface", err=True)
                sys.exit(2)
            m = SoemMaster(iface)
        m.open()
        slaves = m.scan()
        m.configure()
    except MasterError as e:
        click.echo(f"error: {e}", err=True)
        sys.exit(2)
    click.echo(f"{len(slaves)} slave(s)")
    click.echo("pos  station  vendor      product     revision  name  [state]  process data")
    for s in slaves:
        click.echo(s.describe())
    m.close()


@ethercat.command("plan")
@click.argument("config_path", type=click.Path(exists=True))
@click.option("--cycle", default=None, help="Cycle time to check, e.g. 1ms (default: the file's).")
def ethercat_plan(config_path, cycle):
    """Frame bytes, wire time at 100 Mbit/s, per-slave and end-to-end delays, and whether the cycle fits."""
    from .io.ethercat.config import ConfigError, build_devices, parse_duration
    from .io.ethercat.plan import SegmentTiming, SlaveTiming, format_plan, plan

    cfg = _segment_config_or_exit(config_path)
    try:
        devices = build_devices(cfg)
        cyc = parse_duration(cycle, "--cycle") if cycle else (cfg.cycle_s or 0.001)
    except ConfigError as e:
        click.echo(str(e), err=True)
        sys.exit(2)
    slaves = []
    for sc, d in zip(cfg.slaves, devices):
        fwd = sc.forwarding_delay_us if sc.forwarding_delay_us is not None else cfg.forwarding_delay_us
        slaves.append(
            SlaveTiming(
                sc.name,
                d.rx_layout.size,
                d.tx_layout.size,
                forwarding_delay_s=fwd * 1e-6,
                cable_m=cfg.cable_m,
                is_drive=sc.type != "dio",
            )
        )
    click.echo(format_plan(plan(SegmentTiming(slaves, cyc, host_s=cfg.host_delay_us * 1e-6, dc=cfg.dc))))


@ethercat.command("serve")
@click.option("--iface", required=True, help="The interface to answer on (e.g. one end of a veth pair).")
@click.option("--config", "config_path", type=click.Path(exists=True), required=True)
@click.option("--ready-file", type=click.Path(), default=None, help="Created once the socket is bound.")
@click.option("--capture", type=click.Path(), default=None, help="Write every frame to a pcap file.")
@click.option("--duration", type=float, default=0.0, help="Stop after this many seconds (0: until SIGTERM).")
def ethercat_serve(iface, config_path, ready_file, capture, duration):
    """Serve the emulated segment on a network interface for a real master (SOEM)."""
    from .io.ethercat.config import build_segment
    from .io.ethercat.serve import serve

    seg = build_segment(_segment_config_or_exit(config_path))
    if capture:
        seg.open_capture(capture)
    try:
        n = serve(iface, seg, ready_file=ready_file, announce=lambda m: click.echo(m, err=True), duration=duration)
    except PermissionError:
        click.echo(f"error: opening a raw socket on {iface} needs root or CAP_NET_RAW", err=True)
        sys.exit(2)
    except OSError as e:
        click.echo(f"error: {iface}: {e.strerror or e}", err=True)
        sys.exit(2)
    click.echo(f"answered {n} frame(s)", err=True)


if __name__ == "__main__":
    main()
