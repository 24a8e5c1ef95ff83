"""An online change carries the state over without work in proportion to the data at the swap
(issue 32): arrays of elementary values and of unchanged structures are moved, not copied; what
changed is carried member by member; references follow; what the old program leaves is freed in
the background. The timings are in bench/bench_online_change.py; these tests check the mechanism."""

from __future__ import annotations

import pytest

from st import PLC
from st.api import compile_text
from st.runtime import relink as relink_module
from st.runtime.online_change import OnlineChangeRefused, releaser

BIG = 200_000  # more than a chunk: built by _fill, freed a chunk at a time

SOURCE = """
TYPE Rec : STRUCT a : DINT; b : LREAL; inner : Pair; END_STRUCT; END_TYPE
TYPE Pair : STRUCT x, y : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK Acc
  VAR_INPUT inc : DINT; END_VAR
  VAR_OUTPUT total : DINT; END_VAR
  total := total + inc;
END_FUNCTION_BLOCK
PROGRAM main
  VAR
    buf : ARRAY[0..{last}] OF LREAL;
    grid : ARRAY[1..3, 1..4] OF INT;
    recs : ARRAY[0..99] OF Rec;
    accs : ARRAY[1..3] OF Acc;
    one : Rec;
    k : DINT;
    x : LREAL;
    pk : POINTER TO LREAL;
    rr : REF_TO Rec;
    vp, vr : LREAL;
    {extra}
  END_VAR
  k := k + 1;
  buf[k MOD {n}] := k;
  grid[2, 3] := grid[2, 3] + 1;
  recs[k MOD 100].a := k;
  recs[7].inner.y := 77;
  accs[2](inc := 5);
  one.b := 2.5;
  IF k = 1 THEN pk := ADR(buf[10]); rr := REF(recs[7]); END_IF;
  IF pk <> 0 THEN vp := pk^; END_IF;
  IF rr <> NULL THEN vr := rr^.b; END_IF;
  x := {constant};
END_PROGRAM
"""


def source(constant="1.0", extra="", n=BIG):
    return SOURCE.format(last=n - 1, n=n, constant=constant, extra=extra)


def make(n=BIG):
    plc = PLC(compile_text(source(n=n), "carry.st", use_cache=False))
    plc.scan(12)
    return plc


def change(plc, **kw):
    return plc.online_change(compile_text(source(**kw), "carry.st", use_cache=False))


def test_an_unchanged_array_of_elementary_values_is_moved_not_copied():
    plc = make()
    old = plc.instances["main"][1]
    buf, grid = old.buf, old.grid
    assert change(plc, constant="2.0") == "online change: 1 instance(s) carried over"
    new = plc.instances["main"][1]
    assert new is not old and new.buf is buf and new.grid is grid  # the same lists: no element copied
    assert (plc["main.buf[11]"], plc["main.buf[12]"], plc["main.grid[2, 3]"], plc["main.k"]) == (11.0, 12.0, 12, 12)
    plc.scan()
    assert (plc["main.x"], plc["main.k"], plc["main.buf[13]"]) == (2.0, 13, 13.0)


def test_an_array_of_unchanged_structures_is_moved_and_given_the_new_classes_in_the_background():
    plc = make()
    recs = plc.instances["main"][1].recs
    with releaser().held():  # (the background must not have given them their classes yet)
        change(plc, constant="2.0")
        new_cls = plc.ns["_st_Rec"]
        assert plc.instances["main"][1].recs is recs and type(recs[0]) is not new_cls  # moved as they are
    assert releaser().flush()  # the background work handed over so far is done
    assert all(type(r) is new_cls for r in recs) and type(recs[7].inner) is plc.ns["_st_Pair"]
    assert (plc["main.recs[11].a"], plc["main.recs[7].inner.y"]) == (11, 77)


def _walks_of_a_change(n: int) -> int:
    plc = make(n)
    calls = []
    real = relink_module._walk

    def counting(*a):
        calls.append(1)
        return real(*a)

    relink_module._walk = counting
    try:
        change(plc, constant="2.0", n=n)
    finally:
        relink_module._walk = real
    return len(calls)


