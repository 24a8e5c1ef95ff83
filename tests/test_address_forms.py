"""Direct addresses in the forms IEC 61131-3 allows, per preset (st/model/addresses.py):

- `%IX1` (a bit address with one number): bit 0 of byte 1 under every preset, as OpenPLC's glue
  generator binds MatIEC's `__IX1` (`bool_input[1][0]`);
- `%QX0.4.2`, `%IW2.1.3` (hierarchical): openplc and the default bind them by their leading numbers as
  OpenPLC does (W011); iec, codesys and twincat accept the declaration as their compilers do, and a
  run refuses it at the declaration, since st's image (OpenPLC's) has no place for it;
- `x AT %QB2 : WORD;`: a located E058, never an internal error.
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from st import PLC
from st.api import compile_text
from st.cli import main
from st.diagnostics import Code, Diagnostic, DiagnosticSink, Severity
from st.model.addresses import AddressError, UnplacedAddress, canonical, openplc_reading, parse_address
from st.runtime.faults import PLCStartError
from st.source import Span

PRESETS = [None, "openplc", "iec", "codesys", "twincat"]
OPENPLC_READING = [None, "openplc"]  # dotted_word_addresses on (None: no preset, st's default)
AS_WRITTEN = ["iec", "codesys", "twincat"]


def _diags(src: str, dialect: str | None) -> list[tuple[str, str, int, int, str]]:
    r = compile_text(src, "t.st", dialect=dialect, use_cache=False, raise_on_error=False)
    return [(d.severity.value, str(d.code), d.span.line, d.span.col, d.message) for d in r.diagnostics]


# ---------------------------------------------------------------------- the model's rule


@pytest.mark.parametrize(
    "addr, cell",
    [
        ("%IX1", ("I", "X", 8)),
        ("%QX1", ("Q", "X", 8)),
        ("%q1", ("Q", "X", 8)),
        ("%MX0", ("M", "X", 0)),
        ("%IX1.0", ("I", "X", 8)),
        ("%QX1.2", ("Q", "X", 10)),
        ("%IX1023", ("I", "X", 8184)),
        ("%IW3", ("I", "W", 3)),
        ("%ML1024", ("M", "L", 1024)),
    ],
)
def test_where_each_address_lands_in_the_image(addr, cell):
    assert parse_address(addr) == cell


@pytest.mark.parametrize(
    "addr, message",
    [
        ("%QX0.4.2", "%QX0.4.2: a hierarchical address"),
        ("%IW2.1.3", "%IW2.1.3: a hierarchical address"),
        ("%IW3.0", "%IW3.0: a hierarchical address"),
    ],
)
def test_a_hierarchical_address_has_no_place_in_the_image(addr, message):
    with pytest.raises(UnplacedAddress) as info:
        parse_address(addr)
    assert str(info.value).startswith(message)
    assert str(info.value).endswith(
        "st's process image is OpenPLC's (%"
        + addr[1]
        + "X<byte>.<bit>, %"
        + addr[1]
        + "B/W/D/L<n>) and has no place for it"
    )


@pytest.mark.parametrize(
    "addr, message",
    [
        ("%QX1.8", "%QX1.8: bit 8 is not 0..7"),
        ("%IX1024", "%IX1024 is outside the process image (1024 entries per table)"),
        ("%QX", "malformed address '%QX'"),
    ],
)
def test_what_stays_refused(addr, message):
    with pytest.raises(AddressError) as info:
        parse_address(addr)
    assert not isinstance(info.value, UnplacedAddress)
    assert str(info.value) == message


def test_spellings_of_one_cell_and_openplc_s_reading():
    assert [canonical(a) for a in ("%ix1", "%Q1", "%q0.1", "%QX0.4.2", "%IW3", "%I*")] == [
        "%IX1.0",
        "%QX1.0",
        "%QX0.1",
        "%QX0.4.2",
        "%IW3",
        "%I*",
    ]
    assert [openplc_reading(a) for a in ("%QX0.4.2", "%IW2.1.3", "%IW3.0", "%QX0.4", "%IX1", "%I*")] == [
        "%QX0.4",
        "%IW2",
        "%IW3",
        None,
        None,
        None,
    ]


# ---------------------------------------------------------------------- %IX1: every preset

NO_BIT = """PROGRAM main
VAR
  a AT %IX1 : BOOL;
  b AT %QX1 : BOOL;
  c : BOOL;
END_VAR
b := a;
c := %IX1.0 AND %I1;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", PRESETS)
def test_a_bit_address_without_its_bit_is_bit_0_of_the_byte(dialect):
    assert _diags(NO_BIT, dialect) == []
    plc = PLC(compile_text(NO_BIT, "t.st", dialect=dialect, use_cache=False))
    plc.image.set("%IX1.0", True)
    plc.scan()
    assert (plc["main.a"], plc["main.b"], plc["main.c"]) == (True, True, True)
    assert (plc.image.get("%QX1.0"), plc.image.get("%QX1"), plc.image.get("%QX1.1")) == (True, True, False)
    assert sorted(plc.bindings) == ["%IX1.0", "%QX1.0"]  # %IX1, %IX1.0 and %I1: one variable


# ---------------------------------------------------------------------- hierarchical addresses

