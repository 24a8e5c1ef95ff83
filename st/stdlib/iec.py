"""The IEC 61131-3 standard library: function signatures, conversions and standard FBs.

Standard function blocks are written in ST (`standard_fbs.st`), compiled with
the user's program like any other POU; functions are native (Python).
"""

from __future__ import annotations

import ast as py
import re
from functools import cache, lru_cache
from pathlib import Path

from ..compiler.codegen.emit import call, const, wrap
from ..compiler.library import FuncSig, Library, Param
from ..model import types as T
from . import functions

FBS_PATH = Path(__file__).with_name("standard_fbs.st")
FUNCTIONS_PATH = Path(__file__).with_name("standard_functions.st")
OPENPLC_FBS_PATH = Path(__file__).with_name("openplc_fbs.st")  # PID, RAMP, RTC, SEMA...: OpenPLC's extra blocks
NS_PER_MS = 1_000_000


def _p(name, constraint, group=""):
    return Param(name, constraint, group)


def _emit_helper(helper):
    def emit(ctx, args, types, rt):
        return call(helper, *args)

    return emit


def _emit_wrap(node, rt):
    b = T.base_of(rt)
    if b.is_intlike:
        return wrap(node, b)
    if b is T.REAL:
        return call("_f32", node)
    return node


def _real_result(types):
    """ANY_REAL functions accept integers and compute them as LREAL (REAL for ≤16-bit ints)."""
    t = T.base_of(types[0])
    if t.is_real:
        return t
    if isinstance(t, T.LiteralType):
        return T.LREAL
    return T.REAL if t.bits <= 16 else T.LREAL


def _math(name, helper):
    def emit(ctx, args, types, rt):
        node = call(helper, args[0])
        return call("_f32", node) if T.base_of(rt) is T.REAL else node

    return FuncSig(name, [_p("IN", "ANY_REAL")], _real_result, emit=emit)


def _bits_of(t):
    b = T.base_of(t)
    return b.bits if b.is_intlike else 1


def _shift_inline(name, v, n, bits):
    """SHL/SHR/ROL/ROR of an unsigned value by a constant count, inline (None: keep the helper,
    which also faults on a negative count)."""
    mask = (1 << bits) - 1
    if name == "SHL" and 0 <= n < bits:
        return py.BinOp(py.BinOp(v, py.LShift(), const(n)), py.BitAnd(), const(mask))
    if name == "SHR" and 0 <= n < bits:
        masked = v if _simple(v) else py.BinOp(v, py.BitAnd(), const(mask))  # an exact intermediate
        return py.BinOp(masked, py.RShift(), const(n))
    if name in ("ROL", "ROR") and _simple(v):
        n %= bits
        if n == 0:
            return py.BinOp(v, py.BitAnd(), const(mask))
        left, right = (n, bits - n) if name == "ROL" else (bits - n, n)
        both = py.BinOp(py.BinOp(v, py.LShift(), const(left)), py.BitOr(), py.BinOp(v, py.RShift(), const(right)))
        return py.BinOp(both, py.BitAnd(), const(mask))
    return None


def _shift(name, helper):
    def emit(ctx, args, types, rt):
        b = T.base_of(rt)
        n = args[1]
        if b.is_intlike and not b.signed and isinstance(n, py.Constant) and type(n.value) is int:
            inline = _shift_inline(name, args[0], n.value, b.bits)
            if inline is not None:
                return inline
        node = call(helper, args[0], args[1], const(b.bits))
        if b.is_int and b.signed:
            node = call("_signed", node, const(b.bits))
        return node

    sig = FuncSig(name, [_p("IN", "ANY_BIT", "T"), _p("N", "ANY_INT")], "T", emit=emit)
    sig.exact = True
    return sig


