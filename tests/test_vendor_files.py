"""TwinCAT's file blocks, directory listing, string FIFO and dynamic memory in the vendor library
(st/stdlib/vendor/files.st, findfile.py, utilities.st, dynmem.st: what TcLog needs), and the
CODESYS behaviours TcLog's suites rely on (REPLACE/DELETE at position 0, TIME's unsigned bytes, a
REFERENCE TO property, SIZEOF of a variable in a constant)."""

from __future__ import annotations

import os
import time

import pytest

from st.stdlib.vendor import sysfile

from helpers import fault, program, run

VENDOR = [None, "codesys", "twincat"]


@pytest.fixture
def root(tmp_path, monkeypatch):
    monkeypatch.setattr(sysfile, "FILE_ROOT", tmp_path)
    yield tmp_path
    sysfile.close_all()


# A sequence of requests, one step per scan; each waits for its block's bBusy to fall, as TwinCAT code does.
FILE_STEPS = """
CASE step OF
0: fo(sPathName := 'C:\\logs\\a.txt', nMode := FOPEN_MODEWRITE OR FOPEN_MODETEXT, bExecute := TRUE);
   busyAtStart := fo.bBusy;
   IF NOT fo.bBusy THEN h := fo.hFile; fo(bExecute := FALSE); step := 1; END_IF
1: fw(hFile := h, pWriteBuff := ADR(buf), cbWriteLen := 3, bExecute := TRUE);
   IF NOT fw.bBusy THEN n := fw.cbWrite; fw(bExecute := FALSE); step := 2; END_IF
2: fp(hFile := h, sLine := 'second$N', bExecute := TRUE);
   IF NOT fp.bBusy THEN fp(bExecute := FALSE); step := 3; END_IF
3: fc(hFile := h, bExecute := TRUE);
   IF NOT fc.bBusy THEN fc(bExecute := FALSE); step := 4; END_IF
4: fo(sPathName := 'C:\\logs\\a.txt', nMode := FOPEN_MODEREAD, bExecute := TRUE);
   IF NOT fo.bBusy THEN h := fo.hFile; fo(bExecute := FALSE); step := 5; END_IF
5: fg(hFile := h, bExecute := TRUE);
   IF NOT fg.bBusy THEN line1 := fg.sLine; fg(bExecute := FALSE); step := 6; END_IF
6: fg(hFile := h, bExecute := TRUE);
   IF NOT fg.bBusy THEN line2 := fg.sLine; fg(bExecute := FALSE); step := 7; END_IF
7: fg(hFile := h, bExecute := TRUE);
   IF NOT fg.bBusy THEN eof := fg.bEOF; fg(bExecute := FALSE); step := 8; END_IF
8: fc(hFile := h, bExecute := TRUE);
   IF NOT fc.bBusy THEN fc(bExecute := FALSE); step := 9; END_IF
9: fo(sPathName := 'C:\\nope\\x.txt', nMode := FOPEN_MODEREAD, bExecute := TRUE);
   IF NOT fo.bBusy THEN missing := fo.nErrId; fo(bExecute := FALSE); step := 10; END_IF
10: fo(sPathName := 'C:\\logs\\a.txt', nMode := FOPEN_MODEBINARY, bExecute := TRUE);
   IF NOT fo.bBusy THEN badMode := fo.nErrId; step := 11; END_IF
11: fr(sOldName := 'C:\\logs\\a.txt', sNewName := 'C:\\logs\\b.txt', bExecute := TRUE);
   IF NOT fr.bBusy THEN renamed := NOT fr.bError; step := 12; END_IF
12: fd(sPathName := 'C:\\logs\\b.txt', bExecute := TRUE);
   IF NOT fd.bBusy THEN deleted := NOT fd.bError; step := 13; END_IF
END_CASE
"""
FILE_VARS = """
fo : FB_FileOpen; fw : FB_FileWrite; fc : FB_FileClose; fp : FB_FilePuts; fg : FB_FileGets;
fr : FB_FileRename; fd : FB_FileDelete;
step : INT; h : UINT; buf : ARRAY[0..9] OF BYTE := [72, 105, 10];
line1 : STRING; line2 : STRING; eof : BOOL; n : UDINT; missing : UDINT; badMode : UDINT;
renamed : BOOL; deleted : BOOL; busyAtStart : BOOL;
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_file_blocks_open_write_read_and_delete_a_file_one_request_a_scan(dialect, root):
    (root / "C" / "logs").mkdir(parents=True)
    plc = run(program(FILE_STEPS, FILE_VARS), 1, dialect)
    assert plc["main.busyatstart"] is True  # the request made on the rising edge completes at the next call
    assert (root / "C" / "logs" / "a.txt").read_bytes() == b""
    plc.scan(40)
    got = [plc[f"main.{v}"] for v in ("step", "n", "line1", "line2", "eof", "missing", "badmode", "renamed")]
    assert got == [13, 3, "Hi\n", "second\n", True, 0x70C, 0x706, True]
    assert plc["main.deleted"] is True
    assert list((root / "C" / "logs").iterdir()) == []


def test_a_directory_is_made_and_removed(root):
    body = """
