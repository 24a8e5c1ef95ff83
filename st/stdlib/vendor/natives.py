"""The vendor compatibility library's native functions: signatures (FuncSig) and the Python that
generated code calls.

Memory functions (MEMCPY, MEMSET, MEMCMP, MEMMOVE) work on st's values where they can: whole
variables of one type, or whole elements of arrays of one element type, are copied, filled or
compared as values (structures, instances and pointers included). Anything else (two types, part
of a value, a byte view such as an ANY input's pValue) goes through the byte images of the values
(runtime/byteimage.py); what has no byte image (a pointer, an instance) is a PLC fault that says so.
"""

from __future__ import annotations

import ast as py
from typing import Any

from ...compiler.codegen.emit import call, const
from ...compiler.library import FuncSig, Param
from ...model import types as T
from ...runtime.faults import PLCFault
from ...runtime.pointers import ByteView, byte_view

MAX_STRING = T.StringType(255, False)


def _max_string(_types) -> T.Type:
    return MAX_STRING


# ------------------------------------------------------------------ strings


def _vd_ltrim(s: str) -> str:
    return s.lstrip(" ")


def _vd_rtrim(s: str) -> str:
    return s.rstrip(" ")


def _vd_upper(s: str) -> str:
    return "".join(c.upper() if "a" <= c <= "z" else c for c in s)


def _vd_lower(s: str) -> str:
    return "".join(c.lower() if "A" <= c <= "Z" else c for c in s)


def _vd_digits(value: int, precision: int, a: Any, b: Any = None) -> str:
    """`value` in a base, at least `precision` digits (zeros in front); 0 with precision 0 is ''.
    (in, iPrecision, base) or, for *_TO_HEXSTR, (in, iPrecision, bLoCase, base)."""
    base, lower = (a, False) if b is None else (b, bool(a))
    digits = "0123456789abcdef" if lower else "0123456789ABCDEF"
    out = ""
    while value > 0:
        value, d = divmod(value, base)
        out = digits[d] + out
    return out.rjust(max(0, precision), "0")[-255:] if out or precision > 0 else ""


def _vd_wstring_to_string2(dest: Any, src: Any, size: int, room: int) -> bool:
    """WSTRING_TO_STRING2: the WSTRING at `src` into the STRING at `dest` (`size` bytes there, its NUL
    included; `room` characters the variable holds). Characters a STRING cannot hold (outside
    Latin-1, its byte image) are skipped; FALSE when the rest does not fit and is cut."""
    text = "".join(c for c in str(_get(src)) if ord(c) < 256)
    return _put_text(dest, text, min(size - 1, room))


