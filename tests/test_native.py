"""The native tier (--native, st/compiler/native): the same results, faults and lifecycle as Python.

Each distinct program costs one Cython + C build (about 2 s), so the programs here are few and
shared by module-scoped fixtures; tests/test_native_differential.py compares the tiers on
generated programs. The interval rules (kinds.py) are checked directly, with exact intervals.
"""

from __future__ import annotations

import ast as py
import math
import struct
from pathlib import Path

import pytest
from click.testing import CliRunner

from st import PLC
from st.api import compile_text
from st.cli import main
from st.compiler.codegen.facts import BodyCall, BodyFacts, Helper, Local, Loop
from st.compiler.native import kinds, toolchain
from st.compiler.native.kinds import Int
from st.compiler.native.pyx import module_text
from st.compiler.native.typer import ClassInfo, NotEligible, type_body
from st.model import types as T
from st.model.compiled import CompiledProgram
from st.runtime.faults import PLCFaultError

ROOT = Path(__file__).resolve().parents[1]
needs_toolchain = pytest.mark.skipif(toolchain.missing() is not None, reason=f"native tier: {toolchain.missing()}")

DINT = Int(-(1 << 31), (1 << 31) - 1)

# faults inside loops, selected by `mode`; and ordinary work that must survive them
FAULTS = """\
PROGRAM main
VAR
  mode : INT;
  a : ARRAY[1..5] OF DINT;
  i : DINT;
  d : DINT;
  x : DINT;
  big : DINT := 2000000000;
  wide : BOOL;
  r : REAL := 1.0;
END_VAR
FOR i := 1 TO 3 DO
  a[i] := a[i] + i;
  r := r / 3.0;
END_FOR;
wide := big * big * 4 > big;  (* exact in ST: a product beyond int64 compared *)
IF mode = 1 THEN
  FOR i := 1 TO 2 DO
    x := 10 / d;
  END_FOR;
ELSIF mode = 2 THEN
  FOR i := 1 TO 6 DO
    a[i] := i;
  END_FOR;
ELSIF mode = 3 THEN
  WHILE TRUE DO
    x := x + 1;
  END_WHILE;
END_IF;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def faults_native() -> CompiledProgram:
    return compile_text(FAULTS, "faults.st", native=True)


def _run_mode(compiled: CompiledProgram, mode: int):
    plc = PLC(compiled, watchdog="100ms")
    plc.scan(2)
    plc["main.mode"] = mode
    with pytest.raises(PLCFaultError) as e:
        plc.scan(1)
    return plc, e.value.fault


# ---------------------------------------------------------------------------- intervals
def test_int_binop_intervals():
    assert kinds.int_binop(py.Add(), DINT, Int(1, 1)) == Int(-(1 << 31) + 1, 1 << 31)
    assert kinds.int_binop(py.Mult(), DINT, DINT) == Int(-(1 << 62) + (1 << 31), 1 << 62)
    # a third DINT factor leaves int64: computed on Python integers
    assert kinds.int_binop(py.Mult(), kinds.int_binop(py.Mult(), DINT, DINT), DINT) is None
    assert kinds.int_binop(py.Mod(), DINT, Int(17, 17)) == Int(0, 16)
    assert kinds.int_binop(py.Mod(), DINT, Int(-5, 7)) == Int(-6, 6)
    assert kinds.int_binop(py.LShift(), Int(0, 65535), Int(1, 1)) == Int(0, 131070)
    assert kinds.int_binop(py.LShift(), Int(0, 65535), Int(0, 63)) is None  # a count beyond 62
    assert kinds.int_binop(py.LShift(), Int(-1, 1), Int(1, 1)) is None  # negative: Python's meaning
    assert kinds.int_binop(py.RShift(), Int(-8, 8), Int(1, 2)) == Int(-4, 4)
    assert kinds.int_binop(py.BitAnd(), Int(0, 255), Int(0, 15)) == Int(0, 15)
    assert kinds.int_binop(py.BitOr(), Int(0, 255), Int(0, 256)) == Int(0, 511)
    assert kinds.int_binop(py.BitXor(), Int(-1, 0), Int(0, 3)) == Int(-4, 3)
    assert kinds.int_binop(py.FloorDiv(), DINT, Int(-1, 1)) == Int(-(1 << 31), 1 << 31)
    full = Int(kinds.INT64_MIN, kinds.INT64_MAX)
    assert kinds.int_binop(py.FloorDiv(), full, Int(-1, 1)) is None  # INT64_MIN // -1


def test_exact_float_conversion_bound():
    assert kinds.exact_float(Int(-(1 << 53), 1 << 53))
    assert not kinds.exact_float(Int(0, (1 << 53) + 1))
    assert kinds.exact_float(kinds.BOOL) and kinds.exact_float(kinds.FLOAT)


def _body(src: str) -> py.FunctionDef:
    fn = py.parse(src).body[0]
    assert isinstance(fn, py.FunctionDef)
    return fn


def _facts(**cached: T.Type) -> BodyFacts:
    """The facts codegen records for a hand-written body: its cached variables (VARs), `_range`."""
    return BodyFacts("body", {n: Local(t, "VAR") for n, t in cached.items()}, helpers={"_range": Helper.RANGE})


def test_a_product_beyond_int64_is_computed_on_python_integers():
    fn = _body(
        "def _body(self):\n"
        "    x = self.x\n"
        "    try:\n"
        "        for i in _range(0, 3):\n"
        "            x = (x * x * x + 2147483648 & 4294967295) - 2147483648\n"
        "    finally:\n"
        "        self.x = x\n"
    )
    classes = {"_prg_main": ClassInfo(frozenset({"x"}), {"x": DINT})}
    typed = type_body(fn, "_prg_main", classes, frozenset(), facts=_facts(x=T.DINT))
    assert typed.decls == {"x": "int64_t"}
    text, _ = module_text([("_prg_main", "p.st", "main", typed)])
    assert "_k_obj(x * x) * x" in text
    assert "2147483648LL" in text  # a C literal, not a Python object


def test_a_body_writing_a_global_or_using_a_reserved_name_stays_python():
    with pytest.raises(NotEligible, match="writes a global variable"):
        fn = _body("def _body(self):\n    global g\n    while g:\n        g = 0\n")
        type_body(fn, "_fb_x", {}, frozenset(), facts=_facts())
    with pytest.raises(NotEligible, match="uses the name double, which C or Cython reserve"):
        type_body(_body("def _body(self):\n    double = self.double\n"), "_fb_x", {}, frozenset(), facts=_facts())
    with pytest.raises(NotEligible, match="the code generator recorded no facts for it"):
        type_body(_body("def _body(self):\n    pass\n"), "_fb_x", {}, frozenset())


def test_rebound_globals_are_read_from_the_namespace_at_each_use():
    fn = _body("def _body(self):\n    for i in _range(0, 2):\n        self.t = _g_count + _helper(i)\n")
    typed = type_body(fn, "_fb_x", {}, frozenset({"_g_count"}), facts=_facts())
    text, _ = module_text([("_fb_x", "p.st", "x", typed)])
    assert "self.t = _k_c.ns['_g_count'] + _k_c._helper(i)" in text
    assert "    _k_c._helper = _k_ns['_helper']" in text  # bound once per PLC, in its context
    assert typed.captured == {"_helper"}


def test_slots_of_known_blocks_are_reached_at_their_offsets():
    fn = _body(
        "def _body(self):\n"
        "    n = self.n\n"
        "    try:\n"
        "        _t1 = self.f\n"
        "        _t1.x = n + 1\n"
        "        _t1._body()\n"
        "        n = self.f.q\n"
        "        self.t = _now\n"
        "    finally:\n"
        "        self.n = n\n"
    )
    classes = {
        "_prg_main": ClassInfo(frozenset({"n", "f", "t"}), {"n": DINT, "f": kinds.Inst("_fb_f")}),
        "_fb_f": ClassInfo(frozenset({"x", "q"}), {"x": DINT, "q": DINT}),
    }
    typed = type_body(fn, "_prg_main", classes, frozenset(), facts=_facts(n=T.DINT))
    assert typed.decls == {"n": "int64_t"}
    assert typed.slots == {("_prg_main", "n"), ("_prg_main", "f"), ("_prg_main", "t"), ("_fb_f", "x"), ("_fb_f", "q")}
    text, _ = module_text([("_prg_main", "p.st", "main", typed)])
    # a C value is stored and read at the slot with its C type; an object (`self.f`) as an object
    assert "_k_sti(_t1, _k_c._k_T_fb_f, _k_c._k_O5__fb_f_x, 'x', n + 1)" in text
    assert "        _t1._body()  # st:" in text  # _fb_f's body is not compiled in this module: the method call stays
    assert (
        "n = _k_ldi(_k_ld(self, _k_c._k_T_prg_main, _k_c._k_O9__prg_main_f, 'f'), "
        "_k_c._k_T_fb_f, _k_c._k_O5__fb_f_q, 'q')"
    ) in text
    assert "_k_now = _k_c.ns['_now']" in text and "'t', _k_now)" in text  # the job's time, read once per body


def test_a_call_of_a_block_compiled_in_the_same_module_is_a_c_call():
    fn = _body("def _body(self):\n    _t1 = self.f\n    _t1._body()\n")
    classes = {
        "_prg_main": ClassInfo(frozenset({"f"}), {"f": kinds.Inst("_fb_f")}),
        "_fb_f": ClassInfo(frozenset(), {}),
    }
    call = fn.body[1].value  # `_t1._body()`: codegen's fact names the block's class
    assert isinstance(call, py.Call)
    facts = _facts()
    facts.body_calls.append(BodyCall(call, "_fb_f"))
    main = type_body(fn, "_prg_main", classes, frozenset(), facts=facts)
    callee = type_body(_body("def _body(self):\n    pass\n"), "_fb_f", classes, frozenset(), facts=_facts())
    text, _ = module_text([("_prg_main", "p.st", "main", main), ("_fb_f", "p.st", "f", callee)])
    assert "_k_impl_fb_f(_k_c, _t1) if _k_c._k_own_fb_f and type(_t1) is _k_c._k_T_fb_f else _t1._body()" in text
    assert "cdef object _k_impl_fb_f(_k_Ctx _k_c, object self):" in text


def test_what_codegen_meant_comes_from_its_facts_not_from_the_shape():
    src = (
        "def _body(self):\n"
        "    n = self.n\n"
        "    try:\n"
        "        for i in _range(1, 101):\n"
        "            if _wd_armed:\n"
        "                _wd_check()\n"
        "            n = i * i * i + _div2(n, 7)\n"
        "        if _wd_armed:\n"
        "            _wd_check()\n"
        "    finally:\n"
        "        self.n = n\n"
    )
    classes = {"_prg_main": ClassInfo(frozenset({"n"}), {"n": DINT})}
    fn = _body(src)
    loop = fn.body[1].body[0]
    assert isinstance(loop, py.For)
    facts = _facts(n=T.DINT, i=T.DINT)
    facts.helpers["_div2"] = Helper.DIV  # codegen's name for IEC DIV, whatever it is
    facts.guards.append(loop.body[0])  # the loop's guard; the second `if` only looks like one
    facts.loops.append(Loop(loop, "i", Int(1, 100)))
    typed = type_body(fn, "_prg_main", classes, frozenset({"_wd_armed"}), facts=facts)
    text, _ = module_text([("_prg_main", "p.st", "main", typed)])
    assert "if not _k_wd & 1023:" in text and text.count("_k_c._wd_check()") == 2
    assert "if _k_c.ns['_wd_armed']:" in text  # the look-alike stays what it is
    # i is 1..100 in the loop: i * i * i is computed in C (three DINTs would not be)
    assert "n = i * i * i + _k_idiv(n, 7)" in text
    without = _facts(n=T.DINT, i=T.DINT)
    text, _ = module_text(
        [("_prg_main", "p.st", "main", type_body(_body(src), "_prg_main", classes, frozenset(), facts=without))]
    )
    assert "_k_obj(i * i) * i" in text and "_k_c._div2(n, 7)" in text and "_k_wd &" not in text


# ---------------------------------------------------------------------------- whole programs
@needs_toolchain
def test_the_integer_loop_workload_computes_the_same_checksum_on_both_tiers():
    path = ROOT / "bench" / "workloads" / "int_arrays.st"
    text = path.read_text()
    out = {}
    for native in (False, True):
        compiled = compile_text(text, str(path), dialect="openplc", native=native)
        assert bool(compiled.native) is native
        plc = PLC(compiled)
        plc.scan(300)
        inst = plc.instances["instance0"][1]
        out[native] = (inst.checksum, inst.total, inst.k, list(inst.a), list(inst.b))
    assert out[True] == out[False]
    assert out[True][:3] == (520235, 520235, 98)  # as the Python tier (and MatIEC, bench_native.py)
    assert compiled.native[0].classes == ("_prg_main",)


@needs_toolchain
@pytest.mark.parametrize(
    "mode, kind, line, message",
    [
        (1, "DIV0", 19, "division by zero"),
        (2, "INDEX", 23, "array index 6 is outside the bounds 1..5"),
        (3, "WATCHDOG", 26, "the job did not finish within 100 ms (endless loop?)"),
    ],
)
def test_faults_in_compiled_loops_name_their_st_line(faults_native, mode, kind, line, message):
    python = compile_text(FAULTS, "faults.st", use_cache=False)
    for compiled in (python, faults_native):
        plc, fault = _run_mode(compiled, mode)
        assert (fault.kind, fault.file, fault.line, fault.pou, fault.message) == (
            kind,
            "faults.st",
            line,
            "main",
            message,
        )
        assert plc["main.a"] == ([1, 2, 3, 4, 5] if mode == 2 else [3, 6, 9, 0, 0])
        assert plc["main.wide"] is True
    assert faults_native.native[0].classes == ("_prg_main",)


@needs_toolchain
def test_two_plcs_of_one_build_keep_their_own_state(faults_native):
    one, two = PLC(faults_native), PLC(faults_native)
    one.scan(3)
    two.scan(1)
    assert one["main.a"] == [3, 6, 9, 0, 0]
    assert two["main.a"] == [1, 2, 3, 0, 0]
    assert one["main.r"] == pytest.approx(1.0 / 3**9, rel=1e-6)
    assert type(one.instances["main"][1])._body is not type(two.instances["main"][1])._body


@needs_toolchain
def test_online_change_binds_the_new_program_and_keeps_values(faults_native):
    plc = PLC(faults_native)
    plc.scan(2)
    changed = compile_text(FAULTS.replace("a[i] := a[i] + i;", "a[i] := a[i] + 10 * i;"), "faults.st", native=True)
    assert changed.native and changed.native[0].name != faults_native.native[0].name
    plc.online_change(changed)
    plc.scan(1)
    assert plc["main.a"] == [2 + 10, 4 + 20, 6 + 30, 0, 0]


@needs_toolchain
def test_a_missing_module_runs_the_program_as_python_and_says_why(faults_native, tmp_path):
    from dataclasses import replace

    gone = replace(faults_native.native[0], name="st_k_gone")  # no module of that hash in the cache
    plc = PLC(replace(faults_native, native=[gone]))
    plc.scan(1)
    assert plc["main.a"] == [1, 2, 3, 0, 0]
    assert any("native module st_k_gone not used" in m.text for m in plc.log.entries)


def test_without_the_toolchain_the_program_compiles_as_python_with_w012(monkeypatch):
    import st.compiler.native as native

    monkeypatch.setattr(native, "missing", lambda: "Cython is not installed")
    compiled = compile_text(FAULTS, "faults.st", native=True, use_cache=False)
    assert compiled.native == []
    (w,) = [d for d in compiled.diagnostics if d.code == "W012"]
    assert w.message == "the native tier is not available: Cython is not installed"
    plc = PLC(compiled)
    plc.scan(1)
    assert plc["main.a"] == [1, 2, 3, 0, 0]


@needs_toolchain
def test_a_build_is_found_again_not_repeated(faults_native):
    m = faults_native.native[0]
    text = m.file.with_name(m.pyx).read_text()
    assert toolchain.module_name(text) == m.name
    assert toolchain.build(text) == (m.name, m.file, False)


@needs_toolchain
def test_cli_compile_native_says_which_bodies_are_compiled(tmp_path):
    src = tmp_path / "p.st"
    src.write_text(
        FAULTS + "FUNCTION_BLOCK odd\nVAR double : INT; END_VAR\ndouble := double + 1;\nEND_FUNCTION_BLOCK\n"
    )
    r = CliRunner().invoke(main, ["compile", "--native", str(src)])
    assert r.exit_code == 0, r.output
    assert "native: main\n" in r.output
    assert "  odd: Python (it uses the name double, which C or Cython reserve)\n" in r.output


@needs_toolchain
def test_a_module_cython_refuses_is_kept_for_a_bug_report(tmp_path, monkeypatch):
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path))
    with pytest.raises(toolchain.ToolchainError, match=r"^Cython failed: .*Expected an identifier or literal") as e:
        toolchain.build("def make(dict _k_ns):\n    return {\n")
    kept = Path(str(e.value).rsplit("kept in ", 1)[1].split(" for a bug report")[0])
    assert kept.parent == tmp_path / "compiled" / "native" / "failed"
    assert kept.read_text() == "def make(dict _k_ns):\n    return {\n"
    assert "Expected an identifier or literal" in kept.with_suffix(".txt").read_text()


def test_an_expression_nested_beyond_cythons_parser_keeps_its_body_python():
    chain = " + ".join(["x"] * 150)  # a left-nested chain of 149 additions
    with pytest.raises(NotEligible, match="an expression is nested more than 100 deep"):
        fn = _body(f"def _body(self):\n    x = self.x\n    self.y = {chain}\n")
        type_body(fn, "_fb_x", {}, frozenset(), facts=_facts(x=T.DINT))
    fn = _body(f"def _body(self):\n    x = self.x\n    self.y = {' + '.join(['x'] * 90)}\n")
    type_body(fn, "_fb_x", {}, frozenset(), facts=_facts(x=T.DINT))


def test_a_subrange_variable_has_its_base_types_interval():
    # a POINTER writes a subrange variable without the check: C may not assume the subrange
    from st.model import types as T

    sub = T.SubrangeType("S", T.DINT, 0, 1000000)
    assert kinds.of_type(sub) == Int(-(1 << 31), (1 << 31) - 1)
    assert kinds.of_type(T.SubrangeType("L", T.LINT, 0, 5)) is None


# slots read and written with C types: their fast paths (an exact bool, small int or float in the
# slot) and everything else (an int beyond one CPython digit, an int in a REAL, 1 in a BOOL, an
# instance of a derived block, reached by name)
SLOTS = """\
FUNCTION_BLOCK acc
VAR_INPUT k : DINT; f : REAL; b : BOOL; END_VAR
VAR_OUTPUT big : DINT; r : REAL; q : BOOL; n : INT; END_VAR
big := big + k;
r := f * 2.0;
q := b AND NOT q;
n := n + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK acc2 EXTENDS acc
SUPER^();
END_FUNCTION_BLOCK
PROGRAM slots
VAR
  one : acc;
  two : acc2;
  k : DINT := 600000000;
  f : REAL := 1.5;
  b : BOOL := TRUE;
  big : DINT;
  r : REAL;
  q : BOOL;
  n : INT;
