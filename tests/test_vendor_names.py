"""Names and constructs of TwinCAT's and CODESYS's libraries that library code uses (issue 34):
T_FILETIME, TIMESTRUCT, FB_LocalSystemTime and the FILETIME / SYSTEMTIME / DT conversions,
WSTRING_TO_STRING2, VAR_INFO, TestAndSet, `__TRY … __CATCH … __FINALLY … __ENDTRY` with
__SYSTEM.ExceptionCode, and SUB of two dates. Exact values on virtual time (a 10 ms task: scan k
runs at (k - 1) × 10 ms, the PLC's calendar is 1970-01-01 UTC + that)."""

from __future__ import annotations

from datetime import datetime

import pytest

from st import PLC
from st.api import compile_text
from st.compiler.native import toolchain
from st.runtime.faults import PLCFaultError

from helpers import errors, fault, program, run

VENDOR = [None, "codesys", "twincat"]  # the presets that load the compatibility library
EPOCH_1970 = 116444736000000000  # 1970-01-01 as a FILETIME (100 ns since 1601-01-01)


def filetime(year: int, month: int, day: int, h: int = 0, m: int = 0, s: int = 0, ms: int = 0) -> int:
    """A FILETIME counted here, independently of the library: whole years, then months, then days."""

    def leap(y):
        return y % 4 == 0 and (y % 100 != 0 or y % 400 == 0)

    days = sum(366 if leap(y) else 365 for y in range(1601, year))
    days += sum([31, 29 if leap(year) else 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31][: month - 1]) + day - 1
    return (((days * 24 + h) * 60 + m) * 60 + s) * 10_000_000 + ms * 10_000


def fields(plc, path: str) -> tuple:
    names = ("wYear", "wMonth", "wDayOfWeek", "wDay", "wHour", "wMinute", "wSecond", "wMilliseconds")
    return tuple(plc[f"{path}.{n}"] for n in names)


def ft_value(plc, path: str) -> int:
    return plc[f"{path}.dwHighDateTime"] << 32 | plc[f"{path}.dwLowDateTime"]


def test_the_counting_helper_agrees_with_python():
    td = datetime(2024, 2, 29, 13, 14, 15, 678000) - datetime(1601, 1, 1)
    assert filetime(2024, 2, 29, 13, 14, 15, 678) == (td.days * 86400 + td.seconds) * 10**7 + td.microseconds * 10
    assert filetime(1970, 1, 1) == EPOCH_1970


# ------------------------------------------------------------------ the PLC's clock


@pytest.mark.parametrize("dialect", VENDOR)
def test_fb_localsystemtime_gives_the_plc_calendar(dialect):
    src = program(
        "IF n = 2 THEN en := TRUE; END_IF n := n + 1;"
        " fb(sNetID := '', bEnable := en, dwCycle := 1, dwOpt := 1, tTimeout := DEFAULT_ADS_TIMEOUT);"
        " v := fb.bValid; t := fb.systemTime; z := fb.tzID;",
        "fb : Tc2_Utilities.FB_LocalSystemTime; en, v : BOOL; n : INT; t : Tc2_Utilities.TIMESTRUCT; z : E_TimeZoneID;",
    )
    plc = run(src, 1, dialect)
    assert plc["main.v"] is False and fields(plc, "main.t") == (0,) * 8
    plc.scan(3)  # scans 2..4: enabled from the third (20 ms) on; 1970-01-01 was a Thursday
    assert plc["main.v"] is True
    assert fields(plc, "main.t") == (1970, 1, 4, 1, 0, 0, 0, 30)
    assert plc["main.z"] == "eTimeZoneID_Unknown"
    plc.scan(100)
    assert fields(plc, "main.t") == (1970, 1, 4, 1, 0, 0, 1, 30)


def test_getsystemtime_reads_the_same_calendar_as_a_filetime():
    src = program("g(timeLoDW => lo, timeHiDW => hi);", "g : Tc2_System.GETSYSTEMTIME; lo, hi : UDINT;")
    plc = run(src, 2, "twincat")  # the second scan runs at 10 ms
    assert plc["main.hi"] << 32 | plc["main.lo"] == EPOCH_1970 + 100_000


# ------------------------------------------------------------------ conversions