def _arith(name, op, extensible):
    def emit(ctx, args, types, rt):
        if T.base_of(rt).is_time and op in ("*", "/"):
            # MUL(TIME, ANY_NUM), DIV(TIME, ANY_NUM): the time functions' overloads
            return _time_fn(name, "TIME", "ANY_NUM", "TIME", op).emit(ctx, args, types, rt)
        node = args[0]
        for a in args[1:]:
            if op == "/":
                b = T.base_of(rt)
                node = call("_fdiv", node, a) if b.is_real else call("_idiv", node, a)
            elif op == "MOD":
                node = call("_imod", node, a)
            else:
                node = py.BinOp(node, {"+": py.Add(), "-": py.Sub(), "*": py.Mult()}[op], a)
        return node

    params = [_p("IN1", "ANY_MAGNITUDE", "T"), _p("IN2", "ANY_MAGNITUDE", "T")]
    result = "T"
    if op in ("*", "/"):
        # ANY_NUM × ANY_NUM, or TIME × ANY_NUM → TIME
        params = [_p("IN1", "ANY_MAGNITUDE"), _p("IN2", "ANY_NUM")]
        result = _mul_div_result(name)
    if op == "MOD":
        params = [_p("IN1", "ANY_INT", "T"), _p("IN2", "ANY_INT", "T")]
    if op == "-":
        # SUB of two dates of one type (DT, TOD, DATE) is the TIME between them, as `-` is (IEC 61131-3
        # overloads SUB for the time types; SUB_DT_DT and its kin are the typed forms)
        params = [_p("IN1", "ANY_MAGNITUDE or ANY_DATE", "T"), _p("IN2", "ANY_MAGNITUDE or ANY_DATE", "T")]
    sig = FuncSig(name, params, result, extensible=extensible, emit=emit, min_args=2)
    if op == "-":
        sig.group_result = _date_difference
    return sig


def _date_difference(t: T.Type) -> T.Type:
    """The type SUB gives for arguments of the common type `t`: a date's is a TIME (LTIME for the long ones)."""
    b = T.base_of(t)
    if isinstance(b, T.ElemType) and b.kind in ("dt", "tod", "date"):
        return T.LTIME if b.long else T.TIME
    return t


def _mul_div_result(name):
    def result(types):
        a = T.base_of(types[0])
        if a.is_time:
            return a
        if any(T.base_of(t).is_time for t in types[1:]):
            return f"{name}: only the first argument may be a TIME"
        out = types[0]
        for t in types[1:]:
            c = T.common_type(out, t)
            if c is None:
                return f"{name}: incompatible argument types {out} and {t}"
            out = c
        return out

    return result


def _cmp(name, helper):
    return FuncSig(
        name,
        [_p("IN1", "ANY_ELEMENTARY", "T"), _p("IN2", "ANY_ELEMENTARY", "T")],
        "BOOL",
        extensible=name != "NE",
        helper=helper,
        min_args=2,
    )


def _time_fn(name, a, b, result, op):
    def emit(ctx, args, types, rt):
        x, y = args
        if op == "+":
            node = py.BinOp(x, py.Add(), y)
        elif op == "-":
            node = py.BinOp(x, py.Sub(), y)
        elif op == "*":
            yt = T.base_of(types[1])
            node = py.BinOp(x, py.Mult(), y)
            if yt.is_real or yt is T.LIT_REAL:
                node = call("_round", node)
        elif op == "/":
            yt = T.base_of(types[1])
            node = call("_round", call("_fdiv", x, y)) if (yt.is_real or yt is T.LIT_REAL) else call("_idiv", x, y)
        elif op == "concat":
            node = py.BinOp(x, py.Add(), py.BinOp(y, py.Mod(), const(functions.DAY)))
        if result in ("TOD", "LTOD"):
            node = py.BinOp(node, py.Mod(), const(functions.DAY))
        return node

    return FuncSig(name, [_p("IN1", a), _p("IN2", b)], result, emit=emit)


def _len_emit(ctx, args, types, rt):
    return call("_len", args[0])


def _simple(node: py.expr) -> bool:
    """An operand that may be evaluated twice: a name, a constant, `x.y`, `-1`."""
    if isinstance(node, py.UnaryOp):
        node = node.operand
    if isinstance(node, py.Attribute):
        node = node.value
    return isinstance(node, (py.Name, py.Constant))


