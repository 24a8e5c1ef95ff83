"""Runtime implementations of the IEC standard functions (called by generated code).

Values follow the representation in st.model.types: times are ns integers.
String positions are 1-based as in IEC 61131-3.
"""

from __future__ import annotations

import math
from datetime import date

from ..model.literals import (
    DAY,
    LiteralError,
    format_date,
    format_dt,
    format_duration,
    format_tod,
    parse_duration,
    parse_int,
    parse_real,
)
from ..runtime.faults import PLCFault
from ..runtime.helpers import round_f32, round_half_away

# ------------------------------------------------------------------ numeric


def _std_sqrt(x):
    return math.sqrt(x) if x >= 0 else math.nan


def _std_ln(x):
    if x > 0:
        return math.log(x)
    return -math.inf if x == 0 else math.nan


def _std_log(x):
    if x > 0:
        return math.log10(x)
    return -math.inf if x == 0 else math.nan


def _std_exp(x):
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def _safe(fn):
    def f(x):
        try:
            return fn(x)
        except ValueError:
            return math.nan

    f.__name__ = fn.__name__
    return f


_std_asin = _safe(math.asin)
_std_acos = _safe(math.acos)
_std_sin = _safe(math.sin)  # SIN/COS/TAN of ±INF: NaN, as IEEE 754 says
_std_cos = _safe(math.cos)
_std_tan = _safe(math.tan)


# ------------------------------------------------------------------ bit shifts


def _negative_shift(name, n):
    return PLCFault(f"{name}: the shift count {n} is negative", "RANGE")


def _std_shl(v, n, bits):
    if n < 0:
        raise _negative_shift("SHL", n)
    return (v << n) & ((1 << bits) - 1) if n < bits else 0


def _std_shr(v, n, bits):
    if n < 0:
        raise _negative_shift("SHR", n)
    return (v & ((1 << bits) - 1)) >> n if n < bits else 0


def _std_rol(v, n, bits):
    m = (1 << bits) - 1
    v &= m
    n %= bits
    return ((v << n) | (v >> (bits - n))) & m


def _std_ror(v, n, bits):
    m = (1 << bits) - 1
    v &= m
    n %= bits
    return ((v >> n) | (v << (bits - n))) & m


def _signed(v, bits):
    """Reinterpret an unsigned bit pattern as signed (for shifts on signed ints)."""
    v &= (1 << bits) - 1
    return v - (1 << bits) if v >> (bits - 1) else v


# ------------------------------------------------------------------ selection


def _std_limit(mn, v, mx):
    return mn if v < mn else (mx if v > mx else v)


def _std_mux(k, *args):
    if 0 <= k < len(args):
        return args[k]
    raise PLCFault(f"MUX selector {k} is outside 0..{len(args) - 1}", "INDEX")


def _std_mux_or_default(k, *args):
    """MUX as MatIEC computes it: a selector out of range gives the last argument, the result
    type's default value (the compiler passes it)."""
    *inputs, default = args
    return inputs[k] if 0 <= k < len(inputs) else default


def _std_sel(g, a, b):
    return b if g else a


def _cmp_chain(op):
    def f(*args):
        return all(op(args[i], args[i + 1]) for i in range(len(args) - 1))

    return f


_std_gt = _cmp_chain(lambda a, b: a > b)
_std_ge = _cmp_chain(lambda a, b: a >= b)
_std_eq = _cmp_chain(lambda a, b: a == b)
_std_le = _cmp_chain(lambda a, b: a <= b)
_std_lt = _cmp_chain(lambda a, b: a < b)


def _std_ne(a, b):
    return a != b


# ------------------------------------------------------------------ strings (1-based)


def _std_left(s, n):
    return s[:n] if n > 0 else ""


def _std_right(s, n):
    return s[-n:] if n > 0 else ""


def _std_mid(s, n, p):
    if p < 1:
        raise PLCFault(f"MID: position {p} must be at least 1", "RANGE")
    return s[p - 1 : p - 1 + n] if n > 0 else ""


def _std_concat(*parts):
    return "".join(parts)


def _std_insert(s1, s2, p):
    if p < 0 or p > len(s1):
        raise PLCFault(f"INSERT: position {p} is outside 0..{len(s1)}", "RANGE")
    return s1[:p] + s2 + s1[p:]


def _std_delete(s, n, p):
    if p < 1 or p > len(s) + 1:
        raise PLCFault(f"DELETE: position {p} is outside 1..{len(s)}", "RANGE")
    return s[: p - 1] + s[p - 1 + max(n, 0) :]


def _std_replace(s1, s2, n, p):
    if p < 1 or p > len(s1) + 1:
        raise PLCFault(f"REPLACE: position {p} is outside 1..{len(s1)}", "RANGE")
    return s1[: p - 1] + s2 + s1[p - 1 + max(n, 0) :]


def _std_delete_p0(s, n, p):
    """DELETE as CODESYS's Standard library does it: P = 0 addresses the first character too, with
    L one less (its documented quirk, kept for compatibility)."""
    if p == 0:
        return _std_delete(s, n - 1, 1)
    return _std_delete(s, n, p)


def _std_replace_p0(s1, s2, n, p):
    """REPLACE as CODESYS's Standard library does it: P = 0 as P = 1 with L one less."""
    if p == 0:
        return _std_replace(s1, s2, n - 1, 1)
    return _std_replace(s1, s2, n, p)


def _std_find(s1, s2):
    return s1.find(s2) + 1 if s2 else 0


# ------------------------------------------------------------------ conversions


