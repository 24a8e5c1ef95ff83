"""`st lsp` with a real LSP client over stdio (pytest-lsp): diagnostics as a document changes,
hover, definition, references, symbols, completion, rename, semantic tokens, and half-typed
statements that never upset the server."""

from __future__ import annotations

import asyncio
import glob
import sys
from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types as L
from pytest_lsp import ClientServerConfig, LanguageClient, client_capabilities

from st.api import libraries, provided_libraries
from st.compiler.check import TreeMemo
from st.compiler.driver import check, load_files, parse
from st.compiler.options import CompileOptions
from st.diagnostics import CompileError, DiagnosticSink

pytestmark = pytest.mark.slow

TYPES = """TYPE Mode : (Idle, Running, Done); END_TYPE
TYPE Recipe : STRUCT
  speed : REAL;  (* mm/s *)
  count : INT;
END_STRUCT; END_TYPE
VAR_GLOBAL
  g_total : DINT;  (* parts made since start *)
END_VAR
FUNCTION Twice : DINT
VAR_INPUT v : DINT; END_VAR
Twice := 2 * v;
END_FUNCTION
"""
STATION = """FUNCTION_BLOCK Station
VAR_INPUT
  start : BOOL;  (* the operator's button *)
  recipe : Recipe;
END_VAR
VAR_OUTPUT
  busy : BOOL;
END_VAR
VAR
  mode : Mode := Idle;
  t : TON;
END_VAR
t(IN := start, PT := T#2s);
busy := t.Q;
IF t.Q THEN mode := Mode#Done; END_IF;
END_FUNCTION_BLOCK
"""
MAIN = """PROGRAM main
VAR
  st1 : Station;
  made : DINT;
END_VAR
st1(start := TRUE);
IF st1.busy THEN
  made := made + 1;
  g_total := Twice(made);
END_IF;
END_PROGRAM
CONFIGURATION cell RESOURCE r ON PLC TASK t(INTERVAL := T#10ms); PROGRAM p WITH t : main; END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("lsp")
    (d / "types.st").write_text(TYPES)
    (d / "station.st").write_text(STATION)
    (d / "main.st").write_text(MAIN)
    return d


@pytest_lsp.fixture(config=ClientServerConfig(server_command=[sys.executable, "-m", "st.cli", "lsp"]))
async def client(lsp_client: LanguageClient, folder):
    params = L.InitializeParams(capabilities=client_capabilities("visual-studio-code"), root_uri=folder.as_uri())
    await lsp_client.initialize_session(params)
    yield
    await lsp_client.shutdown_session()


def uri(folder: Path, name: str) -> str:
    return (folder / name).as_uri()


async def open_doc(client: LanguageClient, folder: Path, name: str, text: str | None = None) -> str:
    u = uri(folder, name)
    client.text_document_did_open(
        L.DidOpenTextDocumentParams(
            text_document=L.TextDocumentItem(
                uri=u, language_id="structured-text", version=1, text=text or (folder / name).read_text()
            )
        )
    )
    await diagnostics_for(client, u)
    return u


async def diagnostics_for(client: LanguageClient, u: str, timeout: float = 20.0):
    end = asyncio.get_running_loop().time() + timeout
    while u not in client.diagnostics:
        if asyncio.get_running_loop().time() > end:
            raise TimeoutError(f"no diagnostics for {u}")
        await client.wait_for_notification("textDocument/publishDiagnostics")
    return client.diagnostics[u]


async def change(client: LanguageClient, u: str, version: int, text: str):
    client.diagnostics.pop(u, None)
    client.text_document_did_change(
        L.DidChangeTextDocumentParams(
            text_document=L.VersionedTextDocumentIdentifier(uri=u, version=version),
            content_changes=[L.TextDocumentContentChangeWholeDocument(text=text)],
        )
    )
    return await diagnostics_for(client, u)


def at(text: str, needle: str, nth: int = 0, offset: int = 0) -> L.Position:
    k = -1
    for i, line in enumerate(text.splitlines()):
        j = line.find(needle)
        while j >= 0:
            k += 1
            if k == nth:
                return L.Position(line=i, character=j + offset)
            j = line.find(needle, j + 1)
    raise KeyError(needle)


@pytest.mark.asyncio
async def test_diagnostics_follow_the_edits(client: LanguageClient, folder):
    u = await open_doc(client, folder, "main.st")
    assert [d.message for d in client.diagnostics[u]] == []
    broken = MAIN.replace("made := made + 1;", "made := made + 'x';")
    diags = await change(client, u, 2, broken)
    assert [(d.code, d.range.start.line, d.severity) for d in diags] == [("E014", 7, L.DiagnosticSeverity.Error)]
    assert diags[0].source == "st" and diags[0].code_description.href.endswith("/E014.md")
    assert Path(diags[0].code_description.href.removeprefix("file://")).read_text().startswith("# E014")
    unknown = MAIN.replace("g_total := Twice(made);", "g_totl := Twice(made);")
    diags = await change(client, u, 3, unknown)
    assert [(d.code, d.range.start.line, d.range.start.character) for d in diags] == [("E010", 8, 2)]
    assert "g_totl" in diags[0].message
    assert [d.code for d in await change(client, u, 4, MAIN)] == []


@pytest.mark.asyncio
async def test_hover(client: LanguageClient, folder):
    u = await open_doc(client, folder, "station.st")
    h = await client.text_document_hover_async(
        L.HoverParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(STATION, "start", 1))
    )
    assert h.contents.value.startswith("```st\nVAR_INPUT start : BOOL\n```")
    assert "the operator's button" in h.contents.value
    h = await client.text_document_hover_async(
        L.HoverParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(STATION, "t : TON", 0, 4))
    )
    assert "FUNCTION_BLOCK TON(IN : BOOL; PT : TIME) => (Q : BOOL; ET : TIME)" in h.contents.value
    h = await client.text_document_hover_async(
        L.HoverParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(STATION, "Mode#Done", 0, 6))
    )
    assert "Mode#Done = 2" in h.contents.value


@pytest.mark.asyncio
async def test_definition_and_references_across_files(client: LanguageClient, folder):
    u = await open_doc(client, folder, "main.st")
    d = await client.text_document_definition_async(
        L.DefinitionParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(MAIN, "Station", 0, 2))
    )
    assert d.uri == uri(folder, "station.st") and (d.range.start.line, d.range.start.character) == (0, 15)
    d = await client.text_document_definition_async(
        L.DefinitionParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(MAIN, "g_total", 0, 1))
    )
    assert d.uri == uri(folder, "types.st") and d.range.start.line == 6
    d = await client.text_document_definition_async(  # a function's name in its call
        L.DefinitionParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(MAIN, "Twice", 0, 2))
    )
    assert d.uri == uri(folder, "types.st") and (d.range.start.line, d.range.start.character) == (8, 9)
    refs = await client.text_document_references_async(
        L.ReferenceParams(
            text_document=L.TextDocumentIdentifier(uri=u),
            position=at(MAIN, "busy", 0, 1),
            context=L.ReferenceContext(include_declaration=True),
        )
    )
    assert sorted((r.uri.rsplit("/", 1)[-1], r.range.start.line) for r in refs) == [
        ("main.st", 6),
        ("station.st", 6),
        ("station.st", 13),
    ]


@pytest.mark.asyncio
async def test_symbols(client: LanguageClient, folder):
    u = await open_doc(client, folder, "station.st")
    syms = await client.text_document_document_symbol_async(
        L.DocumentSymbolParams(text_document=L.TextDocumentIdentifier(uri=u))
    )
    assert [(s.name, s.kind) for s in syms] == [("Station", L.SymbolKind.Class)]
    assert [c.name for c in syms[0].children] == ["start", "recipe", "busy", "mode", "t"]
    found = await client.workspace_symbol_async(L.WorkspaceSymbolParams(query="rec"))
    assert sorted(s.name for s in found) == ["Recipe", "recipe"]


async def _complete(client: LanguageClient, u: str, text: str, version: int, needle: str) -> list[str]:
    client.text_document_did_change(
        L.DidChangeTextDocumentParams(
            text_document=L.VersionedTextDocumentIdentifier(uri=u, version=version),
            content_changes=[L.TextDocumentContentChangeWholeDocument(text=text)],
        )
    )
    pos = at(text, needle, 0, len(needle))
    got = await client.text_document_completion_async(
        L.CompletionParams(text_document=L.TextDocumentIdentifier(uri=u), position=pos)
    )
    return [i.label for i in got.items]


@pytest.mark.asyncio
async def test_completion_in_half_typed_statements(client: LanguageClient, folder):
    u = await open_doc(client, folder, "station.st")
    body = "busy := t.Q;"
    labels = await _complete(client, u, STATION.replace(body, body + "\nrecipe."), 10, "recipe.")
    assert labels == ["speed", "count"]
    labels = await _complete(client, u, STATION.replace(body, body + "\n    t."), 11, "    t.")
    assert labels == ["IN", "PT", "Q", "ET"]
    labels = await _complete(client, u, STATION.replace(body, body + "\nt(IN := TRUE, "), 12, "TRUE, ")
    assert labels[:3] == ["PT :=", "Q =>", "ET =>"]
    labels = await _complete(client, u, STATION.replace(body, body + "\nmode := Mode#"), 13, "Mode#")
    assert labels == ["Idle", "Running", "Done"]
    labels = await _complete(client, u, STATION.replace(body, body + "\n    bu"), 14, "    bu")
    assert {"busy", "start", "recipe", "mode", "t", "g_total", "Station", "IF", "BOOL"} <= set(labels)


@pytest.mark.asyncio
async def test_a_half_typed_statement_keeps_the_rest_of_its_file(client: LanguageClient, folder):
    """While station.st does not parse, its POU is still declared (from its last tree): main.st
    has no error, and completion in the unfinished statement knows the block's variables."""
    u = await open_doc(client, folder, "station.st")  # its project's other files are published too
    m = uri(folder, "main.st")
    body = "busy := t.Q;"
    half = STATION.replace(body, body + "\n  mo")
    client.diagnostics.pop(m, None)
    diags = await change(client, u, 30, half)
    assert [(d.code, d.range.start.line) for d in diags] == [("E001", 15)]
    assert list(await diagnostics_for(client, m)) == []  # published again by that check
    labels = await _complete(client, u, STATION.replace(body, body + "\n  mod"), 31, "  mod")
    assert {"mode", "recipe", "start", "busy", "t"} <= set(labels)
    assert [d.code for d in await change(client, u, 32, STATION)] == []