CASE step OF
0: cd(sPathName := 'out', bExecute := TRUE); IF NOT cd.bBusy THEN made := NOT cd.bError; cd(bExecute := FALSE); step := 1; END_IF
1: cd(sPathName := 'out', bExecute := TRUE); IF NOT cd.bBusy THEN again := cd.nErrId; step := 2; END_IF
2: rd(sPathName := 'out', bExecute := TRUE); IF NOT rd.bBusy THEN removed := NOT rd.bError; step := 3; END_IF
END_CASE
"""
    decls = "cd : FB_CreateDir; rd : FB_RemoveDir; step : INT; made : BOOL; again : UDINT; removed : BOOL;"
    plc = run(program(body, decls), 10, "twincat")
    assert [plc["main.made"], plc["main.again"], plc["main.removed"]] == [True, 0x70F, True]
    assert not (root / "out").exists()


LISTING = """
CASE step OF
0: en(sPathName := 'C:\\data\\*.log', eCmd := eEnumCmd_First, pFindList := ADR(list), cbFindList := SIZEOF(list),
      bExecute := TRUE);
   IF NOT en.bBusy THEN
     n1 := en.nFindFiles; eoe1 := en.bEOE; first1 := list[1].sFileName; second1 := list[2].sFileName;
     size1 := list[1].fileSize.dwLowPart; en(bExecute := FALSE); step := 1;
   END_IF
1: en(eCmd := eEnumCmd_Next, bExecute := TRUE);
   IF NOT en.bBusy THEN n2 := en.nFindFiles; eoe2 := en.bEOE; first2 := list[1].sFileName; en(bExecute := FALSE); step := 2; END_IF
2: en(sPathName := 'C:\\data', eCmd := eEnumCmd_First, bExecute := TRUE);
   IF NOT en.bBusy THEN dir := list[2].fileAttributes.bDirectory; dirName := list[2].sFileName;
     en(bExecute := FALSE); step := 3; END_IF
3: en(sPathName := 'C:\\data\\b.*', eCmd := eEnumCmd_First, bExecute := TRUE);
   IF NOT en.bBusy THEN
     age := UInt64Sub64(__VD_ULARGE(__VD_NOW()), __VD_ULARGE(__VD_U64(list[1].lastWriteTime.dwHighDateTime,
       list[1].lastWriteTime.dwLowDateTime)));
     en(bExecute := FALSE); step := 4; END_IF
4: en(sPathName := 'C:\\nothing\\*', eCmd := eEnumCmd_First, bExecute := TRUE);
   IF NOT en.bBusy THEN missing := en.nErrID; step := 5; END_IF