def test_the_swap_walks_no_array_element():
    # the same few steps for 100 values as for 200,000 (and the 100 records are not walked either)
    assert _walks_of_a_change(100) == _walks_of_a_change(BIG) < 80  # (the library's classes count too)


def test_members_blocks_and_changed_structures_are_carried():
    plc = make(n=100)
    plc.scan(3)  # accs[2].total = 75
    changed = source(constant="2.0", n=100).replace("a : DINT; b : LREAL;", "a : DINT; c : INT := 9; b : LREAL;")
    plc.online_change(compile_text(changed, "carry.st", use_cache=False))
    # Rec gained a member: carried element by element, the new member at its initial value
    assert (plc["main.recs[14].a"], plc["main.recs[14].c"], plc["main.recs[7].inner.y"]) == (14, 9, 77)
    assert (plc["main.accs[2].total"], plc["main.one.b"], plc["main.k"]) == (75, 2.5, 15)


def test_references_follow_what_was_moved_and_what_was_rebuilt():
    plc = make()
    change(plc, constant="2.0")
    plc["main.buf[10]"] = 123.0
    plc["main.recs[7].b"] = 4.5
    text = compile_text(source(constant="2.0") + "\n", "carry.st", use_cache=False)
    plc.online_change(text)
    plc.scan()
    # pk points at buf[10] of the moved list, rr at the moved record recs[7]
    assert (plc["main.vp"], plc["main.vr"]) == (123.0, 4.5)


def test_a_removed_array_is_freed_in_the_background():
    plc = make()
    left_behind = plc.instances["main"][1].buf
    smaller = source(constant="2.0").replace(f"    buf : ARRAY[0..{BIG - 1}] OF LREAL;\n", "")
    smaller = smaller.replace(f"  buf[k MOD {BIG}] := k;\n", "").replace("pk := ADR(buf[10]); ", "")
    # and the pointer into it (a pointer the new program keeps would keep the array alive)
    smaller = smaller.replace("    pk : POINTER TO LREAL;\n", "").replace("  IF pk <> 0 THEN vp := pk^; END_IF;\n", "")
    plc.online_change(compile_text(smaller, "carry.st", use_cache=False))
    assert releaser().flush() and len(left_behind) == 0  # emptied a chunk at a time, not at the swap
    plc.scan()
    assert plc["main.x"] == 2.0


def test_a_large_array_is_built_a_chunk_at_a_time():
    text = "\n".join(compile_text(source(), "carry.st", emit_python=True, use_cache=False).python_source.values())
    assert f"_fill(0.0, {BIG})" in text and "[0] * 12" in text  # the small one stays as it was
    fill = PLC(compile_text(source(n=100), "carry.st", use_cache=False)).ns["_fill"]  # as generated code calls it
    assert fill(0.5, 150_000) == [0.5] * 150_000 and fill(0, 70_000, [1, 2]) == [1, 2] + [0] * 69_998


def test_an_array_a_kept_pointer_points_into_is_not_freed():
    plc = make()
    left_behind = plc.instances["main"][1].buf
    smaller = source(constant="2.0").replace(f"    buf : ARRAY[0..{BIG - 1}] OF LREAL;\n", "")
    smaller = smaller.replace(f"  buf[k MOD {BIG}] := k;\n", "").replace("pk := ADR(buf[10]); ", "")
    plc.online_change(compile_text(smaller, "carry.st", use_cache=False))
    assert releaser().flush()
    plc.scan(3)
    assert len(left_behind) == BIG and plc["main.vp"] == 10.0  # pk still reads the old buf[10]


def test_a_change_that_cannot_be_carried_leaves_the_old_program_as_it_was():
    plc = make(n=100)
    buf = plc.instances["main"][1].buf
    with pytest.raises(OnlineChangeRefused, match="main.k changed its type from DINT to INT"):
        plc.online_change(compile_text(source(n=100).replace("k : DINT;", "k : INT;"), "carry.st", use_cache=False))
    assert plc.instances["main"][1].buf is buf and plc["main.k"] == 12
