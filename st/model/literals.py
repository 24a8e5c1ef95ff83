"""Literal text → values. Time and date values are integers of nanoseconds.

TIME/LTIME: a duration in ns.  DATE/DT: ns since 1970-01-01 (UTC, no zone).
TOD: ns since midnight.  These are also the runtime representations.
"""

from __future__ import annotations

import math
import re
import struct
from datetime import UTC, date, datetime

NS = 1
US = 1_000
MS = 1_000_000
SEC = 1_000_000_000
MIN = 60 * SEC
HOUR = 60 * MIN
DAY = 24 * HOUR

_UNITS = {"d": DAY, "h": HOUR, "m": MIN, "s": SEC, "ms": MS, "us": US, "ns": NS}
_TIME_PART = re.compile(r"([0-9][0-9_]*(?:\.[0-9_]+)?)(ms|us|ns|d|h|m|s)", re.I)
_EPOCH = datetime(1970, 1, 1, tzinfo=UTC)


class LiteralError(ValueError):
    pass


class LiteralRangeError(LiteralError):
    """A well-formed literal whose value its type cannot hold (E021, where LiteralError is E004).
    The message reads after the literal: "does not fit in TIME (…)"."""


# TIME, LTIME, DATE, DT, TOD (and the other L- types) are 64-bit signed counts of ns in st's type
# model (types.py); a literal outside this range does not fit its type in any preset
NS_MIN, NS_MAX = -(1 << 63), (1 << 63) - 1
# CODESYS and TwinCAT hold LTIME as an unsigned 64-bit count of ns: a literal up to 2**64 - 1 is
# read here and the checker decides by the preset (E021, or the same 64 bits as st's signed value)
LTIME_UNSIGNED_MAX = (1 << 64) - 1


MAX_INT_DIGITS = 128  # far beyond ULINT (20 decimal digits); longer is a slip, not a number


def parse_int(text: str) -> int:
    t = text.replace("_", "")
    base, digits = t.split("#", 1) if "#" in t else ("10", t)
    if not digits:
        raise LiteralError(f"missing digits in '{text}'")
    if len(digits.lstrip("0")) > MAX_INT_DIGITS:
        raise LiteralError(f"{len(digits)} digits: too long for any integer type (ULINT holds 20 decimal digits)")
    return int(digits, int(base))


def parse_real(text: str) -> float:
    return float(text.replace("_", ""))


# --------------------------------------------------------------------------- literals in source text
# The parsers above are lenient (STRING_TO_INT, values typed into the API); a literal in a program
# goes through the functions below, which also apply IEC 61131-3's rules for '_' and the ranges.

_F32 = struct.Struct("<f")
_HEX = frozenset("0123456789abcdefABCDEF")
_DEC = frozenset("0123456789")
_LETTERS = re.compile(r"[A-Za-z]+")
_UNDERSCORE_RULE = "IEC 61131-3 allows a single '_' only between two digits"


def underscore_problem(text: str, *, based: bool = False, duration: bool = False) -> str | None:
    """What is wrong with the '_' in a number's text, or None. IEC 61131-3: a single '_' between
    two digits (1_000, 16#FF_FF); a based number may also have one right after its '#' (the 3rd
    edition's `16#_FF`); a duration one after a unit, before the next number (T#1d_2h)."""
    digits = _HEX if based else _DEC
    n = len(text)
    for i, ch in enumerate(text):
        if ch != "_":
            continue
        before = text[i - 1] if i else ""
        after = text[i + 1] if i + 1 < n else ""
        if after == "_":
            return f"two '_' in a row; {_UNDERSCORE_RULE}"
        if after in digits and after:
            if before in digits and before:
                continue
            if based and before == "#":
                continue
            if duration and before.isalpha():
                continue
        if not after:
            return f"'_' at its end; {_UNDERSCORE_RULE}"
        if after not in digits:
            word = _LETTERS.match(text, i + 1)
            return f"'_' before '{word.group(0) if word else after}'; {_UNDERSCORE_RULE}"
        return f"'_' after '{before}'; {_UNDERSCORE_RULE}"
    return None


def _check_underscores(text: str, **kind: bool) -> None:
    problem = underscore_problem(text, **kind)
    if problem:
        raise LiteralError(problem)


def int_literal(text: str) -> int:
    """An integer literal of a program (1_000, 16#FF_FF, 2#1010): '_' checked, then its value."""
    _check_underscores(text, based="#" in text)
    return parse_int(text)


REAL_MAX = 3.4028234663852886e38  # the largest finite IEEE single (REAL)
LREAL_MAX = 1.7976931348623157e308  # the largest finite IEEE double (LREAL)


def real_text(v: float) -> str:
    """A REAL/LREAL limit as ST writes it: 3.4028234663852886E38."""
    return repr(v).upper().replace("E+", "E")