@pytest.mark.asyncio
async def test_rename_across_files(client: LanguageClient, folder):
    u = await open_doc(client, folder, "station.st")
    pos = at(STATION, "busy", 0, 1)
    prep = await client.text_document_prepare_rename_async(
        L.PrepareRenameParams(text_document=L.TextDocumentIdentifier(uri=u), position=pos)
    )
    assert prep.placeholder == "busy"
    edit = await client.text_document_rename_async(
        L.RenameParams(text_document=L.TextDocumentIdentifier(uri=u), position=pos, new_name="running")
    )
    changes = {
        k.rsplit("/", 1)[-1]: sorted((e.range.start.line, e.range.start.character) for e in v)
        for k, v in edit.changes.items()
    }
    assert changes == {"station.st": [(6, 2), (13, 0)], "main.st": [(6, 7)]}
    ton = at(STATION, "TON", 0, 1)
    assert (
        await client.text_document_prepare_rename_async(
            L.PrepareRenameParams(text_document=L.TextDocumentIdentifier(uri=u), position=ton)
        )
        is None
    )  # a library block is not renamed


@pytest.mark.asyncio
async def test_semantic_tokens(client: LanguageClient, folder):
    u = await open_doc(client, folder, "station.st")
    got = await client.text_document_semantic_tokens_full_async(
        L.SemanticTokensParams(text_document=L.TextDocumentIdentifier(uri=u))
    )
    data = got.data
    tokens, line, col = [], 0, 0
    legend_types = ["namespace", "type", "class", "enum", "interface", "struct", "parameter", "variable", "property",
                    "enumMember", "function", "method"]  # fmt: skip
    for k in range(0, len(data), 5):
        line += data[k]
        col = data[k + 1] if data[k] else col + data[k + 1]
        tokens.append((line, col, data[k + 2], legend_types[data[k + 3]], data[k + 4]))
    lines = STATION.splitlines()
    named = {(lines[t[0]][t[1] : t[1] + t[2]], t[3], t[4]) for t in tokens}
    assert ("Station", "class", 1) in named  # its declaration
    assert ("Recipe", "struct", 0) in named
    assert ("TON", "class", 4) in named  # defaultLibrary
    assert ("t", "variable", 1 | 8) in named  # a function block instance, declared
    assert ("Done", "enumMember", 2) in named  # readonly