@pytest.mark.parametrize(
    ("date", "weekday"),
    [
        ((2024, 2, 29, 13, 14, 15, 678), 4),
        ((1601, 1, 1, 0, 0, 0, 0), 1),  # FILETIME 0, a Monday
        ((1970, 1, 1, 0, 0, 0, 0), 4),
        ((2000, 12, 31, 23, 59, 59, 999), 0),
        ((2100, 3, 1, 0, 0, 0, 1), 1),
        ((30827, 12, 31, 23, 59, 59, 999), 5),  # the last moment SYSTEMTIME_TO_FILETIME takes
    ],
)
def test_systemtime_and_filetime_convert_both_ways(date, weekday):
    y, mo, d, h, mi, s, ms = date
    src = program(
        f"t.wYear := {y}; t.wMonth := {mo}; t.wDay := {d}; t.wHour := {h}; t.wMinute := {mi};"
        f" t.wSecond := {s}; t.wMilliseconds := {ms}; t.wDayOfWeek := 6;"
        " f := SYSTEMTIME_TO_FILETIME(t); back := FILETIME_TO_SYSTEMTIME(f); txt := SYSTEMTIME_TO_STRING(back);"
        " again := STRING_TO_SYSTEMTIME(txt);",
        "t, back, again : TIMESTRUCT; f : T_FILETIME; txt : STRING;",
    )
    plc = run(src, 1, "twincat")
    assert ft_value(plc, "main.f") == filetime(*date)
    assert fields(plc, "main.back") == (y, mo, weekday, d, h, mi, s, ms)  # wDayOfWeek from the date
    assert plc["main.txt"] == f"{y:04d}-{mo:02d}-{d:02d}-{h:02d}:{mi:02d}:{s:02d}.{ms:03d}"
    if y <= 9999:
        assert fields(plc, "main.again") == fields(plc, "main.back")


@pytest.mark.parametrize(
    "assign",
    [
        "t.wYear := 2023; t.wMonth := 2; t.wDay := 29;",  # no 29 February in 2023
        "t.wYear := 2024; t.wMonth := 13; t.wDay := 1;",
        "t.wYear := 1600; t.wMonth := 12; t.wDay := 31;",
        "t.wYear := 2024; t.wMonth := 1; t.wDay := 1; t.wHour := 24;",
        "t.wYear := 2024; t.wMonth := 1; t.wDay := 1; t.wMilliseconds := 1000;",
    ],
)
def test_an_invalid_systemtime_gives_filetime_0(assign):
    plc = run(program(assign + " f := SYSTEMTIME_TO_FILETIME(t);", "t : TIMESTRUCT; f : T_FILETIME;"), 1, "twincat")
    assert ft_value(plc, "main.f") == 0


def test_a_filetime_with_its_top_bit_set_gives_a_zero_systemtime():
    src = program("f.dwHighDateTime := 16#80000000; t := FILETIME_TO_SYSTEMTIME(f);", "t : TIMESTRUCT; f : T_FILETIME;")
    assert fields(run(src, 1, "twincat"), "main.t") == (0,) * 8


@pytest.mark.parametrize(
    ("ft", "dt"),
    [
        (filetime(2024, 2, 29, 13, 14, 15, 678), "DT#2024-02-29-13:14:15"),
        (filetime(1969, 12, 31, 23, 59, 59), "DT#1970-01-01-00:00:00"),  # clamped to DT's range
        (filetime(2200, 1, 1), "DT#2106-02-07-06:28:15"),
    ],
)
def test_filetime_to_dt_and_back(ft, dt):
    src = program(
        f"f.dwLowDateTime := {ft & 0xFFFFFFFF}; f.dwHighDateTime := {ft >> 32}; d := FILETIME_TO_DT(f);"
        " g := DT_TO_FILETIME(d); e := d = want; d2 := FILETIME_TO_DT(g);",
        f"f, g : T_FILETIME; d, d2 : DT; want : DT := {dt}; e : BOOL;",
    )
    plc = run(src, 1, "twincat")
    assert plc["main.e"] is True
    if dt.startswith("DT#2024"):  # inside DT's range: back to the FILETIME, to the second
        assert ft_value(plc, "main.g") == ft // 10_000_000 * 10_000_000
    assert plc["main.d2"] == plc["main.d"]