HIERARCHICAL = """PROGRAM main
VAR
  c AT %QX0.4.2 : BOOL;
  d AT %IW2.1.3 : WORD;
END_VAR
c := d > 40;
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", OPENPLC_READING)
def test_openplc_binds_a_hierarchical_address_by_its_leading_numbers(dialect):
    assert _diags(HIERARCHICAL, dialect) == [
        ("warning", "W011", 3, 3, "'%QX0.4.2': OpenPLC binds it to %QX0.4 and ignores '.2'"),
        ("warning", "W011", 4, 3, "'%IW2.1.3': OpenPLC binds it to %IW2 and ignores '.1.3'"),
    ]
    plc = PLC(compile_text(HIERARCHICAL, "t.st", dialect=dialect, use_cache=False))
    plc.image.set("%IW2", 41)
    plc.scan()
    assert (plc["main.d"], plc["main.c"], plc.image.get("%QX0.4")) == (41, True, True)


@pytest.mark.parametrize("dialect", AS_WRITTEN)
def test_iec_codesys_and_twincat_accept_the_declaration_and_a_run_names_it(dialect):
    assert _diags(HIERARCHICAL, dialect) == []
    compiled = compile_text(HIERARCHICAL, "t.st", dialect=dialect, use_cache=False)
    with pytest.raises(PLCStartError) as info:
        PLC(compiled)
    assert str(info.value) == (
        "t.st:3:3: %QX0.4.2: a hierarchical address (its place is the controller's I/O configuration); "
        "st's process image is OpenPLC's (%QX<byte>.<bit>, %QB/W/D/L<n>) and has no place for it"
    )


@pytest.mark.parametrize("dialect", AS_WRITTEN)
def test_st_run_says_why_it_cannot_bind_it_without_a_traceback(dialect, tmp_path):
    path = tmp_path / "h.st"
    path.write_text(HIERARCHICAL)
    r = CliRunner().invoke(main, ["run", "--dialect", dialect, "--virtual", "--scans", "1", str(path)])
    assert r.exit_code != 0 and "Traceback" not in r.output
    assert f"cannot start the PLC: {path}:3:3: %QX0.4.2: a hierarchical address" in r.output


@pytest.mark.parametrize("dialect", AS_WRITTEN)
def test_a_hierarchical_address_used_in_code_has_no_cell(dialect):
    src = "PROGRAM main\nVAR b : BOOL; END_VAR\nb := %IX0.1.2;\nEND_PROGRAM\n"
    assert _diags(src, dialect) == [
        (
            "error",
            "E004",
            3,
            6,
            "%IX0.1.2: a hierarchical address (its place is the controller's I/O configuration); "
            "st's process image is OpenPLC's (%IX<byte>.<bit>, %IB/W/D/L<n>) and has no place for it",
        )
    ]


@pytest.mark.parametrize("dialect", PRESETS)
def test_a_bit_beyond_7_stays_refused_however_it_is_written(dialect):
    src = "PROGRAM main\nVAR\n  c AT %QX0.9.1 : BOOL;\nEND_VAR\nEND_PROGRAM\n"
    got = [d for d in _diags(src, dialect) if d[0] == "error"]
    assert got == ([("error", "E004", 3, 3, "%QX0.9: bit 9 is not 0..7")] if dialect in OPENPLC_READING else [])


@pytest.mark.parametrize("dialect", AS_WRITTEN)
def test_a_hierarchical_address_is_still_as_wide_as_its_size(dialect):
    src = "PROGRAM main\nVAR\n  d AT %IB2.1 : WORD;\nEND_VAR\nEND_PROGRAM\n"
    assert _diags(src, dialect) == [("error", "E058", 3, 3, "'%IB2.1' is 8 bit(s) wide; it cannot hold a WORD")]


# ---------------------------------------------------------------------- the crash: a located E058

WORD_AT_BYTE = """PROGRAM main
VAR
  x AT %QB2 : WORD;
END_VAR
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", PRESETS)
def test_a_word_at_a_byte_address_is_a_located_error(dialect):
    assert _diags(WORD_AT_BYTE, dialect) == [("error", "E058", 3, 3, "'%QB2' is 8 bit(s) wide; it cannot hold a WORD")]


@pytest.mark.parametrize("dialect", PRESETS)
def test_st_check_reports_it_without_an_internal_error(dialect, tmp_path):
    path = tmp_path / "w.st"
    path.write_text(WORD_AT_BYTE)
    args = ["check", str(path)] + (["--dialect", dialect] if dialect else [])
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 1
    assert r.output == (
        f"{path}:3:3: error[E058]: '%QB2' is 8 bit(s) wide; it cannot hold a WORD\n"
        "      3 |   x AT %QB2 : WORD;\n"
        "        |   ^\n"
        "1 error(s), 0 warning(s)\n"
    )


def test_diagnostics_sort_even_when_one_lacks_its_location():
    sink = DiagnosticSink()
    sink.error(Code.LOCATED_TYPE, Span("b.st", 3, 3), "b")
    sink.add(Diagnostic(Code.LOCATED_TYPE, Severity.ERROR, None, "lost"))  # type: ignore[arg-type]
    sink.error(Code.LOCATED_TYPE, Span("a.st", 9, 1), "a")
    assert [(d.span.file, d.span.line, d.message) for d in sink.sorted()] == [
        ("<builtin>", 0, "lost"),
        ("a.st", 9, "a"),
        ("b.st", 3, "b"),
    ]


def test_a_bit_address_without_its_bit_is_read_and_forced_by_either_spelling():
    src = "PROGRAM main\nVAR o AT %QX1 : BOOL; i AT %IX2 : BOOL; END_VAR\no := i;\nEND_PROGRAM\n"
    plc = PLC(compile_text(src, use_cache=False))
    plc.force("%IX2", True)
    plc.scan(1)
    assert plc["%QX1"] is True and plc["%QX1.0"] is True and plc["main.o"] is True
    plc.unforce("%ix2.0")
    plc.force("%I2.0", False)
    plc.scan(1)
    assert plc["%qx1"] is False
