"""The language server's analysis in-process: a check stopped at any of its cancel points leaves
trees the next check gives the full answer on; a file that does not parse keeps the declarations
its errors are not in (st/lsp/tolerant.py)."""

from __future__ import annotations

import threading

import pytest

from st.compiler.check import CheckCancelled
from st.lsp.analysis import Analyzer
from st.lsp.tolerant import regions
from st.source import SourceFile

LIB = """FUNCTION_BLOCK FB_Count
VAR_INPUT up : BOOL; END_VAR
VAR_OUTPUT n : INT; END_VAR
VAR edge : R_TRIG; unused : INT; END_VAR
edge(CLK := up);
IF edge.Q THEN n := n + 1; END_IF;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Pair
VAR a, b : FB_Count; total : INT; END_VAR
a(up := TRUE); b(up := FALSE);
total := a.n + b.n;
END_FUNCTION_BLOCK

FUNCTION Fact : DINT
VAR_INPUT k : DINT; END_VAR
IF k <= 1 THEN Fact := 1; ELSE Fact := k * Fact(k - 1); END_IF;
END_FUNCTION
"""
MAIN = """PROGRAM main
VAR p : FB_Pair; c : FB_Count; x : DINT; s : STRING[4]; END_VAR
p();
c(up := x > 3);
x := Fact(5) + c.n;
s := 'too long';
y := 1;
END_PROGRAM
"""


def sources(lib: str = LIB) -> list[SourceFile]:
    return [SourceFile("/p/lib.st", lib), SourceFile("/p/main.st", MAIN)]


def answer(a) -> dict:
    return {f: [(d.code, d.span.line, d.span.col, d.message) for d in ds] for f, ds in a.diagnostics.items()}


class StopAt(threading.Event):
    """Set from the n-th time it is asked on."""

    def __init__(self, n: int) -> None:
        super().__init__()
        self.n = n
        self.asked = 0

    def is_set(self) -> bool:
        self.asked += 1
        return self.asked >= self.n


def test_a_stopped_check_leaves_trees_the_next_check_answers_in_full():
    expected = answer(Analyzer().analyze(sources()))
    codes = sorted(c for ds in expected.values() for c, *_ in ds)
    assert codes == ["E010", "W002", "W003", "W013"]  # y unknown, `unused`, the string cut, Fact recursive
    points = StopAt(10**9)
    Analyzer().analyze(sources(), points)
    assert points.asked > 100  # between passes and between bodies (the libraries' too)
    every_pass = range(1, 15)  # the first passes, then the bodies: every ninth
    for n in sorted({*every_pass, *range(15, points.asked + 1, 9), points.asked}):
        an = Analyzer()
        with pytest.raises(CheckCancelled):
            an.analyze(sources(), StopAt(n))
        assert answer(an.analyze(sources())) == expected, n
        assert answer(an.analyze(sources())) == expected, n  # and again, on what it kept


def test_a_property_with_a_setter_checked_again():
    """A SET accessor's input is added to its tree by the check: once (the second check of the same
    tree said the property's name was declared twice)."""
    oop = """FUNCTION_BLOCK FB_Buffer
VAR _len : UDINT; END_VAR
PROPERTY Length : UDINT
GET
  Length := _len;
END_GET
SET
  _len := Length;
END_SET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM main
VAR b : FB_Buffer; n : UDINT; END_VAR
b.Length := 3;
n := b.Length;
END_PROGRAM
"""
    an = Analyzer()
    first = answer(an.analyze([SourceFile("/p/oop.st", oop)]))
    assert first == {"/p/oop.st": []}
    assert answer(an.analyze([SourceFile("/p/oop.st", oop)])) == first