@pytest.mark.asyncio
async def test_garbage_never_upsets_the_server(client: LanguageClient, folder):
    u = await open_doc(client, folder, "main.st")
    texts = ["", "PROGRAM", "PROGRAM p VAR x : ", "IF THEN ELSE (* unterminated", "st1(start := ", "}{%%$$", MAIN[:57]]
    for k, text in enumerate(texts, 20):
        await change(client, u, k, text)
        await client.text_document_hover_async(
            L.HoverParams(text_document=L.TextDocumentIdentifier(uri=u), position=L.Position(line=0, character=3))
        )
        await client.text_document_completion_async(
            L.CompletionParams(
                text_document=L.TextDocumentIdentifier(uri=u),
                position=L.Position(line=0, character=len(text.splitlines()[0]) if text else 0),
            )
        )
    assert [d.code for d in await change(client, u, 40, MAIN)] == []


def test_the_checker_answers_the_same_on_a_tree_it_checked():
    """What the server's parse cache relies on: checking a tree again gives the same diagnostics
    (also with what the first check kept in a TreeMemo)."""
    root = Path(__file__).resolve().parents[1]
    fixtures = sorted(glob.glob(str(root / "tests/fixtures/**/*.st"), recursive=True))
    files = fixtures[::4] + sorted(glob.glob(str(root / "programs/*.st")))  # a quarter: a parse is the cost
    assert len(files) > 60
    for f in files:
        srcs = load_files([f], [], provided_libraries())
        try:
            opts = CompileOptions.for_sources(srcs)
        except CompileError:
            continue  # refused before any check (an unknown {dialect} pragma)
        libs = libraries(opts)
        first, second = DiagnosticSink(), DiagnosticSink()
        parsed = parse(srcs, libs, opts, first)
        for d in first.items:
            second.add(d)
        memo = TreeMemo()  # filled by the first check, read by the second
        check(parsed, opts, first, memo)
        check(parsed, opts, second, memo)
        assert [(d.code, str(d.span), d.message) for d in second.sorted()] == [
            (d.code, str(d.span), d.message) for d in first.sorted()
        ], f