END_VAR
one(k := k, f := f, b := b);
two(k := k, f := f, b := b);
big := one.big - two.big + one.big;
r := one.r + two.r;
q := one.q AND two.q;
n := one.n + two.n;
END_PROGRAM
"""


@needs_toolchain
def test_typed_slot_access_agrees_with_python_beyond_its_fast_paths(features):
    out = {}
    for native, compiled in features.items():
        assert bool(compiled.native) is native
        plc = PLC(compiled)
        seen = []
        for scan in range(5):
            if scan == 2:
                main = plc.instances["slots"][1]  # written past the API, which would convert them:
                main.f = 3  # an int in a REAL slot
                main.b = 1  # and 1 in a BOOL slot
            plc.scan(1)
            seen.append(tuple(plc[f"slots.{v}"] for v in ("big", "r", "q", "n", "one.big", "two.r", "one.q")))
        out[native] = seen
    assert out[True] == out[False]
    # 600000000 * 4 wraps past DINT's top: -1894967296; one.big and two.big always agree
    assert [s[0] for s in out[True]] == [600000000, 1200000000, 1800000000, -1894967296, -1294967296]
    assert [s[1] for s in out[True]] == [6.0, 6.0, 12.0, 12.0, 12.0]
    assert [s[2] for s in out[True]] == [True, False, True, False, True]
    assert [s[3] for s in out[True]] == [2, 4, 6, 8, 10]
    assert [type(v) for v in out[True][4]] == [int, float, bool, int, int, float, bool]


# the standard functions computed by their C twins: every edge case bit for bit as on the Python
# tier (the same libm, the helpers' NaN/INF rules), and REAL → DINT rounding of both dialects
TWINS = """\
PROGRAM main
VAR
  x : ARRAY[0..15] OF LREAL;
  f : ARRAY[0..15] OF REAL;
  r : ARRAY[0..175] OF LREAL;
  y : ARRAY[0..7] OF LREAL := [2.5, -2.5, 3.5, -3.5, 0.49999999999999994, -0.5, 2147483647.4, -2147483648.4];
  k : ARRAY[0..7] OF DINT;
  big : LREAL := 3.0E9;
  out : DINT;
  mode : INT;
  b : BOOL;
  n : DINT;
  i : INT;