def test_a_constant_read_as_null_checked_again():
    """`itf <> Invalid` (a constant 0, TcLog's): NULL; a second check of the tree still finds the
    constant used (it said W002 'never used')."""
    src = """INTERFACE ILog
METHOD Log : BOOL
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB
VAR_OUTPUT ok : BOOL; END_VAR
VAR l : ILog; END_VAR
VAR CONSTANT Invalid : UDINT := 0; END_VAR
IF l <> Invalid THEN ok := l.Log(); END_IF;
END_FUNCTION_BLOCK
PROGRAM main
VAR f : FB; END_VAR
f();
END_PROGRAM
"""
    an = Analyzer()
    assert answer(an.analyze([SourceFile("/p/itf.st", src)])) == {"/p/itf.st": []}
    assert answer(an.analyze([SourceFile("/p/itf.st", src)])) == {"/p/itf.st": []}


def test_a_file_that_does_not_parse_keeps_its_other_declarations():
    an = Analyzer()
    before = answer(an.analyze(sources()))
    half = LIB.replace("total := a.n + b.n;", "total := a.n + b.n;\n  a.")
    a = an.analyze(sources(half))
    got = answer(a)
    assert [(c, line) for c, line, *_ in got["/p/lib.st"]] == [("W002", 4), ("E001", 14), ("W013", 18)]
    assert got["/p/main.st"] == before["/p/main.st"]  # FB_Pair still declared: no new error there
    assert a.cuts == {"/p/lib.st": [(8, 13)]}
    scope = a.scope_at("/p/lib.st", 12)  # the new line, past the old block's end
    assert scope.pou.name == "FB_Pair" and {"a", "b", "total"} <= set(scope.pou.vars)
    # a file that never parsed has nothing to keep: the block is missing, and main.st says so
    fresh = answer(Analyzer().analyze(sources(half)))
    assert ("E012", 2) in [(c, line) for c, line, *_ in fresh["/p/main.st"]]
    assert answer(an.analyze(sources())) == before


def test_regions_nest_and_end_where_the_next_declaration_starts():
    text = "\n".join(
        [
            "FUNCTION_BLOCK A",  # 0
            "VAR x : INT; END_VAR",
            "METHOD M",  # 2
            "VAR_INPUT v : INT; END_VAR",
            "x := v;",
            "END_METHOD",  # 5
            "END_FUNCTION_BLOCK",  # 6
            "FUNCTION_BLOCK B",  # 7: never ended
            "x := 1;",
            "TYPE T : INT; END_TYPE",  # 9
            "VAR_GLOBAL g : T; END_VAR",  # 10
        ]
    )
    got = [(r.kind, r.first, r.last) for r in regions(text)]
    assert got == [
        ("FUNCTION_BLOCK", 0, 6),
        ("METHOD", 2, 5),
        ("FUNCTION_BLOCK", 7, 8),
        ("TYPE", 9, 9),
        ("VAR_GLOBAL", 10, 10),
    ]


GVL = """{gvl 'GVL_Cell'}
VAR_GLOBAL
  speed : REAL := 1.5;  (* mm/s *)
  count : DINT;
END_VAR
"""
USES = """PROGRAM main
VAR t : Tc2_Standard.TON; x : REAL; p : POINTER TO REAL; n : DINT; END_VAR
GVL_Cell.count := GVL_Cell.count + 1;
t(IN := TRUE, PT := T#1s);
x := LIMIT(0.0, GVL_Cell.speed, 10.0);
p := ADR(x);
n := SIZEOF(x);
END_PROGRAM
CONFIGURATION Cell
  RESOURCE Res0 ON PLC
    TASK fast(INTERVAL := T#10ms, PRIORITY := 1);
    PROGRAM inst WITH fast : main;
  END_RESOURCE
END_CONFIGURATION
"""


def names_answered():
    from st.lsp import features as F

    a = Analyzer().analyze([SourceFile("/p/gvl.st", GVL), SourceFile("/p/main.st", USES)])
    assert answer(a) == {"/p/gvl.st": [], "/p/main.st": []}
    lines = USES.splitlines()

    def hover(needle: str, nth: int = 0, offset: int = 1) -> str | None:
        line = [i for i, text in enumerate(lines) if needle in text][nth]
        return F.hover(a, "/p/main.st", line, lines[line].index(needle) + offset)

    return a, F, hover


