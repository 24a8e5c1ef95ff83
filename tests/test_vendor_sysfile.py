"""CODESYS's SysFile and SysDir in the vendor compatibility library (st/stdlib/vendor/sysfile.st,
sysfile.py): files under the file root, handles, result codes, buffers through pointers."""

from __future__ import annotations

import pytest

from st.stdlib.vendor import sysfile

from helpers import errors, fault, program, run

ERR_OK, ERR_FAILED, ERR_PARAMETER = 0, 1, 2
ERR_NO_OBJECT, ERR_DUPLICATE, ERR_INVALID_HANDLE = 0x10, 0x12, 0x14
ERR_FILE_ERROR = 0x32
INVALID = 0xFFFFFFFFFFFFFFFF


@pytest.fixture(autouse=True)
def root(tmp_path, monkeypatch):
    """Every test's files in its own directory; no handle left open after it."""
    monkeypatch.setattr(sysfile, "FILE_ROOT", tmp_path)
    yield tmp_path
    sysfile.close_all()


def go(body: str, decls: str, extra: str = "", dialect: str | None = "twincat"):
    return run(program(body, decls, extra), 1, dialect)


# ------------------------------------------------------------------ writing and reading


def test_write_from_a_byte_array_and_a_string_then_read_back_into_both(root):
    plc = go(
        """
        h := SysFileOpen('data.bin', AM_WRITE, ADR(r1));
        n1 := SysFileWrite(h, ADR(arr), 5, ADR(r2));
        n2 := SysFileWrite(hFile := h, pbyBuffer := ADR(s), ulSize := LEN(s), pResult := ADR(r3));
        c1 := SysFileClose(h);
        h2 := SysFileOpen('data.bin', AM_READ, ADR(r4));
        n3 := SysFileRead(h2, ADR(back), 4, ADR(r5));
        n4 := SysFileRead(h2, ADR(text), 80, ADR(r6));
        n5 := SysFileRead(h2, ADR(back), 10, ADR(r7));
        c2 := SysFileClose(h2);
        """,
        "h, h2 : RTS_IEC_HANDLE; r1, r2, r3, r4, r5, r6, r7, c1, c2 : RTS_IEC_RESULT;"
        " n1, n2, n3, n4, n5 : RTS_IEC_SIZE;"
        " arr : ARRAY[0..9] OF BYTE := [72, 101, 108, 108, 111, 33, 33];"
        " s : STRING := ', file'; back : ARRAY[0..9] OF BYTE; text : STRING;",
    )
    assert (root / "data.bin").read_bytes() == b"Hello, file"
    assert (plc["main.h"], plc["main.h2"]) == (1, 1)  # the lowest free handle, again after the close
    assert [plc[f"main.n{i}"] for i in range(1, 6)] == [5, 6, 4, 7, 0]
    assert [plc[f"main.r{i}"] for i in range(1, 8)] == [ERR_OK] * 7
    assert (plc["main.c1"], plc["main.c2"]) == (ERR_OK, ERR_OK)
    assert plc["main.back"] == [72, 101, 108, 108, 0, 0, 0, 0, 0, 0]
    assert plc["main.text"] == "o, file"


def test_write_through_a_pointer_to_byte_starts_where_it_points(root):
    go(
        """
        pb := ADR(arr[2]);
        h := SysFileOpen('p.bin', AM_WRITE, 0);
        SysFileWrite(h, pb, 3, 0);
        SysFileWrite(h, ADR(w), SIZEOF(w), 0);
        SysFileClose(h);
        """,
        "h : RTS_IEC_HANDLE; arr : ARRAY[0..5] OF BYTE := [1, 2, 3, 4, 5, 6]; pb : POINTER TO BYTE;"
        " w : ARRAY[0..1] OF WORD := [16#0201, 16#0403];",
    )
    assert (root / "p.bin").read_bytes() == bytes([3, 4, 5, 1, 2, 3, 4])


