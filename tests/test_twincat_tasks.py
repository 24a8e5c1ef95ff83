"""A TwinCAT project's tasks (.TcTTO) run as TwinCAT runs them (issue 34): only the programs a task
calls, at its cycle time, each program the instance its name stands for."""

from __future__ import annotations

from pathlib import Path

from st import PLC
from st.api import compile_paths
from st.compiler.twincat_tasks import TwinCATTask, configuration, tasks

TTO = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <Task Name="PlcTask" Id="{7e5aa001-f7ee-4f61-adc3-64abda31d2bd}">
    <!--CycleTime in micro seconds.-->
    <CycleTime>{cycle}</CycleTime>
    <Priority>20</Priority>
    <PouCall>
      <Name>MAIN</Name>
    </PouCall>
    <PouCall>
      <Name>Logger</Name>
    </PouCall>
    <TaskFBGuid>{5ce6756a-f77c-4a46-85ec-c1eb74b19457}</TaskFBGuid>
  </Task>
</TcPlcObject>
"""


def test_a_tcTTO_is_its_task_and_the_programs_it_calls():
    assert tasks(TTO.replace("{cycle}", "10000")) == [TwinCATTask("PlcTask", 10000, 20, ("MAIN", "Logger"))]
    assert configuration("My Project", tasks(TTO.replace("{cycle}", "2500"))) == (
        "CONFIGURATION My_Project\n  RESOURCE PLC ON PLC\n"
        "    TASK PlcTask (INTERVAL := T#2500us, PRIORITY := 20);\n"
        "    PROGRAM MAIN WITH PlcTask : MAIN;\n"
        "    PROGRAM Logger WITH PlcTask : Logger;\n"
        "  END_RESOURCE\nEND_CONFIGURATION\n"
    )
    assert configuration("P", [TwinCATTask("Idle", 0, 1, ())]) == ""  # no task calls a program


PLCPROJ = """<?xml version="1.0" encoding="utf-8"?>
<Project DefaultTargets="Build" xmlns="http://schemas.microsoft.com/developer/msbuild/2003">
  <PropertyGroup>
    <Name>Cell</Name>
  </PropertyGroup>
  <ItemGroup>
    <Compile Include="POUs\\MAIN.TcPOU">
      <SubType>Code</SubType>
    </Compile>
    <Compile Include="POUs\\Unused.TcPOU">
      <SubType>Code</SubType>
    </Compile>
    <Compile Include="PlcTask.TcTTO">
      <SubType>Code</SubType>
    </Compile>
  </ItemGroup>
</Project>
"""


def _pou(name: str, decl: str, body: str) -> str:
    return (
        '<?xml version="1.0" encoding="utf-8"?>\n<TcPlcObject Version="1.1.0.1">\n'
        f'  <POU Name="{name}" Id="{{00000000-0000-0000-0000-000000000001}}" SpecialFunc="None">\n'
        f"    <Declaration><![CDATA[{decl}]]></Declaration>\n"
        f"    <Implementation>\n      <ST><![CDATA[{body}]]></ST>\n    </Implementation>\n"
        "  </POU>\n</TcPlcObject>\n"
    )


def test_a_project_runs_the_programs_its_task_calls_at_its_cycle(tmp_path: Path):
    (tmp_path / "POUs").mkdir()
    (tmp_path / "Cell.plcproj").write_text(PLCPROJ)
    only_main = TTO.replace("{cycle}", "2500").replace("<PouCall>\n      <Name>Logger</Name>\n    </PouCall>\n", "")
    (tmp_path / "PlcTask.TcTTO").write_text(only_main)
    (tmp_path / "POUs" / "MAIN.TcPOU").write_text(
        _pou("MAIN", "PROGRAM MAIN\nVAR\n  n : DINT;\n  t : TIME;\nEND_VAR\n", "n := n + 1;\nt := TIME();")
    )
    (tmp_path / "POUs" / "Unused.TcPOU").write_text(
        _pou("Unused", "PROGRAM Unused\nVAR\n  n : DINT;\nEND_VAR\n", "n := n + 1;")
    )
    compiled = compile_paths([str(tmp_path / "Cell.plcproj")], dialect="twincat", use_cache=False)
    plc = PLC(compiled)
    plc.scan(4)
    assert plc["MAIN.n"] == 4 and sorted(plc.instances) == ["main"]  # Unused is in no task: never run
    assert [t.name for t in plc.tasks] == ["PlcTask"] and plc.tasks[0].interval == 2_500_000