def test_time_zone_blocks_give_utc_and_apply_a_given_bias():
    src = program(
        """
        tz(sNetID := '', bExecute := TRUE);
        utc(in := SYSTEMTIME_TO_FILETIME(t), tzInfo := tz.tzInfo);
        info.bias := -60;  (* UTC+1 *)
        toUtc(in := SYSTEMTIME_TO_FILETIME(t), tzInfo := info);
        toLocal(in := t, tzInfo := info);
        u := FILETIME_TO_SYSTEMTIME(toUtc.out);
        """,
        "tz : FB_GetTimeZoneInformation; utc, toUtc : FB_TzSpecificLocalTimeToFileTime;"
        " toLocal : FB_SystemTimeToTzSpecificLocalTime; info : ST_TimeZoneInformation; u : TIMESTRUCT;"
        " t : TIMESTRUCT := (wYear := 2024, wMonth := 3, wDay := 1, wHour := 0, wMinute := 30);",
    )
    plc = run(src, 1, "twincat")
    assert (plc["main.tz.tzInfo.bias"], plc["main.tz.tzID"], plc["main.tz.bBusy"]) == (0, "eTimeZoneID_Unknown", False)
    assert plc["main.tz.tzInfo.standardName"] == "Coordinated Universal Time"
    assert ft_value(plc, "main.utc.out") == filetime(2024, 3, 1, 0, 30)
    assert fields(plc, "main.u") == (2024, 2, 4, 29, 23, 30, 0, 0)
    assert fields(plc, "main.toLocal.out") == (2024, 3, 5, 1, 1, 30, 0, 0)
    assert (plc["main.toUtc.bB"], plc["main.toLocal.bB"]) == (False, False)


def test_tclog_computes_a_file_age_with_64_bit_halves():
    src = program(
        """
        now := DT_TO_FILETIME(DT#2024-01-02-00:00:00); old := DT_TO_FILETIME(DT#2024-01-01-00:00:00);
        a.dwLowPart := now.dwLowDateTime; a.dwHighPart := now.dwHighDateTime;
        b.dwLowPart := old.dwLowDateTime; b.dwHighPart := old.dwHighDateTime;
        age := LREAL_TO_DINT(UINT64_TO_LREAL(UInt64Sub64(a, b)) / 10000000.0);
        w := UInt64Sub64(b, a);
        """,
        "now, old : Tc2_Utilities.T_FILETIME; a, b, w : Tc2_Utilities.T_ULARGE_INTEGER; age : DINT;",
    )
    plc = run(src, 1, "twincat")
    assert plc["main.age"] == 86400
    assert plc["main.w.dwHighPart"] << 32 | plc["main.w.dwLowPart"] == 2**64 - 864_000_000_000  # wraps


# ------------------------------------------------------------------ strings, system names


def test_wstring_to_string2_skips_what_a_string_cannot_hold_and_reports_a_cut():
    src = program(
        """
        ok1 := Tc2_Utilities.WSTRING_TO_STRING2(ADR(s), ADR(w), SIZEOF(s));
        ok2 := WSTRING_TO_STRING2(pDstString := ADR(s4), pSrcWString := ADR(w), nDstSize := SIZEOF(s4));
        ok3 := WSTRING_TO_STRING2(ADR(s3), ADR(w), 3);
        ok4 := STRING_TO_WSTRING2(ADR(w2), ADR(s), SIZEOF(w2));
        ok5 := STRING_TO_WSTRING2(ADR(w9), ADR(s), SIZEOF(w9));
        """,
        's, s3 : STRING(255); s4 : STRING(4); w : WSTRING := "h\u00e9\u4e2dllo"; w2 : WSTRING(3); w9 : WSTRING(9);'
        " ok1, ok2, ok3, ok4, ok5 : BOOL;",
    )
    plc = run(src, 1, "twincat")
    assert (plc["main.s"], plc["main.ok1"]) == ("héllo", True)  # 中 is no Latin-1 character: skipped
    assert (plc["main.s4"], plc["main.ok2"]) == ("héll", False)  # 5 bytes: 4 characters and the NUL
    assert (plc["main.s3"], plc["main.ok3"]) == ("hé", False)  # nDstSize 3 bytes
    assert (plc["main.w2"], plc["main.ok4"]) == ("hél", False)
    assert (plc["main.w9"], plc["main.ok5"]) == ("héllo", True)