def _limit_emit(ctx, args, types, rt):
    """LIMIT(MN, IN, MX) inline when MN and MX are plain operands (no call per use)."""
    mn, v, mx = args
    if not (_simple(mn) and _simple(mx)) or not hasattr(ctx, "new_tmp"):
        return call("_std_limit", *args)
    if _simple(v):
        first, again = v, v
    else:
        t = ctx.new_tmp()
        first, again = py.NamedExpr(py.Name(t, py.Store()), v), py.Name(t, py.Load())
    inner = py.IfExp(py.Compare(again, [py.Gt()], [mx]), mx, again)
    return py.IfExp(py.Compare(first, [py.Lt()], [mn]), mn, inner)


def _move_emit(ctx, args, types, rt):
    return args[0]


def _abs_emit(ctx, args, types, rt):
    return call("_abs", args[0])


def _minmax(name, helper):
    cmp = py.Lt if name == "MIN" else py.Gt

    def emit(ctx, args, types, rt):
        """Two plain operands inline, deciding as the builtin does (the second replaces the first
        only when strictly smaller, resp. larger: the same result for NaN and equal values)."""
        if len(args) != 2 or not (_simple(args[0]) and _simple(args[1])):
            return call(helper, *args)
        a, b = args
        return py.IfExp(py.Compare(b, [cmp()], [a]), b, a)

    return FuncSig(
        name,
        [_p("IN1", "ANY_ELEMENTARY", "T"), _p("IN2", "ANY_ELEMENTARY", "T")],
        "T",
        extensible=True,
        emit=emit,
        min_args=2,
    )


def _sel_emit(ctx, args, types, rt):
    """SEL of plain operands inline (nothing to evaluate but the one chosen)."""
    if all(_simple(a) for a in args):
        g, in0, in1 = args
        return py.IfExp(g, in1, in0)
    return call("_std_sel", *args)


def _now_emit(ctx, args, types, rt):
    return py.Name("_now", py.Load())


def _string_result(types):
    return T.base_of(types[0]) if isinstance(T.base_of(types[0]), T.StringType) else T.STRING


def _concat_result(types):
    total = 0
    wide = False
    for t in types:
        b = T.base_of(t)
        if isinstance(b, T.StringType):
            total += b.length
            wide = b.wide
        else:
            total += 1
    return T.StringType(max(80, min(total, 65535)), wide)


def _trunc_sig(name, dst):
    def emit(ctx, args, types, rt):
        b = T.base_of(rt)
        if b.is_intlike:
            return call("_real_trunc_to", args[0], const(b.lo), const(b.hi), const(b.name))
        return _emit_wrap(call("_trunc", args[0]), rt)

    res = (lambda ts: T.DINT) if dst is None else dst
    sig = FuncSig(name, [_p("IN", "ANY_REAL")], res, emit=emit)
    sig.result_from_context = dst is None
    return sig


