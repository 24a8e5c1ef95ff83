"""What the OPC UA server publishes (st/opcua/symbols.py) and its users file (st/opcua/users.py):
no server here, the address space's description and the files only."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from st import PLC
from st.opcua.symbols import MapError, describe, load_map
from st.opcua.users import UsersError, add_user, hash_password, load_users, verify_password

SRC = """
TYPE Color : (Red, Green := 5, Blue); END_TYPE
TYPE Pt : STRUCT x : REAL; y : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL
  g_count : DINT := 3; (* parts made today *)
END_VAR
{attribute 'symbol' := 'read'}
FUNCTION_BLOCK Blk
VAR_INPUT go : BOOL; END_VAR
VAR_OUTPUT done : BOOL; END_VAR
VAR inner : INT; END_VAR
done := go;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Plain
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT b : INT; END_VAR
VAR hidden : INT; END_VAR
b := a;
END_FUNCTION_BLOCK
PROGRAM main
VAR_INPUT inp : INT; (* the operator's set-point *) END_VAR
VAR_OUTPUT outp : BOOL; END_VAR
VAR
  {attribute 'symbol' := 'readwrite'}
  c : Color := Blue;
  // how long the last cycle took
  t : TIME := T#1s500ms;
  a : ARRAY[1..3] OF INT := [1, 2, 3];
  {attribute 'symbol' := 'read'}
  p : Pt;
  b : Blk;
  {attribute 'symbol' := 'read'}
  q : Plain;
  lamp AT %QX0.1 : BOOL;
  r : INT(0..100) := 5;
  s : STRING[10];
  {attribute 'symbol' := 'none'}
  secret AT %MW4 : INT;
END_VAR
outp := NOT outp;
END_PROGRAM
CONFIGURATION c RESOURCE r ON PLC TASK t(INTERVAL := T#10ms); PROGRAM main WITH t : main; END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module")
def plc(tmp_path_factory):
    path = tmp_path_factory.mktemp("opcua") / "cell.st"
    path.write_text(SRC)
    return PLC.from_files(str(path))


def _vars(doc):
    return {n["id"]: n for n in doc["nodes"] if n["kind"] == "var"}


def test_defaults_attributes_and_inheritance(plc):
    doc = describe(plc, "cell")
    vs = _vars(doc)
    # program inputs/outputs, located variables and globals: read; what an attribute says otherwise
    assert {k: v["access"] for k, v in vs.items()} == {
        "main.inp": "read",
        "main.outp": "read",
        "main.c": "readwrite",  # its own attribute
        "main.p.x": "read",  # a structure passes its access to every member
        "main.p.y": "read",
        "main.b.go": "read",  # Blk's POU attribute covers its variables, internal ones too
        "main.b.done": "read",
        "main.b.inner": "read",
        "main.q.a": "read",  # a block instance passes its access to its inputs and outputs only
        "main.q.b": "read",
        "main.lamp": "read",
        "g_count": "read",
        "%QX0.1": "read",  # the located variable under Located, by its address
    }
    assert "main.r" not in vs and "main.secret" not in vs and "main.q.hidden" not in vs


def test_types_comments_and_folders(plc):
    doc = describe(plc, "cell", [("main.*", "read")])
    vs = _vars(doc)
    assert (vs["main.inp"]["ua"], vs["main.inp"]["iec"], vs["main.inp"]["desc"]) == (
        "Int16",
        "INT",
        "the operator's set-point",
    )
    assert (vs["main.t"]["ua"], vs["main.t"]["desc"]) == ("Duration", "how long the last cycle took")
    assert vs["g_count"]["desc"] == "parts made today"
    assert (vs["main.c"]["ua"], vs["main.c"]["enum"]) == ("Int32", [[0, "Red"], [5, "Green"], [6, "Blue"]])
    assert (vs["main.a"]["ua"], vs["main.a"]["dims"], vs["main.a"]["lo"]) == ("Int16", [3], [1])
    assert (vs["main.r"]["range"], vs["main.s"]["ua"], vs["main.s"]["length"]) == ([0, 100], "String", 10)
    folders = [n["id"] for n in doc["nodes"] if n["kind"] == "folder"]
    assert folders == ["Programs", "Globals", "Located"]
    parents = {n["id"]: n["parent"] for n in doc["nodes"]}
    assert (parents["main"], parents["main.p"], parents["main.p.x"], parents["%QX0.1"]) == (
        "Programs",
        "main",
        "main.p",
        "Located",
    )


def test_map_wins_last_pattern_first(plc, tmp_path):
    f = tmp_path / "map.toml"
    f.write_text('[symbols]\n"main.*" = "read"\n"MAIN.R" = "readwrite"\n"main.c" = "none"\n"main.secret" = "read"\n')
    rules = load_map(str(f))
    vs = _vars(describe(plc, "cell", rules))
    assert (vs["main.r"]["access"], vs["main.secret"]["access"]) == ("readwrite", "read")
    assert "main.c" not in vs  # the map overrides the declaration's attribute
    assert vs["main.q.hidden"]["access"] == "read"


def test_map_errors_name_the_file(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('[symbols]\n"main.x" = "write"\n')
    with pytest.raises(MapError, match=r"bad.toml: 'main.x' = 'write': the access is one of read, readwrite, none"):
        load_map(str(f))
    f.write_text('"main.x" = "read"\n')
    with pytest.raises(MapError, match=r"expected a \[symbols\] table"):
        load_map(str(f))


def test_users_file(tmp_path):
    f = str(tmp_path / "users")
    add_user(f, "alice", "operate", "correct horse")
    add_user(f, "bob", "read", "battery staple")
    add_user(f, "alice", "engineer", "new password")
    users = load_users(f)
    assert {n: r for n, (r, _h) in users.items()} == {"alice": "engineer", "bob": "read"}
    assert verify_password("new password", users["alice"][1])
    assert not verify_password("correct horse", users["alice"][1])
    assert "new password" not in Path(f).read_text()
    assert Path(f).stat().st_mode & 0o777 == 0o600
    h = hash_password("x")
    assert h.startswith("scrypt$16384$8$1$") and h != hash_password("x")  # salted
    Path(f).write_text("# users\nalice:admin:scrypt$1$2$3$4$5\n")
    with pytest.raises(UsersError, match=r"users:2: expected NAME:ROLE:HASH"):
        load_users(f)


def test_symbol_attribute_is_not_reported_as_ignored(tmp_path):
    path = tmp_path / "p.st"
    path.write_text(SRC)
    out = subprocess.run([sys.executable, "-m", "st.cli", "check", str(path)], capture_output=True, text=True)
    assert "W001" not in out.stdout + out.stderr
    assert out.returncode == 0


def test_cli_symbols_and_user(tmp_path):
    path = tmp_path / "p.st"
    path.write_text(SRC)
    out = subprocess.run(
        [sys.executable, "-m", "st.cli", "opcua", "symbols", str(path)], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert out[0].split() == ["node", "IEC", "type", "OPC", "UA", "type", "access", "comment"]
    assert "ns=2;s=main.inp      INT       Int16        read       the operator's set-point" in out
    users = tmp_path / "users"
    r = subprocess.run(
        [sys.executable, "-m", "st.cli", "opcua", "user", str(users), "ann", "--role", "operate", "--password-stdin"],
        input="long enough\n",
        capture_output=True,
        text=True,
    )
    assert (r.returncode, r.stdout.strip()) == (0, f"ann (operate) is in {users}")
    assert verify_password("long enough", load_users(str(users))["ann"][1])
    r = subprocess.run(
        [sys.executable, "-m", "st.cli", "opcua", "user", str(users), "ann", "--role", "read", "--password-stdin"],
        input="short\n",
        capture_output=True,
        text=True,
    )
    assert (r.returncode, r.stderr.strip()) == (2, "error: the password needs at least 8 characters")


def test_run_refuses_a_server_nobody_could_sign_in_to(tmp_path):
    path = tmp_path / "p.st"
    path.write_text(SRC)
    r = subprocess.run(
        [sys.executable, "-m", "st.cli", "run", str(path), "--opcua", "127.0.0.1:0", "--virtual", "--scans", "3"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2
    assert r.stderr.strip().splitlines()[-1] == (
        "error: cannot start the OPC UA server: no client could sign in: give --opcua-users FILE "
        "(st opcua user adds one) or --opcua-anonymous"
    )
    r = subprocess.run(
        [sys.executable, "-m", "st.cli", "run", str(path), "--opcua-anonymous", "--virtual", "--scans", "3"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2 and "--opcua-anonymous" in r.stderr and "--opcua" in r.stderr