def test_wstring_to_string2_through_a_null_pointer_faults():
    src = program("ok := WSTRING_TO_STRING2(p, ADR(w), 10);", "p : POINTER TO STRING; w : WSTRING; ok : BOOL;")
    _, f = fault(src, "twincat")
    assert f.kind == "NULL"


def test_testandset_claims_a_free_flag_once():
    src = program(
        """
        r1 := TestAndSet(GVL.bFlag); r2 := Tc2_System.TestAndSet(GVL.bFlag);
        IF NOT r2 THEN blocked := blocked + 1; END_IF
        GVL.bFlag := FALSE;
        r3 := TestAndSet(Flag := GVL.bFlag);
        old1 := TEST_AND_SET(dw); old2 := TEST_AND_SET(dw);
        """,
        "r1, r2, r3 : BOOL; blocked : INT; dw : DWORD := 5; old1, old2 : DWORD;",
        "{gvl 'GVL'}\nVAR_GLOBAL bFlag : BOOL; END_VAR",
    )
    plc = run(src, 1, "twincat")
    assert (plc["main.r1"], plc["main.r2"], plc["main.r3"], plc["main.blocked"]) == (True, False, True, 1)
    assert plc["bFlag"] is True
    assert (plc["main.old1"], plc["main.old2"], plc["main.dw"]) == (5, 1, 1)


def test_var_info_as_tclog_uses_it():
    src = """
FUNCTION_BLOCK Logger
VAR_OUTPUT
  line : T_MaxString;
END_VAR
METHOD AppendVariable : BOOL
VAR_INPUT
  varInfo : __SYSTEM.VAR_INFO;
  value : ANY;
END_VAR
VAR
  format : Tc2_Utilities.FB_FormatString;
  symbolName, typeName : Tc2_System.T_MaxString;
END_VAR
symbolName := varInfo.Symbol;
typeName := varInfo.TypeName;
format(sFormat := '%s [%s] : ', arg1 := Tc2_Utilities.F_STRING(symbolName), arg2 := F_STRING(typeName));
line := format.sOut;
END_METHOD
END_FUNCTION_BLOCK
""" + program(
        "info.Symbol := 'main.n'; info.TypeName := 'INT'; info.TypeClass := __SYSTEM.TYPE_CLASS.TYPE_INT;"
        " info.MemoryArea := MEM_LOCAL; log.AppendVariable(info, n); size := SIZEOF(info);",
        "log : Logger; info : __SYSTEM.VAR_INFO; n : INT := 10; size : UDINT;",
    )
    plc = run(src, 1, "twincat")
    assert plc["main.log.line"] == "main.n [INT] : "
    assert (plc["main.info.TypeClass"], plc["main.info.MemoryArea"]) == ("TYPE_INT", "MEM_LOCAL")


def test_getcurtaskindexex_and_max_string_length():
    src = program("i := Tc2_System.GETCURTASKINDEXEX(); m := Tc2_System.MAX_STRING_LENGTH;", "i : BYTE; m : UDINT;")
    plc = run(src, 1, "twincat")
    assert (plc["main.i"], plc["main.m"]) == (1, 255)


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
@pytest.mark.parametrize(
    ("body", "decls", "message"),
    [
        ("fb(bEnable := TRUE);", "fb : FB_LocalSystemTime;", "unknown type 'FB_LocalSystemTime'"),
        ("x := 1;", "f : T_FILETIME; x : INT;", "unknown type 'T_FILETIME'"),
        (
            "ok := WSTRING_TO_STRING2(ADR(s), ADR(w), 81);",
            "s : STRING; w : WSTRING; ok : BOOL;",
            "'WSTRING_TO_STRING2'",
        ),
        ("ok := TestAndSet(b);", "b, ok : BOOL;", "'TestAndSet'"),
        ("x := 1;", "v : VAR_INFO; x : INT;", "unknown type 'VAR_INFO'"),
    ],
)
def test_iec_and_openplc_do_not_know_the_names(dialect, body, decls, message):
    text = errors(program(body, decls), dialect)
    assert message in text and ("error[E010]" in text or "error[E012]" in text)


