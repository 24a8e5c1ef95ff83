"""The OPC UA server with an independent client: node-opcua (tests/opcua_node/client.js), over
SignAndEncrypt + Basic256Sha256 with a user name and password. The client is refused first (its
certificate is unknown: the server saves it to PKI/rejected/), trusted by moving that file to
PKI/trusted/, and then browses, reads, subscribes and writes; it prints one JSON object, checked
here. Skipped with a reason without `node`, or without node-opcua when `npm` cannot install it
(`npm install --prefix tests/opcua_node`, about 20 s the first time)."""

from __future__ import annotations

import json
import shutil
import subprocess
import threading
import time
from pathlib import Path

import pytest

from st import PLC
from st.opcua import OpcUaServer
from st.opcua.users import add_user

pytestmark = pytest.mark.slow

CLIENT_DIR = Path(__file__).parent / "opcua_node"
CLIENT = CLIENT_DIR / "client.js"
NODE_MIN = (18, 0)  # node-opcua 2.182's `engines`

SRC = """
PROGRAM main
VAR_INPUT setpoint : INT := 5; END_VAR
VAR_OUTPUT counter : DINT; level : REAL := 1.5; END_VAR
counter := counter + 1;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC TASK t(INTERVAL := T#10ms); PROGRAM main WITH t : main; END_RESOURCE
END_CONFIGURATION
"""
MAP = """[symbols]
"main.setpoint" = "readwrite"
"""


def _installed() -> bool:
    modules = CLIENT_DIR / "node_modules"
    return all((modules / name / "package.json").is_file() for name in ("node-opcua", "node-opcua-client"))


@pytest.fixture(scope="module")
def node() -> str:
    """The `node` executable, with node-opcua installed beside client.js (installed here if absent)."""
    exe = shutil.which("node")
    if exe is None:
        pytest.skip("node is not installed (the node-opcua client needs Node.js)")
    version = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=30).stdout.strip()
    try:
        major, minor = (int(x) for x in version.lstrip("v").split(".")[:2])
    except ValueError:
        pytest.skip(f"cannot tell node's version from {version!r}")
    if (major, minor) < NODE_MIN:
        pytest.skip(f"node {version} is older than node-opcua needs ({'.'.join(map(str, NODE_MIN))})")
    if not _installed():
        npm = shutil.which("npm")
        if npm is None:
            pytest.skip("tests/opcua_node/node_modules is absent and npm is not installed to install node-opcua")
        # (no package-lock.json: the version is pinned in package.json, nothing is left beside it)
        cmd = [npm, "install", "--prefix", str(CLIENT_DIR), "--no-audit", "--no-fund", "--no-package-lock"]
        try:
            got = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        except subprocess.TimeoutExpired:
            pytest.skip("npm install of node-opcua took more than 600 s")
        if got.returncode != 0 or not _installed():
            tail = (got.stderr or got.stdout).strip().splitlines()[-5:]
            pytest.skip(f"npm install of node-opcua failed ({got.returncode}): {' | '.join(tail)}")
    return exe


def _client(node: str, endpoint: str, pki: Path, client_pki: Path, *extra: str) -> tuple[int, dict, str]:
    """Run client.js; (exit code, its JSON object, its stderr)."""
    cmd = [node, str(CLIENT), endpoint, "op", "secret123", str(pki), str(client_pki), *extra]
    got = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=CLIENT_DIR)
    lines = [line for line in got.stdout.splitlines() if line.startswith("{")]
    assert len(lines) == 1, f"expected one JSON object on stdout:\n{got.stdout}\n{got.stderr[-3000:]}"
    return got.returncode, json.loads(lines[0]), got.stderr


def test_node_opcua_client(node, tmp_path):
    src = tmp_path / "main.st"
    src.write_text(SRC)
    (tmp_path / "map.toml").write_text(MAP)
    users = tmp_path / "users"
    add_user(str(users), "op", "operate", "secret123")
    pki, client_pki = tmp_path / "pki", tmp_path / "client_pki"
    plc = PLC.from_files(str(src))
    srv = OpcUaServer(
        plc,
        "127.0.0.1",
        0,
        users=str(users),
        security=("sign", "encrypt"),
        pki=str(pki),
        map_file=str(tmp_path / "map.toml"),
    )
    srv.start()
    stop = threading.Event()
    th = threading.Thread(target=lambda: plc.run_realtime(duration="60s", on_idle=lambda p: srv.poll(), stop=stop))
    th.start()
    try:
        # 1. an unknown client certificate: refused, and kept in rejected/ for the administrator
        rc, first, err = _client(node, srv.endpoint, pki, client_pki, "--expect-untrusted")
        assert rc == 0, (first, err[-3000:])
        assert "BadCertificateUntrusted" in first["error"]
        rejected = list((pki / "rejected").iterdir())
        assert [p.name.startswith("st-node-opcua-test-") and p.suffix == ".der" for p in rejected] == [True]

        # 2. trusted by moving it to trusted/ (no restart): the whole session
        rejected[0].rename(pki / "trusted" / rejected[0].name)
        rc, got, err = _client(node, srv.endpoint, pki, client_pki)
        assert rc == 0, (got, err[-3000:])
        assert got["connected"] is True
        assert got["security"] == {
            "mode": "SignAndEncrypt",
            "policy": "http://opcfoundation.org/UA/SecurityPolicy#Basic256Sha256",
        }
        assert got["namespace_index"] == 2
        assert {"PLC", "Programs", "Globals"} <= set(got["objects"])
        assert got["programs"] == ["main"]
        assert got["main_node"] == "ns=2;s=main"
        assert {"setpoint", "counter", "level"} <= set(got["browse"])

        read = got["read"]
        assert read["main.level"]["status"] == "Good"
        assert read["main.level"]["value"] == 1.5
        assert read["main.level"]["dataType"] == "Float"
        assert read["main.setpoint"]["value"] == 5
        assert read["main.setpoint"]["dataType"] == "Int16"
        assert read["main.counter"]["dataType"] == "Int32"
        assert read["main.counter"]["value"] > 0
        assert got["user_access_level"] == {"main.setpoint": 3, "main.counter": 1, "main.level": 1}

        sub = got["subscription"]
        assert sub["revised_publishing_interval"] == 100
        assert sub["notifications"]["main.counter"] >= 5
        assert sub["notifications"]["main.level"] >= 1  # the initial value, then no change
        assert sub["last_values"]["main.counter"] > read["main.counter"]["value"]

        assert got["write"] == {
            "setpoint_int16": "Good",
            "setpoint_int32": "BadTypeMismatch",
            "counter_int32": "BadNotWritable",
        }
        assert got["read_back"]["value"] == 42

        deadline = time.monotonic() + 2.0
        while plc["main.setpoint"] != 42 and time.monotonic() < deadline:
            time.sleep(0.02)
        assert plc["main.setpoint"] == 42
    finally:
        stop.set()
        th.join()
        srv.stop()
    texts = [m.text for m in plc.log.since(0)]
    assert any("client certificate of 'st-node-opcua-test' refused (untrusted)" in t for t in texts), texts
    writes = [t for t in texts if "opcua op" in t and "write main.setpoint := 42" in t]
    assert len(writes) == 1, texts
    assert not any("write main.setpoint := 43" in t or "write main.counter" in t for t in texts), texts
