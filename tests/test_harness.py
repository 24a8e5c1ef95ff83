"""Python-side testing helpers: TestPLC (pulse, run_until, trace, set), FB and function handles."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as hs

from st.testing.harness import TestPLC

BLINK = """
PROGRAM main
  VAR start : BOOL; lamp : BOOL; t : TON; n : INT; name : STRING := 'x'; END_VAR
  t(IN := start AND NOT t.Q, PT := T#50ms);
  IF t.Q THEN lamp := NOT lamp; n := n + 1; END_IF;
END_PROGRAM
"""

COUNTER = """
FUNCTION_BLOCK BatchCounter     (* counts parts up to the batch size, then holds *)
  VAR_INPUT part : BOOL; size : INT; END_VAR
  VAR_OUTPUT count : INT; END_VAR
  VAR edge : R_TRIG; END_VAR
  edge(CLK := part);
  IF edge.Q AND count < size THEN count := count + 1; END_IF;
END_FUNCTION_BLOCK

FUNCTION Clamp : INT
  VAR_INPUT x : INT; lo : INT := -5; hi : INT := 5; END_VAR
  Clamp := LIMIT(lo, x, hi);
END_FUNCTION
"""


def test_run_until_trace_pulse_and_set():
    p = TestPLC.from_source(BLINK, cycle="10ms")
    p.set({"main.start": True})
    assert p.run_until("main.lamp") == 60_000_000  # TON at 0, Q at 50 ms: the 6th scan
    rows = p.trace(["main.lamp", "main.n"], "120ms")
    assert [r[1]["main.n"] for r in rows] == [1] * 6 + [2] * 6  # TON restarts at 70 ms, Q at 120 ms
    assert rows[0][0] == 70_000_000 and rows[-1][0] == 180_000_000
    with pytest.raises(AssertionError, match=r"<lambda> did not become true within 0.05 s of PLC time"):
        p.run_until(lambda q: q["main.n"] > 100, timeout="50ms")
    q = TestPLC.from_source(BLINK, cycle="10ms")
    q.pulse("main.start", "30ms")
    assert (q.time, q["main.start"], q["main.t.ET"]) == (30_000_000, False, 20_000_000)


def test_fb_handle_runs_one_call_and_reads_the_plc_clock():
    p = TestPLC.from_source(COUNTER + BLINK, cycle="10ms")
    ton = p.fb("TON")
    ton(IN=True, PT="100ms")
    p.advance("90ms")
    assert ton(IN=True).Q is False and ton.ET == 90_000_000
    p.advance("10ms")
    assert ton(IN=True).Q is True
    with pytest.raises(AttributeError, match="TON has no variable 'QQ'"):
        _ = ton.QQ
    with pytest.raises(ValueError, match="32768 does not fit in INT"):
        p.fb("BatchCounter")(size=32768)
    with pytest.raises(KeyError, match="no FUNCTION_BLOCK or PROGRAM named 'Nope'"):
        p.fb("Nope")


def test_function_handle_positional_named_and_defaults():
    p = TestPLC.from_source(COUNTER + BLINK)
    clamp = p.function("Clamp")
    assert (clamp(9), clamp(-9), clamp(3), clamp(9, hi=7), clamp(x=-9, lo=-1)) == (5, -5, 3, 7, -1)
    with pytest.raises(TypeError, match="Clamp has no input z"):
        clamp(z=1)


@settings(max_examples=40, deadline=None)
@given(parts=hs.lists(hs.booleans(), max_size=60), size=hs.integers(min_value=0, max_value=20))
def test_batch_counter_never_passes_the_batch_size(parts, size):
    c = TestPLC.from_source(COUNTER + BLINK).fb("BatchCounter")
    rising = 0
    prev = False
    for part in parts:
        c(part=part, size=size)
        rising += part and not prev
        prev = part
        assert c.count == min(rising, size)


def test_api_writes_of_bad_values_are_value_errors():
    p = TestPLC.from_source(
        "TYPE Color : (Red, Green); END_TYPE\nPROGRAM main VAR t : TIME; r : REAL; c : Color; END_VAR END_PROGRAM"
    )
    with pytest.raises(ValueError, match="main.t: empty duration"):
        p["main.t"] = ""
    with pytest.raises(ValueError, match="main.r: the value is too large for REAL"):
        p["main.r"] = 10**400
    with pytest.raises(ValueError, match="main.c: True is not a value of Color"):
        p["main.c"] = True
