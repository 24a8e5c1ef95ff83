"""The `st` command line: check, compile, run, test, explain."""

from __future__ import annotations

import functools
import os
import sys
import time

import click

from .app.params import (
    COUNT,
    CPU,
    DURATION,
    ENDPOINT,
    INPUT_FILE,
    INTEGER,
    OUTPUT_DIR,
    OUTPUT_FILE,
    Count,
    InputFile,
    ModbusRanges,
    Number,
    SafeOutput,
    TaskCost,
    UnitIds,
)
from .diagnostics import Code, CompileError, render_all
from .errors_doc import explain as explanation_of

_DIALECT = None  # the --dialect of this command line (set by the @dialect decorator)
_LIBS: tuple[str, ...] = ()  # its --lib paths (the same decorator)


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
        lib_path=_LIBS,
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
    click.option(
        "--lib",
        "lib_paths",
        multiple=True,
        type=InputFile(dirs=True),
        metavar="PATH",
        help="Where the libraries a .plcproj references are: a library .plcproj, or a folder searched "
        "for them (repeatable; then $ST_LIBPATH).",
    ),
]


def dialect(f):
    @functools.wraps(f)
    def with_dialect(*args, dialect_name=None, lib_paths=(), **kw):
        global _DIALECT, _LIBS
        _DIALECT, _LIBS = dialect_name, tuple(lib_paths)
        return f(*args, **kw)

    for opt in reversed(_dialect_options):
        with_dialect = opt(with_dialect)
    return with_dialect


def _usage_error_text(e: click.UsageError) -> str:
    """One line for a refused command line: `--duration 10: a duration needs a unit, e.g. 10s`."""
    from .app.params import OptionValueError

    bad_value = isinstance(e, click.BadParameter) and not isinstance(e, click.MissingParameter)
    msg = e.message if bad_value else e.format_message()
    if bad_value and isinstance(e, click.BadParameter) and e.param is not None:
        if isinstance(e.param, click.Option):
            name = max((o for o in e.param.opts if o.startswith("--")), key=len, default=e.param.opts[0])
            msg = f"{name} {msg}" if isinstance(e, OptionValueError) else f"{name}: {msg}"
        elif not isinstance(e, OptionValueError):
            msg = f"{e.param.human_readable_name}: {msg}"
    msg = msg.strip().rstrip(".")
    if msg[:1].isupper() and msg[1:2].islower():
        msg = msg[0].lower() + msg[1:]
    return msg


