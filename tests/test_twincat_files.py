"""TwinCAT 3 project files read as they are (.TcPOU, .TcDUT, .TcGVL, .TcIO, .plcproj): the ST in
their CDATA sections compiles, and diagnostics name the TwinCAT file at the code's line and column."""

from __future__ import annotations

from pathlib import Path

from st import PLC
from st.api import compile_paths
from st.compiler.twincat import twincat_source

COUNTER_POU = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <POU Name="FB_Counter" Id="{00000000-0000-0000-0000-000000000001}" SpecialFunc="None">
    <Declaration><![CDATA[FUNCTION_BLOCK FB_Counter
VAR_INPUT
    bEnable : BOOL;
END_VAR
VAR
    nCount : INT;
END_VAR]]></Declaration>
    <Implementation>
      <ST><![CDATA[IF bEnable THEN
    nCount := nCount + nStep;
END_IF]]></ST>
    </Implementation>
    <Method Name="Reset" Id="{00000000-0000-0000-0000-000000000002}">
      <Declaration><![CDATA[METHOD Reset : BOOL
VAR_INPUT
    nTo : INT;
END_VAR]]></Declaration>
      <Implementation>
        <ST><![CDATA[nCount := nTo;
Reset := TRUE;]]></ST>
      </Implementation>
    </Method>
    <Property Name="Count" Id="{00000000-0000-0000-0000-000000000003}">
      <Declaration><![CDATA[PROPERTY Count : INT]]></Declaration>
      <Get Name="Get" Id="{00000000-0000-0000-0000-000000000004}">
        <Declaration><![CDATA[]]></Declaration>
        <Implementation>
          <ST><![CDATA[Count := nCount;]]></ST>
        </Implementation>
      </Get>
    </Property>
    <Action Name="Twice" Id="{00000000-0000-0000-0000-000000000005}">
      <Implementation>
        <ST><![CDATA[nCount := nCount * 2;]]></ST>
      </Implementation>
    </Action>
  </POU>
</TcPlcObject>"""

STEP_GVL = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <GVL Name="GVL_Main" Id="{00000000-0000-0000-0000-000000000006}">
    <Declaration><![CDATA[VAR_GLOBAL
    nStep : INT := 3;
END_VAR]]></Declaration>
  </GVL>
</TcPlcObject>"""

MODE_DUT = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <DUT Name="E_Mode" Id="{00000000-0000-0000-0000-000000000007}">
    <Declaration><![CDATA[TYPE E_Mode :
(
    Idle := 0,
    Run := 1
);
END_TYPE]]></Declaration>
  </DUT>
</TcPlcObject>"""

MAIN_POU = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <POU Name="MAIN" Id="{00000000-0000-0000-0000-000000000008}" SpecialFunc="None">
    <Declaration><![CDATA[PROGRAM MAIN
VAR
    fbCounter : FB_Counter;
    eMode : E_Mode := E_Mode.Run;
    nSeen : INT;
    bDone : BOOL;
END_VAR]]></Declaration>
    <Implementation>
      <ST><![CDATA[fbCounter(bEnable := eMode = E_Mode.Run);
nSeen := fbCounter.Count;
IF nSeen >= 9 THEN
    bDone := fbCounter.Reset(nTo := 1);
    fbCounter.Twice();
END_IF]]></ST>
    </Implementation>
  </POU>
</TcPlcObject>"""

PROJECT = """<?xml version="1.0" encoding="utf-8"?>
<Project DefaultTargets="Build" xmlns="http://schemas.microsoft.com/developer/msbuild/2003">
  <ItemGroup>
    <Compile Include="DUTs\\E_Mode.TcDUT"><SubType>Code</SubType></Compile>
    <Compile Include="GVLs\\GVL_Main.TcGVL"><SubType>Code</SubType></Compile>
    <Compile Include="POUs\\FB_Counter.TcPOU"><SubType>Code</SubType></Compile>
    <Compile Include="POUs\\MAIN.TcPOU"><SubType>Code</SubType></Compile>
  </ItemGroup>
</Project>"""