# ------------------------------------------------------------------ __TRY / __CATCH / __FINALLY


TRY_DECLS = (
    "x, zero, caught, fin, after : INT; two : INT := 2; i : INT := 7; a : ARRAY[1..3] OF INT;"
    " exc, other : __SYSTEM.ExceptionCode; p : POINTER TO INT; log : STRING;"
)


def try_run(body: str, dialect: str | None = "twincat", scans: int = 1, decls: str = TRY_DECLS, extra: str = ""):
    return run(program(body, decls, extra), scans, dialect)


@pytest.mark.parametrize("dialect", VENDOR)
@pytest.mark.parametrize(
    ("statement", "code"),
    [
        ("x := 10 / zero;", "RTSEXCPT_DIVIDEBYZERO"),
        ("x := a[i];", "RTSEXCPT_ARRAYBOUNDS"),
        ("a[i] := 1;", "RTSEXCPT_ARRAYBOUNDS"),
        ("x := p^;", "RTSEXCPT_ACCESS_VIOLATION"),
        ("x := LREAL_TO_INT(1.0 / 0.0);", "RTSEXCPT_FPU_INVALID_OPERATION"),
    ],
)
def test_a_caught_fault_gives_its_exception_code(dialect, statement, code):
    plc = try_run(
        f"__TRY {statement} after := 1; __CATCH(exc) caught := caught + 1; __FINALLY fin := fin + 1; __ENDTRY",
        dialect,
        scans=2,
    )
    assert plc.state != "FAULT"
    assert (plc["main.exc"], plc["main.caught"], plc["main.fin"], plc["main.after"]) == (code, 2, 2, 0)


def test_nothing_thrown_runs_the_body_and_finally_not_the_catch():
    plc = try_run(
        "__TRY x := 10 / two; after := 1; __CATCH(exc) caught := 1; __FINALLY fin := fin + 1; __ENDTRY x := x + 1;"
    )
    assert (plc["main.x"], plc["main.after"], plc["main.caught"], plc["main.fin"]) == (6, 1, 0, 1)
    assert plc["main.exc"] == "RTSEXCPT_UNKNOWN"  # untouched: its initial value, the first one


def test_the_exception_code_compares_with_its_values_and_converts_to_udint():
    plc = run(
        program(
            "__TRY x := 1 / zero; __CATCH(exc) is_div := exc = __SYSTEM.ExceptionCode.RTSEXCPT_DIVIDEBYZERO;"
            " n := exc; __ENDTRY",
            "x, zero : INT; exc : __SYSTEM.ExceptionCode; is_div : BOOL; n : UDINT;",
        ),
        1,
        "codesys",
    )
    assert (plc["main.is_div"], plc["main.n"]) == (True, 0x102)


def test_nested_try_the_innermost_catch_handles_and_every_finally_runs_in_order():
    plc = try_run(
        """
        __TRY
          __TRY
            x := 10 / zero;
          __CATCH(exc)
            log := CONCAT(log, 'c1');
          __FINALLY
            log := CONCAT(log, 'f1');
          __ENDTRY
          __TRY
            a[i] := 1;
          __FINALLY
            log := CONCAT(log, 'f2');   (* no __CATCH: the outer one handles it *)
          __ENDTRY
          log := CONCAT(log, 'never');
        __CATCH(other)
          log := CONCAT(log, 'c2');
        __FINALLY
          log := CONCAT(log, 'f3');
        __ENDTRY
        """
    )
    assert plc["main.log"] == "c1f1f2c2f3"
    assert (plc["main.exc"], plc["main.other"]) == ("RTSEXCPT_DIVIDEBYZERO", "RTSEXCPT_ARRAYBOUNDS")


def test_a_fault_in_a_called_function_and_block_is_caught_by_the_caller():
    extra = """
FUNCTION Div : INT
VAR_INPUT a, b : INT; END_VAR
Div := a / b;
END_FUNCTION
FUNCTION_BLOCK Fb
VAR_INPUT k : INT; END_VAR
VAR_OUTPUT steps : INT; END_VAR
VAR arr : ARRAY[0..1] OF INT; END_VAR
steps := steps + 1;
arr[k] := 1;
steps := steps + 10;
END_FUNCTION_BLOCK
"""
    plc = try_run(
        "__TRY x := Div(1, zero); __CATCH(exc) __ENDTRY __TRY fb(k := 5); __CATCH(other) __ENDTRY",
        decls=TRY_DECLS + " fb : Fb;",
        extra=extra,
    )
    assert (plc["main.exc"], plc["main.other"], plc["main.fb.steps"]) == (
        "RTSEXCPT_DIVIDEBYZERO",
        "RTSEXCPT_ARRAYBOUNDS",
        1,
    )