END_VAR
FOR i := 0 TO 15 DO
  r[i] := SQRT(x[i]);
  r[16 + i] := LN(x[i]);
  r[32 + i] := LOG(x[i]);
  r[48 + i] := EXP(x[i]);
  r[64 + i] := SIN(x[i]);
  r[80 + i] := COS(x[i]);
  r[96 + i] := TAN(x[i]);
  r[112 + i] := ASIN(x[i]);
  r[128 + i] := ACOS(x[i]);
  r[144 + i] := ATAN(x[i]);
  r[160 + i] := REAL_TO_LREAL(SIN(f[i]) + EXP(f[i]));
END_FOR;
FOR i := 0 TO 7 DO
  k[i] := LREAL_TO_DINT(y[i]);
END_FOR;
b := NOT b;
n := n + BOOL_TO_DINT(b) * 3;
IF mode = 1 THEN
  out := LREAL_TO_DINT(big);
END_IF;
END_PROGRAM
"""
EDGES = [
    math.nan,
    math.inf,
    -math.inf,
    0.0,
    -0.0,
    1e-310,
    -1.0,
    0.5,
    1.0,
    2.0,
    710.0,
    -1000.0,
    1e300,
    math.pi,
    1e22,
    -2.5,
]


def _bits(v: float) -> bytes:
    return struct.pack("<d", v)


@needs_toolchain
@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_standard_functions_computed_in_c_agree_bit_for_bit(dialect):
    out = {}
    for native in (False, True):
        compiled = compile_text(TWINS, "twins.st", dialect=dialect, native=native)
        assert bool(compiled.native) is native
        plc = PLC(compiled)
        for i, v in enumerate(EDGES):
            plc[f"main.x[{i}]"] = v
            plc[f"main.f[{i}]"] = v if math.isnan(v) or abs(v) < 1e38 else math.copysign(math.inf, v)
        plc.scan(3)
        r = plc["main.r"]
        assert all(type(v) is float for v in r)
        out[native] = ([_bits(v) for v in r], plc["main.k"], plc["main.n"])
        plc["main.mode"] = 1
        with pytest.raises(PLCFaultError) as e:
            plc.scan(1)
        assert (e.value.fault.kind, e.value.fault.line) == ("CONVERSION", 34)
        out[native] += (e.value.fault.message,)
    assert out[True] == out[False]
    halfway = [3, -3, 4, -4] if dialect == "iec" else [2, -2, 4, -4]  # MatIEC makes halfway even
    # 0.49999999999999994 + 0.5 rounds to 1.0 in double: the nearest integer is still 0
    assert out[True][1] == halfway + [0, -1 if dialect == "iec" else 0, 2147483647, -2147483648]
    assert out[True][2] == 6  # BOOL_TO_DINT of TRUE, FALSE, TRUE
    r = out[True][0]
    assert r[48 + 10] == _bits(math.inf) and r[16 + 3] == _bits(-math.inf) and r[64 + 1] == _bits(math.nan)


GRID = """\
PROGRAM grid
VAR
  m : ARRAY[1..3, 0..3] OF INT;
  g : ARRAY[0..1, 0..1, 0..2] OF REAL;
  on : ARRAY[0..2, 0..2] OF BOOL;
  i : INT;
  j : INT;
  s : DINT;
  f : REAL;