def _project(tmp_path: Path, counter: str = COUNTER_POU) -> Path:
    for rel, text in (
        ("DUTs/E_Mode.TcDUT", MODE_DUT),
        ("GVLs/GVL_Main.TcGVL", STEP_GVL),
        ("POUs/FB_Counter.TcPOU", counter),
        ("POUs/MAIN.TcPOU", MAIN_POU),
    ):
        f = tmp_path / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text, encoding="utf-8-sig")  # TwinCAT writes a byte order mark
    proj = tmp_path / "Plc.plcproj"
    proj.write_text(PROJECT)
    return proj


def test_the_st_of_a_tcpou_keeps_the_xml_lines_and_columns():
    text = twincat_source(COUNTER_POU)
    lines = text.split("\n")
    assert len(lines) == len(COUNTER_POU.split("\n"))
    assert lines[3] == " " * len("    <Declaration><![CDATA[") + "FUNCTION_BLOCK FB_Counter"
    assert lines[12] == "    nCount := nCount + nStep;"
    assert "END_FUNCTION_BLOCK" in lines[14]  # the </Implementation> line
    assert [ln.strip() for ln in lines if ln.strip().startswith(("END_", "GET", "ACTION"))] == [
        "END_VAR",
        "END_VAR",
        "END_IF",
        "END_FUNCTION_BLOCK",
        "END_VAR",
        "END_METHOD",
        "GET",
        "END_GET",
        "END_PROPERTY",
        "ACTION Twice :",
        "END_ACTION",
    ]


def test_a_plcproj_compiles_its_files_under_the_twincat_preset_and_runs(tmp_path):
    compiled = compile_paths([str(_project(tmp_path))], use_cache=False)
    assert [d.code for d in compiled.diagnostics if d.is_error] == []
    plc = PLC(compiled)
    plc.scan(3)  # 3, 6, 9: then Reset to 1 and Twice: 2
    assert (plc["MAIN.fbCounter.nCount"], plc["MAIN.nSeen"], plc["MAIN.bDone"]) == (2, 9, True)


def test_diagnostics_point_into_the_tcpou_at_the_line_and_column_of_the_code(tmp_path):
    broken = COUNTER_POU.replace("nCount := nCount + nStep;", "nCount := nCount + nStepp;")
    result = compile_paths([str(_project(tmp_path, broken))], use_cache=False, raise_on_error=False)
    errors = [(Path(d.span.file).name, d.span.line, d.span.col, d.message) for d in result.diagnostics if d.is_error]
    assert errors == [("FB_Counter.TcPOU", 13, 24, "undeclared identifier 'nStepp'")]


def test_a_named_global_variable_list_is_reached_by_its_name(tmp_path):
    qualified = COUNTER_POU.replace("nCount := nCount + nStep;", "nCount := nCount + GVL_Main.nStep;").replace(
        "nCount := nTo;", "nCount := nTo; GVL_Main.nStep := 1;"
    )
    compiled = compile_paths([str(_project(tmp_path, qualified))], use_cache=False)
    assert [d.code for d in compiled.diagnostics if d.is_error] == []
    plc = PLC(compiled)
    plc.scan(4)  # 3, 6, 9 → Reset to 1 (step 1 from now on), Twice: 2; then 2 + 1
    assert (plc["MAIN.fbCounter.nCount"], plc["nStep"]) == (3, 1)


def test_a_name_a_global_list_does_not_have_is_a_located_error(tmp_path):
    typo = COUNTER_POU.replace("nCount := nCount + nStep;", "nCount := nCount + GVL_Main.nStap;")
    result = compile_paths([str(_project(tmp_path, typo))], use_cache=False, raise_on_error=False)
    errors = [(Path(d.span.file).name, d.span.line, d.span.col, d.message) for d in result.diagnostics if d.is_error]
    assert errors == [("FB_Counter.TcPOU", 13, 33, "'nStap' is not a variable of GVL_Main")]
