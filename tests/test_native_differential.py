"""The native tier (st/compiler/native) against the Python tier on generated programs.

A seeded generator (plain `random.Random`, fixed seeds) writes one program of many small
FUNCTION_BLOCKs with loop bodies over every elementary type, those the native tier gives C
types (BOOL, integers up to 32 bits, REAL, LREAL, 1-D arrays of them, lower bounds other than 0)
and those it leaves to Python (LINT, ULINT, LWORD): wrapping arithmetic, products of three
factors compared and divided, DIV and MOD of negative values, MOD 0, shifts and rotations,
conversions between all of them, REAL rounding, INF, NaN and -0.0 (division by zero, negated
operands), nested IF/CASE, FOR loops with steps (negative, from variables, up to the type's
limit), WHILE/REPEAT with bounded counters, EXIT and CONTINUE, subranges (also written through
a POINTER, which does not check them), blocks called from loops (generated ones and TON/CTU),
variables named like Python or C names. The program is compiled once per tier; both PLCs run
the same scans and every variable of every instance (nested blocks and arrays included) must be
identical after each checked scan: floats bit for bit (NaN's sign, -0.0), integers exactly, a
REAL never an int (a BOOL may be `bool` on one tier and 0/1 on the other).

A second, smaller program selects a fault inside a loop with `mode` (DIV0 on each division
path, INDEX below and above the bounds, WATCHDOG, CONVERSION, LOOP, RANGE, MUX, a fault in a
nested block and in the PROGRAM): both tiers must report the same FaultInfo, keep the same
values, and run on after `reset_fault()`.

Each program costs one Cython + C build (a few seconds; then the compile cache has it), so the
blocks are small and many: the C compiler's time grows with the program's size.
"""

from __future__ import annotations

import random
import struct
from dataclasses import dataclass
from typing import Any

import pytest

from st import PLC
from st.api import compile_text
from st.compiler.native.toolchain import missing
from st.model import types as T
from st.model.compiled import CompiledProgram
from st.runtime.faults import FaultInfo, PLCFaultError

pytestmark = pytest.mark.skipif(missing() is not None, reason=f"native tier unavailable: {missing()}")

SEED = 11  # the differential program
FAULT_SEED = 3  # the fault program's ordinary work
N_BLOCKS = 12  # FUNCTION_BLOCKs with loops (and a loop-free one per 8, called from them)
SCANS = 400
CHECK_EVERY = 2  # scans between two comparisons of every variable
DEPTH = 2  # of an expression

SIGNED = {"SINT": 8, "INT": 16, "DINT": 32, "LINT": 64}
UNSIGNED = {"USINT": 8, "UINT": 16, "UDINT": 32, "ULINT": 64}
BITSTR = {"BYTE": 8, "WORD": 16, "DWORD": 32, "LWORD": 64}
INTS = {**SIGNED, **UNSIGNED, **BITSTR}
REALS = ("REAL", "LREAL")
NUMERIC = (*INTS, *REALS)
ELEMENTS = ("DINT", "INT", "SINT", "UINT", "USINT", "UDINT", "BYTE", "WORD", "DWORD", "BOOL", "REAL", "LREAL", "LINT")
# ST names that are Python or C names (not Cython's reserved words: those keep a body Python)
ODD_NAMES = ("object", "len", "list", "make", "goto", "auto", "register", "hash", "print", "next", "cast", "operator")
SUBRANGES = (("INT", -5, 100), ("SINT", -100, 100), ("DINT", 0, 1000000), ("USINT", 1, 10), ("UDINT", 0, 70000))
REAL_LITS = ("0.0", "1.0", "1.5", "-2.5", "0.1", "3.0E38", "1.0E30", "-1.0E-30", "1.0E-45", "16777217.0", "-0.0", "2.5")
LREAL_LITS = (*REAL_LITS, "1.0E300", "-1.0E-310", "0.3333333333333333", "9007199254740993.0")


def bounds(t: str) -> tuple[int, int]:
    b = INTS[t]
    return (-(1 << (b - 1)), (1 << (b - 1)) - 1) if t in SIGNED else (0, (1 << b) - 1)


def narrower(t: str) -> list[str]:
    """The integer types of t's family that widen to t implicitly (t included)."""
    for fam in (SIGNED, UNSIGNED, BITSTR):
        if t in fam:
            return [u for u in fam if fam[u] <= fam[t]]
    return [t]


@dataclass
class Loop:
    counter: str  # a FOR counter, or the counter of a WHILE/REPEAT
    lo: int = 0  # every value the counter takes inside the loop lies in lo..hi
    hi: int = 0