END_CASE
"""
LISTING_VARS = """
en : FB_EnumFindFileList; list : ARRAY[1..2] OF ST_FindFileEntry; step : INT;
n1 : UDINT; n2 : UDINT; eoe1 : BOOL; eoe2 : BOOL; first1 : STRING; second1 : STRING; first2 : STRING;
size1 : DWORD; dir : BOOL; dirName : STRING; missing : UDINT; age : T_ULARGE_INTEGER;
"""


@pytest.mark.parametrize("dialect", ["codesys", "twincat"])
def test_enum_find_file_list_pages_through_a_folder_in_name_order(dialect, root):
    data = root / "C" / "data"
    (data / "Archive").mkdir(parents=True)
    for name, text in (("b.log", "12345"), ("A.LOG", "1"), ("c.log", ""), ("notes.txt", "x")):
        (data / name).write_text(text)
    old = time.time() - 3600  # written an hour before now
    os.utime(data / "b.log", (old, old))
    plc = run(program(LISTING, LISTING_VARS), 14, dialect)
    got = [plc[f"main.{v}"] for v in ("n1", "eoe1", "first1", "second1", "size1", "n2", "eoe2", "first2")]
    assert got == [2, False, "A.LOG", "b.log", 1, 1, True, "c.log"]
    assert (plc["main.dir"], plc["main.dirname"], plc["main.missing"]) == (True, "Archive", 0x70C)
    # an hour old on the PLC's calendar too, whatever the PLC's clock (virtual time starts at 1970)
    ticks = plc["main.age.dwhighpart"] << 32 | plc["main.age.dwlowpart"]
    assert 3599 <= ticks / 10_000_000 <= 3700


STRING_FIFO = """
fifo.pBuffer := ADR(mem);
fifo.cbBuffer := room;
fifo.A_Reset();
FOR i := 1 TO 3 DO
  fifo.putValue := CONCAT('line ', INT_TO_STRING(i));
  fifo.A_AddTail();
END_FOR
fifo.A_GetHead();
head := fifo.getValue;
fifo.A_RemoveHead();
first := fifo.getValue;
count := fifo.nCount;
fifo.putValue := 'this does not fit any more';
fifo.A_AddTail();
full := NOT fifo.bOk;
(* the buffer grows, its bytes kept: the records that wrapped around its end stay in order *)
fifo.putValue := 'wrap';
fifo.A_AddTail();
room := room + 30;
fifo.cbBuffer := room;
FOR i := 1 TO 4 DO
  fifo.A_RemoveHead();
  rest[i] := fifo.getValue;
END_FOR
emptyOk := fifo.bOk;
bytes := MAXSTRING_TO_BYTEARR('Hi');
back := BYTEARR_TO_MAXSTRING(bytes);
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_string_ring_buffer_keeps_strings_in_order_and_survives_a_grown_buffer(dialect):
    decls = """fifo : FB_StringRingBuffer; mem : ARRAY[0..99] OF BYTE; room : UDINT := 40; i : INT;
head : STRING; first : STRING; count : UDINT; full : BOOL; rest : ARRAY[1..4] OF STRING; emptyOk : BOOL;
bytes : ARRAY[0..255] OF BYTE; back : STRING;"""
    plc = run(program(STRING_FIFO, decls), 1, dialect)
    assert [plc[f"main.{v}"] for v in ("head", "first", "count", "full")] == ["line 1", "line 1", 2, True]
    assert plc["main.rest"] == ["line 2", "line 3", "wrap", ""]
    assert plc["main.emptyok"] is False
    assert plc["main.bytes"][:3] == [72, 105, 0] and plc["main.back"] == "Hi"


DYNMEM = """
ok1 := buffer.CreateBuffer(nSize := 4, bReset := TRUE);
p := buffer.pBuffer;
p[0] := 7; p[3] := 9;
ok2 := buffer.Resize(nSize := 8, bPreserve := TRUE, bReset := TRUE);
p := buffer.pBuffer;
kept := p[0] * 10 + p[3];
size := buffer.nBufferSize;
live := manager.nAllocated;
buffer.Clear();
gone := NOT buffer.bAvailable;
after := manager.nAllocated;
"""