def test_append_mode_writes_at_the_end_and_write_mode_empties_the_file(root):
    (root / "log.txt").write_bytes(b"one\n")
    (root / "new.txt").write_bytes(b"old contents")
    go(
        """
        h := SysFileOpen('log.txt', AM_APPEND, ADR(r1));
        SysFileWrite(h, ADR(s), LEN(s), 0);
        SysFileClose(h);
        h := SysFileOpen('new.txt', AM_WRITE, ADR(r2));
        SysFileWrite(h, ADR(s), LEN(s), 0);
        SysFileClose(h);
        h := SysFileOpen('created.txt', AM_APPEND_PLUS, ADR(r3));
        SysFileWrite(h, ADR(s), LEN(s), 0);
        SysFileClose(h);
        """,
        "h : RTS_IEC_HANDLE; r1, r2, r3 : RTS_IEC_RESULT; s : STRING := 'two$N';",
    )
    assert (root / "log.txt").read_bytes() == b"one\ntwo\n"
    assert (root / "new.txt").read_bytes() == b"two\n"
    assert (root / "created.txt").read_bytes() == b"two\n"


def test_read_plus_reads_and_writes_in_place_with_the_position(root):
    (root / "f.bin").write_bytes(b"abcdef")
    plc = go(
        """
        h := SysFileOpen('f.bin', AM_READ_PLUS, ADR(r));
        p0 := SysFileGetPos(h, 0);
        e0 := SysFileSetPos(h, 2, ADR(r2));
        SysFileWrite(h, ADR(s), 2, 0);
        p1 := SysFileGetPos(h, ADR(r3));
        eof1 := SysFileEOF(h, 0);
        n := SysFileRead(h, ADR(b), 10, 0);
        eof2 := SysFileEOF(h, ADR(r4));
        SysFileClose(h);
        """,
        "h : RTS_IEC_HANDLE; r, r2, r3, r4, e0, eof1, eof2 : RTS_IEC_RESULT; p0, p1, n : RTS_IEC_SIZE;"
        " s : STRING := 'XY'; b : ARRAY[0..9] OF BYTE;",
    )
    assert (root / "f.bin").read_bytes() == b"abXYef"
    assert (plc["main.p0"], plc["main.e0"], plc["main.p1"], plc["main.n"]) == (0, ERR_OK, 4, 2)
    assert plc["main.b"][:3] == [ord("e"), ord("f"), 0]
    assert (plc["main.eof1"], plc["main.eof2"]) == (ERR_FAILED, ERR_OK)
    assert [plc[f"main.{v}"] for v in ("r", "r2", "r3", "r4")] == [ERR_OK] * 4


def test_two_open_files_have_their_own_handles(root):
    plc = go(
        """
        a := SysFileOpen('a.txt', AM_WRITE, 0);
        b := SysFileOpen('b.txt', AM_WRITE, 0);
        SysFileClose(a);
        c := SysFileOpen('c.txt', AM_WRITE, 0);
        SysFileClose(b);
        SysFileClose(c);
        """,
        "a, b, c : RTS_IEC_HANDLE;",
    )
    assert (plc["main.a"], plc["main.b"], plc["main.c"]) == (1, 2, 1)


# ------------------------------------------------------------------ files and directories


def test_size_rename_and_delete(root):
    (root / "a.txt").write_bytes(b"12345678901")
    (root / "taken.txt").write_bytes(b"x")
    plc = go(
        """
        size := SysFileGetSize('a.txt', ADR(r1));
        ren := SysFileRename('a.txt', 'b.txt');
        ren2 := SysFileRename('b.txt', 'taken.txt');
        ren3 := SysFileRename('gone.txt', 'c.txt');
        del := SysFileDelete('b.txt');
        del2 := SysFileDelete('b.txt');
        size2 := SysFileGetSize('b.txt', ADR(r2));
        """,
        "size, size2 : RTS_IEC_SIZE; r1, r2, ren, ren2, ren3, del, del2 : RTS_IEC_RESULT;",
    )
    assert (plc["main.size"], plc["main.r1"]) == (11, ERR_OK)
    assert (plc["main.ren"], plc["main.ren2"], plc["main.ren3"]) == (ERR_OK, ERR_DUPLICATE, ERR_NO_OBJECT)
    assert (plc["main.del"], plc["main.del2"]) == (ERR_OK, ERR_NO_OBJECT)
    assert (plc["main.size2"], plc["main.r2"]) == (0, ERR_NO_OBJECT)
    assert sorted(p.name for p in root.iterdir()) == ["taken.txt"]