def test_calls_nested_too_deep_are_a_stack_overflow():
    extra = """
FUNCTION Deep : DINT
VAR_INPUT n : DINT; END_VAR
IF n <= 0 THEN Deep := 0; ELSE Deep := Deep(n - 1) + 1; END_IF
END_FUNCTION
"""
    plc = try_run("__TRY x := 5; x := DINT_TO_INT(Deep(100000)); __CATCH(exc) __ENDTRY", extra=extra)
    assert (plc["main.exc"], plc["main.x"]) == ("RTSEXCPT_STACK_OVERFLOW", 5)


def test_loops_exit_continue_and_return_inside_try():
    extra = """
FUNCTION F : INT
VAR_INPUT n : INT; END_VAR
VAR_IN_OUT count : INT; END_VAR
VAR e : __SYSTEM.ExceptionCode; END_VAR
__TRY
  F := 100 / n;
  RETURN;
__CATCH(e)
  F := -1;
__FINALLY
  count := count + 1;
__ENDTRY
F := 7;
END_FUNCTION
"""
    plc = try_run(
        """
        FOR i := 1 TO 5 DO
          __TRY
            IF i = 2 THEN CONTINUE; END_IF
            IF i = 4 THEN EXIT; END_IF
            x := x + 10 / (i - 3);
          __CATCH(exc)
            caught := caught + 1;
          __FINALLY
            fin := fin + 1;
          __ENDTRY
        END_FOR
        after := F(4, zero) * 1000 + F(0, zero);
        """,
        decls=TRY_DECLS.replace("i : INT := 7;", "i : INT;"),
        extra=extra,
    )
    # i = 1: 10 / -2 = -5; 2: CONTINUE; 3: division by zero, caught; 4: EXIT; FINALLY each time
    assert (plc["main.x"], plc["main.caught"], plc["main.fin"], plc["main.i"]) == (-5, 1, 4, 4)
    # F(4): 25, RETURN (its FINALLY ran); F(0): caught, -1, FINALLY, then F := 7 after __ENDTRY
    assert (plc["main.after"], plc["main.zero"]) == (25 * 1000 + 7, 2)


def test_a_fault_the_catch_does_not_handle_still_faults_the_plc():
    src = program(
        "__TRY FOR i := 1 TO 3 BY zero DO x := 1; END_FOR __CATCH(exc) caught := 1; __FINALLY fin := 1; __ENDTRY",
        TRY_DECLS,
    )
    plc, f = fault(src, "twincat")
    assert (f.kind, f.line, plc.state) == ("LOOP", 6, "FAULT")
    assert plc["main.caught"] == 0


def test_try_without_catch_runs_finally_and_the_plc_faults_at_the_line():
    src = program("__TRY\n  x := 1 / zero;\n__FINALLY\n  fin := 1;\n__ENDTRY", TRY_DECLS)
    plc, f = fault(src, "twincat")
    assert (f.kind, f.line) == ("DIV0", 7)
    assert plc["main.fin"] == 1


def test_the_watchdog_is_not_caught():
    src = program(
        "__TRY\n  WHILE TRUE DO\n    x := x + 1;\n  END_WHILE\n__CATCH(exc)\n  caught := 1;\n__ENDTRY",
        "x : DINT; caught : INT; exc : __SYSTEM.ExceptionCode;",
    )
    plc = PLC(compile_text(src, "t.st", dialect="twincat", use_cache=False), watchdog="100ms")
    with pytest.raises(PLCFaultError) as info:
        plc.scan()
    assert (info.value.fault.kind, info.value.fault.line, plc.state) == ("WATCHDOG", 7, "FAULT")
    assert plc["main.caught"] == 0