class Block:
    """One FUNCTION_BLOCK's declarations and body."""

    def __init__(self, rng: random.Random, name: str, light: bool, sub: Block | None):
        self.rng, self.name, self.light, self.sub = rng, name, light, sub
        self.vars: dict[str, str] = {"k": "DINT", "x": "REAL", "b": "BOOL", "q": "DINT", "y": "LREAL"}
        self.readonly: dict[str, str] = {}  # FOR/WHILE counters: read anywhere, written by their loops only
        self.arrays: dict[str, tuple[str, int, int]] = {}
        self.temps: dict[str, str] = {}
        self.inits: dict[str, str] = {}
        self.subranges: dict[str, tuple[str, int, int]] = {}
        self.timer = False
        names = iter(rng.sample(ODD_NAMES, 2) + [f"v{i}" for i in range(20)])
        for _ in range(rng.randint(4, 6) if not light else 3):
            t = rng.choice(NUMERIC + ("BOOL", "DINT", "INT", "REAL"))
            v = next(names)
            self.vars[v] = t
            if rng.random() < 0.5:
                self.inits[v] = self.lit(t)
        if not light:
            for i in range(1 if rng.random() < 0.7 else 2):
                e = rng.choice(ELEMENTS)
                lo = rng.choice((-3, 0, 1, -10, 100, 5))
                self.arrays[f"a{i}"] = (e, lo, lo + rng.randint(3, 10))
            for i in range(2):
                self.readonly[f"c{i}"] = rng.choice(("SINT", "INT", "DINT", "DINT", "USINT", "UINT", "UDINT", "LINT"))
            for i in range(2):
                self.readonly[f"w{i}"] = rng.choice(("DINT", "INT", "USINT", "SINT"))
            for i in range(rng.randint(0, 2)):
                self.temps[f"t{i}"] = rng.choice(("DINT", "REAL", "BOOL", "INT", "LREAL", "UDINT"))
            self.timer = rng.random() < 0.25  # library blocks (TON, CTU) called from a compiled body
            if rng.random() < 0.4:  # a subrange, also written through a POINTER TO its base type (unchecked)
                base, lo, hi = rng.choice(SUBRANGES)
                self.subranges["s0"] = (base, lo, hi)

    # ------------------------------------------------------------------ expressions
    def lit(self, t: str, v: int | None = None) -> str:
        r = self.rng
        if t == "BOOL":
            return r.choice(("TRUE", "FALSE"))
        if t in REALS:
            return f"{t}#" + r.choice(REAL_LITS if t == "REAL" else LREAL_LITS)
        if v is None:
            v = self.int_value(t)
        if t in BITSTR and r.random() < 0.5:
            return f"{t}#16#{v:X}"
        return f"{t}#{v}"  # typed: an untyped literal takes its type from the other operand

    def int_value(self, t: str) -> int:
        r = self.rng
        lo, hi = bounds(t)
        v = r.choice((0, 1, 2, 3, 7, 10, 100, -1, -2, -7, -100, lo, hi, lo + 1, hi - 1, r.randint(lo, hi)))
        return min(max(v, lo), hi)

    def readable(self, t: str) -> list[str]:
        out = [v for v, vt in {**self.vars, **self.readonly, **self.temps}.items() if vt == t]
        out += [v for v, (base, _, _) in self.subranges.items() if base == t]
        if self.sub is not None and t in ("DINT", "LREAL"):
            out.append("sub.q" if t == "DINT" else "sub.y")
        return out

    def leaf(self, t: str, loops: list[Loop]) -> str:
        r = self.rng
        names = self.readable(t)
        arrs = [a for a, (e, _, _) in self.arrays.items() if e == t]
        subs = [v for v, (base, _, _) in self.subranges.items() if base == t]
        if subs and r.random() < 0.25:
            return r.choice(subs)
        x = r.random()
        if arrs and x < 0.25:
            a = r.choice(arrs)
            return f"{a}[{self.index(a, loops)}]"
        if x < 0.45 and t != "BOOL":  # another type's variable, converted
            srcs = [(v, vt) for v, vt in {**self.vars, **self.readonly}.items() if vt != t and vt in INTS]
            srcs += [(v, vt) for v, vt in self.vars.items() if vt != t and vt in REALS and t in REALS]
            if srcs:
                v, vt = r.choice(srcs)
                return f"{vt}_TO_{t}({v})"
        if names and x < 0.92:
            return r.choice(names)
        return self.lit(t)

    def index(self, a: str, loops: list[Loop]) -> str:
        r = self.rng
        _, lo, hi = self.arrays[a]
        inside = [lp for lp in loops if lp.counter is not None and lo <= lp.lo and lp.hi <= hi]
        x = r.random()
        if inside and x < 0.6:
            lp = r.choice(inside)
            room_up, room_down = hi - lp.hi, lp.lo - lo
            if room_up > 0 and r.random() < 0.3:
                return f"{lp.counter} + {r.randint(1, room_up)}"
            if room_down > 0 and r.random() < 0.3:
                return f"{lp.counter} - {r.randint(1, room_down)}"
            return lp.counter
        if x < 0.75:
            return str(r.randint(lo, hi))
        s = r.choice(("SINT", "INT", "DINT"))
        if x < 0.88:
            return f"LIMIT({lo}, {self.leaf_or('DINT', s, loops)}, {hi})"
        return f"{lo} + ABS({self.leaf(s, loops)} MOD {hi - lo + 1})"

    def factors(self, t: str, n: int, loops: list[Loop]) -> list[str]:
        """The factors of a product: half the time a subrange's power, if one has base type t (its
        interval is the subrange's: not its value once a pointer wrote it)."""
        subs = [v for v, (base, _, _) in self.subranges.items() if base == t]
        if subs and self.rng.random() < 0.5:
            return [self.rng.choice(subs)] * (n - 1) + [self.leaf(t, loops)]
        return [self.leaf(t, loops) for _ in range(n)]

    def leaf_or(self, wide: str, t: str, loops: list[Loop]) -> str:
        """A leaf of type t as a `wide` value (an implicit widening)."""
        return self.leaf(t, loops) if t in narrower(wide) else f"{t}_TO_{wide}({self.leaf(t, loops)})"

    def divisor(self, t: str, loops: list[Loop]) -> str:
        """A value of type t that is never 0."""
        other = self.rng.choice((3, 7, 1) if t not in SIGNED else (-3, 7, -1, 2))
        if self.rng.random() < 0.3:
            return f"{t}#{other}"
        d = self.leaf(t, loops)
        return f"SEL({d} = {t}#0, {d}, {t}#{other})"

    def expr(self, t: str, depth: int, loops: list[Loop]) -> str:
        if depth <= 0 or self.rng.random() < 0.25:
            return self.leaf(t, loops)
        if t == "BOOL":
            return self.bool_expr(depth, loops)
        if t in REALS:
            return self.real_expr(t, depth, loops)
        return self.int_expr(t, depth, loops)

    def int_expr(self, t: str, depth: int, loops: list[Loop]) -> str:
        r = self.rng
        d = depth - 1
        e = lambda u=t: self.expr(u, d, loops)  # noqa: E731
        k = r.choice(
            ("arith", "arith", "arith", "div", "mod", "triple", "neg", "abs", "minmax", "limit", "sel", "conv", "conv")
            + ("bits", "bits", "shift", "not", "mux")
        )
        signed = t in SIGNED
        if k == "arith":
            u = r.choice(narrower(t))
            a, b = (e(), e(u)) if r.random() < 0.5 else (e(u), e())
            return f"({a} {r.choice('+-*')} {b})"
        if k == "div":
            return f"({e()} / {self.divisor(t, loops)})"
        if k == "mod":
            return f"({e()} MOD {self.leaf(t, loops)})"
        if k == "triple":
            f = self.factors(t, 3, loops)
            tail = r.choice((f" / {self.divisor(t, loops)}", f" MOD {self.leaf(t, loops)}", ""))
            return f"({f[0]} * {f[1]} * {f[2]}{tail})"
        if k == "neg" and signed:
            names = self.readable(t)  # (not a literal: -SINT#-128 is a compile error)
            return f"(-{e()})" if names and depth > 1 else f"(-{r.choice(names or [f'{t}#{r.randint(-99, 99)}'])})"
        if k == "abs" and signed:
            return f"ABS({e()})"
        if k == "minmax":
            return f"{r.choice(('MIN', 'MAX'))}({e()}, {e()})"
        if k == "limit":
            lo, hi = sorted((self.int_value(t), self.int_value(t)))
            return f"LIMIT({self.lit(t, lo)}, {e()}, {self.lit(t, hi)})"
        if k == "sel":
            return f"SEL({self.expr('BOOL', d, loops)}, {e()}, {e()})"
        if k == "mux":
            return f"MUX(ABS({self.leaf('DINT', loops)} MOD 3), {e()}, {e()}, {e()})"
        if k == "conv":
            src = r.choice(NUMERIC + ("BOOL",))
            if src == t:
                return e()
            if src in REALS:
                return self.real_to_int(src, t, loops)
            return f"{src}_TO_{t}({self.expr(src, d, loops)})"
        if k in ("bits", "not"):
            if k == "not":
                return f"(NOT {e()})"
            return f"({e()} {r.choice(('AND', 'OR', 'XOR'))} {e()})"
        if k == "shift":
            fn = r.choice(("SHL", "SHR", "ROL", "ROR"))
            return f"{fn}({e()}, {self.count()})"
        return self.leaf(t, loops)

    def count(self) -> str:
        """A shift count: never negative (a negative count is a fault, see the fault program)."""
        r = self.rng
        unsigned = [v for v, vt in {**self.vars, **self.readonly}.items() if vt in ("USINT", "UINT", "BYTE", "WORD")]
        if unsigned and r.random() < 0.5:
            v = r.choice(unsigned)
            return v if r.random() < 0.5 else f"({v} MOD 40)"
        return str(r.choice((0, 1, 3, 7, 8, 15, 16, 17, 31, 32, 33, 63, 64)))

    def real_to_int(self, src: str, t: str, loops: list[Loop]) -> str:
        """A REAL/LREAL variable converted to an integer type without a CONVERSION fault."""
        names = self.readable(src)
        v = self.rng.choice(names) if names else self.lit(src)
        lo, hi = bounds(t)
        lo, hi = max(lo, -1_000_000_000), min(hi, 2_000_000_000)
        fn = self.rng.choice((f"{src}_TO_{t}", f"{src}_TO_{t}", "TRUNC"))
        guarded = f"LIMIT({src}#{lo}.0, SEL({v} = {v}, {src}#0.0, {v}), {src}#{hi}.0)"
        if fn == "TRUNC":
            return f"DINT_TO_{t}(TRUNC({guarded}))" if t != "DINT" else f"TRUNC({guarded})"
        return f"{fn}({guarded})"

    def real_expr(self, t: str, depth: int, loops: list[Loop]) -> str:
        r = self.rng
        d = depth - 1
        e = lambda u=t: self.expr(u, d, loops)  # noqa: E731
        k = r.choice(("arith", "arith", "arith", "div", "neg", "abs", "minmax", "limit", "sel", "conv", "mixed"))
        k = r.choice((k, k, "iprod", "negop"))
        if k == "arith":
            return f"({e()} {r.choice('+-*')} {e()})"
        if k == "iprod":  # integers converted, then multiplied: REAL arithmetic, however exact the operands
            u = r.choice(("DINT", "UDINT", "INT", "SINT", "LINT", "DWORD"))
            f = [f"{u}_TO_{t}({self.leaf(u, loops)})" for _ in range(r.choice((2, 3)))]
            return "(" + f" {r.choice('**+-')} ".join(f) + ")"
        if k == "negop":  # a negated operand (-0.0, and the sign of a NaN)
            a, b = e(), e()
            return r.choice((f"({a} / (-{b}))", f"({a} * (-{b}))", f"((-{a}) + {b})", f"({a} - (-{b}))"))
        if k == "div":
            return f"({e()} / {e()})"  # a zero divisor gives INF or NaN, no fault
        if k == "neg":
            return f"(-{e()})"
        if k == "abs":
            return f"ABS({e()})"
        if k == "minmax":
            return f"{r.choice(('MIN', 'MAX'))}({e()}, {e()})"
        if k == "limit":
            return f"LIMIT({t}#-1.0E6, {e()}, {t}#1.0E6)"
        if k == "sel":
            return f"SEL({self.expr('BOOL', d, loops)}, {e()}, {e()})"
        if k == "mixed":  # an integer operand converted implicitly
            u = r.choice(("SINT", "INT", "DINT", "UINT", "UDINT"))
            return f"({e()} {r.choice('+-*')} {self.expr(u, d, loops)})"
        src = r.choice(NUMERIC)
        if src == t:
            return e()
        return f"{src}_TO_{t}({self.expr(src, d, loops)})"

    def bool_expr(self, depth: int, loops: list[Loop]) -> str:
        r = self.rng
        d = depth - 1
        k = r.choice(("cmp", "cmp", "cmp", "logic", "logic", "not", "bit", "triple"))
        if k == "cmp":
            t = r.choice(NUMERIC)
            op = r.choice(("=", "<>", "<", ">", "<=", ">="))
            return f"({self.expr(t, d, loops)} {op} {self.expr(t, d, loops)})"
        if k == "triple":  # beyond int64 in ST: compared exactly
            t = r.choice(("DINT", "DINT", "UDINT", "INT"))
            f = self.factors(t, 4, loops)
            return f"({f[0]} * {f[1]} * {f[2]} {r.choice(('>', '<', '='))} {f[3]})"
        if k == "logic":
            op = r.choice(("AND", "OR", "XOR"))
            return f"({self.expr('BOOL', d, loops)} {op} {self.expr('BOOL', d, loops)})"
        if k == "not":
            return f"(NOT {self.expr('BOOL', d, loops)})"
        cands = [(v, vt) for v, vt in {**self.vars, **self.readonly}.items() if vt in INTS]
        if cands:
            v, vt = r.choice(cands)
            return f"{v}.{r.randrange(INTS[vt])}"
        return self.leaf("BOOL", loops)

    # ------------------------------------------------------------------ statements
    def assign(self, loops: list[Loop], mult: int) -> str:
        r = self.rng
        targets = list(self.vars) + list(self.temps)
        x = r.random()
        if self.arrays and x < 0.3:
            a = r.choice(list(self.arrays))
            e = self.arrays[a][0]
            return f"{a}[{self.index(a, loops)}] := {self.expr(e, DEPTH, loops)};"
        if self.subranges and x < 0.45:
            v = r.choice(list(self.subranges))
            base, lo, hi = self.subranges[v]
            if r.random() < 0.5:  # through the pointer: any value of the base type, unchecked
                value = (
                    f"{base}#{bounds(base)[1] - r.randint(0, 9)}" if r.random() < 0.5 else self.expr(base, DEPTH, loops)
                )
                return f"p{v}^ := {value};"
            return f"{v} := LIMIT({lo}, {self.expr(base, DEPTH, loops)}, {hi});"
        if self.sub is not None and x < 0.5:  # an input of the block called in this one
            v, t = r.choice((("k", "DINT"), ("x", "REAL")))
            return f"sub.{v} := {self.expr(t, DEPTH, loops)};"
        v = r.choice(targets)
        t = {**self.vars, **self.temps}[v]
        src = t
        if t in INTS and r.random() < 0.15:
            src = r.choice(list(INTS))  # an implicit conversion (wrapped where it narrows)
        elif t == "REAL" and r.random() < 0.2:
            src = "LREAL"
        text = f"{v} := {self.expr(src, DEPTH, loops)};"
        if t in REALS and r.random() < 0.5:  # keep REALs from settling on INF/NaN for good
            text += f"\nIF NOT (ABS({v}) < 1.0E6) THEN {v} := {self.lit(t)}; END_IF;"
        return text

    def stmts(self, n: int, loops: list[Loop], mult: int, depth: int) -> list[str]:
        out = []
        for _ in range(n):
            out.append(self.stmt(loops, mult, depth))
        return out

    def stmt(self, loops: list[Loop], mult: int, depth: int) -> str:
        r = self.rng
        x = r.random()
        if depth > 0 and x < 0.2 and mult <= 12:
            return self.loop(loops, mult, depth)
        if depth > 0 and x < 0.32:
            return self.if_(loops, mult, depth)
        if depth > 0 and x < 0.37:
            return self.case(loops, mult, depth)
        if loops and x < 0.42:
            lp = loops[-1]
            if r.random() < 0.5:
                return f"IF {self.expr('BOOL', 1, loops)} THEN CONTINUE; END_IF;"
            return f"IF {self.expr('BOOL', 1, loops)} AND {lp.counter} >= {r.randint(lp.lo, lp.hi)} THEN EXIT; END_IF;"
        if self.sub is not None and x < 0.47:
            e = self.expr
            return f"sub(k := {e('DINT', 2, loops)}, x := {e('REAL', 2, loops)}, b := {e('BOOL', 1, loops)});"
        return self.assign(loops, mult)

    def block(self, lines: list[str]) -> str:
        return "\n".join("  " + ln for s in lines for ln in s.split("\n"))

    def if_(self, loops: list[Loop], mult: int, depth: int) -> str:
        r = self.rng
        parts = [
            f"IF {self.expr('BOOL', DEPTH, loops)} THEN",
            self.block(self.stmts(1, loops, mult, depth - 1)),
        ]
        if r.random() < 0.4:
            parts += [f"ELSIF {self.expr('BOOL', 2, loops)} THEN", self.block(self.stmts(1, loops, mult, depth - 1))]
        if r.random() < 0.5:
            parts += ["ELSE", self.block(self.stmts(1, loops, mult, depth - 1))]
        return "\n".join([*parts, "END_IF;"])

    def case(self, loops: list[Loop], mult: int, depth: int) -> str:
        r = self.rng
        t, v = r.choice([(vt, v) for v, vt in {**self.vars, **self.readonly}.items() if vt in INTS])
        sel = v if r.random() < 0.6 else f"({v} MOD {t}#9)"
        start = -4 if t in SIGNED else 0
        values = sorted(r.sample(range(start, 12), r.randint(2, 3)))
        parts = [f"CASE {sel} OF"]
        i = 0
        while i < len(values):
            if i + 1 < len(values) and r.random() < 0.3:
                label = f"{values[i]}..{values[i + 1]}"
                i += 2
            elif i + 1 < len(values) and r.random() < 0.3:
                label = f"{values[i]}, {values[i + 1]}"
                i += 2
            else:
                label = str(values[i])
                i += 1
            parts += [f"{label}:", self.block(self.stmts(1, loops, mult, depth - 1))]
        if r.random() < 0.6:
            parts += ["ELSE", self.block(self.stmts(1, loops, mult, depth - 1))]
        return "\n".join([*parts, "END_CASE;"])

    def loop(self, loops: list[Loop], mult: int, depth: int) -> str:
        r = self.rng
        busy = {lp.counter for lp in loops}
        fors = [c for c in self.readonly if c.startswith("c") and c not in busy]
        whiles = [c for c in self.readonly if c.startswith("w") and c not in busy]
        if fors and (r.random() < 0.65 or not whiles):
            return self.for_(r.choice(fors), loops, mult, depth)
        w = r.choice(whiles)
        n = r.randint(0, 7)
        inner = loops + [Loop(w, 1, max(n, 1))]  # the body sees the counter after its increment
        cond = self.expr("BOOL", 2, loops)
        form = r.random()
        first = [f"{w} := {w} + 1;"]  # first: a CONTINUE in the body must not skip it
        if form < 0.2:
            first.append(f"IF {w} > {n} THEN EXIT; END_IF;")
        body = self.block([*first, *self.stmts(r.randint(1, 2), inner, mult * max(n, 1), depth - 1)])
        if form < 0.2:
            return f"{w} := 0;\nWHILE TRUE DO\n{body}\nEND_WHILE;"
        if form < 0.6:
            cond = cond if r.random() < 0.5 else f"NOT {cond}"
            return f"{w} := 0;\nWHILE {w} < {n} AND {cond} DO\n{body}\nEND_WHILE;"
        return f"{w} := 0;\nREPEAT\n{body}\nUNTIL {w} >= {n} OR {cond}\nEND_REPEAT;"

    def for_(self, c: str, loops: list[Loop], mult: int, depth: int) -> str:
        r = self.rng
        ct = self.readonly[c]
        clo, chi = bounds(ct)
        signed = ct in SIGNED
        arrs = [(lo, hi) for _, lo, hi in self.arrays.values() if clo <= lo and hi <= chi]
        x = r.random()
        if arrs and x < 0.7:
            alo, ahi = r.choice(arrs)
            lo = r.randint(alo, ahi)
            hi = r.randint(lo, ahi) if r.random() < 0.5 else ahi
            lo = alo if r.random() < 0.5 else lo
        elif x < 0.85 and INTS[ct] <= 32:
            hi = chi  # up to the type's limit: the counter's last step wraps
            lo = hi - r.randint(0, 6)
        else:
            lo = max(clo, r.randint(-6, 4))
            hi = lo + r.randint(0, 8)
        steps = [1, 1, 2, 3] + ([-1, -1, -2, -3] if signed else [])
        step = r.choice(steps)
        start, end = (lo, hi) if step > 0 else (hi, lo)
        y = r.random()
        by = "" if step == 1 and r.random() < 0.6 else f" BY {step}"
        s_txt, e_txt = str(start), str(end)
        if y < 0.15:
            s_txt = f"LIMIT({start if step > 0 else lo}, {self.leaf(ct, loops)}, {hi if step > 0 else start})"
        elif y < 0.3:
            e_txt = f"LIMIT({lo}, {self.leaf(ct, loops)}, {hi})"
        elif y < 0.4:
            alt = r.choice([s for s in steps if s != step])
            by = f" BY SEL({self.expr('BOOL', 1, loops)}, {step}, {alt})"
        elif y < 0.45:
            s_txt, e_txt = e_txt, s_txt  # no iteration at all (or the other way round)
        trips = (hi - lo) // min(abs(s) for s in steps) + 1
        inner = loops + [Loop(c, lo, hi)]
        body = self.block(self.stmts(r.randint(1, 3), inner, mult * trips, depth - 1))
        return f"FOR {c} := {s_txt} TO {e_txt}{by} DO\n{body}\nEND_FOR;"

    def text(self) -> str:
        r = self.rng
        body: list[str] = []
        if self.light:
            body = [self.assign([], 1) for _ in range(3)]
        else:
            body = [self.loop([], 1, 2)]
            if r.random() < 0.5:
                body.insert(r.randint(0, 1), self.stmt([], 1, 1))
            if self.timer:
                on, reset = self.expr("BOOL", 1, []), self.expr("BOOL", 1, [])
                body.insert(0, f"tm(IN := {on}, PT := T#{r.randint(1, 5) * 10}ms);")
                body.insert(1, f"ct(CU := tm.Q, R := {reset}, PV := {r.randint(2, 6)});\nq := q + ct.CV;")
        decl = [f"FUNCTION_BLOCK {self.name}", "VAR_INPUT k : DINT; x : REAL; b : BOOL; END_VAR"]
        decl.append("VAR_OUTPUT q : DINT; y : LREAL; END_VAR")
        decl.append("VAR")
        for v, t in self.vars.items():
            if v not in ("k", "x", "b", "q", "y"):
                decl.append(f"  {v} : {t}" + (f" := {self.inits[v]}" if v in self.inits else "") + ";")
        for a, (e, lo, hi) in self.arrays.items():
            decl.append(f"  {a} : ARRAY[{lo}..{hi}] OF {e};")
        for v, t in self.readonly.items():
            decl.append(f"  {v} : {t};")
        for v, (base, lo, hi) in self.subranges.items():
            decl.append(f"  {v} : {base}({lo}..{hi}) := {lo};")
            decl.append(f"  p{v} : POINTER TO {base};")
            big = f"{base}#{bounds(base)[1] - r.randint(0, 99)}"
            body[:0] = [f"p{v} := ADR({v});", f"IF {self.expr('BOOL', 1, [])} THEN p{v}^ := {big}; END_IF;"]
            body.append(f"q := q + {v} * {v} * {v} MOD {base}#{min(r.choice((97, 101, 65521)), bounds(base)[1])};")
        if self.sub is not None:
            decl.append(f"  sub : {self.sub.name};")
        if self.timer:
            decl.append("  tm : TON;\n  ct : CTU;")
        decl.append("END_VAR")
        if self.temps:
            decl.append("VAR_TEMP " + " ".join(f"{v} : {t};" for v, t in self.temps.items()) + " END_VAR")
        return "\n".join([*decl, *body, "END_FUNCTION_BLOCK", ""])


