"""One `st run` is a stack of parts (st/app/subsystems.py), each registering its own clean-up: whatever
fails, at whatever point, closes what had started before it (the PLC first, then the drivers it
drove, then real time and the signal handlers), and the user sees the same one error line and exit
status as before. In process with click's CliRunner; every part the run starts is recorded."""

from __future__ import annotations

import signal
import socket
from pathlib import Path

import pytest
from click.testing import CliRunner

import st.app.session as session
import st.app.subsystems as subsystems
import st.io.ethercat as ethercat
import st.io.modbus as modbus
import st.web.link as weblink
from st.cli import main

ROOT = Path(__file__).resolve().parents[1]
GANTRY = [
    str(ROOT / "programs" / "gantry.st"),
    "--ethercat",
    str(ROOT / "programs" / "gantry.segment.toml"),
    "--axes",
    str(ROOT / "programs" / "gantry.axes.toml"),
]
ECAT_LINE = "ethercat: 3 slave(s) in OP (sim backend), 2 drive(s) bound"


class Seen:
    def __init__(self):
        self.events: list[str] = []  # what was closed, in order
        self.plcs: list = []
        self.ethercat: list = []
        self.modbus: list = []
        self.web: list = []


@pytest.fixture
def seen(monkeypatch):
    """The PLC, EtherCAT, the Modbus slave and the web link of the runs, recorded as they start and close
    (subclasses of the real ones: everything starts and closes for real)."""
    log = Seen()

    class PLC(subsystems.PLC):
        def __init__(self, *a, **k):
            super().__init__(*a, **k)
            log.plcs.append(self)

        def close(self):
            log.events.append("plc.close")
            super().close()

    class EtherCATDriver(ethercat.EtherCATDriver):
        def __init__(self, *a, **k):
            log.ethercat.append(self)  # (before its start: a start that fails is seen too)
            self.closed = False
            super().__init__(*a, **k)

        def close(self):
            log.events.append("ethercat.close")
            super().close()
            self.closed = True

    class ModbusSlave(modbus.ModbusSlave):
        def start(self, timeout=10.0):
            log.modbus.append(self)
            return super().start(timeout)

        def stop(self):
            if self.ex is not None:  # what was open: its process and its shared memory
                log.events.append("modbus.stop")
                self.was = (self.proc, self.ex.name, self.ex.port)
            super().stop()

    class WebLink(weblink.WebLink):
        def start(self, timeout=10.0):
            log.web.append(self)
            return super().start(timeout)

        def stop(self):
            if self.ch is not None:
                log.events.append("web.stop")
                self.was = (self.proc, self.ch.name)
            super().stop()

    monkeypatch.setattr(subsystems, "PLC", PLC)
    monkeypatch.setattr(ethercat, "EtherCATDriver", EtherCATDriver)
    monkeypatch.setattr(modbus, "ModbusSlave", ModbusSlave)
    monkeypatch.setattr(weblink, "WebLink", WebLink)
    return log


