"""Rules that differ between the dialect presets, each checked in every preset it belongs to
(issue 18: real code accepted as the compiler it was written for accepts it)."""

from __future__ import annotations

import pytest

from helpers import errors, run

WRITES_OWN_INPUT = """
FUNCTION_BLOCK Cnt
VAR_INPUT n : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
n := n + 1;
q := n;
END_FUNCTION_BLOCK
PROGRAM main
VAR c : Cnt; a, b : INT; END_VAR
c(n := 10);
a := c.q;
c();
b := c.q;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [None, "openplc", "codesys", "twincat"])
def test_a_block_may_write_its_own_input_and_keeps_it_until_a_call_sets_it(dialect):
    plc = run(WRITES_OWN_INPUT, 2, dialect)
    # each scan: the call with n := 10 counts to 11; the call without n counts on from there
    assert (plc["main.a"], plc["main.b"], plc["main.c.n"]) == (11, 12, 12)


def test_iec_keeps_inputs_read_only_inside_their_block():
    assert "t.st:5:1: error[E048]: 'n' is an input of Cnt and cannot be written here" in errors(WRITES_OWN_INPUT, "iec")
