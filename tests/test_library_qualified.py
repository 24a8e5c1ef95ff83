"""A library-qualified block type with FB_init arguments in a declaration (issue 34), as struckig's
users write it: `otg : Struckig.Otg(cycletime := 0.001, dofs := 6);`."""

from __future__ import annotations

import helpers

LIBRARY_BLOCK = """{namespace 'Struckig'}
FUNCTION_BLOCK Otg
VAR cyc : LREAL; n : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; cycletime : LREAL; dofs : INT; END_VAR
cyc := cycletime; n := dofs;
END_METHOD
END_FUNCTION_BLOCK
"""


def test_a_qualified_block_type_takes_fb_init_arguments():
    src = LIBRARY_BLOCK + helpers.program(
        "c := a.cyc + b.cyc; n := a.n * 10 + b.n;",
        "a : Struckig.Otg(cycletime := 0.001, dofs := 6);\n"
        "b : Struckig.Otg(0.002, 3);\nr : INT(1..5) := 2;\nc : LREAL; n : INT;",
    )
    for dialect in ("twincat", "codesys", None):
        plc = helpers.run(src, 1, dialect)
        assert plc["main.c"] == 0.003 and plc["main.n"] == 63 and plc["main.r"] == 2


def test_an_unknown_qualifier_is_named():
    text = helpers.errors(helpers.program("", "a : Nowhere.Otg(cycletime := 0.001);"), "twincat")
    assert "t.st:4:5: error[E012]: 'Nowhere.Otg': no library 'Nowhere' is available" in text


def test_a_qualified_type_behind_pointer_to_and_reference_to():
    """struckig's benchmark: `otg : REFERENCE TO Struckig.Otg;` (the pass that drops qualifiers
    skipped the types a POINTER TO / REFERENCE TO points at)."""
    src = (
        LIBRARY_BLOCK
        + """
FUNCTION_BLOCK User
METHOD Check : LREAL
VAR_INPUT
  otg : REFERENCE TO Struckig.Otg;
  p : POINTER TO Struckig.Otg;
END_VAR
Check := otg.cyc + p^.cyc;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM main
VAR o : Struckig.Otg(cycletime := 0.25, dofs := 1); u : User; r : LREAL; END_VAR
r := u.Check(o, ADR(o));
END_PROGRAM
"""
    )
    assert helpers.run(src, 1, "twincat")["main.r"] == 0.5