END_VAR
FOR i := 1 TO 3 DO
  FOR j := 0 TO 3 DO
    m[i, j] := m[i, j] + i * 10000 + j;  (* wraps past 32767 in the second scan *)
    on[i - 1, j MOD 3] := NOT on[i - 1, j MOD 3];
  END_FOR;
END_FOR;
g[1, 0, 2] := g[1, 0, 2] + 0.1;
s := 0;
FOR i := 1 TO 3 DO
  s := s + m[i, 3] + BOOL_TO_DINT(on[i - 1, 0]);
END_FOR;
f := g[1, 0, 2] * 3.0;
END_PROGRAM
"""


@needs_toolchain
def test_multi_dimensional_arrays_are_flat_lists_read_in_c(features):
    out = {}
    for native, compiled in features.items():
        plc = PLC(compiled)
        plc.scan(3)
        out[native] = (plc["grid.m"], plc["grid.on"], plc["grid.s"], plc["grid.f"], plc["grid.g"])
    assert out[True] == out[False]
    m, on, s, f, g = out[True]
    assert m == [[30000, 30003, 30006, 30009], [-5536, -5533, -5530, -5527], [24464, 24467, 24470, 24473]]
    assert on == [[False, True, True]] * 3
    assert s == 30009 - 5527 + 24473
    tenth = _f32(0.1)
    assert g[1][0][2] == _f32(_f32(tenth + tenth) + tenth) and f == _f32(g[1][0][2] * 3.0)


def _f32(v: float) -> float:
    return struct.unpack("<f", struct.pack("<f", v))[0]


# user FUNCTIONs compiled too: C parameters and result where their kinds have them, a VAR_OUTPUT
# and a VAR_IN_OUT as references (objects), called in C from compiled bodies and from each other
FUNCS = """\
FUNCTION sq : DINT
VAR_INPUT a : INT; END_VAR
sq := INT_TO_DINT(a) * a;
END_FUNCTION
FUNCTION scale : REAL
VAR_INPUT x : REAL; k : INT; END_VAR
VAR i : INT; END_VAR
scale := x;
FOR i := 1 TO k DO
  scale := scale * 1.5;
