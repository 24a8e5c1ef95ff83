"""`st lsp`: the language server over stdio (pygls).

Documents are grouped into projects (project.py); each project is checked again 0.1 s after the
last keystroke in any of its documents (analysis.py, in a worker thread so that the server keeps
answering), and its diagnostics are published for every file of it. A keystroke while a check
runs stops that check at its next pass (its answer would be about an old text); one check of a
project runs at a time. Requests are answered from the project's last analysis and the document's
current text (features.py), so completion works in a statement that does not parse yet; completion
does not wait for the newest analysis's index while the previous one has its own.

Garbage: the automatic cyclic collector is off (it would run in the middle of a check and scan
the whole project every time). The server collects itself, in the worker, right after an
analysis's diagnostics are published and before its index is built: nobody has typed since the
check began, so no request is waiting. A check or index build that an edit stopped leaves its
garbage for then, unless COLLECT_AFTER of them did (a keystroke asks for completion at once: a
collection then would hold it up). After a project's first analysis what stays (the libraries'
and files' trees, the grammar) is frozen out of the collector's sight, so a collection costs about
40 ms on 20,000 lines, where one every few analyses over everything took seconds.
"""

from __future__ import annotations

import asyncio
import gc
import logging
import os
import re
import sys
import threading
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlparse

from lsprotocol import types as L
from pygls.lsp.server import LanguageServer

from ..compiler.check import CheckCancelled
from ..diagnostics import Diagnostic, Severity
from . import features as F
from .analysis import Analysis, Analyzer
from .index import Target
from .project import Overlays, ProjectKey, project_of, sources_of

DEBOUNCE_S = 0.1
COLLECT_AFTER = 8  # analyses stopped by edits before their garbage is collected anyway
_TOKEN = re.compile(r"[A-Za-z_0-9%.#]+")  # what a diagnostic without an end covers
_SEVERITY = {Severity.ERROR: L.DiagnosticSeverity.Error, Severity.WARNING: L.DiagnosticSeverity.Warning}
_SYMBOL_KIND = {
    "gvl": L.SymbolKind.Namespace,
    "namespace": L.SymbolKind.Namespace,
    "configuration": L.SymbolKind.Namespace,
    "resource": L.SymbolKind.Namespace,
    "task": L.SymbolKind.Event,
    "program_instance": L.SymbolKind.Object,
    "function": L.SymbolKind.Function,
    "function_block": L.SymbolKind.Class,
    "program": L.SymbolKind.Module,
    "method": L.SymbolKind.Method,
    "property": L.SymbolKind.Property,
    "action": L.SymbolKind.Event,
    "struct": L.SymbolKind.Struct,
    "enum": L.SymbolKind.Enum,
    "type": L.SymbolKind.TypeParameter,
    "interface": L.SymbolKind.Interface,
    "member": L.SymbolKind.Field,
    "constant": L.SymbolKind.Constant,
    "global": L.SymbolKind.Variable,
    "variable": L.SymbolKind.Variable,
    "instance": L.SymbolKind.Object,
    "enum_value": L.SymbolKind.EnumMember,
}
_COMPLETION_KIND = {
    "keyword": L.CompletionItemKind.Keyword,
    "snippet": L.CompletionItemKind.Snippet,
    "type": L.CompletionItemKind.TypeParameter,
    "pin": L.CompletionItemKind.Field,
    "function": L.CompletionItemKind.Function,
    "function_block": L.CompletionItemKind.Class,
    "program": L.CompletionItemKind.Module,
    "interface": L.CompletionItemKind.Interface,
    "method": L.CompletionItemKind.Method,
    "property": L.CompletionItemKind.Property,
    "action": L.CompletionItemKind.Event,
    "member": L.CompletionItemKind.Field,
    "enum_value": L.CompletionItemKind.EnumMember,
    "constant": L.CompletionItemKind.Constant,
    "global": L.CompletionItemKind.Variable,
    "variable": L.CompletionItemKind.Variable,
    "instance": L.CompletionItemKind.Variable,
}


def uri_to_path(uri: str) -> str:
    p = urlparse(uri)
    return os.path.normpath(unquote(p.path)) if p.scheme == "file" else uri


def path_to_uri(path: str) -> str:
    return Path(path).absolute().as_uri()


