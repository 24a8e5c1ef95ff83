"""PLCopen XML projects (plc.xml of the OpenPLC Editor and Beremiz, CODESYS exports) read as ST:
declarations, configurations, ST and SFC bodies, diagnostics at the XML's lines and columns, the
preset of the tool that wrote the file. Every project here is small XML written for the test."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from st import PLC
from st.api import compile_paths
from st.compiler.driver import load_files
from st.compiler.options import CompileOptions
from st.compiler.plcopen_xml import plcopen_source
from st.diagnostics import CompileError

HEAD = """<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <fileHeader companyName="{company}" productName="{product}" productVersion="1"/>
  <contentHeader name="test"/>
"""


def project(pous: str, types: str = "", configs: str = "", company: str = "Beremiz", product: str = "Beremiz") -> str:
    return (
        HEAD.format(company=company, product=product)
        + f"  <types>\n    <dataTypes>\n{types}    </dataTypes>\n    <pous>\n{pous}    </pous>\n  </types>\n"
        + f"  <instances>\n    <configurations>\n{configs}    </configurations>\n  </instances>\n</project>\n"
    )


def write(tmp_path, xml: str, name: str = "plc.xml") -> str:
    path = tmp_path / name
    path.write_text(xml)
    return str(path)


def errors_of(path: str, **kw) -> list[tuple[str, int, int]]:
    result = compile_paths([path], raise_on_error=False, use_cache=False, **kw)
    return [(d.code, d.span.line, d.span.col) for d in result.diagnostics if d.is_error and d.span.file == path]


TYPES = """\
      <dataType name="Color">
        <baseType><enum><values><value name="Red"/><value name="Green"/><value name="Blue"/></values></enum></baseType>
        <initialValue><simpleValue value="Green"/></initialValue>
      </dataType>
      <dataType name="Point">
        <baseType>
          <struct>
            <variable name="x"><type><INT/></type><initialValue><simpleValue value="3"/></initialValue></variable>
            <variable name="y"><type><REAL/></type></variable>
          </struct>
        </baseType>
      </dataType>
      <dataType name="Row">
        <baseType><array><dimension lower="1" upper="4"/><baseType><DINT/></baseType></array></baseType>
        <initialValue><arrayValue><value repetitionValue="3"><simpleValue value="7"/></value><value><simpleValue value="8"/></value></arrayValue></initialValue>
      </dataType>
      <dataType name="Percent">
        <baseType><subrangeSigned><range lower="0" upper="100"/><baseType><INT/></baseType></subrangeSigned></baseType>
        <initialValue><simpleValue value="50"/></initialValue>
      </dataType>
      <dataType name="Name">
        <baseType><string length="8"/></baseType>
        <initialValue><simpleValue value="abc"/></initialValue>
      </dataType>
      <dataType name="Speed">
        <baseType><derived name="Percent"/></baseType>
      </dataType>
"""

POUS = """\
      <pou name="Acc" pouType="functionBlock">
        <interface>
          <inputVars>
            <variable name="inc"><type><INT/></type><initialValue><simpleValue value="1"/></initialValue></variable>
          </inputVars>
          <outputVars>
            <variable name="total"><type><DINT/></type></variable>
          </outputVars>
          <inOutVars>
            <variable name="log"><type><DINT/></type></variable>
          </inOutVars>
          <localVars constant="true">
            <variable name="LIMIT"><type><DINT/></type><initialValue><simpleValue value="1000"/></initialValue></variable>
          </localVars>
          <tempVars>
            <variable name="t"><type><DINT/></type></variable>
          </tempVars>
          <externalVars>
            <variable name="g_calls"><type><INT/></type></variable>
          </externalVars>
        </interface>
        <body>
          <ST>
            <xhtml:p><![CDATA[t := total + inc;
IF t <= LIMIT THEN total := t; END_IF;
log := log + 1;
g_calls := g_calls + G_K;]]></xhtml:p>
          </ST>
        </body>
        <documentation><xhtml:p><![CDATA[not code: IF IF IF]]></xhtml:p></documentation>
      </pou>
      <pou name="Twice" pouType="function">
        <interface>
          <returnType><INT/></returnType>
          <inputVars>
            <variable name="v"><type><INT/></type></variable>
          </inputVars>
        </interface>
        <body>
          <ST><xhtml:p><![CDATA[Twice := v * 2;]]></xhtml:p></ST>
        </body>
      </pou>
      <pou name="Main" pouType="program">
        <interface>
          <localVars retain="true">
            <variable name="kept"><type><INT/></type></variable>
          </localVars>
          <localVars>
            <variable name="acc"><type><derived name="Acc"/></type></variable>
            <variable name="n"><type><DINT/></type></variable>
            <variable name="c"><type><derived name="Color"/></type></variable>
            <variable name="p">
              <type><derived name="Point"/></type>
              <initialValue><structValue><value member="y"><simpleValue value="1.5"/></value></structValue></initialValue>
              <addData><data name="x" handleUnknown="discard"><anything/></data></addData>
            </variable>
            <variable name="r"><type><derived name="Row"/></type></variable>
            <variable name="pc"><type><derived name="Speed"/></type></variable>
            <variable name="s"><type><derived name="Name"/></type></variable>
            <variable name="w"><type><string length="4"/></type><initialValue><simpleValue value="it's"/></initialValue></variable>
            <variable name="a">
              <type><array><dimension lower="0" upper="2"/><baseType><INT/></baseType></array></type>
              <initialValue><arrayValue><value repetitionValue="2"><simpleValue value="5"/></value><value><simpleValue value="6"/></value></arrayValue></initialValue>
            </variable>
            <variable name="out" address="%QW0"><type><INT/></type></variable>
          </localVars>
        </interface>
        <body>
          <ST>
            <xhtml:p><![CDATA[acc(inc := 2, log := n);
out := Twice(a[2]);
kept := kept + 1;]]></xhtml:p>
          </ST>
        </body>
      </pou>