POU_XML = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <POU Name="FB_Axis" Id="{00000000-0000-0000-0000-000000000001}" SpecialFunc="None">
    <Declaration><![CDATA[FUNCTION_BLOCK FB_Axis
VAR_INPUT
    bEnable : BOOL; // switch the drive on
END_VAR
VAR
    nCount : INT;
END_VAR]]></Declaration>
    <Implementation>
      <ST><![CDATA[IF bEnable THEN
    nCount := nCount + 1;
END_IF]]></ST>
    </Implementation>
  </POU>
</TcPlcObject>
"""
PROJ_XML = """<?xml version="1.0" encoding="utf-8"?>
<Project DefaultTargets="Build" xmlns="http://schemas.microsoft.com/developer/msbuild/2003">
  <PropertyGroup><Name>Axis</Name></PropertyGroup>
  <ItemGroup>
    <Compile Include="POUs\\FB_Axis.TcPOU"><SubType>Code</SubType></Compile>
  </ItemGroup>
</Project>
"""


@pytest.fixture(scope="module")
def twincat(tmp_path_factory):
    d = tmp_path_factory.mktemp("tc")
    (d / "POUs").mkdir()
    (d / "POUs" / "FB_Axis.TcPOU").write_text(POU_XML)
    (d / "Axis.plcproj").write_text(PROJ_XML)
    return d


@pytest_lsp.fixture(config=ClientServerConfig(server_command=[sys.executable, "-m", "st.cli", "lsp"]))
async def tc_client(lsp_client: LanguageClient, twincat):
    params = L.InitializeParams(capabilities=client_capabilities("visual-studio-code"), root_uri=twincat.as_uri())
    await lsp_client.initialize_session(params)
    yield
    await lsp_client.shutdown_session()


@pytest.mark.asyncio
async def test_a_twincat_file_of_its_project(tc_client: LanguageClient, twincat):
    """A .TcPOU is checked with its .plcproj (twincat preset), positions in the XML's lines."""
    path = twincat / "POUs" / "FB_Axis.TcPOU"
    u = await open_doc(tc_client, twincat / "POUs", "FB_Axis.TcPOU")
    assert [d.code for d in tc_client.diagnostics[u]] == []
    broken = POU_XML.replace("nCount := nCount + 1;", "nCount := nCount + 'x';")
    diags = await change(tc_client, u, 2, broken)
    assert [(d.code, d.range.start.line, d.range.start.character) for d in diags] == [("E014", 12, 14)]
    await change(tc_client, u, 3, POU_XML)
    h = await tc_client.text_document_hover_async(
        L.HoverParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(POU_XML, "IF bEnable", 0, 4))
    )
    assert h.contents.value.startswith("```st\nVAR_INPUT bEnable : BOOL\n```")
    assert "switch the drive on" in h.contents.value
    d = await tc_client.text_document_definition_async(
        L.DefinitionParams(text_document=L.TextDocumentIdentifier(uri=u), position=at(POU_XML, "nCount + 1", 0, 1))
    )
    assert d.uri == path.as_uri() and (d.range.start.line, d.range.start.character) == (8, 4)