class StServer(LanguageServer):
    def __init__(self, lib_path: list[str] | None = None) -> None:
        super().__init__("st", "0.1.0")
        self.lib_path = list(lib_path or [])
        self.overlays = Overlays()
        self.analyzers: dict[ProjectKey, Analyzer] = {}
        self.analyses: dict[ProjectKey, Analysis] = {}
        self.indexed: dict[ProjectKey, Analysis] = {}  # the last analysis whose index is built
        self.locks: dict[ProjectKey, asyncio.Lock] = {}
        self.pending: dict[ProjectKey, asyncio.Task] = {}
        self.stops: dict[ProjectKey, threading.Event] = {}  # the running check's
        self.index_stops: dict[ProjectKey, threading.Event] = {}  # the index being built's
        self.frozen: set[ProjectKey] = set()  # projects whose first analysis was frozen
        self.uncollected = 0  # analyses stopped since the last collection
        self.published: dict[ProjectKey, set[str]] = {}
        self.key_of: dict[str, ProjectKey] = {}

    # ------------------------------------------------------------------ projects
    def root(self) -> str | None:
        try:
            return self.workspace.root_path
        except Exception:  # noqa: BLE001 - no workspace yet
            return None

    def key(self, path: str) -> ProjectKey:
        k = self.key_of.get(path)
        if k is None:
            k = self.key_of[path] = project_of(path, self.root(), self.overlays)
        return k

    def schedule(self, path: str) -> None:
        """Check path's project DEBOUNCE_S from now; stop the check that runs (its text is old)."""
        key = self.key(path)
        old = self.pending.get(key)
        if old is not None and not old.done():
            old.cancel()
        for stops in (self.stops, self.index_stops):
            stop = stops.pop(key, None)
            if stop is not None:
                stop.set()
        self.pending[key] = asyncio.get_running_loop().create_task(self._later(key))

    async def _later(self, key: ProjectKey) -> None:
        await asyncio.sleep(DEBOUNCE_S)
        # cancelled from here on (a newer edit), the check itself goes on until its stop is seen:
        # the next one waits for it (two checks must not work on the same trees at once)
        await asyncio.shield(self._analyze_quietly(key))

    async def _analyze_quietly(self, key: ProjectKey) -> None:
        try:
            await self.analyze(key)
        except CheckCancelled:
            pass
        except Exception:  # a bug: logged, the server goes on (the next edit checks again)
            logging.getLogger(__name__).exception("checking %s failed", key)

    async def analyze(self, key: ProjectKey) -> Analysis:
        """Check the project now (after the one that runs) and publish its diagnostics; raises
        CheckCancelled when an edit stopped it."""
        lock = self.locks.setdefault(key, asyncio.Lock())
        async with lock:
            analyzer = self.analyzers.setdefault(key, Analyzer())
            sources = sources_of(key, self.overlays, self.lib_path)
            loop = asyncio.get_running_loop()
            stop = self.stops[key] = threading.Event()
            try:
                a = await loop.run_in_executor(None, self._check, analyzer, sources, stop)
            finally:
                if self.stops.get(key) is stop:
                    del self.stops[key]
            self.analyses[key] = a
            self.publish(key, a)
        stop = self.index_stops[key] = threading.Event()
        loop.run_in_executor(None, self._build_index, key, a, stop)
        return a

    def _build_index(self, key: ProjectKey, a: Analysis, stop: threading.Event) -> None:
        """In a worker: build a's index, ready for the next request; given up when an edit comes
        (it would slow the check of that edit down, and the next analysis is the one wanted).
        Then the garbage (the module docstring says why here)."""
        if not stop.is_set():
            self.collect()
        built = a.build_index(stop)
        if built and self.analyses.get(key) is a:
            self.indexed[key] = a
            if key not in self.frozen:
                self.frozen.add(key)
                gc.collect()
                gc.freeze()
        elif not built:
            self.stopped()

    def collect(self) -> None:
        self.uncollected = 0
        gc.collect()

    def stopped(self) -> None:
        """A check or an index build was stopped by an edit: its garbage waits (the module docstring)."""
        self.uncollected += 1
        if self.uncollected >= COLLECT_AFTER:
            self.collect()

    def _check(self, analyzer: Analyzer, sources: list, stop: threading.Event) -> Analysis:
        """In a worker: the analysis."""
        try:
            return analyzer.analyze(sources, stop)
        except CheckCancelled:
            self.stopped()
            raise

    async def analysis(self, path: str) -> Analysis:
        key = self.key(path)
        a = self.analyses.get(key)
        if a is None or (path in self.overlays.texts and path not in a.sources):
            while True:
                try:
                    a = await self.analyze(key)
                    break
                except CheckCancelled:
                    continue  # an edit came: the request is answered from the check of the new text
        return a

    def ready(self, path: str) -> Analysis | None:
        """The newest analysis of path's project whose index needs no waiting, if any."""
        key = self.key(path)
        a = self.analyses.get(key)
        if a is not None and a.has_index:
            return a
        got = self.indexed.get(key)
        if got is not None and (path not in self.overlays.texts or path in got.sources):
            return got
        return a

    def publish(self, key: ProjectKey, a: Analysis) -> None:
        files = set(a.diagnostics)
        for path in self.published.get(key, set()) - files:
            self.text_document_publish_diagnostics(L.PublishDiagnosticsParams(uri=path_to_uri(path), diagnostics=[]))
        for path, diags in a.diagnostics.items():
            src = a.sources.get(path)
            lines = src.text.splitlines() if src is not None else []
            self.text_document_publish_diagnostics(
                L.PublishDiagnosticsParams(uri=path_to_uri(path), diagnostics=[to_lsp(d, lines) for d in diags])
            )
        self.published[key] = files

    def text_of(self, path: str) -> str:
        try:
            return self.overlays.read(path)
        except OSError:
            return ""