def test_directories_and_backslashes_as_separators(root):
    plc = go(
        """
        d1 := SysDirCreate('out');
        d2 := SysDirCreate('out');
        h := SysFileOpen('out\\x.txt', AM_WRITE, ADR(r));
        SysFileWrite(h, ADR(s), LEN(s), 0);
        SysFileClose(h);
        d3 := SysDirDelete('out');
        SysFileDelete('out/x.txt');
        d4 := SysDirDelete('out');
        d5 := SysDirDelete('out');
        """,
        "h : RTS_IEC_HANDLE; r, d1, d2, d3, d4, d5 : RTS_IEC_RESULT; s : STRING := 'x';",
    )
    assert [plc[f"main.d{i}"] for i in range(1, 6)] == [ERR_OK, ERR_DUPLICATE, ERR_FILE_ERROR, ERR_OK, ERR_NO_OBJECT]
    assert plc["main.r"] == ERR_OK
    assert list(root.iterdir()) == []


def test_a_relative_name_is_taken_from_the_current_directory_without_a_root(tmp_path, monkeypatch):
    monkeypatch.setattr(sysfile, "FILE_ROOT", None)
    monkeypatch.chdir(tmp_path)
    go("h := SysFileOpen('here.txt', AM_WRITE, 0); SysFileClose(h);", "h : RTS_IEC_HANDLE;")
    assert (tmp_path / "here.txt").exists()


# ------------------------------------------------------------------ errors


def test_a_missing_file_to_read(root):
    plc = go("h := SysFileOpen('missing.txt', AM_READ, ADR(r));", "h : RTS_IEC_HANDLE; r : RTS_IEC_RESULT;")
    assert (plc["main.h"], plc["main.r"]) == (INVALID, ERR_NO_OBJECT)


def test_invalid_handles(root):
    plc = go(
        """
        c1 := SysFileClose(RTS_INVALID_HANDLE);
        c2 := SysFileClose(7);
        n := SysFileRead(7, ADR(b), 1, ADR(r1));
        m := SysFileWrite(RTS_INVALID_HANDLE, ADR(b), 1, ADR(r2));
        e := SysFileEOF(7, ADR(r3));
        h := SysFileOpen('x.txt', AM_WRITE, 0);
        c3 := SysFileClose(h);
        c4 := SysFileClose(h);
        """,
        "h : RTS_IEC_HANDLE; c1, c2, c3, c4, r1, r2, r3, e : RTS_IEC_RESULT; n, m : RTS_IEC_SIZE;"
        " b : ARRAY[0..1] OF BYTE;",
    )
    assert [plc[f"main.c{i}"] for i in range(1, 5)] == [ERR_INVALID_HANDLE, ERR_INVALID_HANDLE, ERR_OK, 0x14]
    assert (plc["main.n"], plc["main.m"], plc["main.e"]) == (0, 0, ERR_INVALID_HANDLE)
    assert [plc[f"main.r{i}"] for i in range(1, 4)] == [ERR_INVALID_HANDLE] * 3


def test_writing_a_file_opened_to_read_and_an_unknown_mode(root):
    (root / "ro.txt").write_bytes(b"abc")
    plc = go(
        """
        h := SysFileOpen('ro.txt', AM_READ, 0);
        n := SysFileWrite(h, ADR(s), 1, ADR(r1));
        SysFileClose(h);
        h2 := SysFileOpen('ro.txt', 9, ADR(r2));
        h3 := SysFileOpen('', AM_READ, ADR(r3));
        """,
        "h, h2, h3 : RTS_IEC_HANDLE; n : RTS_IEC_SIZE; r1, r2, r3 : RTS_IEC_RESULT; s : STRING := 'x';",
    )
    assert (plc["main.n"], plc["main.r1"]) == (0, ERR_FILE_ERROR)
    assert (plc["main.h2"], plc["main.r2"], plc["main.h3"], plc["main.r3"]) == (
        INVALID,
        ERR_PARAMETER,
        INVALID,
        ERR_PARAMETER,
    )
    assert (root / "ro.txt").read_bytes() == b"abc"


def test_a_null_presult_is_accepted(root):
    plc = go(
        """
        h := SysFileOpen('n.txt', AM_WRITE, 0);
        n := SysFileWrite(h, ADR(s), 2, 0);
        size := SysFileGetSize(szFileName := 'n.txt', pResult := 0);
        SysFileClose(h);
        bad := SysFileOpen('missing', AM_READ, 0);
        """,
        "h, bad : RTS_IEC_HANDLE; n, size : RTS_IEC_SIZE; s : STRING := 'ok';",
    )
    assert (plc["main.h"], plc["main.n"], plc["main.size"], plc["main.bad"]) == (1, 2, 2, INVALID)
    assert (root / "n.txt").read_bytes() == b"ok"