def test_hover_answers_library_functions_operators_lists_and_the_configuration():
    a, F, hover = names_answered()
    assert hover("LIMIT").startswith("```st\nFUNCTION LIMIT(MN : T; IN : T; MX : T) : T  (T : ANY_ELEMENTARY)\n```")
    assert hover("ADR").startswith("```st\nADR(…) : REF_TO REAL  (an operator of the language)\n```")
    assert hover("Tc2_Standard").startswith("```st\nNAMESPACE Tc2_Standard  (st's iec61131 library)\n```")
    assert hover("TON").startswith("```st\nFUNCTION_BLOCK TON(")  # the name after the qualifier
    assert hover("GVL_Cell").startswith("```st\nVAR_GLOBAL list GVL_Cell (2 variables)\n```\n\n*global variable list*")
    assert F.definition(a, "/p/main.st", 2, 3).file == "/p/gvl.st"
    assert "mm/s" in hover("speed")
    assert hover("fast").startswith("```st\nTASK fast(INTERVAL := …, PRIORITY := …)\n```")
    assert hover("inst").startswith("```st\nPROGRAM inst WITH fast : main\n```\n\n*program instance*")
    assert hover("CONFIGURATION Cell", 0, 15).startswith("```st\nCONFIGURATION Cell\n```")
    task = F.definition(a, "/p/main.st", 11, USES.splitlines()[11].index("fast :") + 1)
    assert (task.name, task.line) == ("fast", 10)


def test_completion_after_a_list_and_a_namespace():
    a, F, _ = names_answered()

    def labels(text: str) -> list[str]:
        line = 4
        return [i.label for i in F.completion(a, "/p/main.st", line, len(text), text_with(line, text))]

    def text_with(line: int, text: str) -> str:
        lines = USES.splitlines()
        lines[line] = text
        return "\n".join(lines)

    assert labels("x := GVL_Cell.") == ["speed", "count"]
    got = labels("t := Tc2_Standard.")
    assert {"TON", "TOF", "CTU", "LIMIT", "CONCAT"} <= set(got)


def test_the_names_in_an_initial_value_are_the_members_they_set():
    """`p : Path := (pts := [(x := 1.0)])`, `m : Mover := (speed := 2.5)`: hover, definition and
    rename reach the member (struckig's tests set a block's inputs so)."""
    from st.lsp import features as F

    src = """TYPE Pt : STRUCT x : REAL; y : REAL; END_STRUCT; END_TYPE
TYPE Path : STRUCT name : STRING; pts : ARRAY[0..1] OF Pt; END_STRUCT; END_TYPE
FUNCTION_BLOCK Mover
VAR_INPUT speed : REAL; home : Pt; END_VAR
END_FUNCTION_BLOCK
PROGRAM main
VAR
  p : Path := (name := 'a', pts := [(x := 1.0, y := 2.0), (x := 3.0)]);
  m : Mover := (speed := 2.5, home := (y := 1.0));
END_VAR
m();
END_PROGRAM
"""
    a = Analyzer().analyze([SourceFile("/p/init.st", src)])
    line = src.splitlines()[7]
    assert F.hover(a, "/p/init.st", 7, line.index("pts :=") + 1).startswith("```st\npts : ARRAY[0..1] OF Pt\n```")
    x = F.definition(a, "/p/init.st", 7, line.index("x := 3") + 1)
    assert (x.name, x.line, x.kind) == ("x", 0, "member")
    speed = F.definition(a, "/p/init.st", 8, src.splitlines()[8].index("speed") + 1)
    assert (speed.name, speed.line) == ("speed", 3)
    edits = F.rename(a, "/p/init.st", 0, src.splitlines()[0].index("x :") + 1, "px")
    assert sorted((ln, col) for ln, col, _, _ in edits["/p/init.st"]) == [
        (0, src.splitlines()[0].index("x :")),
        (7, line.index("x := 1")),
        (7, line.index("x := 3")),
    ]