@pytest.mark.skipif(toolchain.missing() is not None, reason=f"native tier: {toolchain.missing()}")
def test_try_in_the_native_tier():
    src = program(
        "FOR i := 1 TO 3 DO __TRY x := x + 10 / (i - 2); __CATCH(exc) caught := caught + 1;"
        " __FINALLY fin := fin + 1; __ENDTRY END_FOR",
        TRY_DECLS,
    )
    plc = PLC(compile_text(src, "t.st", dialect="twincat", native=True, use_cache=False))
    assert plc.compiled.native  # the body runs compiled
    plc.scan()
    assert (plc["main.x"], plc["main.caught"], plc["main.fin"], plc["main.exc"]) == (0, 1, 3, "RTSEXCPT_DIVIDEBYZERO")


def test_keywords_are_case_insensitive_and_parts_optional():
    plc = try_run("__try x := 1 / zero; __catch(exc) __endtry __Try x := 3; __Finally fin := 4; __EndTry")
    assert (plc["main.exc"], plc["main.x"], plc["main.fin"]) == ("RTSEXCPT_DIVIDEBYZERO", 3, 4)


@pytest.mark.parametrize("dialect", ["iec", "openplc"])
def test_try_is_a_vendor_extension(dialect):
    text = errors(program("__TRY x := 1; __CATCH(e) __ENDTRY", "x : INT; e : DINT;"), dialect)
    assert "error[E044]: exception handling (__TRY … __ENDTRY) is not part of the" in text
    assert "E013" not in text  # the variable's type is not checked where the construct is refused


@pytest.mark.parametrize("dialect", VENDOR)
def test_the_catch_variable_must_be_an_exception_code(dialect):
    text = errors(program("__TRY x := 1; __CATCH(e) __ENDTRY", "x : INT; e : DINT;"), dialect)
    assert "error[E013]: the variable of __CATCH must be of type __SYSTEM.ExceptionCode, not DINT" in text


def test_an_unclosed_try_is_a_syntax_error_at_its_line():
    text = errors(program("__TRY\n  x := 1;\n", "x : INT;"), "twincat")
    assert "error[E001]" in text


# ------------------------------------------------------------------ SUB of two dates


@pytest.mark.parametrize("dialect", [None, "codesys", "twincat", "iec", "openplc"])
def test_sub_of_two_dates_is_a_time(dialect):
    src = program(
        "t1 := SUB(d2, d1); t2 := d2 - d1; t3 := SUB(IN1 := tod2, IN2 := tod1); t4 := SUB(day2, day1);"
        " t5 := SUB_DT_DT(d2, d1); i := SUB(5, 7);",
        "d1 : DT := DT#2024-01-01-00:00:00; d2 : DT := DT#2024-01-02-01:00:00.5;"
        " tod1 : TOD := TOD#08:00:00; tod2 : TOD := TOD#09:30:00; day1 : DATE := D#2024-02-28;"
        " day2 : DATE := D#2024-03-01; t1, t2, t3, t4, t5 : TIME; i : INT;",
    )
    plc = run(src, 1, dialect)
    ns = 1_000_000_000
    assert plc["main.t1"] == plc["main.t2"] == plc["main.t5"] == 25 * 3600 * ns + ns // 2
    assert (plc["main.t3"], plc["main.t4"], plc["main.i"]) == (5400 * ns, 2 * 86400 * ns, -2)


def test_sub_of_a_date_and_something_else_is_refused():
    text = errors(program("t := SUB(d, TRUE); u := SUB(t, d);", "d : DT; t : TIME; u : TIME;"), "twincat")
    assert "argument 2 of SUB must be ANY_MAGNITUDE or ANY_DATE, not BOOL" in text
    assert "arguments of SUB have incompatible types" in text


def test_getcpuaccount_counts_the_plc_clock_in_100_ns_ticks():
    src = """
PROGRAM main
VAR c : Tc2_System.GETCPUACCOUNT; first, d : UDINT; n : INT; END_VAR
c();
IF n = 0 THEN first := c.cpuAccountDW; END_IF
n := n + 1;
d := c.cpuAccountDW - first;
END_PROGRAM
"""
    plc = PLC(compile_text(src, "t.st", dialect="twincat", use_cache=False), cycle="10ms")
    plc.scan(3)
    assert plc["main.d"] == 200_000  # two 10 ms cycles