"""

CONFIGS = """\
      <configuration name="Cfg">
        <resource name="Res">
          <task name="fast" interval="T#10ms" priority="1">
            <pouInstance name="inst" typeName="Main"/>
          </task>
          <globalVars>
            <variable name="g_calls"><type><INT/></type></variable>
          </globalVars>
        </resource>
        <globalVars constant="true">
          <variable name="G_K"><type><INT/></type><initialValue><simpleValue value="4"/></initialValue></variable>
        </globalVars>
      </configuration>
"""

FULL = project(POUS, TYPES, CONFIGS)


def _lines(xml: str) -> list[str]:
    """The laid-out ST's non-blank lines, spaces squeezed (the XML's line numbers and columns are
    tested below)."""
    text, diags = plcopen_source(xml, "plc.xml")
    assert diags == []
    assert text.count("\n") == xml.count("\n")  # the same number of lines as the XML
    return [" ".join(line.split()) for line in text.split("\n") if line.strip()]


def line_of(xml: str, needle: str) -> int:
    """The 1-based line of the first `needle` in `xml`."""
    return xml[: xml.index(needle)].count("\n") + 1


def test_every_kind_of_declaration_is_written_as_st_on_its_elements_line():
    assert _lines(FULL) == [
        "{dialect 'openplc'}",
        "TYPE",
        "Color : (Red, Green, Blue) := Green;",
        "Point : STRUCT",
        "x : INT := 3;",
        "y : REAL;",
        "END_STRUCT;",
        "Row : ARRAY [1..4] OF DINT := [3(7), 8];",
        "Percent : INT (0..100) := 50;",
        "Name : STRING[8] := 'abc';",
        "Speed : Percent;",
        "END_TYPE",
        "FUNCTION_BLOCK Acc",
        "VAR_INPUT",
        "inc : INT := 1;",
        "END_VAR",
        "VAR_OUTPUT",
        "total : DINT;",
        "END_VAR",
        "VAR_IN_OUT",
        "log : DINT;",
        "END_VAR",
        "VAR CONSTANT",
        "LIMIT : DINT := 1000;",
        "END_VAR",
        "VAR_TEMP",
        "t : DINT;",
        "END_VAR",
        "VAR_EXTERNAL",
        "g_calls : INT;",
        "END_VAR",
        "t := total + inc;",
        "IF t <= LIMIT THEN total := t; END_IF;",
        "log := log + 1;",
        "g_calls := g_calls + G_K;",
        "END_FUNCTION_BLOCK",
        "FUNCTION Twice",
        ": INT",
        "VAR_INPUT",
        "v : INT;",
        "END_VAR",
        "Twice := v * 2;",
        "END_FUNCTION",
        "PROGRAM Main",
        "VAR RETAIN",
        "kept : INT;",
        "END_VAR",
        "VAR",
        "acc : Acc;",
        "n : DINT;",
        "c : Color;",
        "p : Point := (y := 1.5);",
        "r : Row;",
        "pc : Speed;",
        "s : Name;",
        "w : STRING[4] := 'it$'s';",
        "a : ARRAY [0..2] OF INT := [2(5), 6];",
        "out AT %QW0 : INT;",
        "END_VAR",
        "acc(inc := 2, log := n);",
        "out := Twice(a[2]);",
        "kept := kept + 1;",
        "END_PROGRAM",
        "CONFIGURATION Cfg",
        "RESOURCE Res ON PLC",
        "TASK fast(INTERVAL := T#10ms, PRIORITY := 1);",
        "PROGRAM inst WITH fast : Main;",
        "VAR_GLOBAL",
        "g_calls : INT;",
        "END_VAR",
        "END_RESOURCE",
        "VAR_GLOBAL CONSTANT",
        "G_K : INT := 4;",
        "END_VAR",
        "END_CONFIGURATION",
    ]


def test_a_project_with_every_kind_of_declaration_runs_with_exact_values(tmp_path):
    plc = PLC.from_files(write(tmp_path, FULL), use_cache=False)
    plc.scan(3)
    assert plc["inst.acc.total"] == 6
    assert plc["inst.n"] == 3
    assert plc["g_calls"] == 12
    assert plc["inst.out"] == 12
    assert plc["inst.kept"] == 3
    assert plc["inst.p.x"] == 3
    assert plc["inst.p.y"] == 1.5
    assert plc["inst.r"] == [7, 7, 7, 8]
    assert plc["inst.pc"] == 50
    assert plc["inst.s"] == "abc"
    assert plc["inst.w"] == "it's"
    assert plc["inst.a"] == [5, 5, 6]
    assert plc["%QW0"] == 12
    assert (plc.tasks[0].name, plc.tasks[0].interval) == ("fast", 10_000_000)


# ---------------------------------------------------------------- SFC

SFC_POU = """\
      <pou name="Seq" pouType="program">
        <interface>
          <localVars>
            <variable name="go"><type><BOOL/></type></variable>
            <variable name="flag"><type><BOOL/></type></variable>
            <variable name="late"><type><BOOL/></type></variable>
            <variable name="ni"><type><INT/></type></variable>
            <variable name="na"><type><INT/></type></variable>
            <variable name="nb"><type><INT/></type></variable>
            <variable name="nc"><type><INT/></type></variable>
            <variable name="nd"><type><INT/></type></variable>
          </localVars>
        </interface>
        <actions>
          <action name="CountA">
            <body><ST><xhtml:p><![CDATA[na := na + 1;]]></xhtml:p></ST></body>
          </action>
        </actions>
        <transitions>
          <transition name="Stop">
            <body><ST><xhtml:p><![CDATA[:= nc >= 2 AND ni >= 2;]]></xhtml:p></ST></body>
          </transition>
        </transitions>
        <body>
          <SFC>
            <step localId="1" name="Init" initialStep="true"/>
            <actionBlock localId="2">
              <connectionPointIn><connection refLocalId="1"/></connectionPointIn>
              <action localId="0"><inline><ST><xhtml:p><![CDATA[go := TRUE; ni := ni + 1;]]></xhtml:p></ST></inline></action>
            </actionBlock>
            <transition localId="3">
              <connectionPointIn><connection refLocalId="1"/></connectionPointIn>
              <condition><inline name=""><ST><xhtml:p><![CDATA[go]]></xhtml:p></ST></inline></condition>
            </transition>
            <simultaneousDivergence localId="4">
              <connectionPointIn><connection refLocalId="3"/></connectionPointIn>
            </simultaneousDivergence>
            <step localId="5" name="A">
              <connectionPointIn><connection refLocalId="4"/></connectionPointIn>
            </step>
            <actionBlock localId="6">
              <connectionPointIn><connection refLocalId="5"/></connectionPointIn>
              <action localId="0" qualifier="N"><reference name="CountA"/></action>
            </actionBlock>
            <step localId="7" name="B">
              <connectionPointIn><connection refLocalId="4"/></connectionPointIn>
            </step>
            <actionBlock localId="8">
              <connectionPointIn><connection refLocalId="7"/></connectionPointIn>
              <action localId="0"><inline><ST><xhtml:p><![CDATA[nb := nb + 1;]]></xhtml:p></ST></inline></action>
            </actionBlock>
            <transition localId="9">
              <connectionPointIn><connection refLocalId="5"/></connectionPointIn>
              <condition><inline name=""><ST><xhtml:p><![CDATA[na >= 2]]></xhtml:p></ST></inline></condition>
            </transition>
            <step localId="10" name="A2">
              <connectionPointIn><connection refLocalId="9"/></connectionPointIn>
            </step>
            <transition localId="11">
              <connectionPointIn><connection refLocalId="7"/></connectionPointIn>
              <condition><inline name=""><ST><xhtml:p><![CDATA[nb >= 3;]]></xhtml:p></ST></inline></condition>
            </transition>
            <step localId="12" name="B2">
              <connectionPointIn><connection refLocalId="11"/></connectionPointIn>
            </step>
            <simultaneousConvergence localId="13">
              <connectionPointIn><connection refLocalId="10"/></connectionPointIn>
              <connectionPointIn><connection refLocalId="12"/></connectionPointIn>
            </simultaneousConvergence>
            <transition localId="14">
              <connectionPointIn><connection refLocalId="13"/></connectionPointIn>
              <condition><inline name=""><ST><xhtml:p><![CDATA[TRUE]]></xhtml:p></ST></inline></condition>
            </transition>
            <step localId="15" name="C">
              <connectionPointIn><connection refLocalId="14"/></connectionPointIn>
            </step>
            <actionBlock localId="16">
              <connectionPointIn><connection refLocalId="15"/></connectionPointIn>
              <action localId="0"><inline><ST><xhtml:p><![CDATA[nc := nc + 1;]]></xhtml:p></ST></inline></action>
              <action localId="0" qualifier="S"><reference name="flag"/></action>
            </actionBlock>
            <selectionDivergence localId="17">
              <connectionPointIn><connection refLocalId="15"/></connectionPointIn>
            </selectionDivergence>
            <transition localId="18">
              <connectionPointIn><connection refLocalId="17"/></connectionPointIn>
              <condition><inline name=""><ST><xhtml:p><![CDATA[nc >= 2 AND ni < 2]]></xhtml:p></ST></inline></condition>
            </transition>
            <jumpStep localId="19" targetName="Init">
              <connectionPointIn><connection refLocalId="18"/></connectionPointIn>
            </jumpStep>
            <transition localId="20">
              <connectionPointIn><connection refLocalId="17"/></connectionPointIn>
              <condition><reference name="Stop"/></condition>
            </transition>
            <transition localId="24">
              <connectionPointIn><connection refLocalId="17"/></connectionPointIn>
              <condition><inline name=""><ST><xhtml:p><![CDATA[FALSE]]></xhtml:p></ST></inline></condition>
            </transition>
            <selectionConvergence localId="23">
              <connectionPointIn><connection refLocalId="20"/></connectionPointIn>
              <connectionPointIn><connection refLocalId="24"/></connectionPointIn>
            </selectionConvergence>
            <step localId="21" name="Done">
              <connectionPointIn><connection refLocalId="23"/></connectionPointIn>
            </step>
            <actionBlock localId="22">
              <connectionPointIn><connection refLocalId="21"/></connectionPointIn>
              <action localId="0" qualifier="R"><reference name="flag"/></action>
              <action localId="0" qualifier="D" duration="T#20ms"><reference name="late"/></action>
              <action localId="0"><inline><ST><xhtml:p><![CDATA[nd := nd + 1;]]></xhtml:p></ST></inline></action>
            </actionBlock>
          </SFC>
        </body>
      </pou>