def _vd_string_to_wstring2(dest: Any, src: Any, size: int, room: int) -> bool:
    """STRING_TO_WSTRING2: the STRING at `src` into the WSTRING at `dest` (`size` bytes, two a
    character, the NUL included); FALSE when it does not fit and is cut."""
    return _put_text(dest, str(_get(src)), min(size // 2 - 1, room))


def _put_text(dest: Any, text: str, fits: int) -> bool:
    if not isinstance(_get(dest), str):  # (a NULL destination faults in _get)
        raise PLCFault("the destination of a string conversion is no STRING or WSTRING variable", "MEMORY")
    if fits < 0:
        return False
    _set(dest, text[:fits])
    return len(text) <= fits


# ------------------------------------------------------------------ the PLC log


def _vd_adslog(log: Any, now: int, mask: int, fmt: str, arg: Any, spec: str) -> int:
    """ADSLOGSTR/DINT/LREAL: the format with its one argument (%s, %d, %f) into the PLC's log."""
    text, i = "", 0
    while i < len(fmt):
        c = fmt[i]
        if c == "%" and i + 1 < len(fmt):
            k = fmt[i + 1]
            if k == "%":
                text += "%"
            elif k in "sdf":
                text += str(arg) if spec == "s" else (str(int(arg)) if spec == "d" else f"{float(arg):f}")
            else:
                text += fmt[i : i + 2]
            i += 2
            continue
        text += c
        i += 1
    log.add(now, int(mask), text[:253])
    return 0


# ------------------------------------------------------------------ memory


def _get(ref: Any) -> Any:
    if ref is None:
        raise PLCFault("a memory function was given a NULL pointer", "NULL")
    return ref.get() if hasattr(ref, "get") else ref[0]


def _set(ref: Any, v: Any) -> None:
    if hasattr(ref, "set"):
        ref.set(v)
    else:
        ref[0] = v


def _clone(v: Any) -> Any:
    if isinstance(v, list):
        return [_clone(x) for x in v]
    return v._copy() if hasattr(v, "_copy") else v


def _store(ref: Any, v: Any) -> None:
    """Put a copy of `v` into what `ref` points to, in place for arrays and structures."""
    cur = _get(ref)
    if isinstance(cur, list):
        cur[:] = _clone(v)
    elif hasattr(cur, "__slots__") and hasattr(cur, "_copy"):
        for s in cur.__slots__:
            setattr(cur, s, _clone(getattr(v, s)))
    else:
        _set(ref, v)


def _elements(n: int, size: int, esize: int, what: str) -> int | None:
    """How many whole elements n bytes are (None: all of the variable)."""
    if n == size:
        return None
    if esize and n % esize == 0 and n < size:
        return n // esize
    raise PLCFault(f"{what} of {n} bytes: st copies whole variables or whole array elements only", "MEMORY")


def _as_bytes(p: Any, spec: tuple | None, what: str) -> ByteView:
    return byte_view(p, spec, what)


def _whole(p: Any, q: Any, n: int, same: bool, size: int, esize: int) -> bool:
    """Can a memory function work on values here (one type, whole variables or elements)?"""
    if not same or isinstance(p, ByteView) or isinstance(q, ByteView):
        return False
    return n == size or bool(esize and n % esize == 0 and n < size)


def _bytes_of(view: ByteView, n: int, what: str) -> bytes:
    room = view.room()
    if n > room:
        raise PLCFault(f"{what} of {n} bytes beyond a variable of {room} bytes", "MEMORY")
    return view.image(n)


def _vd_memcpy(dest: Any, src: Any, n: int, layout: tuple) -> int:
    """MEMCPY/MEMMOVE over st values (see the module doc); `layout` from the compiler. Between
    different types, or part of a value, it copies byte images (runtime/byteimage.py)."""
    same, dsize, ssize, esize, dspec, sspec = layout
    if n <= 0:
        return 0
    if not _whole(dest, src, n, same, dsize, esize) or n > ssize:
        data = _bytes_of(_as_bytes(src, sspec, "MEMCPY"), n, "MEMCPY")
        target = _as_bytes(dest, dspec, "MEMCPY")
        _bytes_of(target, n, "MEMCPY")
        target.write_image(data)
        return n
    count = _elements(n, dsize, esize, "MEMCPY")
    v = _get(src)
    if count is None:
        _store(dest, v)
    else:
        _get(dest)[:count] = _clone(v[:count])
    return n


def _fill_value(proto: Any, byte: int, spec: tuple) -> Any:
    """The value whose every byte is `byte`, for a variable like `proto`."""
    kind, size = spec
    if kind == "bool":
        return byte != 0
    if kind == "int" or kind == "uint":
        v = int.from_bytes(bytes([byte]) * size, "little")
        return v - (1 << (8 * size)) if kind == "int" and v >= 1 << (8 * size - 1) else v
    if kind == "real":
        import struct

        return struct.unpack("<d" if size == 8 else "<f", bytes([byte]) * size)[0]
    if kind == "string":
        return "" if byte == 0 else chr(byte) * size
    raise PLCFault("MEMSET of this type is only supported with the fill byte 0", "MEMORY")


def _vd_memset(dest: Any, byte: int, n: int, layout: tuple) -> int:
    """MEMSET: every byte of the variable (or of its first whole elements) set to `byte`."""
    size, esize, spec, zero, image = layout
    if n <= 0:
        return 0
    if (not _whole(dest, dest, n, True, size, esize) or spec is None) and (
        image is not None or isinstance(dest, ByteView)
    ):
        target = _as_bytes(dest, image, "MEMSET")
        _bytes_of(target, n, "MEMSET")
        target.write_image(bytes([byte & 0xFF]) * n)
        return n
    if n > size:
        raise PLCFault(f"MEMSET of {n} bytes beyond a variable of {size} bytes", "MEMORY")
    count = _elements(n, size, esize, "MEMSET")
    cur = _get(dest)
    if spec is None:  # a structure or an array of them: only zero is known here
        if byte != 0:
            raise PLCFault("MEMSET of a structure is only supported with the fill byte 0", "MEMORY")
        value = zero
    else:
        value = _fill_value(cur, byte & 0xFF, spec)
    if isinstance(cur, list):
        k = len(cur) if count is None else count
        if isinstance(value, list) or hasattr(value, "_copy"):
            for i in range(k):
                cur[i] = _clone(value)
        else:  # an elementary value: one slice assignment (a 64 KiB buffer in one step)
            cur[:k] = [value] * k
    elif count is None:
        _store(dest, value)
    return n


def _vd_memcmp(a: Any, b: Any, n: int, layout: tuple) -> int:
    """MEMCMP: 0 when equal, else -1 or 1 as the first differing element (or value) compares."""
    same, size, ssize, esize, aspec, bspec = layout
    if n <= 0:
        return 0
    if not _whole(a, b, n, same, size, esize) or n > ssize:
        x = _bytes_of(_as_bytes(a, aspec, "MEMCMP"), n, "MEMCMP")
        y = _bytes_of(_as_bytes(b, bspec, "MEMCMP"), n, "MEMCMP")
        return 0 if x == y else -1 if x < y else 1  # the first differing byte, unsigned
    count = _elements(n, size, esize, "MEMCMP")
    x, y = _get(a), _get(b)
    if count is not None:
        x, y = x[:count], y[:count]
    return _cmp(x, y)


def _cmp(x: Any, y: Any) -> int:
    if isinstance(x, list):
        for p, q in zip(x, y):
            c = _cmp(p, q)
            if c:
                return c
        return 0
    if hasattr(x, "__slots__") and hasattr(x, "_copy"):
        for s in x.__slots__:
            c = _cmp(getattr(x, s), getattr(y, s))
            if c:
                return c
        return 0
    if x == y:
        return 0
    return -1 if x < y else 1


# ------------------------------------------------------------------ signatures


def _target(t) -> T.Type:
    u = T.unalias(t)
    return u.target if isinstance(u, T.RefType) else u


def _pair_layout(types, _rt):
    d, s = _target(types[0]), _target(types[1])
    dsize, ssize = T.size_of(d)[0], T.size_of(s)[0]
    ud, us = T.unalias(d), T.unalias(s)
    esize = T.size_of(ud.element)[0] if isinstance(ud, T.ArrayType) else 0
    return [(str(ud) == str(us), dsize, ssize, esize, T.byte_layout(ud), T.byte_layout(us))]


def _fill_spec(t) -> tuple | None:
    u = T.unalias(t)
    if isinstance(u, T.SubrangeType):
        u = u.base
    if isinstance(u, T.EnumType):
        return None
    if isinstance(u, T.StringType):
        return ("string", u.length)
    if u is T.BOOL:
        return ("bool", 1)
    kind = getattr(u, "kind", "")
    size = T.size_of(u)[0]
    if kind == "real":
        return ("real", size)
    if kind in ("int", "bit", "time", "date", "tod", "dt"):
        return ("int" if getattr(u, "signed", False) else "uint", size)
    return None


def _fill_layout(types, _rt):
    d = T.unalias(_target(types[0]))
    size = T.size_of(d)[0]
    elem = d.element if isinstance(d, T.ArrayType) else d
    esize = T.size_of(elem)[0] if isinstance(d, T.ArrayType) else 0
    spec = _fill_spec(elem)
    return [(size, esize, spec, None, T.byte_layout(d))]


def _string_room(types, _rt):
    """How many characters the destination's STRING / WSTRING variable holds."""
    t = T.unalias(_target(types[0]))
    return [t.length if isinstance(t, T.StringType) else 0]  # (not a string: refused when called)


def _now_ticks(ctx, args, types, rt):
    return py.BinOp(py.Name("_now", py.Load()), py.FloorDiv(), const(100))


def _adslog(name: str, arg: str, constraint: str, spec: str) -> FuncSig:
    def emit(ctx, args, types, rt):
        return call("_vd_adslog", py.Name("_plc_log", py.Load()), py.Name("_now", py.Load()), *args, const(spec))

    params = [Param("msgCtrlMask", "DWORD"), Param("msgFmtStr", "ANY_STRING"), Param(arg, constraint)]
    return FuncSig(name, params, "DINT", emit=emit, doc="a message to the PLC log")


def _string_fn(name: str, helper: str) -> FuncSig:
    return FuncSig(name, [Param("in", "ANY_STRING")], _max_string, helper=helper)


def signatures() -> list[FuncSig]:
    out = [
        _string_fn("F_LTrim", "_vd_ltrim"),
        _string_fn("F_RTrim", "_vd_rtrim"),
        _string_fn("F_ToUCase", "_vd_upper"),
        _string_fn("F_ToLCase", "_vd_lower"),
        FuncSig("WLEN", [Param("STR", "ANY_STRING")], "INT", helper="_vd_len"),
        FuncSig("F_GetSystemTime", [], "ULINT", emit=_now_ticks),
        _adslog("ADSLOGSTR", "strArg", "ANY_STRING", "s"),
        _adslog("ADSLOGDINT", "dintArg", "DINT", "d"),
        _adslog("ADSLOGLREAL", "lrealArg", "LREAL", "f"),
    ]
    for name, dst, src, helper in (
        ("WSTRING_TO_STRING2", "pDstString", "pSrcWString", "_vd_wstring_to_string2"),
        ("STRING_TO_WSTRING2", "pDstWString", "pSrcString", "_vd_string_to_wstring2"),
    ):
        out.append(
            FuncSig(
                name,
                [Param(dst, "ANY_POINTER"), Param(src, "ANY_POINTER"), Param("nDstSize", "ANY_INT")],
                "BOOL",
                helper=helper,
                extra=_string_room,
            )
        )
    for name in ("MEMCPY", "MEMMOVE"):
        out.append(
            FuncSig(
                name,
                [Param("destAddr", "ANY_POINTER"), Param("srcAddr", "ANY_POINTER"), Param("n", "ANY_INT")],
                "UDINT",
                helper="_vd_memcpy",
                extra=_pair_layout,
            )
        )
    out.append(
        FuncSig(
            "MEMCMP",
            [Param("pBuf1", "ANY_POINTER"), Param("pBuf2", "ANY_POINTER"), Param("n", "ANY_INT")],
            "DINT",
            helper="_vd_memcmp",
            extra=_pair_layout,
        )
    )
    out.append(
        FuncSig(
            "MEMSET",
            [Param("destAddr", "ANY_POINTER"), Param("fillByte", "ANY_INT"), Param("n", "ANY_INT")],
            "UDINT",
            helper="_vd_memset",
            extra=_fill_layout,
        )
    )
    for ty in ("BYTE", "WORD", "DWORD", "LWORD"):
        for suffix, base in (("HEXSTR", 16), ("DECSTR", 10), ("OCTSTR", 8), ("BINSTR", 2)):
            params = [Param("in", ty), Param("iPrecision", "INT")]
            if base == 16:
                params.append(Param("bLoCase", "BOOL"))
            out.append(
                FuncSig(
                    f"{ty}_TO_{suffix}",
                    params,
                    _max_string,
                    helper="_vd_digits",
                    extra=(lambda b: lambda types, rt: [b])(base),
                    emit=None,
                )
            )
    return out


HELPERS = {
    "_vd_len": len,
    "_vd_ltrim": _vd_ltrim,
    "_vd_rtrim": _vd_rtrim,
    "_vd_upper": _vd_upper,
    "_vd_lower": _vd_lower,
    "_vd_digits": _vd_digits,
    "_vd_adslog": _vd_adslog,
    "_vd_memcpy": _vd_memcpy,
    "_vd_memset": _vd_memset,
    "_vd_memcmp": _vd_memcmp,
    "_vd_wstring_to_string2": _vd_wstring_to_string2,
    "_vd_string_to_wstring2": _vd_string_to_wstring2,
}