def build_library(
    *,
    f_trig_first_scan: bool = False,
    time_unit: str = "ms",
    matiec_errors: bool = False,
    position_zero: bool = False,
) -> Library:
    """The IEC standard library. `time_unit`: what TIME_TO_<int> counts (ms, or s as MatIEC).
    `matiec_errors`: where IEC calls a case an error and leaves the reaction open, do what MatIEC
    does (a MUX selector out of range gives the type's default value) instead of a PLC fault.
    `position_zero`: DELETE and REPLACE take P = 0 as CODESYS's Standard library does (the first
    character, L one less) instead of a RANGE fault."""
    lib = Library(
        "iec61131",
        version=f"1-{int(f_trig_first_scan)}-{time_unit}-{int(matiec_errors)}-{int(position_zero)}",
        namespaces=("Standard", "Tc2_Standard"),
        inline_blocks=True,
    )
    lib.sources.append((str(FBS_PATH), standard_fbs_source(f_trig_first_scan)))
    lib.sources.append((str(FUNCTIONS_PATH), FUNCTIONS_PATH.read_text()))
    lib.sources.append((str(OPENPLC_FBS_PATH), OPENPLC_FBS_PATH.read_text()))
    lib.helpers.update(functions.NAMESPACE)
    if matiec_errors:  # REAL → integer rounds as MatIEC does: halfway cases to even
        lib.helpers["_real_to_int"] = functions._real_to_int_matiec
    if position_zero:
        lib.helpers["_std_delete"] = functions._std_delete_p0
        lib.helpers["_std_replace"] = functions._std_replace_p0
    add = lib.add
    # numeric
    add(FuncSig("ABS", [_p("IN", "ANY_NUM", "T")], "T", emit=_abs_emit))
    for name, helper in (
        ("SQRT", "_std_sqrt"),
        ("LN", "_std_ln"),
        ("LOG", "_std_log"),
        ("EXP", "_std_exp"),
        ("SIN", "_std_sin"),
        ("COS", "_std_cos"),
        ("TAN", "_std_tan"),
        ("ASIN", "_std_asin"),
        ("ACOS", "_std_acos"),
        ("ATAN", "_atan"),
    ):
        add(_math(name, helper))

    def atan2_emit(ctx, args, types, rt):
        node = call("_atan2", args[0], args[1])
        return call("_f32", node) if T.base_of(rt) is T.REAL else node

    add(
        FuncSig(
            "ATAN2",
            [_p("Y", "ANY_REAL", "T"), _p("X", "ANY_REAL", "T")],
            lambda ts: _real_result([T.common_type(ts[0], ts[1]) or ts[0]]),
            emit=atan2_emit,
        )
    )

    def expt_emit(ctx, args, types, rt):
        node = call("_pow", args[0], args[1])
        return call("_f32", node) if T.base_of(rt) is T.REAL else node

    add(FuncSig("EXPT", [_p("IN1", "ANY_REAL"), _p("IN2", "ANY_NUM")], _real_result, emit=expt_emit))
    add(_arith("ADD", "+", True))
    add(_arith("MUL", "*", True))
    add(_arith("SUB", "-", False))
    add(_arith("DIV", "/", False))
    add(_arith("MOD", "MOD", False))
    add(FuncSig("MOVE", [_p("IN", "ANY", "T")], "T", emit=_move_emit))
    # bit strings
    add(_shift("SHL", "_std_shl"))
    add(_shift("SHR", "_std_shr"))
    add(_shift("ROL", "_std_rol"))
    add(_shift("ROR", "_std_ror"))

    # AND/OR/XOR/NOT in function form, as the OpenPLC Editor writes them for FBD/LD blocks
    def _bitwise(name, pyop):
        def emit(ctx, args, types, rt):
            node = args[0]
            for a in args[1:]:
                node = py.BinOp(node, pyop(), a)
            return node

        sig = FuncSig(
            name, [_p("IN1", "ANY_BIT", "T"), _p("IN2", "ANY_BIT", "T")], "T", extensible=True, emit=emit, min_args=2
        )
        sig.exact = True
        return sig

    add(_bitwise("AND", py.BitAnd))
    add(_bitwise("OR", py.BitOr))
    add(_bitwise("XOR", py.BitXor))

    def not_emit(ctx, args, types, rt):
        b = T.base_of(rt)
        if b.is_bool:
            return py.UnaryOp(py.Not(), args[0])
        if b.is_intlike and not b.signed:
            return py.BinOp(py.UnaryOp(py.Invert(), args[0]), py.BitAnd(), const(b.hi))
        return py.UnaryOp(py.Invert(), args[0])

    add(FuncSig("NOT", [_p("IN", "ANY_BIT", "T")], "T", emit=not_emit))
    # selection
    add(FuncSig("SEL", [_p("G", "BOOL"), _p("IN0", "ANY", "T"), _p("IN1", "ANY", "T")], "T", emit=_sel_emit))
    add(_minmax("MAX", "_max"))
    add(_minmax("MIN", "_min"))
    add(
        FuncSig(
            "LIMIT",
            [_p("MN", "ANY_ELEMENTARY", "T"), _p("IN", "ANY_ELEMENTARY", "T"), _p("MX", "ANY_ELEMENTARY", "T")],
            "T",
            emit=_limit_emit,
        )
    )
    add(
        FuncSig(
            "MUX",
            [_p("K", "ANY_INT"), _p("IN0", "ANY", "T"), _p("IN1", "ANY", "T")],
            "T",
            extensible=True,
            helper="_std_mux" if not matiec_errors else "_std_mux_or_default",
            extra=None if not matiec_errors else _mux_default,
            min_args=2,
            eno_ok=None if not matiec_errors else _mux_in_range,
        )
    )
    # comparison
    for name in ("GT", "GE", "EQ", "LE", "LT", "NE"):
        add(_cmp(name, "_std_" + name.lower()))
    # strings
    add(FuncSig("LEN", [_p("IN", "ANY_STRING")], "INT", emit=_len_emit))
    add(FuncSig("LEFT", [_p("IN", "ANY_STRING"), _p("L", "ANY_INT")], _string_result, helper="_std_left"))
    add(FuncSig("RIGHT", [_p("IN", "ANY_STRING"), _p("L", "ANY_INT")], _string_result, helper="_std_right"))
    add(
        FuncSig(
            "MID", [_p("IN", "ANY_STRING"), _p("L", "ANY_INT"), _p("P", "ANY_INT")], _string_result, helper="_std_mid"
        )
    )
    add(
        FuncSig(
            "CONCAT",
            [_p("IN1", "ANY_CHARS"), _p("IN2", "ANY_CHARS")],
            _concat_result,
            extensible=True,
            helper="_std_concat",
            min_args=2,
        )
    )
    add(
        FuncSig(
            "INSERT",
            [_p("IN1", "ANY_STRING"), _p("IN2", "ANY_STRING"), _p("P", "ANY_INT")],
            _concat_result,
            helper="_std_insert",
        )
    )
    add(
        FuncSig(
            "DELETE",
            [_p("IN", "ANY_STRING"), _p("L", "ANY_INT"), _p("P", "ANY_INT")],
            _string_result,
            helper="_std_delete",
        )
    )
    add(
        FuncSig(
            "REPLACE",
            [_p("IN1", "ANY_STRING"), _p("IN2", "ANY_STRING"), _p("L", "ANY_INT"), _p("P", "ANY_INT")],
            _concat_result,
            helper="_std_replace",
        )
    )
    add(FuncSig("FIND", [_p("IN1", "ANY_STRING"), _p("IN2", "ANY_STRING")], "INT", helper="_std_find"))
    # TwinCAT's (Tc2_Standard's) names of the string functions' parameters, beside IEC's
    for name, aliases in (
        ("LEN", {"str": "in"}),
        ("LEFT", {"str": "in", "size": "l"}),
        ("RIGHT", {"str": "in", "size": "l"}),
        ("MID", {"str": "in", "len": "l", "pos": "p"}),
        ("CONCAT", {"str1": "in1", "str2": "in2"}),
        ("INSERT", {"str1": "in1", "str2": "in2", "pos": "p"}),
        ("DELETE", {"str": "in", "len": "l", "pos": "p"}),
        ("REPLACE", {"str1": "in1", "str2": "in2"}),
        ("FIND", {"str1": "in1", "str2": "in2"}),
    ):
        lib.functions[name].aliases = aliases
    # time and date
    for name, a, b, r, op in (
        ("ADD_TIME", "TIME", "TIME", "TIME", "+"),
        ("ADD_LTIME", "LTIME", "LTIME", "LTIME", "+"),
        ("SUB_TIME", "TIME", "TIME", "TIME", "-"),
        ("SUB_LTIME", "LTIME", "LTIME", "LTIME", "-"),
        ("ADD_TOD_TIME", "TOD", "TIME", "TOD", "+"),
        ("ADD_DT_TIME", "DT", "TIME", "DT", "+"),
        ("SUB_TOD_TIME", "TOD", "TIME", "TOD", "-"),
        ("SUB_DT_TIME", "DT", "TIME", "DT", "-"),
        ("SUB_DATE_DATE", "DATE", "DATE", "TIME", "-"),
        ("SUB_TOD_TOD", "TOD", "TOD", "TIME", "-"),
        ("SUB_DT_DT", "DT", "DT", "TIME", "-"),
        ("MUL_TIME", "TIME", "ANY_NUM", "TIME", "*"),
        ("MULTIME", "TIME", "ANY_NUM", "TIME", "*"),
        ("DIV_TIME", "TIME", "ANY_NUM", "TIME", "/"),
        ("DIVTIME", "TIME", "ANY_NUM", "TIME", "/"),
        ("MUL_LTIME", "LTIME", "ANY_NUM", "LTIME", "*"),
        ("DIV_LTIME", "LTIME", "ANY_NUM", "LTIME", "/"),
        ("CONCAT_DATE_TOD", "DATE", "TOD", "DT", "concat"),
    ):
        add(_time_fn(name, a, b, r, op))
    add(
        FuncSig(
            "CONCAT_DATE",
            [_p("YEAR", "ANY_INT"), _p("MONTH", "ANY_INT"), _p("DAY", "ANY_INT")],
            "DATE",
            helper="_concat_date",
        )
    )
    add(
        FuncSig(
            "CONCAT_TOD",
            [_p("HOUR", "ANY_INT"), _p("MINUTE", "ANY_INT"), _p("SECOND", "ANY_INT"), _p("MILLISECOND", "ANY_INT")],
            "TOD",
            helper="_concat_tod",
        )
    )
    add(FuncSig("DAY_OF_WEEK", [_p("IN", "DATE")], "INT", helper="_day_of_week"))
    add(_trunc_sig("TRUNC", None))
    # the PLC clock, for the standard timers
    add(FuncSig("__PLC_TIME", [], "TIME", emit=_now_emit))
    # CODESYS and TwinCAT: TIME() is the time since the PLC started (here: the PLC clock, latched per scan)
    add(FuncSig("TIME", [], "TIME", emit=_now_emit))
    lib.conversion = lambda name: _conversion(name, time_unit)
    return lib


