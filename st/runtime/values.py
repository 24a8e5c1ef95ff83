"""Runtime values ↔ Python API values and JSON, driven by IEC types."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NoReturn

from ..model import types as T
from ..model.literals import (
    LiteralError,
    format_date,
    format_dt,
    format_duration,
    format_tod,
    parse_date_literal,
    parse_dt_literal,
    parse_duration,
    parse_int,
    parse_real,
    parse_string,
    parse_time_literal,
    parse_tod_literal,
)
from .helpers import round_f32


class ValueError_(ValueError):
    pass


def _convert(v: Any, t: T.Type, leaf: Callable[[Any, Any], Any], ref: Callable[[Any], str] | None = None) -> Any:
    """Walk a value by its type: aggregates become lists/dicts, scalars go through `leaf`,
    references through `ref` (None when not given: a reference is shown as null)."""
    t = T.unalias(t)
    if isinstance(t, T.EnumType):
        return t.names_by_value.get(v, v)
    if isinstance(t, T.ArrayType):
        return _nest([_convert(x, t.element, leaf, ref) for x in v], t.dims)
    if isinstance(t, T.StructType):
        return {m.name: _convert(getattr(v, m.pyname), m.type, leaf, ref) for m in t.members.values()}
    if isinstance(t, T.POUType) and t.pou_kind == "INTERFACE":
        # an interface variable: which block type it refers to (the instance is shown where it is declared)
        return None if v is None else type(v).__name__.removeprefix("_fb_")
    if isinstance(t, T.POUType):
        return {
            s.name: _convert(getattr(v, s.pyname), s.type, leaf, ref)
            for s in t.vars.values()
            if s.section not in ("VAR_EXTERNAL", "VAR_IN_OUT", "VAR_TEMP", "VAR_STAT")
        }
    if isinstance(t, T.RefType):
        return None if v is None or ref is None else ref(v)
    return leaf(v, t)


def to_python(v: Any, t: T.Type, ref: Callable[[Any], str] | None = None) -> Any:
    """A runtime value as a plain Python value (API reads). TIME etc. stay ns integers."""
    return _convert(v, t, lambda v, t: v, ref)


def _json_leaf(v: Any, t: Any) -> Any:
    if isinstance(t, T.ElemType):
        k = t.kind
        if k == "time":
            return format_duration(v, "LTIME#" if t.long else "T#")
        if k == "date":
            return format_date(v, "LDATE#" if t.long else "D#")
        if k == "tod":
            return format_tod(v, "LTOD#" if t.long else "TOD#")
        if k == "dt":
            return format_dt(v, "LDT#" if t.long else "DT#")
        if k == "real" and (v != v or v in (math.inf, -math.inf)):
            return str(v)
    return v


def to_json(v: Any, t: T.Type, ref: Callable[[Any], str] | None = None) -> Any:
    """A runtime value as JSON: times and dates as IEC literal text, enums by name."""
    return _convert(v, t, _json_leaf, ref)


def to_st_literal(v: Any, t: T.Type | None) -> str:
    """A runtime value as ST source text (TRUE, 16#FF stays 255, 0.1, T#1s500ms, 'text'), for reports."""
    if t is None:
        return repr(v)
    ut = T.unalias(t)
    if isinstance(ut, T.EnumType):
        name = ut.names_by_value.get(v)
        return f"{ut.name}#{name}" if name is not None else str(v)
    if ut.is_aggregate or isinstance(ut, T.RefType):
        import json

        return json.dumps(to_json(v, t))
    bt = T.base_of(t)
    if isinstance(v, bool) or bt.is_bool:
        return "TRUE" if v else "FALSE"
    if isinstance(bt, T.StringType) or bt.kind == "char":
        q = '"' if getattr(bt, "wide", False) or getattr(bt, "name", "") == "WCHAR" else "'"
        body = str(v).replace("$", "$$").replace(q, "$" + q).replace("\n", "$N").replace("\r", "$R").replace("\t", "$T")
        return q + body + q
    if isinstance(v, float):
        if v != v or v in (math.inf, -math.inf):
            return str(v)
        if bt is T.REAL:  # the fewest digits that give this single-precision value back
            for digits in range(1, 10):
                text = f"{v:.{digits}g}"
                if round_f32(float(text)) == v:
                    return _real_text(repr(float(text)))
        return _real_text(repr(v))
    if isinstance(bt, T.ElemType) and bt.kind in ("time", "date", "tod", "dt"):
        return str(_json_leaf(v, bt))
    return str(v)


def _real_text(text: str) -> str:
    """Python's shortest text of a float as an IEC real literal: 40.0, 0.1, 1.5E-5, 1.0E30 (a
    fraction always, an exponent without '+' or leading zeros)."""
    mantissa, e, exponent = text.lower().partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return f"{mantissa}E{int(exponent)}" if e else mantissa


def _nest(flat: list[Any], dims: list[tuple[int, int]]) -> list[Any]:
    if len(dims) <= 1:
        return flat
    inner = 1
    for lo, hi in dims[1:]:
        inner *= hi - lo + 1
    return [_nest(flat[i : i + inner], dims[1:]) for i in range(0, len(flat), inner)]


def from_python(v: Any, t: T.Type, where: str = "") -> Any:
    """A Python value (API write) as a runtime value of type t, checked and converted."""
    ut: Any = T.unalias(t)
    bt: Any = T.base_of(t)
    if isinstance(ut, T.EnumType):
        if isinstance(v, str):
            for name, val in ut.members.values():
                if name.lower() == v.lower() or f"{ut.name}#{name}".lower() == v.lower():
                    return val
            raise ValueError_(f"{where}: '{v}' is not a value of {ut.name}")
        if isinstance(v, int) and not isinstance(v, bool) and v in ut.names_by_value:
            return v
        raise ValueError_(f"{where}: {v!r} is not a value of {ut.name}")
    if isinstance(ut, T.ArrayType):
        raise ValueError_(f"{where}: write array elements one by one (e.g. {where}[1])")
    if isinstance(ut, (T.StructType, T.POUType)):
        raise ValueError_(f"{where}: write the fields one by one")
    if isinstance(bt, T.StringType):
        if not isinstance(v, str):
            raise ValueError_(f"{where}: expected a string, got {v!r}")
        return v[: bt.length]
    k = bt.kind
    if k == "bool":
        if isinstance(v, bool) or v in (0, 1):
            return bool(v)
        raise ValueError_(f"{where}: expected a BOOL, got {v!r}")
    if k in ("int", "bit"):
        if isinstance(v, bool) or not isinstance(v, int):
            raise ValueError_(f"{where}: expected an integer, got {v!r}")
        if isinstance(ut, T.SubrangeType) and not (ut.lo <= v <= ut.hi):
            raise ValueError_(f"{where}: {v} is outside {ut.lo}..{ut.hi}")
        if not (bt.lo <= v <= bt.hi):
            raise ValueError_(f"{where}: {v} does not fit in {bt.name} ({bt.lo}..{bt.hi})")
        return v
    if k == "real":
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ValueError_(f"{where}: expected a number, got {v!r}")
        try:
            return round_f32(float(v)) if bt.bits == 32 else float(v)
        except OverflowError:
            raise ValueError_(f"{where}: the value is too large for {bt.name}") from None
    if k in ("time", "date", "tod", "dt"):
        if isinstance(v, int) and not isinstance(v, bool):
            return v
        if isinstance(v, str):
            try:
                if "#" not in v:
                    return parse_duration(v) if k == "time" else _raise(where, v)
                return {
                    "time": parse_time_literal,
                    "date": parse_date_literal,
                    "tod": parse_tod_literal,
                    "dt": parse_dt_literal,
                }[k](v)
            except ValueError as e:
                raise ValueError_(f"{where}: {e}") from None
        if hasattr(v, "total_seconds") and k == "time":
            return round(v.total_seconds() * 1e9)
        raise ValueError_(f"{where}: expected a {bt.name}, got {v!r}")
    if k == "char":
        if isinstance(v, str) and len(v) == 1:
            return v
        raise ValueError_(f"{where}: expected one character, got {v!r}")
    return v


def _raise(where: str, v: Any) -> NoReturn:
    raise ValueError_(f"{where}: '{v}' needs an IEC literal such as D#2024-01-31")


def parse_duration_arg(d: Any) -> int:
    """'2.5s', 'T#20ms', 2.5 (seconds) or an int of ns → ns."""
    if isinstance(d, bool):
        raise ValueError(f"not a duration: {d!r}")
    if isinstance(d, int):
        return d
    if isinstance(d, float):
        return round(d * 1e9)
    if hasattr(d, "total_seconds"):
        seconds: float = d.total_seconds()
        return round(seconds * 1e9)
    s = str(d).strip()
    if "#" in s:
        ns: int = parse_time_literal(s)
        return ns
    ns = parse_duration(s)
    return ns


def from_st_text(text: str, t: T.Type, where: str = "") -> Any:
    """What a person types for a variable of type t (an ST literal: TRUE, 16#FF, -1.5E3, T#2s,
    'text', an enumerated value, INT#5) as a runtime value, checked as an API write is."""
    s = text.strip()
    bt: Any = T.base_of(t)
    if not isinstance(T.unalias(t), T.EnumType) and "#" in s and s.split("#", 1)[0].isalpha():
        prefix, rest = s.split("#", 1)
        if T.ELEMENTARY.get(prefix.upper()) is not None and prefix.upper() not in ("T", "TIME"):
            s = rest  # a typed literal: INT#5, REAL#1.5, BOOL#TRUE
    v: Any = s
    try:
        if isinstance(bt, T.StringType):
            v = parse_string(s, bt.wide) if len(s) >= 2 and s[0] == s[-1] and s[0] in "'\"" else s
        elif getattr(bt, "kind", "") == "bool":
            v = {"TRUE": True, "FALSE": False, "1": True, "0": False}.get(s.upper(), s)
        elif getattr(bt, "kind", "") in ("int", "bit"):
            sign = -1 if s.startswith("-") else 1
            v = sign * parse_int(s.lstrip("+-"))
        elif getattr(bt, "kind", "") == "real":
            v = parse_real(s)
    except (LiteralError, ValueError):
        raise ValueError_(f"{where}: not a literal of {getattr(T.unalias(t), 'name', 'its type')}: {text!r}") from None
    return from_python(v, t, where)
