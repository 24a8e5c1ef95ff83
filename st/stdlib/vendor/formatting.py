"""FB_FormatString's formatting (utilities.st): printf-style conversions of T_Arg arguments, whose
values are read through their pData byte pointers (runtime/byteimage.py)."""

from __future__ import annotations

import re
import struct
from typing import Any

from ...compiler.library import FuncSig, Param
from ...model import types as T
from ...runtime.pointers import byte_view

# E_ArgType (utilities.st) → struct format of the value's bytes; STRING is read up to its NUL
_FORMATS = {1: "B", 2: "H", 3: "I", 4: "f", 5: "d", 6: "b", 7: "h", 8: "i", 9: "B", 10: "H", 11: "I", 13: "?"}
_FORMATS.update({15: "Q", 17: "q", 19: "Q"})
STRING = 12
_SPEC = re.compile(r"%([-+0 #]*)(\d*)(?:\.(\d+))?([diuxXobfeEgGsc%])?")
MAX_STRING = T.StringType(255, False)
NO_ERROR = 0xFFFFFFFF  # what __ST_FORMAT_ERROR gives when the format and its arguments fit


def _value(arg: Any) -> Any:
    """The value a T_Arg points to, or None for an empty argument (ARGTYPE_UNKNOWN)."""
    kind = int(arg.eType)
    if kind == 0 or arg.pData is None:
        return None
    data = byte_view(arg.pData, what="FB_FormatString").image()
    if kind == STRING:
        return data[: max(0, int(arg.cbLen) - 1)].split(b"\0", 1)[0].decode("latin-1")
    fmt = _FORMATS.get(kind)
    if fmt is None:
        return None
    return struct.unpack_from("<" + fmt, data)[0]


def _convert(flags: str, width: str, prec: str | None, kind: str, v: Any) -> str | None:
    """One conversion, or None when the value does not fit the conversion type."""
    if kind in "diuxXob":
        if isinstance(v, (str, float)):
            return None
        n = int(v)
        if kind == "b":
            digits = format(abs(n), "b")
            if prec is not None:
                digits = digits.rjust(int(prec), "0")
            text = ("-" if n < 0 else "+" if "+" in flags else " " if " " in flags else "") + digits
            pad = "0" if "0" in flags and "-" not in flags else " "
            w = int(width or 0)
            return text.ljust(w) if "-" in flags else text.rjust(w, pad) if pad == " " else _zero_pad(text, w)
        spec = "%" + flags + width + ("." + prec if prec is not None else "") + ("d" if kind in "iu" else kind)
        return spec % n
    if kind in "feEgG":
        if isinstance(v, str) or v is None:
            return None
        return ("%" + flags + width + ("." + prec if prec is not None else "") + kind) % float(v)
    if kind == "s":
        text = v if isinstance(v, str) else ("TRUE" if v is True else "FALSE" if v is False else str(v))
        if prec is not None:
            text = text[: int(prec)]
        return ("%" + ("-" if "-" in flags else "") + width + "s") % text
    if kind == "c":
        if isinstance(v, (str, float)):
            return None
        return ("%" + ("-" if "-" in flags else "") + width + "s") % chr(int(v) & 0xFF)
    return None


def _zero_pad(text: str, width: int) -> str:
    sign = text[0] if text[:1] in "+- " and text[:1] != "" else ""
    body = text[len(sign) :]
    return sign + body.rjust(width - len(sign), "0")


def _format(fmt: str, args: tuple) -> tuple[str, int]:
    """(the text, NO_ERROR) or ('', the number of the argument at fault, 0 for the format)."""
    out: list[str] = []
    pos = 0
    used = 0
    for m in _SPEC.finditer(fmt):
        out.append(fmt[pos : m.start()])
        pos = m.end()
        flags, width, prec, kind = m.group(1), m.group(2), m.group(3), m.group(4)
        if kind is None:
            return "", 0
        if kind == "%":
            out.append("%")
            continue
        used += 1
        if used > len(args):
            return "", used
        v = _value(args[used - 1])
        if v is None:
            return "", used
        text = _convert(flags, width, prec, kind, v)
        if text is None:
            return "", used
        out.append(text)
    out.append(fmt[pos:])
    return "".join(out)[:255], NO_ERROR


def _vd_format(fmt: str, *args: Any) -> str:
    return _format(fmt, args)[0]


def _vd_format_error(fmt: str, *args: Any) -> int:
    return _format(fmt, args)[1]


def signatures() -> list[FuncSig]:
    params = [Param("sFormat", "ANY_STRING")] + [Param(f"arg{i}", "ANY") for i in range(1, 11)]
    return [
        FuncSig("__ST_FORMAT", params, lambda _types: MAX_STRING, helper="_vd_format", doc="FB_FormatString's text"),
        FuncSig("__ST_FORMAT_ERROR", params, "UDINT", helper="_vd_format_error", doc="FB_FormatString's error"),
    ]


HELPERS = {"_vd_format": _vd_format, "_vd_format_error": _vd_format_error}