@pytest.fixture
def taken():
    """A port of 127.0.0.1 that another program listens on."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield s.getsockname()[1]


def st_run(*args):
    return CliRunner().invoke(main, ["run", *[str(a) for a in args]])


def gone(proc, shm_name: str) -> bool:
    """The server process has ended (and was waited for) and its shared memory is unlinked."""
    return proc is not None and proc.poll() is not None and not Path("/dev/shm", shm_name).exists()


def closed_plc(plc) -> bool:
    return plc.state != "RUN" and plc.retain_store is None


# ---------------------------------------------------------------------------- a part that cannot start


def test_a_taken_modbus_port_closes_ethercat_and_the_plc(seen, taken):
    r = st_run(*GANTRY, "--modbus", f"127.0.0.1:{taken}", "--virtual", "--duration", "1s")
    assert (r.exit_code, r.stdout) == (2, "")
    assert r.stderr.splitlines() == [
        ECAT_LINE,
        f"error: cannot start the Modbus slave: the Modbus server could not listen on 127.0.0.1:{taken} "
        "(address in use?)",
    ]
    (slave,) = seen.modbus
    assert gone(*slave.was[:2])  # its own start stopped it: nothing left for the stack
    # the PLC stops first (its safe outputs go out through EtherCAT), then EtherCAT closes
    assert seen.events == ["modbus.stop", "plc.close", "ethercat.close"]
    (ecat,) = seen.ethercat
    assert ecat.closed
    assert closed_plc(seen.plcs[0])


def test_a_taken_web_port_closes_modbus_ethercat_and_the_plc(seen, taken, tmp_path):
    capture = tmp_path / "segment.pcap"
    r = st_run(*GANTRY, "--ethercat-capture", capture, "--modbus", "127.0.0.1:0", "--web", f"127.0.0.1:{taken}")
    assert (r.exit_code, r.stdout) == (2, "")
    (slave,) = seen.modbus
    assert r.stderr.splitlines() == [
        ECAT_LINE,
        f"modbus: serving on 127.0.0.1:{slave.was[2]} (OpenPLC map)",
        f"error: cannot start the web server: the web server could not listen on 127.0.0.1:{taken} (address in use?)",
    ]
    assert seen.events == ["web.stop", "plc.close", "modbus.stop", "ethercat.close"]
    (web,) = seen.web
    assert gone(*web.was)
    assert gone(*slave.was[:2])
    (ecat,) = seen.ethercat
    assert ecat.closed and ecat.segment.capture is None  # the emulated segment closed: its capture written
    assert capture.stat().st_size > 0
    assert closed_plc(seen.plcs[0])


def test_a_modbus_map_that_is_wrong_closes_ethercat(seen, tmp_path):
    bad = tmp_path / "map.toml"
    bad.write_text("[[holding]]\naddress = 0\nvariable = 'gantry.x'\n")
    r = st_run(*GANTRY, "--modbus", "127.0.0.1:0", "--modbus-map", bad, "--virtual", "--duration", "1s")
    assert (r.exit_code, r.stdout) == (2, "")
    assert r.stderr.splitlines() == [
        ECAT_LINE,
        f"{bad}:1:3: error: unknown section 'holding' (use [[register]] entries)",
    ]
    assert seen.modbus == []  # refused before its server was started
    assert seen.events == ["plc.close", "ethercat.close"]
    assert seen.ethercat[0].closed


def test_an_invalid_axes_file_refuses_the_run_before_ethercat_starts(seen, tmp_path):
    """The axes are configured before EtherCAT starts (a drive binds to its configured axis): an invalid
    --axes file leaves nothing but the PLC to close."""
    bad = tmp_path / "axes.toml"
    bad.write_text("[[axis]]\nno = 1\nmax_velocty = 5.0\n")
    args = [*GANTRY[:3], "--axes", bad, "--modbus", "127.0.0.1:0", "--virtual", "--duration", "1s"]
    r = st_run(*args)
    assert (r.exit_code, r.stdout) == (2, "")
    (line,) = r.stderr.splitlines()
    assert line.startswith(f"error: {bad}: axis 1: unknown setting 'max_velocty' (known: buffer_size, ")
    assert (seen.ethercat, seen.modbus, seen.events) == ([], [], ["plc.close"])


def test_a_segment_that_names_no_task_of_the_program_closes_the_plc(seen, tmp_path):
    seg = tmp_path / "segment.toml"
    seg.write_text(
        (ROOT / "programs" / "gantry.segment.toml").read_text().replace("[segment]", "[segment]\ntask = 'x'")
    )
    r = st_run(GANTRY[0], "--ethercat", seg, "--modbus", "127.0.0.1:0", "--virtual", "--duration", "1s")
    assert (r.exit_code, r.stdout) == (2, "")
    assert r.stderr == f"error: {seg}: [segment] task 'x' is not a task of the program (Motion)\n"
    assert seen.modbus == [] and seen.events == ["plc.close"]


def test_nothing_to_run_closes_the_retained_data_store(seen, tmp_path):
    src = tmp_path / "fb.st"
    src.write_text("FUNCTION_BLOCK F\nVAR RETAIN n : INT; END_VAR\nn := n + 1;\nEND_FUNCTION_BLOCK\n")
    r = st_run(src, "--retain", tmp_path / "r.db", "--virtual", "--scans", "3")
    assert (r.exit_code, r.stderr) == (2, "error: nothing to run: no PROGRAM and no CONFIGURATION\n")
    assert seen.events == ["plc.close"] and closed_plc(seen.plcs[0])


def test_an_unknown_task_of_sim_cost_closes_the_plc(seen):
    r = st_run(GANTRY[0], "--virtual", "--scans", "3", "--sim-cost", "nosuch=1ms")
    assert (r.exit_code, r.stderr) == (2, "error: cannot start the PLC: \"no task named 'nosuch'\"\n")
    assert seen.events == ["plc.close"]


# ---------------------------------------------------------------------------- the end of a run, clean or not


def test_a_clean_run_closes_the_plc_then_its_drivers_then_reports(seen):
    before = signal.getsignal(signal.SIGINT)
    r = st_run(*GANTRY, "--modbus", "127.0.0.1:0", "--virtual", "--duration", "1s")
    assert r.exit_code == 0, r.output
    (slave,) = seen.modbus
    lines = r.stderr.splitlines()
    assert lines[:3] == [
        ECAT_LINE,
        f"modbus: serving on 127.0.0.1:{slave.was[2]} (OpenPLC map)",
        "stopped at PLC time 1 s, state STOP",
    ]
    # two frames while starting, one per 1 ms job, and the safe outputs of the stopped PLC (before EtherCAT closed)
    assert lines[3] == "  ethercat: 1003 frames, 0 lost, 0 working-counter errors, 0 outage(s)"
    assert seen.events == ["plc.close", "modbus.stop", "ethercat.close"]
    assert gone(*slave.was[:2])
    assert signal.getsignal(signal.SIGINT) is before


def test_an_exception_while_running_still_closes_everything(seen, monkeypatch):
    before = signal.getsignal(signal.SIGINT)

    def fails(plc, o, stop, *servers):
        assert signal.getsignal(signal.SIGINT) is not before  # the run's handler
        raise RuntimeError("boom")

    monkeypatch.setattr(session, "_run_virtual", fails)
    r = st_run(*GANTRY, "--modbus", "127.0.0.1:0", "--virtual", "--duration", "1s")
    assert isinstance(r.exception, RuntimeError) and str(r.exception) == "boom"
    assert seen.events == ["plc.close", "modbus.stop", "ethercat.close"]
    assert gone(*seen.modbus[0].was[:2])
    assert signal.getsignal(signal.SIGINT) is before


def test_real_time_is_given_back_after_the_drivers_and_before_the_signal_handlers(seen, monkeypatch):
    before = signal.getsignal(signal.SIGINT)

    class Realtime:  # the real one would ask for SCHED_FIFO and lock this test process's memory
        def apply(self, priority, cpu):
            seen.events.append("rt.apply")
            return {"SCHED_FIFO": f"priority {priority}"}

        def release(self):
            seen.events.append("rt.release")
            seen.handler_at_release = signal.getsignal(signal.SIGINT)

    def fails(*a, **k):
        raise RuntimeError("boom")

    monkeypatch.setattr(subsystems, "RealtimeSetup", Realtime)
    monkeypatch.setattr(session, "_run_real", fails)
    r = st_run(*GANTRY, "--modbus", "127.0.0.1:0", "--duration", "1s")
    assert isinstance(r.exception, RuntimeError)
    assert r.stderr.splitlines()[2:] == [
        "real time: SCHED_FIFO priority 30",
        "running in real time: 1 task(s), base tick 1 ms; Ctrl-C stops",
    ]
    assert seen.events == ["rt.apply", "plc.close", "modbus.stop", "ethercat.close", "rt.release"]
    assert seen.handler_at_release is not before  # the signal handlers are put back last
    assert signal.getsignal(signal.SIGINT) is before


def test_ctrl_c_while_starting_closes_what_had_started(seen, monkeypatch):
    def interrupted(stack, plc, o):
        raise KeyboardInterrupt

    monkeypatch.setattr(session, "start_web", interrupted)
    r = st_run(*GANTRY, "--modbus", "127.0.0.1:0", "--web", "127.0.0.1:0", "--duration", "1s")
    assert r.exit_code == 1  # click: "Aborted!"
    assert seen.events == ["plc.close", "modbus.stop", "ethercat.close"]
    assert gone(*seen.modbus[0].was[:2])