def real_range_text(bits: int) -> str:
    top = real_text(REAL_MAX if bits == 32 else LREAL_MAX)
    return f"-{top}..{top}"


def fits_real(v: float, bits: int) -> bool:
    """Does a number stay finite as a REAL (bits 32) or LREAL (64)? Rounding to 0 or to the
    largest value is fine: only a value that would become inf does not fit."""
    try:
        f = float(v)
        if bits == 32:
            _F32.pack(f)
    except OverflowError:
        return False
    return not math.isinf(f) or math.isinf(v)


def real_literal(text: str, bits: int = 64) -> float:
    """A REAL/LREAL literal of a program: '_' checked; a value beyond LREAL's range (which float()
    would turn into inf) does not fit any real type (bits: 32 names REAL in the message, for
    REAL#…). Values that only round (1E-400 → 0) are fine; REAL's own range needs the context."""
    _check_underscores(text)
    v = parse_real(text)
    if math.isinf(v):
        raise LiteralRangeError(f"does not fit in {'REAL' if bits == 32 else 'LREAL'} ({real_range_text(bits)})")
    return v


def parse_duration(body: str) -> int:
    """'1h2m3s4ms', '1.5s', '-5s', '1d_2h' → ns."""
    s = body.strip()
    sign = 1
    if not s:
        raise LiteralError("empty duration")
    if s[0] in "+-":
        sign = -1 if s[0] == "-" else 1
        s = s[1:]
    s = s.replace("_", "") if "." not in s else s
    pos = 0
    total = 0
    s_clean = s.replace("_", "")
    for m in _TIME_PART.finditer(s_clean):
        if m.start() != pos:
            raise LiteralError(f"malformed duration '{body}'")
        num, unit = m.group(1).replace("_", ""), m.group(2).lower()
        if "." in num:
            whole, frac = num.split(".")
            total += int(whole or "0") * _UNITS[unit] + int(frac) * _UNITS[unit] // 10 ** len(frac)
        else:
            total += int(num) * _UNITS[unit]
        pos = m.end()
    if pos != len(s_clean) or pos == 0:
        raise LiteralError(f"malformed duration '{body}': expected e.g. T#1h2m3s4ms")
    return sign * total


def parse_time_literal(text: str) -> int:
    return parse_duration(text.split("#", 1)[1])


def _time_type(prefix: str) -> str:
    return "LTIME" if prefix.upper() in ("LT", "LTIME") else "TIME"


def time_range_text(type_name: str = "TIME") -> str:
    p = "LT#" if type_name == "LTIME" else "T#"
    return f"{format_duration(NS_MIN, p)}..{format_duration(NS_MAX, p)}"


def time_literal(text: str) -> int:
    """A TIME/LTIME literal of a program: '_' checked in its numbers, the value within 64-bit ns."""
    prefix, body = text.split("#", 1)
    _check_underscores(body.lstrip("+-"), duration=True)
    ns = parse_duration(body)
    t = _time_type(prefix)
    if not NS_MIN <= ns <= (LTIME_UNSIGNED_MAX if t == "LTIME" else NS_MAX):
        raise LiteralRangeError(f"does not fit in {t} ({time_range_text(t)})")
    return ns


_DATE_NAMES = {"date": ("DATE", "LDATE"), "dt": ("DATE_AND_TIME", "LDATE_AND_TIME"), "tod": ("TOD", "LTOD")}


def _date_type(kind: str, prefix: str) -> str:
    short, long = _DATE_NAMES[kind]
    return long if prefix.upper().startswith("L") else short


def date_range_text(kind: str) -> str:
    if kind == "date":  # whole days within the range
        return f"{format_date(-(-NS_MIN // DAY) * DAY)}..{format_date(NS_MAX // DAY * DAY)}"
    return f"{format_dt(NS_MIN)}..{format_dt(NS_MAX)}"


def _checked_date(kind: str, text: str, ns: int) -> int:
    if not NS_MIN <= ns <= NS_MAX:
        t = _date_type(kind, text.split("#", 1)[0])
        raise LiteralRangeError(f"does not fit in {t} ({date_range_text(kind)})")
    return ns


def date_literal(text: str) -> int:
    """A DATE/LDATE literal of a program: a real date whose midnight is within 64-bit ns of 1970."""
    return _checked_date("date", text, parse_date_literal(text))


def dt_literal(text: str) -> int:
    """A DT/LDT literal of a program: a real date and time within 64-bit ns of 1970."""
    return _checked_date("dt", text, parse_dt_literal(text))


def tod_literal(text: str) -> int:
    """A TOD/LTOD literal of a program (its fields in range: always within 0..24 h)."""
    return parse_tod_literal(text)


