"""TwinCAT projects as they are (issue 34): a .plcproj's <Compile> files found as Windows finds them
(names case-insensitive), a missing one reported at its <Compile> element, and the libraries it
references (<PlaceholderReference>, <LibraryReference>) found as library projects on a search path
(--lib, ST_LIBPATH, the API's lib_path=), transitively, each once (st/compiler/libpath.py)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from click.testing import CliRunner

from st import PLC
from st.api import compile_paths
from st.cli import main
from st.compiler import libpath
from st.compiler.twincat import find_ignoring_case

CORPORA = Path("/work/scratch/corpora")
TCUNIT = CORPORA / "tcunit-TcUnit"
VERIFIER = (
    TCUNIT / "TcUnit-Verifier/TcUnit-Verifier_TwinCAT/TcUnit-Verifier_TwinCAT/TcUnitVerifier/TcUnitVerifier.plcproj"
)


def _pou(name: str, decl: str, body: str = "") -> str:
    return f"""<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <POU Name="{name}" Id="{{00000000-0000-0000-0000-000000000001}}" SpecialFunc="None">
    <Declaration><![CDATA[{decl}]]></Declaration>
    <Implementation>
      <ST><![CDATA[{body}]]></ST>
    </Implementation>
  </POU>
</TcPlcObject>
"""


def _gvl(name: str, decl: str) -> str:
    return f"""<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <GVL Name="{name}" Id="{{00000000-0000-0000-0000-000000000002}}">
    <Declaration><![CDATA[{decl}]]></Declaration>
  </GVL>
</TcPlcObject>
"""


def _reference(name: str, vendor: str = "Me", namespace: str | None = None) -> str:
    ns = f"\n      <Namespace>{namespace}</Namespace>" if namespace else ""
    return (
        f'    <PlaceholderReference Include="{name}">\n'
        f"      <DefaultResolution>{name}, * ({vendor})</DefaultResolution>{ns}\n"
        "    </PlaceholderReference>\n"
    )


def _plcproj(name: str, includes: list[str], references: str = "", extra: str = "") -> str:
    compiles = "".join(
        f'    <Compile Include="{i}">\n      <SubType>Code</SubType>\n    </Compile>\n' for i in includes
    )
    return f"""<?xml version="1.0" encoding="utf-8"?>