def test_a_null_buffer_is_a_fault(root):
    (root / "z.txt").write_bytes(b"z")
    _, f = fault(program("h := SysFileOpen('z.txt', AM_READ, 0);\nSysFileRead(h, 0, 1, 0);", "h : ULINT;"), "twincat")
    assert (f.kind, f.line, f.message) == ("NULL", 7, "SysFileRead was given a NULL buffer for 1 byte(s)")


def test_a_size_beyond_the_buffer_is_a_fault(root):
    src = program("h := SysFileOpen('big.txt', AM_WRITE, 0);\nSysFileWrite(h, ADR(b), 5, 0);", "h : ULINT; b : DINT;")
    _, f = fault(src, "twincat")
    assert (f.kind, f.line) == ("MEMORY", 7)
    assert f.message == "SysFileWrite of 5 byte(s) beyond the 4 byte(s) of the buffer's variable"
    assert (root / "big.txt").read_bytes() == b""  # nothing written; the file stays open (handle 1)
    assert list(sysfile._files) == [1]


def test_arguments_of_the_wrong_kind_are_refused():
    msg = errors(program("h := SysFileOpen('a', x, ADR(i));", "h : ULINT; i : INT; x : REAL;"), "twincat")
    assert "t.st:6:6: error[E013]: 'am' must be ACCESS_MODE, not REAL" in msg
    msg = errors(program("h := SysFileOpen('a', AM_READ, ADR(i));", "h : ULINT; i : INT;"), "twincat")
    assert (
        "t.st:6:6: error[E013]: 'pResult' must be a POINTER TO RTS_IEC_RESULT (ADR of a UDINT) or 0, "
        "not POINTER TO INT" in msg
    )
    msg = errors(program("n := SysFileWrite(1, b, 1, 0);", "n : ULINT; b : DINT;"), "twincat")
    assert "t.st:6:6: error[E013]: 'pbyBuffer' must be a pointer to a variable with bytes" in msg


# ------------------------------------------------------------------ names and presets


def test_the_types_and_values_as_codesys_defines_them():
    plc = go(
        """
        a := SysDir.CmpErrors.Errors.ERR_OK;
        b := SysFile.CmpErrors.Errors.ERR_FILE_ERROR;
        c := Errors.ERR_DISK_FULL;
        d := ERR_NO_ACCESS_RIGHTS;
        e := SysFile.ACCESS_MODE.AM_APPEND_PLUS;
        f := SysFile.SysTypes.RTS_INVALID_HANDLE;
        g := SIZEOF(x); k := SIZEOF(y); l := SIZEOF(z);
        """,
        "a, b, c, d, e : UDINT; f : ULINT; g, k, l : UDINT; x : SysFile.SysTypes.RTS_IEC_RESULT;"
        " y : SysFile.SysTypes.RTS_IEC_HANDLE; z : SysFile.RTS_IEC_SIZE;",
    )
    got = [plc[f"main.{v}"] for v in "abcdefgkl"]
    assert got == [0, 0x32, 0x29, 0x19, 5, INVALID, 4, 8, 8]


def test_qualified_calls(root):
    plc = go(
        """
        h := SysFile.SysFileOpen(szFile := 'q.txt', am := SysFile.AM_WRITE_PLUS, pResult := ADR(r));
        IF r = SysDir.CmpErrors.Errors.ERR_OK THEN
          n := SysFile.SysFileWrite(hFile := h, pbyBuffer := ADR(s), ulSize := INT_TO_ULINT(LEN(s)), pResult := 0);
        END_IF;
        c := SysFile.SysFileclose(hFile := h);
        """,
        "h : SysFile.SysTypes.RTS_IEC_HANDLE; r, c : SysFile.SysTypes.RTS_IEC_RESULT; n : SysFile.SysTypes.RTS_IEC_SIZE;"
        " s : T_MaxString := 'qualified';",
    )
    assert (plc["main.r"], plc["main.n"], plc["main.c"]) == (ERR_OK, 9, ERR_OK)
    assert (root / "q.txt").read_bytes() == b"qualified"