# ------------------------------------------------------------------ X_TO_Y


_TYPE_NAMES = sorted(T.ELEMENTARY, key=len, reverse=True)


@cache
def _conversion(name: str, time_unit: str):
    up = name.upper()
    m = re.fullmatch(r"(?:([A-Z_]+)_)?TRUNC_([A-Z_]+)", up)
    if m and (m.group(1) is None or m.group(1) in ("REAL", "LREAL")) and m.group(2) in T.ELEMENTARY:
        dst = T.ELEMENTARY[m.group(2)]
        if dst.is_int:
            return _trunc_sig(up, dst.name)
    for i in [k.start() for k in re.finditer("_TO_", up)] + ([-1] if up.startswith("TO_") else []):
        if i == -1:
            left, right = "", up[3:]
        else:
            left, right = up[:i], up[i + 4 :]
        src_bcd = dst_bcd = False
        if left == "BCD":
            left, src_bcd = "WORD", True
        elif left.endswith("_BCD") and left[:-4] in T.ELEMENTARY:
            left, src_bcd = left[:-4], True
        if right == "BCD":
            right, dst_bcd = "WORD", True
        elif right.startswith("BCD_") and right[4:] in T.ELEMENTARY:
            right, dst_bcd = right[4:], True
        if right not in T.ELEMENTARY or (left and left not in T.ELEMENTARY):
            continue
        dst = T.ELEMENTARY[right]
        src = T.ELEMENTARY[left] if left else None
        if dst_bcd and src is not None and not src.is_intlike:
            continue
        if src is not None:
            try:  # only pairs IEC defines exist (REAL_TO_TOD does not)
                convert(py.Name("x", py.Load()), src, dst, src_bcd, dst_bcd, time_unit)
            except TypeError:
                return None
        return _conversion_sig(up, src, dst, src_bcd, dst_bcd, time_unit)
    return None