@pytest.mark.parametrize("dialect", ["codesys", "twincat"])
def test_dynamic_memory_buffer_grows_keeping_its_bytes(dialect):
    decls = """manager : Tc3_DynamicMemory.FB_DynMem_Manager;
buffer : Tc3_DynamicMemory.FB_DynMem_Buffer(ipMemMan := manager);
p : POINTER TO BYTE; ok1 : BOOL; ok2 : BOOL; kept : INT; size : LINT; live : UDINT; gone : BOOL; after : UDINT;"""
    plc = run(program(DYNMEM, decls), 1, dialect)
    got = [plc[f"main.{v}"] for v in ("ok1", "ok2", "kept", "size", "live", "gone", "after")]
    assert got == [True, True, 79, 8, 1, True, 0]


def test_setting_the_host_clock_is_refused_with_an_ads_error():
    body = "set(START := TRUE); IF NOT set.BUSY THEN err := set.ERR; id := set.ERRID; END_IF"
    plc = run(program(body, "set : NT_SetLocalTime; err : BOOL; id : UDINT;"), 2, "twincat")
    assert (plc["main.err"], plc["main.id"]) == (True, 0x701)


# ------------------------------------------------------------- CODESYS behaviours TcLog relies on


@pytest.mark.parametrize(
    ("expr", "expected"),
    [
        ("REPLACE('abcdef', 'XY', 3, 0)", "XYcdef"),  # P = 0: the first character, L one less
        ("REPLACE('-hh:mm-', '', 0, 0)", "-hh:mm-"),  # TcLog: a placeholder FIND did not find
        ("REPLACE('abcdef', 'XY', 2, 1)", "XYcdef"),
        ("DELETE('abcdef', 3, 0)", "cdef"),
        ("DELETE('abcdef', 2, 1)", "cdef"),
    ],
)
@pytest.mark.parametrize("dialect", ["codesys", "twincat"])
def test_replace_and_delete_at_position_zero_as_codesys(dialect, expr, expected):
    assert run(program(f"s := {expr};", "s : STRING;"), 1, dialect)["main.s"] == expected


@pytest.mark.parametrize("dialect", [None, "iec"])
def test_replace_at_position_zero_is_a_range_fault_elsewhere(dialect):
    _plc, info = fault(program("s := REPLACE('abcdef', 'XY', 3, 0);", "s : STRING;"), dialect)
    assert info.kind == "RANGE" and "REPLACE: position 0 is outside 1..6" in info.message


@pytest.mark.parametrize("dialect", VENDOR)
def test_time_is_an_unsigned_count_of_ms_in_its_bytes(dialect):
    body = "MEMCPY(ADR(t), ADR(d), 4); MEMCPY(ADR(back), ADR(t), 4);"
    plc = run(program(body, "d : DWORD := 16#FFFFFFFF; t : TIME; back : DWORD;"), 1, dialect)
    assert plc["main.t"] == 4_294_967_295 * 1_000_000  # T#49d17h2m47s295ms
    assert plc["main.back"] == 0xFFFFFFFF


REFERENCE_PROPERTY = """
TYPE Err : STRUCT Info : STRING; Code : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK Core
  VAR _e : Err; END_VAR
  PROPERTY Error : REFERENCE TO Err
    GET Error REF= _e; END_GET
  END_PROPERTY
  METHOD Fail
    _e.Info := 'bad';
    Error.Code := 3;
  END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Buffered
  VAR_OUTPUT m : UDINT; END_VAR
  METHOD Room : UDINT
    VAR_INST buffer : ARRAY[0..99] OF BYTE; END_VAR
    VAR CONSTANT MaxPos : UDINT := SIZEOF(buffer) - 10; END_VAR
    Room := MaxPos;
  END_METHOD
  m := Room();
END_FUNCTION_BLOCK
"""


@pytest.mark.parametrize("dialect", VENDOR)
def test_a_reference_property_reads_and_writes_what_it_refers_to(dialect):
    body = "c.Fail(); s := c.Error.Info; c.Error.Code := c.Error.Code + 1; n := c.Error.Code; b(); m := b.m;"
    plc = run(program(body, "c : Core; b : Buffered; s : STRING; n : INT; m : UDINT;", REFERENCE_PROPERTY), 1, dialect)
    assert (plc["main.s"], plc["main.n"], plc["main.m"]) == ("bad", 4, 90)