def test_the_iec_preset_does_not_know_the_names():
    src = program(
        "h := SysFile.SysFileOpen('a.txt', 0, 0);\nr := SysDir.CmpErrors.Errors.ERR_OK;", "h : ULINT; r : UDINT;"
    )
    assert errors(src, "iec").splitlines()[::3] == [
        "t.st:6:6: error[E010]: undeclared identifier 'SysFile'",
        "t.st:7:6: error[E010]: undeclared identifier 'SysDir'",
        "2 error(s), 0 warning(s)",
    ]


# ------------------------------------------------------------------ a TcUnit-style file block

FILE_CONTROL = """
FUNCTION_BLOCK FB_FileControl
VAR
  FileHandle : SysFile.SysTypes.RTS_IEC_HANDLE;
  result : SysFile.SysTypes.RTS_IEC_RESULT;
END_VAR

METHOD PUBLIC Open : SysFile.SysTypes.RTS_IEC_RESULT
VAR_INPUT
  FileName : Tc2_System.T_MaxString;
  FileAccessMode : SysFile.ACCESS_MODE := SysFile.ACCESS_MODE.AM_APPEND_PLUS;
END_VAR
FileHandle := SysFile.SysFileOpen(szFile := FileName, am := FileAccessMode, pResult := ADR(result));
Open := result;
END_METHOD

METHOD PUBLIC Write : SysFile.SysTypes.RTS_IEC_RESULT
VAR_INPUT
  pString : POINTER TO BYTE;
  Size : UDINT;
END_VAR
IF FileHandle <> SysFile.SysTypes.RTS_INVALID_HANDLE THEN
  SysFile.SysFileWrite(hFile := FileHandle, pbyBuffer := pString, ulSize := Size, pResult := ADR(result));
  Write := result;
ELSE
  Write := SysDir.CmpErrors.Errors.ERR_INVALID_HANDLE;
END_IF
END_METHOD

METHOD PUBLIC Close : SysFile.SysTypes.RTS_IEC_RESULT
IF FileHandle <> SysFile.SysTypes.RTS_INVALID_HANDLE THEN
  Close := SysFile.SysFileClose(hFile := FileHandle);
  FileHandle := SysFile.SysTypes.RTS_INVALID_HANDLE;
ELSE
  Close := SysDir.CmpErrors.Errors.ERR_INVALID_HANDLE;
END_IF
END_METHOD
END_FUNCTION_BLOCK
"""


@pytest.mark.parametrize("dialect", ["twincat", "codesys"])
def test_a_tcunit_style_file_control_block(root, dialect):
    plc = go(
        """
        IF NOT done THEN
          fc.Close();  (* no file yet: ERR_INVALID_HANDLE *)
          r1 := fc.Open(FileName := 'report.xml', FileAccessMode := SysFile.ACCESS_MODE.AM_WRITE);
          r2 := fc.Write(pString := ADR(line), Size := INT_TO_UDINT(LEN(line)));
          r3 := fc.Write(pString := ADR(bytes), Size := SIZEOF(bytes));
          r4 := fc.Close();
          r5 := fc.Close();
          r6 := fc.Write(pString := ADR(line), Size := 1);
          r7 := fc.Open(FileName := 'report.xml');  (* AM_APPEND_PLUS by default *)
          r8 := fc.Write(pString := ADR(line), Size := 2);
          fc.Close();
          done := TRUE;
        END_IF;
        """,
        "fc : FB_FileControl; r1, r2, r3, r4, r5, r6, r7, r8 : SysFile.SysTypes.RTS_IEC_RESULT; done : BOOL;"
        " line : Tc2_System.T_MaxString := '<a/>$N'; bytes : ARRAY[1..3] OF BYTE := [16#41, 16#42, 16#0A];",
        FILE_CONTROL,
        dialect,
    )
    got = [plc[f"main.r{i}"] for i in range(1, 9)]
    assert got == [ERR_OK, ERR_OK, ERR_OK, ERR_OK, ERR_INVALID_HANDLE, ERR_INVALID_HANDLE, ERR_OK, ERR_OK]
    assert (root / "report.xml").read_bytes() == b"<a/>\nAB\n<a"
    assert sysfile._files == {}
