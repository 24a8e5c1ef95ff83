"""Dialect presets: named sets of switches, never forks of the grammar.

    openplc   what MatIEC (OpenPLC v3) accepts: TIME_TO_<int> counts seconds, F_TRIG pulses on the
              first scan; a POU may assign its own inputs (MatIEC forbids only writing a block's
              outputs from outside, FOR variables and constants); a FOR's body may not write its
              control variable (E052); no object-oriented ST and no vendor extensions; REAL
              arithmetic as MatIEC's C computes it, %IW0.0 read as %IW0 and %QX0.4.2 as %QX0.4
              (W011), MatIEC's answers where IEC leaves an error's reaction open
    iec       IEC 61131-3 3rd edition, strict: object-oriented ST (THIS.x read as THIS^.x),
              REF_TO/REF()/NULL; a FOR's body may not write its control variable (E052); no vendor
              extensions (POINTER TO, REFERENCE TO, REF=, ADR, SIZEOF, __QUERYINTERFACE, __ISVALIDREF,
              __NEW, __DELETE, VAR_INST, VAR_STAT, STRUCT EXTENDS, methods of programs)
    codesys   the 3rd edition plus CODESYS's extensions; {attribute '…'} pragmas accepted silently;
              a POU may assign its own inputs; enumeration values read as integers where one is
              expected (CODESYS's non-strict enumerations); bit strings and numbers convert
              implicitly where the value is kept (BYTE into INT or REAL, INT into WORD)
    twincat   as codesys (TwinCAT 3 is CODESYS-based)

Without a preset everything any preset accepts is accepted (a POU may assign its own inputs, as
under openplc, codesys and twincat) and only --time-unit / --f-trig-first-scan apply. A preset is chosen with `--dialect NAME` (API: dialect=…)
or with a pragma `{dialect 'NAME'}` in a source file; an explicit flag wins.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..diagnostics import Code, CompileError, Diagnostic, Severity
from ..source import Span


@dataclass(frozen=True)
class Dialect:
    name: str
    time_unit: str = "ms"
    f_trig_first_scan: bool = False
    oop: bool = True  # METHOD, PROPERTY, INTERFACE, CLASS, EXTENDS, IMPLEMENTS, THIS, SUPER
    vendor_extensions: bool = True  # POINTER TO, REFERENCE TO, REF=, ADR, SIZEOF, __QUERYINTERFACE, __ISVALIDREF,
    #                                    __NEW, __DELETE, VAR_INST in methods, VAR_STAT, STRUCT EXTENDS,
    #                                    METHODs of a PROGRAM
    attribute_pragmas: bool = False  # {attribute '…'} without a warning
    writable_inputs: bool = False  # a POU may assign its own VAR_INPUT (a local copy); else E018
    enum_as_int: bool = False  # an enumeration value is usable as its integer (not {attribute 'strict'})
    bits_as_numbers: bool = False  # bit strings and numbers convert implicitly where the value is kept
    nested_comments: bool = True  # (* (* *) *) nests (IEC 3rd edition, CODESYS); MatIEC ends at the first *)
    # a value outside a subrange: "fault" (IEC calls it an error: a RANGE fault), "clamp" (MatIEC's
    # generated check functions give the nearest limit), "store" (CODESYS and TwinCAT check only
    # with CheckRange functions in the project: the value is kept, wrapped to the base type)
    subranges: str = "fault"
    # the body of a FOR may write its control variable (CODESYS, TwinCAT: the loop tests what it
    # left); IEC 61131-3 and MatIEC forbid it (E052)
    writable_for_counter: bool = True
    # a POU that calls itself: E032 (IEC 61131-3, MatIEC), or W013 as CODESYS and TwinCAT warn and run it
    recursion_allowed: bool = True
    # THIS and SUPER name the instance itself, as IEC 61131-3's 3rd edition writes them (THIS.x,
    # SUPER.M()): read as CODESYS's THIS^.x, SUPER^.M(); elsewhere THIS is only the pointer (THIS^.x)
    this_as_instance: bool = False
    # REAL arithmetic as MatIEC's generated C computes it: single precision where both operands
    # are C floats (REAL variables, integers), double where a REAL literal takes part
    c_float_arithmetic: bool = False
    # a hierarchical address, more numbers than its cell needs (%IW0.0, %QX0.4.2), is bound by its
    # leading numbers (%IW0, %QX0.4), as OpenPLC's glue generator does, with a warning (W011); off,
    # it is accepted as written as IEC, CODESYS and TwinCAT accept it (its place is the I/O
    # configuration's) and a run refuses it at its declaration (st/model/addresses.py). A bit
    # address with one number (%IX1) is %IX1.0 under every preset.
    dotted_word_addresses: bool = False
    # where IEC calls a case an error and leaves the reaction open, do what MatIEC does (a MUX
    # selector out of range gives the type's default value, REAL to integer rounds halfway cases
    # to even) instead of a PLC fault
    matiec_errors: bool = False
    # the vendor compatibility library (st/stdlib/vendor: T_MaxString, MEMCPY, ADSLOGSTR, SysFile,
    # ...) is part of the compilation; iec and openplc programs know none of its names
    vendor_library: bool = True
    # LTIME is an unsigned 64-bit count of ns (CODESYS, TwinCAT): a literal up to
    # LTIME#213503d23h34m33s709ms551us615ns is accepted and held as the same 64 bits in st's signed
    # LTIME; IEC leaves LTIME's range to the implementation and st's is signed (E021 beyond it)
    unsigned_ltime: bool = True
    # DELETE and REPLACE with P = 0 address the first character with L one less, as CODESYS's
    # Standard library documents (and TwinCAT code relies on: FIND's 0 for "not found" passed on);
    # IEC's positions start at 1 and st faults (RANGE) below
    position_zero: bool = False


PRESETS = {
    "openplc": Dialect(
        "openplc",
        time_unit="s",
        f_trig_first_scan=True,
        oop=False,
        vendor_extensions=False,
        writable_inputs=True,
        nested_comments=False,
        subranges="clamp",
        writable_for_counter=False,
        recursion_allowed=False,
        c_float_arithmetic=True,
        dotted_word_addresses=True,
        matiec_errors=True,
        vendor_library=False,
        unsigned_ltime=False,
    ),
    "iec": Dialect(
        "iec",
        vendor_extensions=False,
        writable_for_counter=False,
        recursion_allowed=False,
        this_as_instance=True,
        vendor_library=False,
        unsigned_ltime=False,
    ),
    "codesys": Dialect(
        "codesys",
        attribute_pragmas=True,
        position_zero=True,
        writable_inputs=True,
        enum_as_int=True,
        bits_as_numbers=True,
        subranges="store",
    ),
    "twincat": Dialect(
        "twincat",
        attribute_pragmas=True,
        position_zero=True,
        writable_inputs=True,
        enum_as_int=True,
        bits_as_numbers=True,
        subranges="store",
    ),
}

_PRAGMA = re.compile(r"\{\s*dialect\s+'([A-Za-z]+)'\s*\}", re.I)


def from_sources(sources) -> tuple[str, Span] | None:
    """The preset named by a `{dialect '…'}` pragma in the sources (the first one) and where the
    name stands, if any. The name is not checked here: see `pragma_preset`."""
    for src in sources:
        m = _PRAGMA.search(src.text)
        if m:
            return m.group(1).lower(), src.span_at(m.start(1))
    return None


def pragma_preset(sources) -> Dialect | None:
    """The preset a pragma in the sources chooses; an unknown name is a located error (E045)."""
    found = from_sources(sources)
    if found is None:
        return None
    name, span = found
    if name not in PRESETS:
        diag = Diagnostic(
            Code.UNKNOWN_DIALECT,
            Severity.ERROR,
            span,
            f"unknown dialect '{name}' in a {{dialect}} pragma",
            hint=f"the presets are {', '.join(PRESETS)}",
        )
        raise CompileError([diag], {s.path: s for s in sources})
    return PRESETS[name]


_TYPE_AFTER_PRAGMAS = re.compile(r"((?:\{[^{}]*\}\s*)+)TYPE\s+([A-Za-z_][A-Za-z0-9_]*)", re.I)


def strict_types(texts) -> set:
    """Lower-case names of the types declared right after an {attribute 'strict'} pragma: their
    enumeration values are not integers, even where a preset lets enumerations be read as such."""
    out = set()
    for text in texts:
        for m in _TYPE_AFTER_PRAGMAS.finditer(text):
            if re.search(r"attribute\s+'strict'", m.group(1), re.I):
                out.add(m.group(2).lower())
    return out


def preset(name: str | None) -> Dialect | None:
    if name is None:
        return None
    d = PRESETS.get(name.lower())
    if d is None:
        raise ValueError(f"unknown dialect '{name}' (known: {', '.join(PRESETS)})")
    return d