END_FOR;
END_FUNCTION
FUNCTION pick : BOOL
VAR_INPUT g : BOOL; d : DINT; END_VAR
VAR_OUTPUT twice : DINT; END_VAR
VAR_IN_OUT hits : DINT; END_VAR
twice := d * 2;
hits := hits + 1;
pick := g AND d > 0;
END_FUNCTION
FUNCTION quot : DINT
VAR_INPUT a : DINT; b : DINT; END_VAR
quot := a / b;
END_FUNCTION
FUNCTION outer : DINT
VAR_INPUT n : INT; END_VAR
outer := sq(n) + sq(n + 1) + SEL(n > 2, 10, 20);
END_FUNCTION
PROGRAM funcs
VAR n : INT; s : DINT; r : REAL; b : BOOL; t : DINT; hits : DINT; d : DINT := 1; q : DINT; END_VAR
n := n + 1;
s := s + outer(n) + sq(300);
r := scale(1.0, n);
b := pick(n MOD 2 = 0, s, twice => t, hits := hits);
q := quot(100, d);
END_PROGRAM
"""


@needs_toolchain
def test_functions_are_compiled_and_called_in_c_with_the_same_results_and_faults(features):
    out = {}
    for native, compiled in features.items():
        plc = PLC(compiled)
        seen = []
        for _ in range(3):
            plc.scan(1)
            seen.append(tuple(plc[f"funcs.{v}"] for v in ("s", "r", "b", "t", "hits", "q")))
        plc["funcs.d"] = 0
        with pytest.raises(PLCFaultError) as e:
            plc.scan(1)
        f = e.value.fault
        out[native] = (seen, (f.kind, f.file, f.line, f.pou, f.message))
    assert out[True] == out[False]
    assert out[True][0] == [
        (90015, 1.5, False, 180030, 1, 100),
        (180038, 2.25, True, 360076, 2, 100),
        (270083, 3.375, False, 540166, 3, 100),
    ]
    line = FEATURES.splitlines().index("quot := a / b;") + 1
    assert out[True][1] == ("DIV0", "features.st", line, "quot", "division by zero")
    assert compiled.native[0].functions == ("_fn_sq", "_fn_scale", "_fn_pick", "_fn_quot", "_fn_outer")
    text = compiled.native[0].file.with_name(compiled.native[0].pyx).read_text()
    assert "cdef int64_t _k_impl_fn_sq(_k_Ctx _k_c, int64_t a) except? -1:" in text
    assert (
        "cdef bint _k_impl_fn_pick(_k_Ctx _k_c, bint g, int64_t d, object _r_twice, object _r_hits) except -1:" in text
    )
    assert "_k_impl_fn_sq(_k_c, n) if _k_c._k_own_fn_sq else _k_i64(_k_c._fn_sq(n))" in text


# one program (one build) for the tests of slots, multi-dimensional arrays and FUNCTIONs
FEATURES = SLOTS + GRID + FUNCS


@pytest.fixture(scope="module")
def features() -> dict[bool, CompiledProgram]:
    """FEATURES compiled for the Python tier (False) and the native one (True)."""
    return {native: compile_text(FEATURES, "features.st", native=native) for native in (False, True)}