"""

SFC_CONFIG = """\
      <configuration name="Cfg">
        <resource name="Res">
          <task name="t" interval="PT0.01S" priority="0">
            <pouInstance name="seq" typeName="Seq"/>
          </task>
        </resource>
      </configuration>
"""


def test_an_sfc_network_is_written_as_textual_sfc():
    lines = _lines(project(SFC_POU, configs=SFC_CONFIG))
    sfc = lines[lines.index("ACTION CountA:") : lines.index("END_PROGRAM")]
    assert sfc == [
        "ACTION CountA:",
        "na := na + 1;",
        "END_ACTION",
        "TRANSITION Stop FROM C TO Done",
        ":= nc >= 2 AND ni >= 2;",
        "END_TRANSITION",
        "INITIAL_STEP Init: _inline_2_1(N); END_STEP",
        "ACTION _inline_2_1: go := TRUE; ni := ni + 1; END_ACTION",
        "TRANSITION FROM Init TO (A, B) :=",
        "go",
        "; END_TRANSITION",
        "STEP A: CountA(N); END_STEP",
        "STEP B: _inline_8_1(N); END_STEP",
        "ACTION _inline_8_1: nb := nb + 1; END_ACTION",
        "TRANSITION FROM A TO A2 :=",
        "na >= 2",
        "; END_TRANSITION",
        "STEP A2: END_STEP",
        "TRANSITION FROM B TO B2 :=",
        "nb >= 3",  # the condition's own ';' left out
        "; END_TRANSITION",
        "STEP B2: END_STEP",
        "TRANSITION FROM (A2, B2) TO C :=",
        "TRUE",
        "; END_TRANSITION",
        "STEP C: _inline_16_1(N); flag(S); END_STEP",
        "ACTION _inline_16_1: nc := nc + 1; END_ACTION",
        "TRANSITION FROM C TO Init :=",  # through the selection divergence and the jump
        "nc >= 2 AND ni < 2",
        "; END_TRANSITION",
        "TRANSITION FROM C TO Done :=",  # through the selection convergence
        "FALSE",
        "; END_TRANSITION",
        "STEP Done: flag(R); late(D, T#20ms); _inline_22_3(N); END_STEP",
        "ACTION _inline_22_3: nd := nd + 1; END_ACTION",
    ]
    assert "TASK t(INTERVAL := T#10ms, PRIORITY := 0);" in lines


def test_an_sfc_project_steps_through_its_network_scan_by_scan(tmp_path):
    plc = PLC.from_files(write(tmp_path, project(SFC_POU, configs=SFC_CONFIG)), use_cache=False)

    def state():
        return [plc[f"seq.{v}"] for v in ("ni", "na", "nb", "nc", "nd", "flag", "late")]

    plc.scan(1)  # Init: its action sets go
    assert state() == [1, 0, 0, 0, 0, False, False]
    plc.scan(1)  # Init → (A, B), both count
    assert state() == [1, 1, 1, 0, 0, False, False]
    plc.scan(2)  # A → A2 after na reached 2; B still counting
    assert state() == [1, 2, 3, 0, 0, False, False]
    plc.scan(1)  # B → B2
    assert state() == [1, 2, 3, 0, 0, False, False]
    plc.scan(1)  # (A2, B2) → C: counts, sets flag
    assert state() == [1, 2, 3, 1, 0, True, False]
    plc.scan(2)  # C → jump to Init (ni < 2)
    assert state() == [2, 2, 3, 2, 0, True, False]
    plc.scan(3)  # Init → (A, B) → (A2, B2) → C
    assert state() == [2, 3, 4, 3, 0, True, False]
    plc.scan(1)  # C → Done through the named transition Stop: flag reset
    assert state() == [2, 3, 4, 3, 1, False, False]
    plc.scan(1)
    assert state() == [2, 3, 4, 3, 2, False, False]
    plc.scan(1)  # late (D, T#20ms) two cycles of 10 ms after Done became active
    assert state() == [2, 3, 4, 3, 3, False, True]


# ---------------------------------------------------------------- diagnostics at the XML's places

BAD = """<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <fileHeader companyName="Beremiz" productName="Beremiz" productVersion="1"/>
  <contentHeader name="bad"/>
  <types>
    <dataTypes/>
    <pous>
      <pou name="main" pouType="program">
        <interface>
          <localVars>
            <variable name="x">
              <type><derived name="NoSuchType"/></type>
            </variable>
            <variable name="n">
              <type><INT/></type>
            </variable>
          </localVars>
        </interface>
        <body>
          <ST>
            <xhtml:p><![CDATA[n := n + 1;
n := undeclared_thing;]]></xhtml:p>
          </ST>
        </body>
      </pou>
      <pou name="graphic" pouType="functionBlock">
        <interface/>
        <body>
          <FBD>
            <block localId="1" typeName="AND"/>
          </FBD>
        </body>
      </pou>
    </pous>
  </types>
  <instances><configurations/></instances>