def _conversion_sig(name, src, dst, src_bcd, dst_bcd, time_unit):
    def emit(ctx, args, types, rt):
        s = T.base_of(types[0])
        return convert(args[0], s, dst, src_bcd, dst_bcd, time_unit, ctx)

    constraint = src.name if src is not None else "ANY_ELEMENTARY"
    if src is not None and src.is_string:
        constraint = "ANY_STRING"
    sig = FuncSig(
        name, [_p("IN", constraint)], dst.name if not isinstance(dst, T.StringType) else (lambda ts: dst), emit=emit
    )
    sig.exact = True
    sig.typed_args = lambda i, t: not _wraps_itself(t, dst, src_bcd or dst_bcd)
    return sig


def _wraps_itself(t, dst, bcd: bool) -> bool:
    """Does converting an integer of type t to dst wrap to dst (to a type no wider that cannot hold
    all of t's values), which keeps the low bits a wrap to t first would keep?"""
    return not bcd and dst.is_intlike and t.bits >= dst.bits and not (dst.lo <= t.lo and t.hi <= dst.hi)


def convert(node, s, d, src_bcd=False, dst_bcd=False, time_unit="ms", ctx=None):
    """Python code converting a value of type s to type d (IEC conversion rules)."""
    if isinstance(s, T.LiteralType):
        s = T.LREAL if s is T.LIT_REAL else T.LINT
    if isinstance(s, T.EnumType):
        s = s.base
    if isinstance(s, T.SubrangeType):
        s = s.base
    sk, dk = s.kind, d.kind
    unit = 1_000_000_000 if time_unit == "s" else NS_PER_MS
    if src_bcd:
        node = call("_from_bcd", node)
        sk = "int"
        s = T.ULINT
    if dst_bcd:
        return call("_to_bcd", node, const(d.bits))
    if s is d:
        return node
    if dk == "string":
        if sk == "string":
            return node
        txt = call("_to_string", node, const(sk), const(1 if (sk == "time" and s.long) else s.bits))
        return txt
    if sk == "string":
        if dk in ("int", "bit"):
            return wrap(call("_str_to_int", node), d)
        if dk == "real":
            return call("_f32", call("_str_to_real", node)) if d is T.REAL else call("_str_to_real", node)
        if dk == "bool":
            return call("_str_to_bool", node)
        if dk == "time":
            return call("_str_to_time", node)
        if dk == "char":
            return py.Subscript(py.BinOp(node, py.Add(), const("\0")), const(0), py.Load())
        raise TypeError
    if dk == "bool":
        return py.Compare(node, [py.NotEq()], [const(0)])
    if sk == "bool":
        node = call("_int", node)
        if dk == "real":
            return call("_float", node)
        if dk == "time":
            return py.BinOp(node, py.Mult(), const(unit))
        return node
    if sk == "char":
        node = call("_ord", node)
        sk = "int"
        s = T.UINT
    if dk == "char":
        if sk == "real":
            node = call("_real_to_int", node, const(0), const(d.hi), const(d.name))
        return call("_chr", py.BinOp(node, py.BitAnd(), const(0xFF if d is T.CHAR else 0xFFFF)))
    if sk in ("int", "bit") and dk in ("int", "bit"):
        if s.lo >= d.lo and s.hi <= d.hi:
            return node
        return wrap(node, d)
    if sk == "real" and dk in ("int", "bit"):
        return call("_real_to_int", node, const(d.lo), const(d.hi), const(d.name))
    if sk in ("int", "bit") and dk == "real":
        node = call("_float", node)
        return call("_f32", node) if d is T.REAL and s.bits > 16 else node
    if sk == "real" and dk == "real":
        return call("_f32", node) if d is T.REAL else node
    # time and dates (ns integers)
    if sk == "time" and dk in ("int", "bit"):
        per = 1 if s.long else unit
        return wrap(call("_idiv", node, const(per)) if per != 1 else node, d)
    if sk in ("int", "bit") and dk == "time":
        per = 1 if d.long else unit
        return py.BinOp(node, py.Mult(), const(per)) if per != 1 else node
    if sk == "time" and dk == "real":
        per = 1 if s.long else unit
        node = py.BinOp(node, py.Div(), const(float(per)))
        return call("_f32", node) if d is T.REAL else node
    if sk == "real" and dk == "time":
        per = 1 if d.long else unit
        return call("_round", py.BinOp(node, py.Mult(), const(float(per))))
    if sk == dk:  # TIME ↔ LTIME, DATE ↔ LDATE, ...
        return node
    DAY = functions.DAY
    if sk == "dt" and dk == "date":
        return py.BinOp(node, py.Sub(), py.BinOp(node, py.Mod(), const(DAY)))
    if sk == "dt" and dk == "tod":
        return py.BinOp(node, py.Mod(), const(DAY))
    if sk == "date" and dk == "dt":
        return node
    if sk == "tod" and dk == "time" or sk == "time" and dk == "tod":
        return node if dk == "time" else py.BinOp(node, py.Mod(), const(DAY))
    if sk == "time" and dk == "dt" or sk in ("dt", "date") and dk == "time":  # CODESYS: from 1970-01-01
        return node
    if sk == "time" and dk == "date":
        return py.BinOp(node, py.Sub(), py.BinOp(node, py.Mod(), const(DAY)))
    if sk in ("dt", "date") and dk in ("int", "bit"):
        return wrap(call("_idiv", node, const(1_000_000_000)), d)
    if sk == "tod" and dk in ("int", "bit"):
        return wrap(call("_idiv", node, const(NS_PER_MS)), d)
    if sk in ("int", "bit") and dk in ("dt", "date"):
        node = py.BinOp(node, py.Mult(), const(1_000_000_000))
        if dk == "date":
            node = py.BinOp(node, py.Sub(), py.BinOp(node, py.Mod(), const(DAY)))
        return node
    if sk in ("int", "bit") and dk == "tod":
        return py.BinOp(py.BinOp(node, py.Mult(), const(NS_PER_MS)), py.Mod(), const(DAY))
    raise TypeError(f"no conversion from {s} to {d}")


