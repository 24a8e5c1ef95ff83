"""The calendar arithmetic of datetime.st (TwinCAT's FILETIME, TIMESTRUCT and DT conversions), as
native functions the library's thin ST POUs call: the proleptic Gregorian calendar, exactly, for the
years 1601..30827 (H. Hinnant's days_from_civil / civil_from_days). A FILETIME is an integer of
100 ns ticks since 1601-01-01 00:00:00 UTC here; a DT is st's (ns since 1970)."""

from __future__ import annotations

import ast as py

from ...compiler.codegen.emit import const
from ...compiler.library import FuncSig, Param
from ...model import types as T

EPOCH_1970 = 116444736000000000  # 1970-01-01 00:00:00 as a FILETIME
_DAY = 864_000_000_000  # ticks a day
_DAYS_1601 = 584694  # 1601-01-01 in days since 0000-03-01 (civil_from_days' origin)
_DT_MAX = 0xFFFFFFFF  # the PLCs' DT: a UDINT of seconds since 1970


def _days(y: int, m: int, d: int) -> int:
    """Days since 1601-01-01 of a valid date."""
    y -= m <= 2
    era, yoe = divmod(y, 400)
    doy = (153 * (m - 3 if m > 2 else m + 9) + 2) // 5 + d - 1
    return era * 146097 + yoe * 365 + yoe // 4 - yoe // 100 + doy - _DAYS_1601


def _month_days(y: int, m: int) -> int:
    if m == 2:
        return 29 if (y % 4 == 0 and y % 100 != 0) or y % 400 == 0 else 28
    return 30 if m in (4, 6, 9, 11) else 31


def _vd_ft(y: int, mo: int, d: int, h: int, mi: int, s: int, ms: int) -> int:
    """SYSTEMTIME_TO_FILETIME: the FILETIME of the fields, 0 when one is out of its range."""
    if not (1601 <= y <= 30827 and 1 <= mo <= 12 and 1 <= d <= _month_days(y, mo)):
        return 0
    if not (0 <= h <= 23 and 0 <= mi <= 59 and 0 <= s <= 59 and 0 <= ms <= 999):
        return 0
    return (((_days(y, mo, d) * 24 + h) * 60 + mi) * 60 + s) * 10_000_000 + ms * 10_000


def _vd_cal(ticks: int, field: int) -> int:
    """FILETIME_TO_SYSTEMTIME: one field of a FILETIME (0 wYear, 1 wMonth, 2 wDayOfWeek, 3 wDay,
    4 wHour, 5 wMinute, 6 wSecond, 7 wMilliseconds); all 0 when the top bit is set (Windows refuses it)."""
    if ticks >= 1 << 63:
        return 0
    days, rest = divmod(ticks, _DAY)
    if field >= 4:
        ms = rest // 10_000
        return (ms // 3_600_000, ms // 60_000 % 60, ms // 1000 % 60, ms % 1000)[field - 4]
    if field == 2:
        return (days + 1) % 7  # 1601-01-01 was a Monday; 0 = Sunday
    era, doe = divmod(days + _DAYS_1601, 146097)
    yoe = (doe - doe // 1460 + doe // 36524 - doe // 146096) // 365
    doy = doe - (365 * yoe + yoe // 4 - yoe // 100)
    mp = (5 * doy + 2) // 153
    month = mp + 3 if mp < 10 else mp - 9
    year = yoe + era * 400 + (month <= 2)
    return (year, month, 0, doy - (153 * mp + 2) // 5 + 1)[field]


def _vd_ft_dt(ticks: int) -> int:
    """FILETIME_TO_DT: to the second, clamped to the PLCs' DT (1970-01-01 .. 2106-02-07-06:28:15)."""
    s = ticks // 10_000_000 - EPOCH_1970 // 10_000_000
    return min(max(s, 0), _DT_MAX) * 1_000_000_000


def _vd_dt_ft(dt: int) -> int:
    """DT_TO_FILETIME: a DT (st: ns since 1970), to the second."""
    return (dt // 1_000_000_000) * 10_000_000 + EPOCH_1970


def _vd_tz(ticks: int, minutes: int, to_utc: bool) -> int:
    """A FILETIME moved by a time zone's bias: UTC = local time + bias (modulo 2^64)."""
    shift = minutes * 600_000_000
    return (ticks + shift if to_utc else ticks - shift) % (1 << 64)


def _vd_fmt(y: int, mo: int, d: int, h: int, mi: int, s: int, ms: int) -> str:
    """SYSTEMTIME_TO_STRING: 'YYYY-MM-DD-hh:mm:ss.xxx'."""
    return f"{y:04d}-{mo:02d}-{d:02d}-{h:02d}:{mi:02d}:{s:02d}.{ms:03d}"[:24]


_PLACES = ((0, 4), (5, 7), (8, 10), (11, 13), (14, 16), (17, 19), (20, 23))  # wYear .. wMilliseconds


def _vd_parse(text: str, field: int) -> int:
    """STRING_TO_SYSTEMTIME: the number at field `field`'s place of 'YYYY-MM-DD-hh:mm:ss.xxx' (0 wYear
    .. 6 wMilliseconds; no digits there: 0)."""
    a, b = _PLACES[field]
    part = text[a:b].strip()
    return int(part) % 65536 if part.isdigit() else 0


def _now_emit(ctx, args, types, rt) -> py.expr:
    """The PLC's calendar now: 1970-01-01 + the PLC clock (ns, latched per scan), in FILETIME ticks."""
    ticks = py.BinOp(py.Name("_now", py.Load()), py.FloorDiv(), const(100))
    return py.BinOp(ticks, py.Add(), const(EPOCH_1970))


def _u64_emit(ctx, args, types, rt) -> py.expr:
    hi, lo = args
    return py.BinOp(py.BinOp(hi, py.LShift(), const(32)), py.BitOr(), lo)


def signatures() -> list[FuncSig]:
    fields = [Param(n, "ANY_INT") for n in ("y", "mo", "d", "h", "mi", "s", "ms")]
    return [
        FuncSig("__VD_NOW", [], "ULINT", emit=_now_emit, doc="the PLC's calendar now, as a FILETIME"),
        FuncSig("__VD_U64", [Param("hi", "DWORD"), Param("lo", "DWORD")], "ULINT", emit=_u64_emit),
        FuncSig("__VD_FT", fields, "ULINT", helper="_vd_ft"),
        FuncSig("__VD_CAL", [Param("ticks", "ULINT"), Param("field", "ANY_INT")], "WORD", helper="_vd_cal"),
        FuncSig("__VD_FT_DT", [Param("ticks", "ULINT")], "DT", helper="_vd_ft_dt"),
        FuncSig("__VD_DT_FT", [Param("dt", "DT")], "ULINT", helper="_vd_dt_ft"),
        FuncSig(
            "__VD_TZ",
            [Param("ticks", "ULINT"), Param("minutes", "DINT"), Param("toUtc", "BOOL")],
            "ULINT",
            helper="_vd_tz",
        ),
        FuncSig("__VD_FMT", fields, lambda _types: T.StringType(24, False), helper="_vd_fmt"),
        FuncSig("__VD_PARSE", [Param("text", "ANY_STRING"), Param("field", "ANY_INT")], "WORD", helper="_vd_parse"),
    ]


HELPERS = {
    "_vd_ft": _vd_ft,
    "_vd_cal": _vd_cal,
    "_vd_ft_dt": _vd_ft_dt,
    "_vd_dt_ft": _vd_dt_ft,
    "_vd_tz": _vd_tz,
    "_vd_fmt": _vd_fmt,
    "_vd_parse": _vd_parse,
}