class _Main(click.Group):
    """The `st` group: a refused command line (a bad value, an unknown option, a missing argument)
    is one `error: …` line on stderr and exit status 2, never a usage block or a traceback."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):  # type: ignore[override]
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.UsageError as e:
            click.echo(f"error: {_usage_error_text(e)}", err=True)
            sys.exit(2)
        except click.ClickException as e:
            e.show()
            sys.exit(e.exit_code)
        except click.Abort:
            click.echo("Aborted!", err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


@click.group(cls=_Main)
@click.version_option(package_name="st-plc")
def main():
    """st: compile, check and run IEC 61131-3 Structured Text."""


@main.command()
@click.argument("files", nargs=-1, required=True, type=INPUT_FILE)
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
@click.argument("files", nargs=-1, required=True, type=INPUT_FILE)
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
@click.argument("files", nargs=-1, required=True, type=INPUT_FILE)
@click.option("--scans", type=COUNT, default=None, metavar="N", help="Stop after N base ticks.")
@click.option("--duration", type=DURATION, default=None, help="Stop after this much PLC time (e.g. 5s).")
@click.option(
    "--cycle", type=DURATION, default=None, help="Task cycle for a program without CONFIGURATION (default 10ms)."
)
@click.option("--virtual", is_flag=True, help="Run on virtual time, as fast as the CPU allows (default: real time).")
@click.option(
    "--policy",
    type=click.Choice(["openplc", "priority", "edf", "frame"]),
    default="openplc",
    show_default=True,
    help="Scheduling policy (docs/runtime.md).",
)
@click.option(
    "--dump-json",
    is_flag=True,
    help="After the run, print the variables as one JSON object (function block instances: their "
    "inputs, outputs and in-outs; --all: everything).",
)
@click.option(
    "--all",
    "dump_all",
    is_flag=True,
    help="With --dump-json: every variable of every block instance, its internal state too.",
)
@click.option("--stats-json", type=OUTPUT_FILE, default=None, help="Write per-task statistics to this JSON file.")
@click.option("--stats-plot", type=OUTPUT_FILE, default=None, help="Draw the wake-up latency histogram (PNG).")
@click.option(
    "--on-fault",
    type=click.Choice(["stop", "restart"]),
    default="stop",
    show_default=True,
    help="After a fault: stay in FAULT with safe outputs, or restart warm.",
)
@click.option("--watchdog", type=DURATION, default=None, help="Watchdog budget per task (default 10 x its interval).")
@click.option(
    "--retain",
    "retain_file",
    type=OUTPUT_FILE,
    default=None,
    help="SQLite file for RETAIN/PERSISTENT variables. Default, when the program has any, in real time: "
    "a file of the project in $XDG_DATA_HOME/st/retain/ (~/.local/share/st/retain/); none for --virtual.",
)
@click.option("--no-retain", is_flag=True, help="Do not keep retained variables.")
@click.option(
    "--retain-interval", type=DURATION, default="1s", show_default=True, help="How often retained data is committed."
)
@click.option("--cold", is_flag=True, help="Cold start: clear retained data first.")
@click.option("--watch", is_flag=True, help="Online change: recompile when a file changes and swap at a scan boundary.")
@click.option(
    "--rt/--no-rt", default=True, help="Real time: ask for SCHED_FIFO, mlockall, cpu_dma_latency (default on)."
)
@click.option(
    "--rt-priority",
    type=Count(1, 99),
    metavar="1-99",
    default=30,
    show_default=True,
    help="SCHED_FIFO priority (1-99).",
)
@click.option("--cpu", type=CPU(), default=None, help="Pin the scan to this CPU.")
@click.option(
    "--sim-cost",
    type=TaskCost(),
    multiple=True,
    metavar="TASK=DURATION",
    help="Virtual time: simulated execution time of a task's job (overload studies).",
)
@click.option(
    "--safe-output",
    "safe_outputs",
    type=SafeOutput(),
    multiple=True,
    metavar="ADDR=VALUE",
    help="Value of an output in STOP and FAULT (default FALSE/0), e.g. %QX0.1=TRUE.",
)
@click.option(
    "--web",
    type=ENDPOINT,
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
    "--web-host",
    "web_hosts",
    multiple=True,
    metavar="NAME",
    help="A name the page is reached by besides its address (e.g. plc1.plant.local); repeatable. "
    "Requests naming another host are refused.",
)
@click.option(
    "--web-insecure",
    is_flag=True,
    help="Serve --web beyond this machine without a --web-password (refused otherwise).",
)
@click.option(
    "--web-cert",
    type=click.Path(dir_okay=False),
    default=None,
    help="Serve the page over HTTPS: the certificate (PEM).",
)
@click.option("--web-key", type=click.Path(dir_okay=False), default=None, help="The private key of --web-cert (PEM).")
@click.option(
    "--modbus",
    type=ENDPOINT,
    default=None,
    metavar="[HOST:]PORT",
    help="Serve a Modbus TCP slave (OpenPLC's map), e.g. 127.0.0.1:5020; port 502 needs root. No "
    "authentication: another address than loopback lets the network write (see --modbus-read-only).",
)
@click.option(
    "--modbus-map",
    type=INPUT_FILE,
    default=None,
    help="TOML file mapping any variable to a Modbus table and address.",
)
@click.option(
    "--modbus-read-only",
    is_flag=True,
    help="Refuse every Modbus write function (exception 01, illegal function); reads are served.",
)
@click.option(
    "--modbus-writable",
    type=ModbusRanges(),
    default=None,
    metavar="RANGES",
    help="Only these are writable, e.g. holding:0-99,coil:0-15 (a write elsewhere gets 02).",
)
@click.option(
    "--modbus-max-connections",
    type=COUNT,
    metavar="N",
    default=16,
    show_default=True,
    help="Most simultaneous connections. When full, a new one closes one that is not regular (one "
    "without a request yet, else the newest of the busiest address); regular clients (requests "
    "at least 1 s apart) are never closed: the new connection is refused instead.",
)
@click.option(
    "--modbus-idle-timeout", type=Number(), metavar="SECONDS", default=60.0, show_default=True, help="Seconds."
)
@click.option(
    "--modbus-rate",
    type=Number(zero=True),
    metavar="R",
    default=1000.0,
    show_default=True,
    help="Requests per second per connection (0: unbounded).",
)
@click.option(
    "--modbus-unit-ids",
    type=UnitIds(),
    default=None,
    metavar="IDS",
    help="Answer only these unit ids, e.g. 1,255 (others: exception 0x0B). Default: all.",
)
@click.option(
    "--opcua",
    type=ENDPOINT,
    default=None,
    is_flag=False,
    flag_value="127.0.0.1:4840",
    metavar="[HOST:]PORT",
    help="Serve the program's variables over OPC UA (default 127.0.0.1:4840; docs/opcua.md). Published: "
    "inputs, outputs, globals and located variables, read-only, unless the symbol configuration says otherwise.",
)
@click.option(
    "--opcua-map",
    type=INPUT_FILE,
    default=None,
    help='TOML [symbols] table of "pattern" = "read" | "readwrite" | "none" (what is published, writable).',
)
@click.option(
    "--opcua-users",
    type=INPUT_FILE,
    default=None,
    help="The users who may sign in, with their roles (read, operate, engineer): `st opcua user` writes it.",
)
@click.option("--opcua-anonymous", is_flag=True, help="Let clients in without a user (role read).")
@click.option(
    "--opcua-security",
    default="sign,encrypt",
    show_default=True,
    metavar="MODES",
    help="Security modes offered, of none, sign, encrypt (Basic256Sha256); none only when named.",
)
@click.option(
    "--opcua-pki",
    type=click.Path(file_okay=False),
    default=None,
    help="The server's certificate (made on first start) and its trusted/ and rejected/ client "
    "certificates (default ~/.local/share/st/opcua).",
)
@click.option(
    "--axes",
    type=INPUT_FILE,
    default=None,
    help="Axis configuration (TOML, [[axis]] tables by AxisNo): modulo, limits, …",
)
@click.option(
    "--trace",
    multiple=True,
    metavar="AXIS_REF",
    help="Record an axis every cycle, e.g. main.axis1 (repeatable); written as CSV at the end.",
)
@click.option("--trace-plot", type=OUTPUT_FILE, default=None, help="Draw the traced axes (PNG).")
@click.option(
    "--trace-csv",
    type=OUTPUT_FILE,
    default=None,
    help="Where the trace CSV goes (default beside the plot, else trace.csv).",
)
@click.option(
    "--ethercat",
    type=INPUT_FILE,
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
    type=OUTPUT_FILE,
    default=None,
    help="sim backend: write every frame to a pcap file (Wireshark/tshark).",
)
@click.option("--quiet", "-q", is_flag=True, help="No live status line and no summary.")
@_NATIVE
@click.option(
    "--python",
    "python_only",
    is_flag=True,
    help="Stay on the Python tier (by default the program is also built compiled to C in the background and "
    "swapped in at a scan boundary when ready; --native waits for that build instead).",
)
@dialect
def run(
    files,
    scans,
    duration,
    cycle,
    virtual,
    policy,
    dump_json,
    dump_all,
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
    web_hosts,
    web_insecure,
    web_cert,
    web_key,
    modbus,
    modbus_map,
    modbus_read_only,
    modbus_writable,
    modbus_max_connections,
    modbus_idle_timeout,
    modbus_rate,
    modbus_unit_ids,
    opcua,
    opcua_map,
    opcua_users,
    opcua_anonymous,
    opcua_security,
    opcua_pki,
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
    python_only,
    time_unit,
    f_trig_first_scan,
):
    """Run a program: its CONFIGURATION's tasks (or a lone PROGRAM as one cyclic task), in real time
    with a live status line until Ctrl-C, --duration or --scans; --virtual runs on virtual time."""
    from .app.options import RunOptions
    from .app.session import run_plc
    from .app.watch import source_mtimes

    _check_run_options(click.get_current_context())
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
        dump_all=dump_all,
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
        web_hosts=list(web_hosts),
        web_insecure=web_insecure,
        web_cert=web_cert,
        web_key=web_key,
        modbus=modbus,
        modbus_map=modbus_map,
        modbus_read_only=modbus_read_only,
        modbus_writable=modbus_writable,
        modbus_max_connections=modbus_max_connections,
        modbus_idle_timeout=modbus_idle_timeout,
        modbus_rate=modbus_rate,
        modbus_unit_ids=modbus_unit_ids,
        opcua=opcua,
        opcua_map=opcua_map,
        opcua_users=opcua_users,
        opcua_anonymous=opcua_anonymous,
        opcua_security=opcua_security,
        opcua_pki=opcua_pki,
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
        python=python_only,
        time_unit=time_unit,
        f_trig_first_scan=f_trig_first_scan,
        compiled_mtimes=seen,
        dialect=_DIALECT,
        lib_path=_LIBS,
    )
    sys.exit(run_plc(result, opts))


# an option of `st run` → the option it is a part of (given alone, it would change nothing)
_RUN_NEEDS = {
    "dump_all": "dump_json",
    "web_read_only": "web",
    "web_password": "web",
    "web_hosts": "web",
    "web_insecure": "web",
    "web_cert": "web",
    "web_key": "web",
    "modbus_map": "modbus",
    "modbus_read_only": "modbus",
    "modbus_writable": "modbus",
    "modbus_max_connections": "modbus",
    "modbus_idle_timeout": "modbus",
    "modbus_rate": "modbus",
    "modbus_unit_ids": "modbus",
    "opcua_map": "opcua",
    "opcua_users": "opcua",
    "opcua_anonymous": "opcua",
    "opcua_security": "opcua",
    "opcua_pki": "opcua",
    "ethercat_backend": "ethercat",
    "ethercat_iface": "ethercat",
    "ethercat_capture": "ethercat",
    "trace_plot": "trace",
    "trace_csv": "trace",
}


def _check_run_options(ctx: click.Context) -> None:
    """What no single option's type can see: options that need or exclude each other. Refused
    before anything is compiled, built or restored (click.UsageError: `error: …`, exit 2)."""
    import importlib.util

    from click.core import ParameterSource

    from .app.params import writable_file

    p = ctx.params
    flag = {o.name: max(o.opts, key=len) for o in ctx.command.params if isinstance(o, click.Option)}
    for name, needed in _RUN_NEEDS.items():
        if ctx.get_parameter_source(name) == ParameterSource.COMMANDLINE and not p[needed]:
            raise click.UsageError(f"{flag[name]} needs {flag[needed]}")
    if p["virtual"]:
        if p["duration"] is None and p["scans"] is None:
            raise click.UsageError(
                "--virtual needs --duration or --scans (virtual time runs as fast as the CPU allows)"
            )
        for name in ("web", "watch"):
            if p[name]:
                raise click.UsageError(f"{flag[name]} needs a run in real time (not --virtual)")
    if p["retain_file"] and p["no_retain"]:
        raise click.UsageError("--retain and --no-retain exclude each other")
    if p["ethercat"] and p["ethercat_backend"] == "soem" and not p["ethercat_iface"]:
        raise click.UsageError("--ethercat-backend soem needs --ethercat-iface (a network interface)")
    if p["ethercat_capture"] and p["ethercat_backend"] != "sim":
        raise click.UsageError("--ethercat-capture needs --ethercat-backend sim (the emulated segment)")
    for name in ("stats_plot", "trace_plot"):
        if p[name] and importlib.util.find_spec("matplotlib") is None:
            raise click.UsageError(f"{flag[name]} needs matplotlib: pip install 'st-plc[plot]'")
    if p["trace"] and not p["trace_csv"]:
        from .app.report import trace_csv_path

        csv = trace_csv_path(p["trace_plot"])
        problem = writable_file(csv)
        if problem:
            raise click.UsageError(f"the trace's CSV file {csv}: {problem} (choose another with --trace-csv)")


@main.command("test")
@click.argument("files", nargs=-1, required=True, type=InputFile(dirs=True))
@click.option("-k", "keyword", default="", help="Run only tests whose name contains this text (or matches a glob).")
@click.option("-x", "--exitfirst", is_flag=True, help="Stop at the first failing test.")
@click.option("-q", "--quiet", is_flag=True, help="Print failing tests and the summary only.")
@click.option(
    "--timeout",
    type=DURATION,
    default="10s",
    show_default=True,
    help="Watchdog per test (an endless loop fails the test).",
)
@click.option("--cov", "cov", is_flag=True, help="Measure which ST lines and branches ran; print a table.")
@click.option(
    "--cov-html", type=OUTPUT_DIR, default=None, metavar="DIR", help="Also write the coverage report as HTML into DIR."
)
@click.option(
    "--max-cycles",
    type=click.IntRange(min=1),
    default=10_000,
    show_default=True,
    help="TcUnit: scans before the tests not finished fail.",
)
@dialect
def test_cmd(files, keyword, exitfirst, quiet, timeout, cov, cov_html, max_cycles, time_unit, f_trig_first_scan):
    """Run the TEST blocks of ST files (STruC++ syntax). A file test_X.st is compiled with X.st beside it.

    Prints PASS/FAIL per test and ends with `N passed, M failed`; exit code 0 when all pass,
    1 when a test failed, 2 when the sources do not compile, 5 when there is no test to run.

    A TwinCAT project (.plcproj or TwinCAT files; or ST files with TcUnit suites and no TEST block)
    runs its TcUnit test suites instead: on virtual time until TcUnit reports them finished (at most
    --max-cycles scans), each TEST('name') a PASS/FAIL/SKIP with TcUnit's messages, then TcUnit's
    summary; --lib finds its libraries (TcUnit's project)."""
    from .compiler.twincat import is_twincat
    from .testing import tcunit
    from .testing.runner import TestSuite, is_test_file, resolve_sources

    paths = resolve_sources(files)
    if any(is_twincat(f) for f in files) or (
        not any(is_test_file(p) for p in paths) and any(tcunit.uses_tcunit(p) for p in paths)
    ):
        sys.exit(tcunit.command(files, _LIBS, keyword=keyword, quiet=quiet, max_cycles=max_cycles, dialect=_DIALECT))
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
            lib_path=_LIBS,
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
        raise click.UsageError(f"unknown code {code}; codes: {', '.join(sorted(c.value for c in Code))}")
    click.echo(f"{code.upper()}: {text}")


@main.group()
def modbus():
    """The Modbus TCP slave (see `st run --modbus`)."""


@modbus.command("map")
@click.argument("files", nargs=-1, required=True, type=INPUT_FILE)
@click.option(
    "--modbus-map", "map_file", type=INPUT_FILE, default=None, help="A TOML map file to add (as on `st run`)."
)
@click.option("--map", "old_map_file", type=INPUT_FILE, default=None, hidden=True)  # the old name: deprecated
@dialect
def modbus_map(files, map_file, old_map_file, time_unit, f_trig_first_scan):
    """Print the effective Modbus map of a program: OpenPLC's located variables (each with its
    variable's path and IEC type) plus the map file."""
    from .io.modbus import MapError, effective_map, load_map
    from .io.modbus.exchange import TABLE_NAMES
    from .runtime.plc import PLC

    if old_map_file is not None:
        if map_file is not None:
            raise click.UsageError("--map is the old name of --modbus-map: give one of them")
        click.echo("warning: --map is deprecated, use --modbus-map", err=True)
        map_file = old_map_file
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
    head = ("table", "addresses", "location", "variable", "type", "encoding", "access")
    body = [
        (
            TABLE_NAMES[r.table],
            str(r.first) if r.first == r.last else f"{r.first}-{r.last}",
            r.location or "-",
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


@main.command()
@click.option(
    "--lib",
    "lib_path",
    multiple=True,
    type=click.Path(),
    help="A library project or a folder of them, for a .plcproj's references (as on `st check`); repeatable.",
)
@click.option("--stdio", is_flag=True, hidden=True, help="Accepted and ignored: stdio is the only transport.")
def lsp(lib_path, stdio):
    """Run the language server on stdin/stdout (for editors: docs/editors.md)."""
    from .lsp.server import main as serve

    serve(list(lib_path))


@main.group()
def opcua():
    """The OPC UA server (see `st run --opcua`, docs/opcua.md)."""


@opcua.command("symbols")
@click.argument("files", nargs=-1, required=True, type=INPUT_FILE)
@click.option("--opcua-map", "map_file", type=INPUT_FILE, default=None, help="A map file to apply (as on `st run`).")
@dialect
def opcua_symbols(files, map_file, time_unit, f_trig_first_scan):
    """Print what `st run --opcua` publishes: each variable's node, IEC and OPC UA type, access and comment."""
    from .opcua.symbols import MapError, describe, load_map
    from .runtime.plc import PLC

    result = _compile_or_exit(files, time_unit=time_unit, f_trig_first_scan=f_trig_first_scan)
    try:
        rules = load_map(map_file) if map_file else []
        doc = describe(PLC(result), "st", rules)
    except MapError as e:
        click.echo(str(e), err=True)
        sys.exit(2)
    head = ("node", "IEC type", "OPC UA type", "access", "comment")
    body = [
        (f"ns=2;s={n['id']}", n["iec"], n["ua"] + ("[]" if n["dims"] else ""), n["access"], n["desc"])
        for n in doc["nodes"]
        if n["kind"] == "var"
    ]
    widths = [max(len(x[i]) for x in [head] + body) for i in range(len(head))]
    for line in [head] + body:
        click.echo("  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip())


@opcua.command("user")
@click.argument("users_file", type=click.Path(dir_okay=False))
@click.argument("name")
@click.option("--role", type=click.Choice(["read", "operate", "engineer"]), required=True, help="What the user may do.")
@click.option("--password-stdin", is_flag=True, help="Read the password from standard input instead of asking.")
def opcua_user(users_file, name, role, password_stdin):
    """Add a user to an OPC UA users file (made if missing), or change one's role and password."""
    from .opcua.users import UsersError, add_user

    if password_stdin:
        password = sys.stdin.readline().rstrip("\n")
    else:
        password = click.prompt("password", hide_input=True, confirmation_prompt=True)
    if len(password) < 8:
        click.echo("error: the password needs at least 8 characters", err=True)
        sys.exit(2)
    try:
        add_user(users_file, name, role, password)
    except UsersError as e:
        click.echo(str(e), err=True)
        sys.exit(2)
    click.echo(f"{name} ({role}) is in {users_file}")


@main.command("experiment")
@click.argument("name", required=False)
@click.option(
    "--out",
    "out_dir",
    type=OUTPUT_DIR,
    default=None,
    help="Where the CSV, PNG and summary.md go (default: experiments/NAME).",
)
@click.option("--quick", is_flag=True, help="A shortened run (fewer cycles, shorter holds) for a first look.")
@click.option("--seed", type=INTEGER, default=1, show_default=True)
def experiment(name, out_dir, quick, seed):
    """Run one of the thesis's experiments (programs/thesis/README.md); without NAME, list them."""
    from .experiments import EXPERIMENTS
    from .experiments import run as run_experiment

    if not name:
        for key, (_mod, what) in EXPERIMENTS.items():
            click.echo(f"{key:<12}  {what}")
        return
    if name not in EXPERIMENTS:
        raise click.UsageError(f"unknown experiment '{name}' (known: {', '.join(EXPERIMENTS)})")
    out = out_dir or os.path.join("experiments", name)
    if out_dir is None:
        from .app.params import writable_dir

        problem = writable_dir(out)
        if problem:
            raise click.UsageError(f"{out}: {problem} (choose another folder with --out)")
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
    type=INPUT_FILE,
    default=None,
    help="sim: the segment configuration to emulate.",
)
@click.option("--backend", type=click.Choice(["sim", "soem"]), default="sim", show_default=True)
@click.option("--iface", default=None, help="soem: the network interface.")
def ethercat_scan(config_path, backend, iface):
    """List the slaves a master finds, with their identity, state and process-data sizes."""
    from .io.ethercat.master import FrameMaster, MasterError

    if backend == "sim" and not config_path:
        raise click.UsageError("the sim backend needs --config segment.toml")
    if backend == "soem" and not iface:
        raise click.UsageError("the soem backend needs --iface")
    try:
        if backend == "sim":
            from .io.ethercat.config import build_segment

            seg = build_segment(_segment_config_or_exit(config_path))
            clock = [0.0]

            def transport(frame):
                clock[0] += 20e-6
                return seg.exchange(frame, clock[0])

            m = FrameMaster(transport, pause=lambda s: clock.__setitem__(0, clock[0] + s))
        else:
            from .io.ethercat.soem import SoemMaster

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
@click.argument("config_path", type=INPUT_FILE)
@click.option("--cycle", type=DURATION, default=None, help="Cycle time to check, e.g. 1ms (default: the file's).")
def ethercat_plan(config_path, cycle):
    """Frame bytes, wire time at 100 Mbit/s, per-slave and end-to-end delays, and whether the cycle fits."""
    from .io.ethercat.config import ConfigError, build_devices
    from .io.ethercat.plan import SegmentTiming, SlaveTiming, format_plan, plan

    cfg = _segment_config_or_exit(config_path)
    try:
        devices = build_devices(cfg)
        cyc = cycle / 1e9 if cycle else (cfg.cycle_s or 0.001)
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
@click.option("--config", "config_path", type=INPUT_FILE, required=True)
@click.option("--ready-file", type=OUTPUT_FILE, default=None, help="Created once the socket is bound.")
@click.option("--capture", type=OUTPUT_FILE, default=None, help="Write every frame to a pcap file.")
@click.option(
    "--duration", type=DURATION, default=None, help="Stop after this much time, e.g. 10s (default: at SIGTERM)."
)
def ethercat_serve(iface, config_path, ready_file, capture, duration):
    """Serve the emulated segment on a network interface for a real master (SOEM)."""
    from .io.ethercat.config import build_segment
    from .io.ethercat.serve import serve

    seg = build_segment(_segment_config_or_exit(config_path))
    if capture:
        seg.open_capture(capture)
    try:
        n = serve(
            iface,
            seg,
            ready_file=ready_file,
            announce=lambda m: click.echo(m, err=True),
            duration=duration / 1e9 if duration else 0.0,
        )
    except PermissionError:
        click.echo(f"error: opening a raw socket on {iface} needs root or CAP_NET_RAW", err=True)
        sys.exit(2)
    except OSError as e:
        click.echo(f"error: {iface}: {e.strerror or e}", err=True)
        sys.exit(2)
    click.echo(f"answered {n} frame(s)", err=True)


if __name__ == "__main__":
    main()