<Project DefaultTargets="Build" xmlns="http://schemas.microsoft.com/developer/msbuild/2003">
  <PropertyGroup>
    <Name>{name}</Name>{extra}
  </PropertyGroup>
  <ItemGroup>
{compiles}  </ItemGroup>
  <ItemGroup>
{references}  </ItemGroup>
</Project>
"""


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)


def _library(root: Path, name: str, fb: str, body: str, references: str = "", extra: str = "") -> Path:
    """A library project `name` with one block `fb` (an INT input `a`, an INT output `y`)."""
    decl = f"FUNCTION_BLOCK {fb}\nVAR_INPUT\n    a : INT;\nEND_VAR\nVAR_OUTPUT\n    y : INT;\nEND_VAR"
    _write(root, {f"{name}/POUs/{fb}.TcPOU": _pou(fb, decl, body)})
    proj = root / name / f"{name}.plcproj"
    proj.write_text(_plcproj(name, [f"POUs\\{fb}.TcPOU"], references, extra))
    return proj


def _app(root: Path, references: str, decl_vars: str, body: str, name: str = "App") -> Path:
    decl = f"PROGRAM MAIN\nVAR\n{decl_vars}\n    r : INT;\nEND_VAR"
    _write(root, {"POUs/MAIN.TcPOU": _pou("MAIN", decl, body)})
    proj = root / f"{name}.plcproj"
    proj.write_text(_plcproj(name, ["POUs\\MAIN.TcPOU"], references))
    return proj


def _errors(result) -> list[tuple[str, str]]:
    return [(str(d.code), d.message) for d in result.diagnostics if d.is_error]


def _w014(result) -> list[tuple[str, int, int, str]]:
    return [(d.span.file, d.span.line, d.span.col, d.message) for d in result.diagnostics if d.code == "W014"]


@pytest.fixture(autouse=True)
def _no_libpath(monkeypatch):
    monkeypatch.delenv(libpath.ENV, raising=False)


# ---------------------------------------------------------------------- <Compile> files, as Windows finds them


def test_a_compile_include_is_found_whatever_the_case_of_its_names(tmp_path):
    _write(
        tmp_path,
        {
            "CONSTANTS.TcGVL": _gvl("Constants", "VAR_GLOBAL CONSTANT\n    nStep : INT := 3;\nEND_VAR"),
            "pous/Main.TcPOU": _pou("MAIN", "PROGRAM MAIN\nVAR\n    n : INT;\nEND_VAR", "n := n + nStep;"),
        },
    )
    proj = tmp_path / "Plc.plcproj"
    proj.write_text(_plcproj("Plc", ["Constants.TcGVL", "POUs\\MAIN.TcPOU"]))
    assert find_ignoring_case(str(tmp_path), "POUs/MAIN.TcPOU") == str(tmp_path / "pous" / "Main.TcPOU")
    assert find_ignoring_case(str(tmp_path), "POUs/Other.TcPOU") is None
    plc = PLC.from_files(str(proj), dialect="twincat", use_cache=False)
    plc.scan(2)
    assert plc["MAIN.n"] == 6
    assert plc.compiled.diagnostics == []


def test_a_missing_compile_file_is_e000_at_its_compile_element(tmp_path):
    _write(tmp_path, {"POUs/MAIN.TcPOU": _pou("MAIN", "PROGRAM MAIN\nVAR\n    n : INT;\nEND_VAR", "n := 1;")})
    proj = tmp_path / "Plc.plcproj"
    proj.write_text(_plcproj("Plc", ["POUs\\MAIN.TcPOU", "GVLs\\Gone.TcGVL"]))
    result = compile_paths([str(proj)], dialect="twincat", use_cache=False, raise_on_error=False)
    assert [(d.span.file, d.span.line, d.span.col, str(d.code), d.message) for d in result.diagnostics] == [
        (
            str(proj),
            10,
            5,
            "E000",
            "cannot read file 'GVLs\\Gone.TcGVL' of this project: no such file, nor one whose name differs only in case",
        )
    ]
    shown = result.diagnostics[0].render(result.sources).splitlines()
    assert shown[1:3] == ['     10 | //  <Compile Include="GVLs\\Gone.TcGVL">', "        |     ^"]


# ---------------------------------------------------------------------- libraries on the search path

ADD = "y := a + 1;"
USES_LIB = "    fb : MyLib.FB_Add;"
CALL = "fb(a := 41); r := fb.y;"


def _lib_and_app(tmp_path: Path) -> tuple[Path, Path]:
    libs = tmp_path / "libs"
    lib = _library(libs, "MyLib", "FB_Add", ADD)
    app = _app(tmp_path / "app", _reference("MyLib", namespace="MyLib"), USES_LIB, CALL)
    return lib, app


def test_a_referenced_library_is_found_in_a_lib_folder(tmp_path):
    _lib, app = _lib_and_app(tmp_path)
    r = CliRunner().invoke(main, ["check", "--dialect", "twincat", str(app), "--lib", str(tmp_path / "libs")])
    assert (r.exit_code, r.output) == (0, "ok: 1 file(s), 2 POU(s)\n")  # MAIN and the library's FB_Add
    plc = PLC.from_files(str(app), dialect="twincat", lib_path=[tmp_path / "libs"], use_cache=False)
    plc.scan()
    assert plc["MAIN.r"] == 42


def test_a_referenced_library_is_found_through_st_libpath(tmp_path, monkeypatch):
    lib, app = _lib_and_app(tmp_path)
    monkeypatch.setenv(libpath.ENV, os.pathsep.join([str(tmp_path / "nothing-here"), str(lib)]))
    result = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False)
    assert _errors(result) == [] and _w014(result) == []
    r = CliRunner().invoke(main, ["check", "--dialect", "twincat", str(app)])
    assert (r.exit_code, r.output) == (0, "ok: 1 file(s), 2 POU(s)\n")  # MAIN and the library's FB_Add


def test_a_referenced_library_is_found_through_the_api(tmp_path):
    lib, app = _lib_and_app(tmp_path)
    for where in ([lib], [str(tmp_path / "libs")], [tmp_path]):
        result = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False, lib_path=where)
        assert _errors(result) == [] and _w014(result) == [], where
        assert sorted(Path(s).name for s in result.sources if s.endswith((".TcPOU", ".plcproj"))) == [
            "App.plcproj",
            "FB_Add.TcPOU",
            "MAIN.TcPOU",
            "MyLib.plcproj",
        ]


def test_a_library_named_on_the_command_line_is_not_searched_for_again(tmp_path):
    lib, app = _lib_and_app(tmp_path)
    result = compile_paths([app, lib], dialect="twincat", use_cache=False, raise_on_error=False, lib_path=[tmp_path])
    assert _errors(result) == [] and _w014(result) == []


def test_libraries_are_followed_transitively_each_once(tmp_path):
    libs = tmp_path / "libs"
    _library(libs, "LibB", "FB_B", "y := a * 2;")
    _library(
        libs,
        "LibA",
        "FB_A",
        "inner(a := a); y := inner.y + 1;",
        _reference("LibB"),
    )
    # FB_A needs an instance of LibB's block: declared in its VAR
    pou = libs / "LibA" / "POUs" / "FB_A.TcPOU"
    pou.write_text(pou.read_text().replace("VAR_OUTPUT", "VAR\n    inner : LibB.FB_B;\nEND_VAR\nVAR_OUTPUT"))
    app = _app(
        tmp_path / "app",
        _reference("LibA") + _reference("LibB"),
        "    fa : LibA.FB_A;\n    fb : FB_B;",
        "fa(a := 10); fb(a := 1); r := fa.y + fb.y;",
    )
    result = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False, lib_path=[libs])
    assert _errors(result) == [] and _w014(result) == []
    assert sorted(Path(s).name for s in result.sources if s.endswith(".plcproj")) == [
        "App.plcproj",
        "LibA.plcproj",
        "LibB.plcproj",
    ]
    plc = PLC(result)
    plc.scan()
    assert plc["MAIN.r"] == 23  # (10 * 2 + 1) + 1 * 2


def test_a_library_found_nowhere_is_a_located_warning_and_its_use_stays_an_error(tmp_path):
    _lib, app = _lib_and_app(tmp_path)
    empty = tmp_path / "empty"
    empty.mkdir()
    result = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False, lib_path=[empty])
    assert _w014(result) == [
        (
            str(app),
            12,
            5,
            f"library 'MyLib' not found: no project named here and no library project in the search path is "
            f"named so (searched: {empty})",
        )
    ]
    assert ("E012", "'MyLib.FB_Add': no library 'MyLib' is available") in [
        (c, m.split(" (namespaces here")[0]) for c, m in _errors(result)
    ]
    shown = next(d for d in result.diagnostics if d.code == "W014").render(result.sources).splitlines()
    assert shown[1] == '     12 | //  <PlaceholderReference Include="MyLib">'
    bare = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False)
    assert _w014(bare)[0][3].endswith("(searched: nothing (no --lib given, ST_LIBPATH unset))")


def test_system_libraries_are_not_searched_for(tmp_path):
    refs = (
        _reference("Tc2_Standard", "Beckhoff Automation GmbH", "Tc2_Standard")
        + _reference("Tc3_Module", "Beckhoff Automation GmbH")
        + _reference("SysFile", "System", "SysFile")
        + '    <LibraryReference Include="Base Interfaces,newest,System">\n'
        "      <Namespace>IBaseLibrary</Namespace>\n    </LibraryReference>\n"
        + _reference("Tc2_Utilities", "Somebody")  # a namespace of st's vendor library
    )
    app = _app(tmp_path, refs, "    t : Tc2_Standard.TON;", "t(IN := TRUE, PT := T#1S); r := 1;")
    result = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False)
    assert _errors(result) == [] and _w014(result) == []


def test_a_library_is_known_by_its_title_default_namespace_and_reference_namespace(tmp_path):
    libs = tmp_path / "libs"
    # TcLog's layout: <Name>TcLog</Name>, <DefaultNamespace>TcLogLib</DefaultNamespace>
    _library(
        libs,
        "LogProj",
        "FB_Log",
        ADD,
        extra="\n    <Title>TcLog</Title>\n    <DefaultNamespace>TcLogLib</DefaultNamespace>",
    )
    app = _app(
        tmp_path / "app",
        _reference("TcLog", namespace="Logging"),
        "    a : TcLog.FB_Log;\n    b : TcLogLib.FB_Log;\n    c : Logging.FB_Log;\n    d : LogProj.FB_Log;",
        "a(a := 1); b(a := 2); c(a := 3); d(a := 4); r := a.y + b.y + c.y + d.y;",
    )
    result = compile_paths([app], dialect="twincat", use_cache=False, raise_on_error=False, lib_path=[libs])
    assert _errors(result) == [] and _w014(result) == []
    plc = PLC(result)
    plc.scan()
    assert plc["MAIN.r"] == 14


def test_the_project_s_own_namespace_qualifies_its_own_names(tmp_path):
    _write(
        tmp_path,
        {"POUs/FB_Own.TcPOU": _pou("FB_Own", "FUNCTION_BLOCK FB_Own\nVAR_OUTPUT\n    y : INT;\nEND_VAR", "y := 7;")},
    )
    app = _app(tmp_path, "", "    o : App.FB_Own;", "o(); r := o.y;")
    app.write_text(_plcproj("App", ["POUs\\MAIN.TcPOU", "POUs\\FB_Own.TcPOU"]))
    plc = PLC.from_files(str(app), dialect="twincat", use_cache=False)
    plc.scan()
    assert plc["MAIN.r"] == 7


def test_a_library_project_is_read_once_per_process_while_unchanged(tmp_path, monkeypatch):
    lib, app = _lib_and_app(tmp_path)
    first = libpath.read_project(str(lib))
    assert first is not None and first.names == frozenset({"mylib"})
    assert libpath.read_project(str(lib)) is first
    os.utime(lib, ns=(1, 1))  # changed: read again
    again = libpath.read_project(str(lib))
    assert again is not first and again == first
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path / "cache"))
    runs = [compile_paths([app], dialect="twincat", lib_path=[tmp_path / "libs"]) for _ in range(2)]
    assert [r.from_cache for r in runs] == [False, True]


def test_references_as_a_plcproj_writes_them():
    xml = (
        "<Project>\n  <ItemGroup>\n"
        + _reference("TcUnit", "www.tcunit.org", "TcUnit")
        + '    <LibraryReference Include="Base Interfaces,newest,System">\n'
        "      <Namespace>IBaseLibrary</Namespace>\n    </LibraryReference>\n"
        '    <LibraryReference Include="TcUnit, * (www.tcunit.org)" />\n'
        "  </ItemGroup>\n</Project>\n"
    )
    refs = libpath.references(xml)
    assert [(r.name, r.vendor, r.namespace, r.line, r.col) for r in refs] == [
        ("TcUnit", "www.tcunit.org", "TcUnit", 3, 5),
        ("Base Interfaces", "System", "IBaseLibrary", 7, 5),
        ("TcUnit", "www.tcunit.org", "", 10, 5),
    ]
    assert [libpath.is_system(r) for r in refs] == [False, True, False]


# ---------------------------------------------------------------------- the real TcUnit verifier


@pytest.mark.slow
@pytest.mark.skipif(not VERIFIER.is_file(), reason=f"the TcUnit repository is not at {TCUNIT}")
def test_tcunit_s_verifier_checks_with_tcunit_from_the_lib_path():
    r = CliRunner().invoke(main, ["check", "--dialect", "twincat", str(VERIFIER), "--lib", str(TCUNIT / "TcUnit")])
    errors = [line for line in r.output.splitlines() if ": error[" in line]
    assert (r.exit_code, errors) == (0, [])
    assert "W014" not in r.output and r.output.endswith("ok: 1 file(s), 82 POU(s)\n")