def generate(seed: int, n_blocks: int = N_BLOCKS) -> tuple[str, list[Block]]:
    """The differential program: the blocks, and `main`, which calls each with inputs from its scan counter."""
    rng = random.Random(seed)
    blocks: list[Block] = []
    lights: list[Block] = []
    for i in range(n_blocks):
        if i % 8 == 0:
            lights.append(Block(rng, f"Lite_{i}x", True, None))
        sub = rng.choice(lights) if rng.random() < 0.4 else None
        blocks.append(Block(rng, rng.choice(("Fb", "fB", "FB_Mix", "Blk")) + f"_{i}", False, sub))
    texts = [b.text() for b in lights + blocks]
    main = ["PROGRAM main", "VAR", "  n : DINT;", "  tot : LINT;", "  rt : LREAL;"]
    main += [f"  i{i} : {b.name};" for i, b in enumerate(blocks)]
    main += ["  lite : " + lights[0].name + ";", "END_VAR", "n := n + 1;"]
    for i, _ in enumerate(blocks):
        k = rng.choice(
            (
                f"n * {rng.randint(2, 9999)} - {rng.randint(0, 50000)}",
                f"n * n * {rng.randint(1000, 3000000)}",
                f"(n MOD {rng.randint(2, 19)}) - {rng.randint(0, 9)}",
                f"-n * {rng.randint(1, 1000)}",
                f"n * {rng.randint(100000, 99999999)}",
            )
        )
        x = rng.choice(
            (
                f"DINT_TO_REAL(n) * {rng.uniform(-3, 3):.3f}",
                f"DINT_TO_REAL(n MOD {rng.randint(2, 9)}) / DINT_TO_REAL(n MOD {rng.randint(2, 5)})",
                "1.0E30 * DINT_TO_REAL(n * n)",
                f"DINT_TO_REAL(n) / {rng.randint(1, 9)}.0 - 7.25",
            )
        )
        b = rng.choice((f", b := (n MOD {rng.randint(2, 5)}) = 0", f", b := n > {rng.randint(1, 60)}", ""))
        main.append(f"i{i}(k := {k}, x := {x}{b});")
        if rng.random() < 0.3:
            main.append(f"tot := tot + i{i}.q;")
        if rng.random() < 0.2:
            main.append(f"rt := SEL(rt = rt, 0.0, rt * 0.5) + LIMIT(-1.0E3, i{i}.y, 1.0E3);")
    main += ["lite(k := n, x := DINT_TO_REAL(n), b := TRUE);", "tot := tot - lite.q;", "END_PROGRAM", ""]
    return "\n".join(texts + ["\n".join(main)]), blocks