def to_lsp(d: Diagnostic, lines: list[str]) -> L.Diagnostic:
    line = max(d.span.line - 1, 0)
    col = max(d.span.col - 1, 0)
    if d.span.end_line:
        end = L.Position(line=d.span.end_line - 1, character=max(d.span.end_col - 1, 0))
    else:
        text = lines[line] if line < len(lines) else ""
        m = _TOKEN.match(text[col:])
        end = L.Position(line=line, character=col + (len(m.group()) if m else 1))
    message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
    return L.Diagnostic(
        range=L.Range(start=L.Position(line=line, character=col), end=end),
        message=message,
        severity=_SEVERITY.get(d.severity, L.DiagnosticSeverity.Information),
        code=d.code,
        code_description=L.CodeDescription(href=explain_uri(d.code)),
        source="st",
    )


def explain_uri(code: str) -> str:
    """A page with `st explain CODE`'s text, written once into st's cache, as the code's link."""
    from ..errors_doc import explain

    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "st" / "explain"
    page = base / f"{code}.md"
    if not page.exists():
        try:
            base.mkdir(parents=True, exist_ok=True)
            page.write_text(f"# {code}\n\n{explain(code) or 'no explanation'}\n\n(`st explain {code}`)\n")
        except OSError:
            pass
    return page.as_uri()


def _range(line: int, col: int, length: int) -> L.Range:
    return L.Range(start=L.Position(line=line, character=col), end=L.Position(line=line, character=col + length))


def _location(t: Target) -> L.Location:
    return L.Location(uri=path_to_uri(t.file), range=_range(t.line, t.col, len(t.name)))