</project>
"""


def test_errors_name_the_xml_file_at_the_variable_and_in_the_cdata(tmp_path):
    path = write(tmp_path, BAD)
    assert errors_of(path) == [
        ("E012", 11, 17),  # x : NoSuchType; on the <variable> line
        ("E010", 22, 6),  # inside the CDATA, at the code's own line and column
        ("E050", 28, 9),  # the FBD body of `graphic`, at its <body>
    ]
    with pytest.raises(CompileError) as info:
        compile_paths([path], use_cache=False)
    text = str(info.value)
    assert f"{path}:22:6: error[E010]: undeclared identifier 'undeclared_thing'" in text
    assert f"{path}:28:9: error[E050]: POU graphic is written in FBD: st reads ST and SFC bodies" in text
    assert "     22 | n := undeclared_thing;" in text


def test_an_fbd_body_is_refused_and_the_other_pous_still_run(tmp_path):
    pous = POUS.replace(
        '<pou name="Twice" pouType="function">',
        '<pou name="Drawn" pouType="functionBlock">\n<interface/>\n<body><LD/></body>\n</pou>\n'
        '      <pou name="Twice" pouType="function">',
    )
    xml = project(pous, TYPES, CONFIGS)
    path = write(tmp_path, xml)
    assert errors_of(path) == [("E050", line_of(xml, "<body><LD/>"), 1)]
    result = compile_paths([path], raise_on_error=False, use_cache=False)
    assert [d.message for d in result.diagnostics if d.code == "E050"] == [
        "POU Drawn is written in LD: st reads ST and SFC bodies"
    ]


def test_codesys_text_with_entities_keeps_its_columns(tmp_path):
    pou = """\
      <pou name="main" pouType="program">
        <interface><localVars><variable name="n"><type><INT/></type></variable></localVars></interface>
        <body>
          <ST>
            <xhtml xmlns="http://www.w3.org/1999/xhtml">IF n &lt; 3 THEN n := nope; END_IF;</xhtml>
          </ST>
        </body>
      </pou>