# ---------------------------------------------------------------------------- comparing
def snapshot(plc: PLC) -> tuple[dict[str, Any], list[str]]:
    """Every variable of every program instance, walked by its type: {path: value}, with floats as
    their bits; and the integers outside their type's range (a value a typed C local relies on)."""
    out: dict[str, Any] = {}
    bad: list[str] = []

    def walk(path: str, v: Any, t: Any) -> None:
        t = T.unalias(t)
        if isinstance(t, T.ArrayType):
            for i, item in enumerate(v):
                walk(f"{path}[{i}]", item, t.element)
        elif isinstance(t, T.POUType):
            for s in t.vars.values():
                if s.section not in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP", "VAR_STAT"):
                    walk(f"{path}.{s.name}", getattr(v, s.pyname), s.type)
        elif isinstance(t, T.RefType):
            out[path] = ("REF", v is None)
        elif isinstance(v, float):
            out[path] = ("REAL", struct.pack("<d", v).hex())
        elif isinstance(v, int):  # bool included: True == 1
            out[path] = ("INT", int(v))
            rt = t.base if isinstance(t, T.SubrangeType) else t  # a pointer may leave a subrange
            lo, hi = getattr(rt, "lo", None), getattr(rt, "hi", None)
            if isinstance(lo, int) and isinstance(hi, int) and not lo <= v <= hi:
                bad.append(f"{path} = {v} is outside {rt.name} ({lo}..{hi})")
        else:
            out[path] = ("OTHER", repr(v))

    for _lname, (name, obj, pou) in sorted(plc.instances.items()):
        walk(name, obj, pou)
    return out, bad