_round_half_away = round_half_away  # (st.runtime.helpers: the one rounding of REAL → integer)


def _out_of_range(v, lo, hi, name):
    what = "NaN" if v != v else repr(v)
    return PLCFault(f"{what} is outside the range of {name} ({lo}..{hi})", "CONVERSION")


def _real_to_int(v, lo, hi, name):
    """REAL/LREAL → an integer type: rounded half away from zero; out of range (NaN, ±INF
    included) is a CONVERSION fault, never a silently wrapped value."""
    if v != v or not (lo - 0.5 < v < hi + 0.5):
        raise _out_of_range(v, lo, hi, name)
    return round_half_away(v)


def _real_to_int_matiec(v, lo, hi, name):
    """REAL/LREAL → an integer as MatIEC converts (lib/C/iec_std_lib.h, __real_round): v ± 0.5 in
    double precision, truncated, and a result that was an exact integer (v exactly halfway)
    made even: 2.5 → 2, 3.5 → 4, -2.5 → -2. Out of range stays a CONVERSION fault (MatIEC's cast
    is undefined there)."""
    if v != v or not (lo - 0.5 < v < hi + 0.5):
        raise _out_of_range(v, lo, hi, name)
    x = v + 0.5 if v >= 0 else v - 0.5
    q = int(x)  # toward zero, as C's cast
    if x == q:  # halfway: C's (q / 2) * 2, toward zero
        q = q - q % 2 if q >= 0 else q + (-q) % 2
    return q


def _real_trunc_to(v, lo, hi, name):
    """TRUNC: toward zero, with the same range rule as _real_to_int."""
    if v != v or not (lo - 1 < v < hi + 1):
        raise _out_of_range(v, lo, hi, name)
    return int(v)


def _real_to_string(v, bits=64):
    if v != v:
        return "NaN"
    if v in (math.inf, -math.inf):
        return "INF" if v > 0 else "-INF"
    if bits == 32:
        # the shortest text that reads back as the same float32
        for digits in range(1, 10):
            t = f"{v:.{digits}g}"
            if round_f32(float(t)) == v:
                break
    else:
        t = repr(float(v))
    if "e" in t or "E" in t:
        m, e = t.lower().split("e")
        if "." not in m:
            m += ".0"
        return f"{m}E{int(e)}"
    if "." not in t and "inf" not in t and "nan" not in t:
        t += ".0"
    return t


def _to_string(v, kind, bits=0):
    if kind == "bool":
        return "TRUE" if v else "FALSE"
    if kind == "real":
        return _real_to_string(v, bits)
    if kind == "time":
        return format_duration(v, "LT#" if bits == 1 else "T#")
    if kind == "date":
        return format_date(v)
    if kind == "tod":
        return format_tod(v)
    if kind == "dt":
        return format_dt(v)
    if kind == "char":
        return v
    return str(v)


def _str_to_int(s):
    t = s.strip().replace("_", "")
    if "#" in t and not t.split("#", 1)[0].isdigit():
        t = t.split("#", 1)[1]
    try:
        return parse_int(t)
    except (ValueError, LiteralError):
        try:
            return _round_half_away(float(t))
        except ValueError:
            return 0


def _str_to_real(s):
    t = s.strip()
    if "#" in t:
        t = t.split("#", 1)[1]
    try:
        return parse_real(t)
    except ValueError:
        return 0.0


def _str_to_bool(s):
    t = s.strip().upper()
    if "#" in t:
        t = t.split("#", 1)[1]
    return t in ("TRUE", "1")


def _str_to_time(s):
    t = s.strip()
    if "#" in t:
        t = t.split("#", 1)[1]
    try:
        return parse_duration(t)
    except (ValueError, LiteralError):
        return 0


def _to_bcd(v, bits):
    v0 = v
    if v < 0:
        raise PLCFault(f"cannot convert the negative value {v} to BCD", "CONVERSION")
    out, shift = 0, 0
    while v:
        v, d = divmod(v, 10)
        out |= d << shift
        shift += 4
    if shift > bits:
        raise PLCFault(f"{v0} has more digits than {bits // 4} BCD digits hold", "CONVERSION")
    return out


def _from_bcd(v):
    out, mul = 0, 1
    while v:
        d = v & 0xF
        if d > 9:
            raise PLCFault(f"invalid BCD digit {d}", "CONVERSION")
        out += d * mul
        mul *= 10
        v >>= 4
    return out


# ------------------------------------------------------------------ dates


def _concat_date(y, m, d):
    try:
        return (date(y, m, d) - date(1970, 1, 1)).days * DAY
    except ValueError:
        raise PLCFault(f"invalid date {y}-{m}-{d}", "RANGE") from None


def _concat_tod(h, m, s, ms):
    return ((h * 60 + m) * 60 + s) * 1_000_000_000 + ms * 1_000_000


def _day_of_week(d):
    # 1970-01-01 was a Thursday; IEC/CODESYS: 0 = Sunday
    return (d // DAY + 4) % 7


NAMESPACE = {
    name: obj
    for name, obj in list(globals().items())
    if name.startswith("_std_")
    or name
    in (
        "_to_string",
        "_str_to_int",
        "_str_to_real",
        "_str_to_bool",
        "_str_to_time",
        "_to_bcd",
        "_from_bcd",
        "_concat_date",
        "_concat_tod",
        "_day_of_week",
        "_signed",
        "_round_half_away",
        "_real_to_string",
        "_real_to_int",
        "_real_trunc_to",
    )
}
NAMESPACE.update({"_atan": math.atan, "_atan2": math.atan2})