"""
    xml = project(pou, company="CODESYS", product="CODESYS")
    path = write(tmp_path, xml)
    line = line_of(xml, "<xhtml xmlns")
    column = '            <xhtml xmlns="http://www.w3.org/1999/xhtml">IF n &lt; 3 THEN n := '.index("n :=") + 6
    assert errors_of(path) == [("E010", line, column)]


def test_malformed_xml_is_a_located_error(tmp_path):
    path = write(
        tmp_path,
        '<?xml version="1.0"?>\n<project xmlns="http://www.plcopen.org/xml/tc6_0201">\n  <types>\n</project>\n',
    )
    result = compile_paths([path], raise_on_error=False, use_cache=False)
    assert [(d.code, d.span.line, d.span.col, d.message) for d in result.diagnostics] == [
        ("E051", 4, 3, "malformed XML: mismatched tag")
    ]


def test_an_xml_file_that_is_not_plcopen_is_a_located_error(tmp_path):
    path = write(tmp_path, '<?xml version="1.0"?>\n<!-- a list -->\n<list><item/></list>\n', "data.xml")
    result = compile_paths([path], raise_on_error=False, use_cache=False)
    assert [(d.code, d.span.line, d.span.col) for d in result.diagnostics] == [("E051", 3, 1)]
    assert result.diagnostics[0].message == "this XML file is not a PLCopen XML project: its root element is <list>"


def test_a_plcopen_project_is_known_by_its_content_whatever_its_name(tmp_path):
    path = write(tmp_path, FULL, "project.plcopen")
    line = load_files([path])[0].text.split("\n")[line_of(FULL, '<dataType name="Color">') - 1]
    assert line == "      Color : (Red, Green, Blue) := Green;"
    assert load_files([write(tmp_path, "PROGRAM p END_PROGRAM\n", "p.st")])[0].text == "PROGRAM p END_PROGRAM\n"


# ---------------------------------------------------------------- the preset of the tool


@pytest.mark.parametrize(
    "company, product, body, preset",
    [
        ("Beremiz", "Beremiz", "xhtml:p", "openplc"),
        ("Unknown", "OpenPLC Editor", "xhtml", "openplc"),
        ("Unknown", "Unnamed", "xhtml:p", "openplc"),  # Beremiz's writer: text in <xhtml:p>
        ("3S-Smart Software Solutions GmbH", "CODESYS", "xhtml", "codesys"),
        ("Beckhoff Automation GmbH", "TwinCAT PLC Control", "xhtml", "twincat"),
        ("Someone", "Some tool", "xhtml", None),
    ],
)
def test_the_tool_that_wrote_the_file_chooses_the_preset(tmp_path, company, product, body, preset):
    pou = (
        '      <pou name="main" pouType="program">\n        <body><ST>'
        f'<{body} xmlns:xhtml="http://www.w3.org/1999/xhtml" xmlns="http://www.w3.org/1999/xhtml">'
        f";</{body}></ST></body>\n      </pou>\n"
    )
    sources = load_files([write(tmp_path, project(pou, company=company, product=product))])
    options = CompileOptions.for_sources(sources)
    assert (options.dialect.name if options.dialect else None) == preset
    assert CompileOptions.for_sources(sources, dialect="iec").dialect.name == "iec"  # a flag wins


def test_openplc_preset_of_a_beremiz_file_counts_time_in_seconds(tmp_path):
    pou = """\
      <pou name="main" pouType="program">
        <interface><localVars><variable name="n"><type><DINT/></type></variable></localVars></interface>
        <body><ST><xhtml:p><![CDATA[n := TIME_TO_DINT(T#3s);]]></xhtml:p></ST></body>
      </pou>
"""
    plc = PLC.from_files(write(tmp_path, project(pou)), use_cache=False)
    plc.scan(1)
    assert plc["main.n"] == 3  # MatIEC: seconds (the default counts milliseconds)


# ---------------------------------------------------------------- the command line


@pytest.mark.slow
def test_st_check_and_st_run_read_plc_xml(tmp_path):
    path = write(tmp_path, project(SFC_POU, configs=SFC_CONFIG))
    check = subprocess.run([sys.executable, "-m", "st", "check", path], capture_output=True, text=True)
    assert (check.returncode, check.stdout.strip()) == (0, "ok: 1 file(s), 1 POU(s)")
    run = subprocess.run(
        [sys.executable, "-m", "st", "run", path, "--virtual", "--scans", "10", "--dump-json"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    values = json.loads(run.stdout.strip().splitlines()[-1])
    assert (values["seq.ni"], values["seq.na"], values["seq.nb"], values["seq.nc"]) == (2, 3, 4, 2)
    bad = subprocess.run([sys.executable, "-m", "st", "check", write(tmp_path, BAD)], capture_output=True, text=True)
    assert bad.returncode == 1
    assert f"{tmp_path / 'plc.xml'}:22:6: error[E010]" in bad.stderr


def _two_steps(condition: str, transitions: str = "") -> str:
    """A program with steps S0 → S1, the transition's <condition> given; S1 counts."""
    return project(f"""\
      <pou name="P" pouType="program">
        <interface><localVars><variable name="n"><type><INT/></type></variable></localVars></interface>
        <transitions>
{transitions}        </transitions>
        <body>
          <SFC>
            <step localId="1" name="S0" initialStep="true"/>
            <transition localId="2">
              <connectionPointIn><connection refLocalId="1"/></connectionPointIn>
              <condition>{condition}</condition>
            </transition>
            <step localId="3" name="S1"><connectionPointIn><connection refLocalId="2"/></connectionPointIn></step>
            <actionBlock localId="4">
              <connectionPointIn><connection refLocalId="3"/></connectionPointIn>
              <action localId="0"><inline><ST><xhtml:p><![CDATA[n := n + 1;]]></xhtml:p></ST></inline></action>
            </actionBlock>
          </SFC>
        </body>
      </pou>
""")


@pytest.mark.parametrize("text", [":= TRUE;", "Go := TRUE;", "TRUE"])
def test_a_named_transition_may_be_written_as_beremiz_codesys_or_a_bare_expression(tmp_path, text):
    named = (
        f'          <transition name="Go"><body><ST><xhtml:p><![CDATA[{text}]]></xhtml:p></ST></body></transition>\n'
    )
    plc = PLC.from_files(write(tmp_path, _two_steps('<reference name="Go"/>', named)), use_cache=False)
    plc.scan(3)
    assert plc["P.n"] == 3  # S0 → S1 in the first scan


def test_graphical_conditions_and_macro_steps_are_located_errors(tmp_path):
    xml = _two_steps('<connectionPointIn><connection refLocalId="9"/></connectionPointIn>')
    path = write(tmp_path, xml)
    result = compile_paths([path], raise_on_error=False, use_cache=False)
    assert [(d.code, d.span.line, d.message) for d in result.diagnostics if d.is_error] == [
        (
            "E050",
            line_of(xml, '<transition localId="2">'),
            "the condition of an SFC transition of P is a graphical network: st reads ST conditions",
        )
    ]
    xml = (
        _two_steps("<inline><ST><xhtml:p>TRUE</xhtml:p></ST></inline>")
        .replace('<step localId="3" name="S1">', '<macroStep localId="3" name="S1">')
        .replace("</connectionPointIn></step>", "</connectionPointIn></macroStep>")
    )
    path = write(tmp_path, xml, "macro.xml")
    result = compile_paths([path], raise_on_error=False, use_cache=False)
    assert [(d.code, d.span.line, d.span.col, d.message) for d in result.diagnostics] == [
        ("E051", line_of(xml, "<macroStep"), 13, "an SFC macro step in P: st does not read macro steps")
    ]


def test_a_named_transition_used_twice_is_copied_and_an_unknown_one_is_an_error(tmp_path):
    sfc = """\
      <pou name="P" pouType="program">
        <interface><localVars><variable name="n"><type><INT/></type></variable></localVars></interface>
        <transitions>
          <transition name="Go"><body><ST><xhtml:p><![CDATA[Go := n >= 0;]]></xhtml:p></ST></body></transition>
        </transitions>
        <body>
          <SFC>
            <step localId="1" name="S0" initialStep="true"/>
            <transition localId="2">
              <connectionPointIn><connection refLocalId="1"/></connectionPointIn>
              <condition><reference name="Go"/></condition>
            </transition>
            <step localId="3" name="S1"><connectionPointIn><connection refLocalId="2"/></connectionPointIn></step>
            <transition localId="4">
              <connectionPointIn><connection refLocalId="3"/></connectionPointIn>
              <condition><reference name="Go"/></condition>
            </transition>
            <step localId="5" name="S2"><connectionPointIn><connection refLocalId="4"/></connectionPointIn></step>
            <actionBlock localId="6">
              <connectionPointIn><connection refLocalId="5"/></connectionPointIn>
              <action localId="0"><inline><ST><xhtml:p><![CDATA[n := n + 1;]]></xhtml:p></ST></inline></action>
            </actionBlock>
          </SFC>
        </body>
      </pou>
"""
    xml = project(sfc)
    lines = _lines(xml)
    assert "TRANSITION Go FROM S0 TO S1 := n >= 0; END_TRANSITION" in lines  # `Go` blanked in `Go := …`
    assert "TRANSITION FROM S1 TO S2 := n >= 0 ; END_TRANSITION" in lines
    plc = PLC.from_files(write(tmp_path, xml), use_cache=False)
    plc.scan(3)
    assert plc["P.n"] == 2
    unknown = xml.replace(
        '<reference name="Go"/></condition>\n            </transition>\n            <step localId="5"',
        '<reference name="Went"/></condition>\n            </transition>\n            <step localId="5"',
    )
    path = write(tmp_path, unknown, "unknown.xml")
    result = compile_paths([path], raise_on_error=False, use_cache=False)
    assert [(d.code, d.span.line, d.message) for d in result.diagnostics] == [
        ("E051", line_of(unknown, '<transition localId="4">'), "transition Went is not a transition of P")
    ]


def test_an_st_body_calls_the_pous_own_actions(tmp_path):
    pou = """\
      <pou name="main" pouType="program">
        <interface><localVars><variable name="n"><type><INT/></type></variable></localVars></interface>
        <actions>
          <action name="Bump"><body><ST><xhtml:p><![CDATA[n := n + 10;]]></xhtml:p></ST></body></action>
        </actions>
        <body><ST><xhtml:p><![CDATA[Bump(); n := n + 1;]]></xhtml:p></ST></body>
      </pou>
"""
    plc = PLC.from_files(write(tmp_path, project(pou)), use_cache=False)
    plc.scan(2)
    assert plc["main.n"] == 22


def test_tc6_xml_1_0_names_a_type_and_a_clock_interval(tmp_path):
    xml = project(
        '      <pou name="P" pouType="program">\n'
        '        <interface><localVars><variable name="n"><type><INT/></type></variable></localVars></interface>\n'
        "        <body><ST><xhtml:p><![CDATA[n := n + 1;]]></xhtml:p></ST></body>\n"
        "      </pou>\n",
        configs='      <configuration name="C"><resource name="R">\n'
        '        <task name="T" interval="00:00:00.050" priority="0"/>\n'
        '        <pouInstance name="inst" type="P"/>\n'
        "      </resource></configuration>\n",
    ).replace("tc6_0201", "tc6.xsd")
    lines = _lines(xml)
    assert lines[-4:] == [
        "CONFIGURATION C RESOURCE R ON PLC",
        "TASK T(INTERVAL := T#50ms, PRIORITY := 0);",
        "PROGRAM inst : P;",
        "END_RESOURCE END_CONFIGURATION",
    ]
    plc = PLC.from_files(write(tmp_path, xml), use_cache=False)
    plc.scan(3)
    assert (plc.tasks[0].interval, plc["inst.n"]) == (50_000_000, 3)