def _date_ns(y: int, mo: int, d: int) -> int:
    try:
        dd = date(y, mo, d)
    except (ValueError, OverflowError) as e:
        raise LiteralError(str(e) if isinstance(e, ValueError) else f"year {y} is out of range") from None
    return (dd - date(1970, 1, 1)).days * DAY


def _tod_ns(body: str) -> int:
    parts = body.split(":")
    if len(parts) not in (2, 3):
        raise LiteralError(f"malformed time of day '{body}'")
    h, m = int(parts[0]), int(parts[1])
    sec_ns = 0
    if len(parts) == 3:
        sec = parts[2]
        if "." in sec:
            whole, frac = sec.split(".")
            frac = (frac + "000000000")[:9]
            sec_ns = int(whole) * SEC + int(frac)
        else:
            sec_ns = int(sec) * SEC
    if h > 23 or m > 59 or sec_ns >= 60 * SEC:
        raise LiteralError(f"time of day out of range '{body}'")
    return h * HOUR + m * MIN + sec_ns


def parse_date_literal(text: str) -> int:
    y, mo, d = (int(x) for x in text.split("#", 1)[1].split("-"))
    return _date_ns(y, mo, d)


def parse_tod_literal(text: str) -> int:
    return _tod_ns(text.split("#", 1)[1])


def parse_dt_literal(text: str) -> int:
    body = text.split("#", 1)[1]
    y, mo, d, rest = body.split("-", 3)
    return _date_ns(int(y), int(mo), int(d)) + _tod_ns(rest)


_ESC = {"$": "$", "'": "'", '"': '"', "L": "\n", "N": "\n", "P": "\f", "R": "\r", "T": "\t"}


def parse_string(text: str, wide: bool) -> str:
    """Decode an IEC string literal including its quotes; '$' escapes."""
    body = text[1:-1]
    if "$" not in body:
        return body
    out = []
    i = 0
    n = len(body)
    hexlen = 4 if wide else 2
    while i < n:
        c = body[i]
        if c != "$":
            out.append(c)
            i += 1
            continue
        if i + 1 >= n:
            raise LiteralError("'$' at the end of a string")
        e = body[i + 1]
        if e.upper() in _ESC:
            out.append(_ESC[e.upper()])
            i += 2
            continue
        h = body[i + 1 : i + 1 + hexlen]
        if len(h) == hexlen and all(ch in "0123456789abcdefABCDEF" for ch in h):
            out.append(chr(int(h, 16)))
            i += 1 + hexlen
            continue
        raise LiteralError(f"unknown escape '${e}' in string")
    return "".join(out)


# --------------------------------------------------------------------------- formatting


def format_duration(ns: int, prefix: str = "T#") -> str:
    """ns → 'T#1h2m3s4ms' (the shortest IEC form, exact to the ns)."""
    if ns == 0:
        return prefix + "0s"
    sign = "-" if ns < 0 else ""
    v = abs(ns)
    parts = []
    for unit, size in (("d", DAY), ("h", HOUR), ("m", MIN), ("s", SEC), ("ms", MS), ("us", US), ("ns", NS)):
        q, v = divmod(v, size)
        if q:
            parts.append(f"{q}{unit}")
    return prefix + sign + "".join(parts)


def format_date(ns: int, prefix: str = "D#") -> str:
    d = date.fromordinal(date(1970, 1, 1).toordinal() + ns // DAY)
    return f"{prefix}{d.year:04d}-{d.month:02d}-{d.day:02d}"


def _format_tod_body(ns: int) -> str:
    ns %= DAY
    h, r = divmod(ns, HOUR)
    m, r = divmod(r, MIN)
    s, frac = divmod(r, SEC)
    text = f"{h:02d}:{m:02d}:{s:02d}"
    if frac:
        text += "." + f"{frac:09d}".rstrip("0")
    return text


def format_tod(ns: int, prefix: str = "TOD#") -> str:
    return prefix + _format_tod_body(ns)


def format_dt(ns: int, prefix: str = "DT#") -> str:
    return format_date(ns - ns % DAY, prefix) + "-" + _format_tod_body(ns % DAY)


def format_string(s: str, wide: bool = False) -> str:
    q = '"' if wide else "'"
    out = []
    for ch in s:
        if ch == "$":
            out.append("$$")
        elif ch == q:
            out.append("$" + q)
        elif ch == "\n":
            out.append("$N")
        elif ch == "\r":
            out.append("$R")
        elif ch == "\t":
            out.append("$T")
        elif ch == "\f":
            out.append("$P")
        elif ord(ch) < 32 or ord(ch) > 126:
            out.append(f"${ord(ch):04X}" if wide else f"${ord(ch) & 0xFF:02X}")
        else:
            out.append(ch)
    return q + "".join(out) + q