# ------------------------------------------------------------------ standard FBs in ST


_COUNTER_TYPES = (("", "INT"), ("_DINT", "DINT"), ("_LINT", "LINT"), ("_UDINT", "UDINT"), ("_ULINT", "ULINT"))


def standard_fbs_source(f_trig_first_scan: bool) -> str:
    text = FBS_PATH.read_text()
    parts = [text]
    ctu = _section(text, "CTU")
    ctd = _section(text, "CTD")
    ctud = _section(text, "CTUD")
    for suffix, ty in _COUNTER_TYPES[1:]:
        for tmpl, name in ((ctu, "CTU"), (ctd, "CTD"), (ctud, "CTUD")):
            parts.append(
                tmpl.replace(f"FUNCTION_BLOCK {name}\n", f"FUNCTION_BLOCK {name}{suffix}\n").replace(
                    ": INT;", f": {ty};"
                )
            )
    if f_trig_first_scan:
        parts[0] = parts[0].replace("M : BOOL := TRUE; (* F_TRIG memory *)", "M : BOOL; (* F_TRIG memory *)")
    return "\n".join(parts)


def _section(text: str, name: str) -> str:
    start = text.index(f"FUNCTION_BLOCK {name}\n")
    end = text.index("END_FUNCTION_BLOCK", start) + len("END_FUNCTION_BLOCK")
    return text[start:end] + "\n"


NAMESPACE_EXTRA = {"_ord": ord, "_chr": chr}


def _mux_in_range(n_args: int):
    """MatIEC's MUX: ENO is whether the selector picked an input (0 <= K < the number of inputs)."""

    def ok(args: list) -> py.expr:
        return py.Compare(const(0), [py.LtE(), py.Lt()], [args[0], const(n_args - 1)])

    return ok


def _mux_default(arg_types, result_type):
    """MatIEC's MUX out of range: the result type's default value, passed after the inputs."""
    b = T.base_of(result_type) if result_type is not None else None
    if isinstance(b, T.StringType):
        return [""]
    default = getattr(b, "default", None)
    return [default if isinstance(default, (bool, int, float, str)) else 0]


@lru_cache(maxsize=8)
def default_library(
    f_trig_first_scan: bool = False, time_unit: str = "ms", matiec_errors: bool = False, position_zero: bool = False
) -> Library:
    lib = build_library(
        f_trig_first_scan=f_trig_first_scan,
        time_unit=time_unit,
        matiec_errors=matiec_errors,
        position_zero=position_zero,
    )
    lib.helpers.update(NAMESPACE_EXTRA)
    return lib