def make_server(lib_path: list[str] | None = None) -> StServer:
    server = StServer(lib_path)

    @server.feature(L.INITIALIZE)
    def initialize(ls: StServer, params: L.InitializeParams) -> None:
        """`initializationOptions: {"libPath": [...]}`: library projects for a .plcproj's references
        (as `st lsp --lib`, which it adds to)."""
        got = params.initialization_options
        if isinstance(got, dict):
            ls.lib_path += [str(p) for p in got.get("libPath", []) if isinstance(p, str)]

    @server.feature(L.TEXT_DOCUMENT_DID_OPEN)
    async def did_open(ls: StServer, params: L.DidOpenTextDocumentParams) -> None:
        path = uri_to_path(params.text_document.uri)
        ls.overlays.texts[path] = params.text_document.text
        ls.key_of.pop(path, None)
        await ls._analyze_quietly(ls.key(path))

    @server.feature(L.TEXT_DOCUMENT_DID_CHANGE)
    async def did_change(ls: StServer, params: L.DidChangeTextDocumentParams) -> None:
        path = uri_to_path(params.text_document.uri)
        ls.overlays.texts[path] = ls.workspace.get_text_document(params.text_document.uri).source
        ls.schedule(path)

    @server.feature(L.TEXT_DOCUMENT_DID_SAVE)
    async def did_save(ls: StServer, params: L.DidSaveTextDocumentParams) -> None:
        path = uri_to_path(params.text_document.uri)
        ls.key_of.pop(path, None)
        ls.schedule(path)

    @server.feature(L.TEXT_DOCUMENT_DID_CLOSE)
    async def did_close(ls: StServer, params: L.DidCloseTextDocumentParams) -> None:
        path = uri_to_path(params.text_document.uri)
        ls.overlays.texts.pop(path, None)
        ls.schedule(path)

    @server.feature(L.TEXT_DOCUMENT_HOVER)
    async def hover(ls: StServer, params: L.HoverParams) -> L.Hover | None:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        text = F.hover(a, path, params.position.line, params.position.character)
        if text is None:
            return None
        return L.Hover(contents=L.MarkupContent(kind=L.MarkupKind.Markdown, value=text))

    @server.feature(L.TEXT_DOCUMENT_DEFINITION)
    async def definition(ls: StServer, params: L.DefinitionParams) -> L.Location | None:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        t = F.definition(a, path, params.position.line, params.position.character)
        return _location(t) if t is not None else None

    @server.feature(L.TEXT_DOCUMENT_REFERENCES)
    async def references(ls: StServer, params: L.ReferenceParams) -> list[L.Location]:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        found = F.references(
            a, path, params.position.line, params.position.character, params.context.include_declaration
        )
        return [L.Location(uri=path_to_uri(f), range=_range(o.line, o.col, o.length)) for f, o in found]

    @server.feature(L.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    async def document_symbol(ls: StServer, params: L.DocumentSymbolParams) -> list[L.DocumentSymbol]:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        out = []
        for t, kids in F.document_symbols(a, path):
            r = _range(t.line, t.col, len(t.name))
            children = [
                L.DocumentSymbol(
                    name=k.name,
                    kind=_SYMBOL_KIND.get(k.kind, L.SymbolKind.Variable),
                    range=_range(k.line, k.col, len(k.name)),
                    selection_range=_range(k.line, k.col, len(k.name)),
                    detail=k.detail,
                )
                for k in kids
                if k.line >= 0
            ]
            out.append(
                L.DocumentSymbol(
                    name=t.name,
                    kind=_SYMBOL_KIND.get(t.kind, L.SymbolKind.Variable),
                    range=r,
                    selection_range=r,
                    detail=t.detail,
                    children=children,
                )
            )
        return out

    @server.feature(L.WORKSPACE_SYMBOL)
    async def workspace_symbol(ls: StServer, params: L.WorkspaceSymbolParams) -> list[L.SymbolInformation]:
        out = []
        seen: set[tuple[str, int, int]] = set()
        for a in list(ls.analyses.values()):
            for t in F.workspace_symbols(a, params.query):
                if (t.file, t.line, t.col) in seen:
                    continue
                seen.add((t.file, t.line, t.col))
                out.append(
                    L.SymbolInformation(
                        name=t.name,
                        kind=_SYMBOL_KIND.get(t.kind, L.SymbolKind.Variable),
                        location=_location(t),
                        container_name=t.owner or None,
                    )
                )
        return out

    @server.feature(L.TEXT_DOCUMENT_COMPLETION, L.CompletionOptions(trigger_characters=[".", "#", "("]))
    async def completion(ls: StServer, params: L.CompletionParams) -> L.CompletionList:
        path = uri_to_path(params.text_document.uri)
        a = ls.ready(path) or await ls.analysis(path)
        items = F.completion(a, path, params.position.line, params.position.character, ls.text_of(path))
        return L.CompletionList(
            is_incomplete=False,
            items=[
                L.CompletionItem(
                    label=i.label,
                    kind=_COMPLETION_KIND.get(i.kind, L.CompletionItemKind.Text),
                    detail=i.detail or None,
                    insert_text=i.insert or None,
                    insert_text_format=L.InsertTextFormat.Snippet if i.snippet else None,
                )
                for i in items
            ],
        )

    @server.feature(L.TEXT_DOCUMENT_PREPARE_RENAME)
    async def prepare_rename(ls: StServer, params: L.PrepareRenameParams) -> Any:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        o = F.occurrence(a, path, params.position.line, params.position.character)
        if o is None or o.target.library or not o.target.file:
            return None
        return L.PrepareRenamePlaceholder(range=_range(o.line, o.col, o.length), placeholder=o.target.name)

    @server.feature(L.TEXT_DOCUMENT_RENAME)
    async def rename(ls: StServer, params: L.RenameParams) -> L.WorkspaceEdit | None:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        try:
            edits = F.rename(a, path, params.position.line, params.position.character, params.new_name)
        except F.RenameRefused as e:
            raise ValueError(str(e)) from None
        return L.WorkspaceEdit(
            changes={
                path_to_uri(f): [L.TextEdit(range=_range(line, col, n), new_text=new) for line, col, n, new in es]
                for f, es in edits.items()
            }
        )

    legend = L.SemanticTokensLegend(token_types=F.TOKEN_TYPES, token_modifiers=F.TOKEN_MODIFIERS)

    @server.feature(L.TEXT_DOCUMENT_SEMANTIC_TOKENS_FULL, L.SemanticTokensRegistrationOptions(legend=legend, full=True))
    async def semantic_tokens(ls: StServer, params: L.SemanticTokensParams) -> L.SemanticTokens:
        path = uri_to_path(params.text_document.uri)
        a = await ls.analysis(path)
        return L.SemanticTokens(data=F.semantic_tokens(a, path))

    return server


def main(lib_path: list[str] | None = None) -> None:
    logging.basicConfig(level=logging.WARNING, format="st lsp: %(message)s")
    gc.disable()  # the server collects: StServer._build_index
    # a request waits for the interpreter while a check runs in its thread: hand it over every
    # millisecond (not every 5), so that completion answers within tens of ms during a check
    sys.setswitchinterval(0.001)
    make_server(lib_path).start_io()
