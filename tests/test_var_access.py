"""VAR_ACCESS (IEC 61131-3, 2nd edition on): a configuration's or resource's access paths, names under
which a variable is reached from outside the program (plc["name"], an HMI, the online mode), READ_ONLY
unless declared READ_WRITE. The checker's refusals: tests/fixtures/errors (E010, E011, E060)."""

from __future__ import annotations

import pytest

from st.runtime.values import ValueError_

from helpers import run

ACCESS = """
TYPE Pt : STRUCT x : INT; y : INT; END_STRUCT END_TYPE
PROGRAM P1
VAR x : INT; p : Pt; sensor AT %IX0.1 : BOOL; END_VAR
x := x + 1;
p.y := x * 2;
END_PROGRAM
CONFIGURATION C
VAR_GLOBAL g : DINT := 5; END_VAR
RESOURCE R ON PLC
TASK t(INTERVAL := T#10ms);
PROGRAM inst WITH t : P1;
VAR_ACCESS
  level : inst.x : INT READ_WRITE;
END_VAR
END_RESOURCE
VAR_ACCESS
  counter : R.inst.x : INT READ_ONLY;
  point : R.inst.p : Pt;
  doubled : inst.p.y : INT;
  gain : g : DINT READ_WRITE;
  flag : R.%IX0.1 : BOOL;
END_VAR
END_CONFIGURATION
"""


@pytest.mark.parametrize("dialect", [None, "iec", "openplc", "codesys", "twincat"])
def test_access_paths_read_the_variables_they_name(dialect):
    plc = run(ACCESS, 3, dialect)
    got = [plc[n] for n in ("counter", "point.y", "doubled", "gain", "flag", "level")]
    assert got == [3, 6, 6, 5, False, 3]
    assert plc["point"] == {"x": 0, "y": 6}


def test_read_write_access_paths_write_and_force_read_only_ones_refuse():
    plc = run(ACCESS, 1)
    plc["level"] = 100
    plc["gain"] = 7
    assert (plc["inst.x"], plc["g"]) == (100, 7)
    for name in ("counter", "point.y", "flag"):
        with pytest.raises(ValueError_, match=f"'{name.split('.')[0]}' is a READ_ONLY access path"):
            plc[name] = 1
    with pytest.raises(ValueError_, match="READ_ONLY"):
        plc.force("counter", 9)
    plc.force("level", 42)
    plc.scan(2)
    assert plc["counter"] == 42  # forced through its READ_WRITE name
    plc.unforce("level")
    plc["%IX0.1"] = True
    plc.scan(1)
    assert plc["flag"] is True  # a located variable's access path reads the variable