def differences(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    keys = sorted(set(a) | set(b))
    return [f"{k}: python {a.get(k)} native {b.get(k)}" for k in keys if a.get(k) != b.get(k)]


@pytest.fixture(scope="module")
def differential() -> tuple[str, CompiledProgram, CompiledProgram, list[Block]]:
    text, blocks = generate(SEED)
    python = compile_text(text, "differential.st", use_cache=False)
    native = compile_text(text, "differential.st", native=True)
    return text, python, native, blocks


def test_the_generated_program_runs_natively(differential):
    _text, _python, native, blocks = differential
    assert native.native, ([d.message for d in native.diagnostics if d.code == "W012"], native.native_skipped)
    classes = set(native.native[0].classes)
    expected = {f"_fb_{b.name}" for b in blocks}
    assert expected <= classes, (sorted(expected - classes), native.native_skipped)


def test_both_tiers_compute_the_same_values_after_every_checked_scan(differential):
    _text, python, native, _blocks = differential
    assert native.native, [d.message for d in native.diagnostics if d.code == "W012"]  # else Python against Python
    plcs = PLC(python, watchdog="2s"), PLC(native, watchdog="2s")
    first: dict[str, str] = {}  # path → the first difference seen there (all of them: one does not hide another)
    compared = 0
    for scan in range(1, SCANS + 1):
        for plc in plcs:
            plc.scan()
        if scan % CHECK_EVERY == 0 or scan <= 2:
            (a, _), (b, _) = snapshot(plcs[0]), snapshot(plcs[1])
            compared = len(a)
            for d in differences(a, b):
                first.setdefault(d.split(":")[0], f"after scan {scan}: {d}")
    assert compared > 25 * N_BLOCKS  # every instance's variables were compared (about 30 per block)
    assert not first, f"{len(first)} variables differ:\n" + "\n".join(sorted(first.values(), key=_scan_no)[:40])


def _scan_no(d: str) -> int:
    return int(d.split()[2].rstrip(":"))


def test_integer_values_stay_in_their_types_on_both_tiers(differential):
    """What the native tier's C types rely on: every integer variable holds a value of its type
    (a subrange's base type: a POINTER may leave the subrange)."""
    _text, python, native, _blocks = differential
    bad: dict[str, str] = {}
    for tier, compiled in (("python", python), ("native", native)):
        plc = PLC(compiled, watchdog="2s")
        for scan in range(1, SCANS // 4 + 1):
            plc.scan()
            for b in snapshot(plc)[1]:
                bad.setdefault(f"{tier} {b.split(' = ')[0]}", f"{tier}, after scan {scan}: {b}")
    assert not bad, "\n".join(sorted(bad.values())[:20])


# ---------------------------------------------------------------------------- faults
# mode → (the fault it raises inside a loop, or None: it runs on), and the line that faults is
# marked (* F<mode> *) in FAULT_BLOCK / the PROGRAM; the POU it names
FAULT_MODES = {
    1: ("DIV0", "Fault_Box"),  # DINT DIV 0: the C helper
    2: ("DIV0", "Fault_Box"),  # UDINT / 0: Python's // on C integers
    3: ("DIV0", "Fault_Box"),  # LINT DIV 0: the Python helper
    4: (None, ""),  # MOD 0 is 0
    5: ("INDEX", "Fault_Box"),  # above the upper bound
    6: ("INDEX", "Fault_Box"),  # below a negative lower bound (a Python list would take it)
    7: ("INDEX", "Fault_Box"),  # an ARRAY OF BOOL
    8: ("INDEX", "Fault_Box"),  # an ARRAY OF REAL, read
    9: ("INDEX", "Fault_Box"),  # an ARRAY OF LINT (Python objects)
    10: ("WATCHDOG", "Fault_Box"),  # endless WHILE
    11: ("WATCHDOG", "Fault_Box"),  # endless REPEAT around a FOR (either loop's line: where the time ran out)
    12: ("INDEX", "Inner_Fault"),  # in a block called from a loop
    13: ("CONVERSION", "Fault_Box"),  # REAL_TO_DINT of 1.0E30
    14: ("LOOP", "Fault_Box"),  # FOR BY 0
    15: ("RANGE", "Fault_Box"),  # a subrange left
    16: ("RANGE", "Fault_Box"),  # SHL by a negative count
    17: ("INDEX", "Fault_Box"),  # MUX selector
    18: (None, ""),  # REAL / 0.0: INF and NaN
    19: ("DIV0", "main"),  # in the PROGRAM's own loop
    20: (None, ""),  # DINT overflow: wraps
    21: ("DIV0", "Fault_Box"),  # a product beyond int64 divided by 0
    22: ("INDEX", "Fault_Box"),  # a LINT index
    23: ("INDEX", "Fault_Box"),  # in nested loops
}

FAULT_BLOCK = """\
FUNCTION_BLOCK Inner_Fault
VAR_INPUT mode : INT; k : DINT; END_VAR
VAR_OUTPUT q : DINT; END_VAR
VAR arr : ARRAY[-3..7] OF INT; i : DINT; END_VAR
FOR i := -3 TO 7 DO
  arr[i] := arr[i] + DINT_TO_INT(k);
END_FOR;
IF mode = 12 THEN
  FOR i := 0 TO 3 DO
    q := q + arr[i * 4 - 3]; (* F12 *)
  END_FOR;
END_IF;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Fault_Box
VAR_INPUT mode : INT; k : DINT; END_VAR
VAR
  i : DINT; j : INT; d : DINT := 1000; x : DINT; hi : DINT := 8; u : UDINT; ud : UDINT; l : LINT; lq : LINT;
  s : SINT; w : WORD := 16#F0F0; r : REAL := 1.0; lr : LREAL; sr : INT(0..100); step : DINT; spin : DINT;
  a : ARRAY[-3..7] OF DINT; ab : ARRAY[1..4] OF BOOL; ar : ARRAY[0..2] OF REAL; al : ARRAY[2..5] OF LINT;
  inner : Inner_Fault;
END_VAR
FOR i := -3 TO 7 DO
  a[i] := a[i] * 3 + k;
  x := x + a[i] MOD 7;
END_FOR;
FOR j := 1 TO 4 DO
  ab[j] := NOT ab[j] XOR (k MOD j = 0);
  inner(mode := mode, k := k + j);
END_FOR;
CASE mode OF
1:
  FOR i := 3 TO -3 BY -1 DO
    x := x + 1000 / i; (* F1 *)
  END_FOR;
2:
  ud := 2;
  FOR i := 1 TO 3 DO
    ud := ud - 1;
    u := u + UDINT#100 / ud; (* F2 *)
  END_FOR;
3:
  l := 5;
  FOR i := 1 TO 4 DO
    l := l - 1;
    lq := lq + LINT#1000 / (l - LINT#2); (* F3 *)
  END_FOR;
4:
  FOR i := -2 TO 2 DO
    x := x + 100 MOD i + i MOD 0;
    s := s + SINT#-7 MOD DINT_TO_SINT(i);
    u := u + UDINT#7 MOD DINT_TO_UDINT(i + 2);
  END_FOR;
5:
  FOR i := 5 TO hi DO
    a[i] := a[i] + 1; (* F5 *)
  END_FOR;
6:
  FOR i := 0 TO 5 DO
    a[-i] := a[-i] - 1; (* F6 *)
  END_FOR;
7:
  FOR j := 2 TO 6 BY 2 DO
    ab[j] := TRUE; (* F7 *)
  END_FOR;
8:
  FOR i := 0 TO 3 DO
    r := r + ar[i]; (* F8 *)
  END_FOR;
9:
  FOR i := 5 TO 6 DO
    lq := lq + al[i]; (* F9 *)
  END_FOR;
10:
  WHILE mode = 10 DO (* F10 *)
    spin := spin + 1;
  END_WHILE;
11:
  REPEAT (* F11 *)
    FOR j := 1 TO 3 DO (* F11 *)
      spin := spin + j;
    END_FOR;
  UNTIL FALSE
  END_REPEAT;
13:
  FOR i := 1 TO 3 DO
    r := r * 1.0E30;
    d := REAL_TO_DINT(r); (* F13 *)
  END_FOR;
14:
  FOR i := 1 TO 3 BY step DO (* F14 *)
    x := x + i;
  END_FOR;
15:
  FOR i := 95 TO 105 DO
    sr := DINT_TO_INT(i); (* F15 *)
  END_FOR;
16:
  FOR i := 2 TO -2 BY -1 DO
    w := SHL(w, DINT_TO_INT(i)); (* F16 *)
  END_FOR;
17:
  FOR i := 0 TO 5 DO
    x := x + MUX(i, 1, 2, 3); (* F17 *)
  END_FOR;
18:
  FOR i := -1 TO 1 DO
    r := r / DINT_TO_REAL(i);
    lr := lr + DINT_TO_LREAL(i) / 0.0 - 1.0 / lr;
    ar[i + 1] := DINT_TO_REAL(i) / DINT_TO_REAL(i);
  END_FOR;
20:
  FOR i := 1 TO 3 DO
    d := d * 2147483647 * d + 2147483647;
    x := (-2147483647 - 1) / -1 + d / -1;
    s := s * SINT#-128 - 127;
  END_FOR;
21:
  FOR i := 2 TO -2 BY -1 DO
    x := x + d * d * d / i; (* F21 *)
  END_FOR;
22:
  l := 5;
  FOR i := 1 TO 3 DO
    l := l + 1;
    a[l] := a[l] + i; (* F22 *)
  END_FOR;
23:
  FOR i := 1 TO 3 DO
    FOR j := 1 TO 3 DO
      a[i * j - 1] := a[i * j - 1] + j; (* F23 *)
    END_FOR;
  END_FOR;
END_CASE;
END_FUNCTION_BLOCK
"""


def fault_program(seed: int) -> str:
    """FAULT_BLOCK, two generated blocks of ordinary work around it, and `main`."""
    rng = random.Random(seed)
    lite = Block(rng, "Lite_F", True, None)
    work = [Block(rng, "Work_A", False, lite), Block(rng, "wORK_b", False, None)]
    main = """\
PROGRAM main
VAR mode : INT; n : DINT; j : INT; m : DINT; g0 : Work_A; fb : Fault_Box; g1 : wORK_b; END_VAR
n := n + 1;
g0(k := n * 7919, x := DINT_TO_REAL(n) / 3.0, b := n MOD 2 = 0);
fb(mode := mode, k := n);
IF mode = 19 THEN
  FOR j := 2 TO -2 BY -1 DO
    m := m + 100 / j; (* F19 *)
  END_FOR;
END_IF;
g1(k := n * n * 65537, x := DINT_TO_REAL(n) * 1.5E3);
END_PROGRAM
"""
    return "\n".join([lite.text(), *(b.text() for b in work), FAULT_BLOCK, main])


@pytest.fixture(scope="module")
def faults() -> tuple[str, CompiledProgram, CompiledProgram]:
    text = fault_program(FAULT_SEED)
    return text, compile_text(text, "faults.st", use_cache=False), compile_text(text, "faults.st", native=True)


def _run_mode(compiled: CompiledProgram, mode: int) -> tuple[PLC, FaultInfo | None]:
    plc = PLC(compiled, watchdog="100ms")
    plc.scan(3)
    plc["main.mode"] = mode
    try:
        plc.scan()
    except PLCFaultError as e:
        return plc, e.fault
    return plc, None


@pytest.mark.parametrize("mode", sorted(FAULT_MODES))
def test_a_fault_in_a_loop_is_the_same_on_both_tiers(faults, mode):
    text, python, native = faults
    assert {"_fb_Fault_Box", "_fb_Inner_Fault", "_prg_main"} <= set(native.native[0].classes)
    kind, pou = FAULT_MODES[mode]
    lines = {i for i, s in enumerate(text.splitlines(), 1) if f"(* F{mode} *)" in s}
    (p, fp), (n, fn) = (_run_mode(compiled, mode) for compiled in (python, native))
    if kind is None:
        assert fp is None and fn is None and p.fault is None and n.fault is None
    else:
        assert fp is not None and fn is not None, f"mode {mode}: python {fp} / native {fn}"
        for f in (fp, fn):
            assert (f.kind, f.file, f.pou, f.task) == (kind, "faults.st", pou, "main") and f.line in lines, str(f)
        if len(lines) == 1:
            assert fp == fn, f"mode {mode}: python {fp} / native {fn}"
        else:  # a watchdog in nested loops: the loop whose guard saw the time run out
            assert (fp.kind, fp.message) == (fn.kind, fn.message)
    timed = ("main.fb.spin:", "main.fb.j:") if kind == "WATCHDOG" else ()  # where the endless loop was stopped
    (a, _), (b, _) = snapshot(p), snapshot(n)
    diff = [d for d in differences(a, b) if not d.startswith(timed)]
    assert not diff, "\n".join(diff[:25])
    for plc in (p, n):  # and both run on
        if plc.fault is not None:
            plc.reset_fault()
        plc["main.mode"] = 0
        plc.scan(3)
    (a, _), (b, _) = snapshot(p), snapshot(n)
    diff = [d for d in differences(a, b) if not d.startswith(timed)]
    assert not diff, "\n".join(diff[:25])
