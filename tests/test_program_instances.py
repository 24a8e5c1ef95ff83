"""A PROGRAM used by its name (CODESYS, TwinCAT; issue 34): `Prg()` runs the program's one
instance, `Prg.x` reads and writes its variables, `Prg.M()` calls its method; the task that runs
the program runs that same instance. IEC 61131-3 and MatIEC have no such thing (E044)."""

from __future__ import annotations

from st import PLC
from st.api import compile_text

import helpers

PROGRAMS = """
PROGRAM Counter
VAR
  n : INT;
  step : INT := 2;
END_VAR
n := n + step;
END_PROGRAM

PROGRAM Roots
VAR
  calls : INT;
END_VAR
METHOD Twice : LREAL
VAR_INPUT x : LREAL; END_VAR
calls := calls + 1;
Twice := 2.0 * x;
END_METHOD
END_PROGRAM

PROGRAM MAIN
VAR
  seen : INT;
  r : LREAL;
END_VAR
Counter();
seen := Counter.n;
r := Roots.Twice(x := 1.5);
Counter.step := 3;
END_PROGRAM
"""


def test_a_program_called_by_name_runs_once_per_call_and_is_not_a_task_of_its_own():
    for dialect in ("twincat", "codesys", None):
        plc = helpers.run(PROGRAMS, 3, dialect)
        # scan 1: n = 2 (step 2), then step := 3; scans 2 and 3: n = 5, 8 (only MAIN calls Counter)
        assert plc["MAIN.seen"] == 8 and plc["Counter.n"] == 8 and plc["Counter.step"] == 3
        assert plc["MAIN.r"] == 3.0 and plc["Roots.calls"] == 3
        assert sorted(plc.instances) == ["main", "roots"]  # Roots has a task of its own (nobody calls it)


def test_the_task_runs_the_instance_code_names():
    src = """
PROGRAM Worker
VAR ticks : INT; END_VAR
ticks := ticks + 1;
END_PROGRAM

PROGRAM Watcher
VAR last : INT; END_VAR
last := Worker.ticks;
END_PROGRAM

CONFIGURATION Cell
  RESOURCE R ON PLC
    TASK Fast (INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM Worker WITH Fast : Worker;
    PROGRAM Watcher WITH Fast : Watcher;
    PROGRAM Other WITH Fast : Worker;
  END_RESOURCE
END_CONFIGURATION
"""
    plc = helpers.run(src, 4, "twincat")
    # Worker runs first in each tick: Watcher sees this tick's count; `Other` is an instance of its own
    assert plc["Worker.ticks"] == 4 and plc["Watcher.last"] == 4 and plc["Other.ticks"] == 4
    plc["Worker.ticks"] = 10
    plc.scan(1)
    assert plc["Watcher.last"] == 11 and plc["Other.ticks"] == 5


def test_a_library_program_and_its_method_are_reached_by_name():
    lib = """
PROGRAM INTERNAL Poly
VAR
  evaluations : DINT;
END_VAR
METHOD Eval : LREAL
VAR_INPUT x : LREAL; END_VAR
evaluations := evaluations + 1;
Eval := x * x - 2.0;
END_METHOD
END_PROGRAM
"""
    main = helpers.program("y := Poly.Eval(x := 3.0); n := Poly.evaluations;", "y : LREAL; n : DINT;")
    plc = helpers.run(lib + main, 2, "twincat")
    assert plc["main.y"] == 7.0 and plc["main.n"] == 2


def test_online_change_keeps_the_program_instance_state():
    plc = PLC(compile_text(PROGRAMS, "p.st", dialect="twincat", use_cache=False))
    plc.scan(3)
    plc.online_change(compile_text(PROGRAMS.replace("2.0 * x", "4.0 * x"), "p.st", dialect="twincat", use_cache=False))
    plc.scan(1)
    assert plc["Counter.n"] == 11 and plc["MAIN.seen"] == 11 and plc["MAIN.r"] == 6.0


def test_iec_and_openplc_refuse_a_program_used_by_name():
    for dialect in ("iec", "openplc"):
        text = helpers.errors(PROGRAMS.replace("METHOD Twice", "(*").replace("END_METHOD", "*)"), dialect)
        assert f"27:9: error[E044]: a PROGRAM used by its name (its instance) is not part of the {dialect}" in text
        assert "26:1: error[E020]: 'Counter' is a PROGRAM type; declare an instance and call that" in text
