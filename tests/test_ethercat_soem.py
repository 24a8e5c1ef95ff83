"""The `soem` backend (pysoem) against the emulated segment served on one end of a veth pair:
SOEM brings it to OP, reads SDOs, exchanges process data, and `st run` moves an axis with it.
Needs root (raw sockets, creating the veth pair) and pysoem; skipped with the reason otherwise."""

import json
import os
import shutil
import struct
import subprocess
import sys
import time

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SEGMENT = """
[segment]
cycle = "4ms"
dc = true

[[slave]]
name = "x"
type = "cia402"
axis = 1
"""

PROGRAM = """
PROGRAM main
  VAR
    ax : AXIS_REF := (AxisNo := 1);
    pw : MC_Power;
    mv : MC_MoveAbsolute;
    pos : MC_ReadActualPosition;
    status : MC_ReadStatus;
    actual : LREAL;
    moved : BOOL;
  END_VAR
  pw(Axis := ax, Enable := TRUE);
  status(Axis := ax, Enable := TRUE);
  mv(Axis := ax, Execute := pw.Status AND status.Standstill AND NOT moved, Position := 90.0, Velocity := 180.0,
     Acceleration := 1800.0, Deceleration := 1800.0);
  IF mv.Done THEN moved := TRUE; END_IF;
  pos(Axis := ax, Enable := TRUE);
  actual := pos.Position;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC
  TASK t (INTERVAL := T#4ms, PRIORITY := 1);
  PROGRAM main WITH t : main;
END_RESOURCE END_CONFIGURATION
"""


def _why_not() -> str:
    if os.geteuid() != 0:
        return "needs root for raw sockets and a veth pair"
    try:
        import pysoem  # noqa: F401
    except ImportError:
        return "pysoem is not installed (pip install pysoem)"
    if shutil.which("ip") is None:
        return "the ip command (iproute2) is missing"
    return ""


pytestmark = pytest.mark.skipif(bool(_why_not()), reason=_why_not() or "ok")


@pytest.fixture
def served(tmp_path):
    """A veth pair with the emulated segment answering on one end; yields the master's end."""
    tag = f"{os.getpid() % 10000}"
    master_if, slave_if = f"ecm{tag}", f"ecs{tag}"
    made = subprocess.run(
        ["ip", "link", "add", master_if, "type", "veth", "peer", "name", slave_if], capture_output=True, text=True
    )
    if made.returncode:
        pytest.skip(f"cannot create a veth pair: {made.stderr.strip()}")
    for i in (master_if, slave_if):
        subprocess.run(["ip", "link", "set", i, "up"], check=True)
    cfg = tmp_path / "segment.toml"
    cfg.write_text(SEGMENT)
    ready = tmp_path / "ready"
    cap = tmp_path / "served.pcap"
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "st",
            "ethercat",
            "serve",
            "--iface",
            slave_if,
            "--config",
            str(cfg),
            "--ready-file",
            str(ready),
            "--capture",
            str(cap),
        ],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        for _ in range(200):
            if ready.exists() or server.poll() is not None:
                break
            time.sleep(0.05)
        assert ready.exists(), server.stderr.read() if server.poll() is not None else "no ready file"
        yield master_if, cfg, cap
    finally:
        server.terminate()
        try:
            server.wait(5)
        except subprocess.TimeoutExpired:
            server.kill()
        subprocess.run(["ip", "link", "del", master_if], capture_output=True)


@pytest.mark.slow
def test_soem_reaches_op_reads_sdo_and_exchanges_process_data(served):
    from st.io.ethercat.driver import drive_state
    from st.io.ethercat.pdo import CIA402_RX, CIA402_TX, PdoLayout
    from st.io.ethercat.soem import SoemMaster

    iface, _cfg, cap = served
    m = SoemMaster(iface)
    m.open()
    try:
        [s] = m.scan()
        assert (s.vendor_id, s.product_code) == (0x66F, 0x60380004)
        m.configure(dc_cycle_ns=4_000_000)
        assert m.states() == ["SAFEOP"] and m.expected_wkc == 3
        assert (m.slaves[0].out_bytes, m.slaves[0].in_bytes) == (11, 12)
        m.set_state("OP")
        assert m.sdo_read(0, 0x1018, 2) == struct.pack("<I", 0x60380004)
        assert m.sdo_read(0, 0x608F, 1) == struct.pack("<I", 1 << 23)
        rx, tx = PdoLayout(CIA402_RX), PdoLayout(CIA402_TX)
        wkcs = []
        status = 0
        # the CiA 402 enable sequence, each command sent until the statusword shows its state
        # (outputs take effect at SYNC0 pulses, which SOEM starts some 100 ms after configuring DC)
        for _ in range(300):
            state = drive_state(status)
            if state == "OPERATION_ENABLED":
                break
            cw = {"SWITCH_ON_DISABLED": 0x06, "READY_TO_SWITCH_ON": 0x07}.get(
                state, 0x0F if state == "SWITCHED_ON" else 0x06
            )
            m.write_outputs(0, rx.pack([cw, 0, 0, 8]))
            wkcs.append(m.exchange())
            status = tx.unpack(m.read_inputs(0))[0]
            time.sleep(0.004)
        assert status & 0x6F == 0x27  # Operation enabled
        assert wkcs.count(3) >= len(wkcs) - 3  # single misses tolerated
    finally:
        m.close()


@pytest.mark.slow
def test_st_run_moves_an_axis_through_soem(served, tmp_path):
    iface, cfg, cap = served
    prog = tmp_path / "move.st"
    prog.write_text(PROGRAM)
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "st",
            "run",
            str(prog),
            "--ethercat",
            str(cfg),
            "--ethercat-backend",
            "soem",
            "--ethercat-iface",
            iface,
            "--duration",
            "2.5s",
            "--no-rt",
            "--quiet",
            "--dump-json",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    v = json.loads(out.stdout)
    assert v["main.moved"] is True
    assert v["main.actual"] == pytest.approx(90.0, abs=0.01)


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("tshark") is None, reason="tshark is not installed")
def test_the_served_capture_decodes_in_tshark(served):
    from st.io.ethercat.soem import SoemMaster

    iface, _cfg, cap = served
    m = SoemMaster(iface)
    m.open()
    m.scan()
    m.configure()
    m.set_state("OP")
    for _ in range(50):
        m.exchange()
    m.close()
    time.sleep(0.3)
    out = subprocess.run(
        ["tshark", "-r", str(cap), "-T", "fields", "-e", "_ws.col.Protocol", "-e", "_ws.col.Info"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    lines = out.stdout.splitlines()
    assert len(lines) > 100 and not [x for x in lines if "Malformed" in x]
