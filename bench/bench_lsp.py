"""`st lsp` on a 20k-line project, driven over stdio by a real LSP client (issue 38: "a 20k-line
project answers diagnostics within 0.5 s after a keystroke and completion within 100 ms").

    python bench/bench_lsp.py                          # 20,000 lines, 20 edits / requests per case (~4 min)
    python bench/bench_lsp.py --lines 5000 --edits 8 --seed 2
    python bench/bench_lsp.py --split                  # and the re-check's stages measured in-process

The project is gen_library.py's library cut at its module boundaries: one .st file per module
and one for program0 with the configuration, in a temporary folder (one project for the server;
`st check` of the files first). The client (pygls's LanguageClient) starts `python -m st.cli lsp`,
opens a module in the middle and measures, as wall time seen by the client:

- cold: didOpen → the document's first publishDiagnostics (the whole project checked);
- keystroke: didChange (full text) → the document's publishDiagnostics for that text, the
  server's debounce (0.1 s) included. A digit typed into and removed from an assignment, once an
  error (`flow := 'a';`) that must show and then go away. "idle": the server has answered a hover
  before the keystroke (so the last check's index is built); "back to back": the next keystroke
  as soon as the diagnostics arrive;
- typing: a statement typed one character at a time (--type-ms apart: faster and slower than
  the debounce), last keystroke → the diagnostics of the final text;
- completion after `instance.`, `instance.member.`, `Type#` and a plain identifier in a new
  statement in a FUNCTION_BLOCK body: with the server idle (the statement written and checked),
  sent right after the didChange that leaves the statement cut at the cursor, sent --busy-ms after
  it (the re-check of the cut text running), and sent --pause-ms after the diagnostics of the text
  cut one character earlier (the popup after a pause in typing);
- hover and definition round trips with the server idle.

Also, per phase, the server's CPU seconds (Linux /proc) and its full garbage collections: a
sitecustomize.py on the server's PYTHONPATH (in the temporary folder; --no-gc-log: none) notes
each generation-2 collection, its thread and its duration. Prints markdown tables and the ratios
to the goals; exits 0 also when a goal is missed.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from lsprotocol import types as L
from pygls.lsp.client import LanguageClient

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE))
from gen_library import generate  # noqa: E402

GOAL_DIAG = 0.5
GOAL_COMPLETION = 0.1
TIMEOUT = 120.0
_MODULE = re.compile(r"^\(\* =+\n   (?:Module (\w+) #(\d+) -- data types|program0 --)", re.M)

GC_HOOK = '''\
"""bench_lsp.py's hook in the measured server: notes every full garbage collection."""
import gc, os, threading, time

_out = open(os.environ["ST_BENCH_GC_LOG"], "a", buffering=1)
_started = {}


def _note(phase, info):
    if info["generation"] != 2:
        return
    me = threading.get_ident()
    if phase == "start":
        _started[me] = time.time()
    elif me in _started:
        t0 = _started.pop(me)
        _out.write(f"{t0:.4f} {time.time() - t0:.4f} {threading.current_thread().name}\\n")


gc.callbacks.append(_note)
'''


# ---------------------------------------------------------------------------- the project
def split_library(text: str, folder: Path) -> list[Path]:
    """One file per module (the library's header goes with the first), one for program0 and the
    configuration; the names keep the library's order."""
    starts = list(_MODULE.finditer(text))
    paths = []
    for i, m in enumerate(starts):
        a = 0 if i == 0 else m.start()
        b = starts[i + 1].start() if i + 1 < len(starts) else len(text)
        name = f"{i:02d}_{m.group(1).lower()}{m.group(2)}.st" if m.group(1) else f"{i:02d}_program0.st"
        p = folder / name
        p.write_text(text[a:b])
        paths.append(p)
    return paths


def st_check(paths: list[Path]) -> tuple[bool, str]:
    r = subprocess.run(
        [sys.executable, "-m", "st.cli", "check", *map(str, paths)], capture_output=True, text=True, check=False
    )
    out = (r.stdout + r.stderr).strip()
    return r.returncode == 0 and "error" not in out.lower(), out


def find_line(lines: list[str], pattern: str, start: int = 0) -> int:
    rx = re.compile(pattern)
    for i in range(start, len(lines)):
        if rx.search(lines[i]):
            return i
    raise KeyError(pattern)


class Doc:
    """The opened module: where its STATION block is and what to type in it."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.uri = path.as_uri()
        self.text = path.read_text()
        self.lines = self.text.splitlines()
        self.head = find_line(self.lines, r"^FUNCTION_BLOCK STATION_\w+")
        self.station = self.lines[self.head].split()[1]
        self.sfx = self.station[len("STATION") :]
        self.end = find_line(self.lines, r"^END_FUNCTION_BLOCK", self.head)  # new lines go before it
        self.flow = find_line(self.lines, r"^\s*flow := valve \* [\d.]+;", self.head)
        m = re.search(r"E_ALARM\w* : \((\w+)_OK", self.text)
        self.ep = m.group(1) if m else ""

    def around(self) -> tuple[str, str]:
        """The text before and after a new line at the end of the STATION body."""
        return "\n".join(self.lines[: self.end]) + "\n", "\n" + "\n".join(self.lines[self.end :]) + "\n"

    def with_line(self, new: str) -> str:
        before, after = self.around()
        return before + new + after

    def edited(self, kind: str) -> str:
        """The text after a keystroke: original, a digit typed into the flow line, or an error."""
        lines = list(self.lines)
        if kind == "digit":
            lines[self.flow] = lines[self.flow].replace(";", "1;")
        elif kind == "error":
            lines[self.flow] = "  flow := 'a';"
        return "\n".join(lines) + "\n"

    def pos(self, needle: str, offset: int = 0) -> L.Position:
        """needle's first place in the STATION block (offset characters into it)."""
        for i in range(self.head, self.end):
            j = self.lines[i].find(needle)
            if j >= 0:
                return L.Position(line=i, character=j + offset)
        raise KeyError(needle)


# ---------------------------------------------------------------------------- the client
class Client(LanguageClient):
    """A pygls client that notes when each publishDiagnostics arrives."""

    def __init__(self) -> None:
        super().__init__("bench-lsp", "1")
        self.waiters: list[tuple[str, asyncio.Future]] = []
        self.stderr: list[str] = []

        @self.feature(L.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def _published(params: L.PublishDiagnosticsParams) -> None:
            t = time.perf_counter()
            keep = []
            for uri, fut in self.waiters:
                if fut.done():
                    continue
                if uri == params.uri:
                    fut.set_result((t, params.diagnostics))
                else:
                    keep.append((uri, fut))
            self.waiters = keep

        @self.feature(L.WINDOW_LOG_MESSAGE)
        def _log(params: L.LogMessageParams) -> None:
            pass

    def expect(self, uri: str) -> asyncio.Future:
        """A future for the next publishDiagnostics of uri: (arrival time, diagnostics)."""
        fut = asyncio.get_running_loop().create_future()
        self.waiters.append((uri, fut))
        return fut

    def change(self, uri: str, version: int, text: str) -> float:
        t0 = time.perf_counter()
        self.text_document_did_change(
            L.DidChangeTextDocumentParams(
                text_document=L.VersionedTextDocumentIdentifier(uri=uri, version=version),
                content_changes=[L.TextDocumentContentChangeWholeDocument(text=text)],
            )
        )
        return t0

    async def drain_stderr(self) -> None:
        server = self._server
        if server is None or server.stderr is None:
            return
        while True:
            line = await server.stderr.readline()
            if not line:
                return
            self.stderr.append(line.decode(errors="replace").rstrip())
            del self.stderr[:-50]


def cpu_seconds(pid: int) -> float | None:
    """utime + stime of a process (Linux), or None."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def status(pid: int, field: str) -> int | None:
    """A number of /proc/PID/status (Linux): Threads (the server's workers stay once started),
    VmRSS (kB)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return None


def errors_of(diags) -> list:
    return [d for d in diags if d.severity == L.DiagnosticSeverity.Error]


def gc_events(log: Path | None) -> list[tuple[float, float, str]]:
    """(wall clock start, seconds, thread) of each full collection the server noted."""
    if log is None or not log.exists():
        return []
    out = []
    for line in log.read_text().splitlines():
        try:
            t, d, who = line.split(" ", 2)
            out.append((float(t), float(d), who))
        except ValueError:
            continue
    return out


# ---------------------------------------------------------------------------- the measurements
class Bench:
    def __init__(self, client: Client, doc: Doc, uris: list[str], pid: int) -> None:
        self.c = client
        self.doc = doc
        self.uris = uris
        self.pid = pid
        self.version = 1
        self.rows: list[tuple[str, list[float], float | None, str]] = []
        self.phases: list[
            tuple[str, float, float, float | None, int | None, int | None]
        ] = []  # wall start, s, CPU s, threads, RSS MB
        self.problems: list[str] = []

    def row(self, what: str, xs: list[float], goal: float | None, note: str = "") -> None:
        self.rows.append((what, xs, goal, note))

    async def phase(self, name: str, coro) -> None:
        c0, w0, t0 = cpu_seconds(self.pid), time.time(), time.perf_counter()
        await coro
        c1, t1 = cpu_seconds(self.pid), time.perf_counter()
        cpu = None if c0 is None or c1 is None else c1 - c0
        rss = status(self.pid, "VmRSS")
        self.phases.append((name, w0, t1 - t0, cpu, status(self.pid, "Threads"), None if rss is None else rss // 1024))

    # ------------------------------------------------------------------ helpers
    async def set_text(self, text: str) -> tuple[float, float, list]:
        """didChange and wait for the document's diagnostics; (latency, time until all files, them)."""
        self.version += 1
        futs = {u: self.c.expect(u) for u in self.uris}
        t0 = self.c.change(self.doc.uri, self.version, text)
        t_doc, diags = await asyncio.wait_for(futs[self.doc.uri], TIMEOUT)
        done = await asyncio.wait_for(asyncio.gather(*futs.values()), TIMEOUT)
        return t_doc - t0, max(t for t, _ in done) - t0, diags

    async def settle(self, text: str) -> None:
        """didChange, then wait for the document's diagnostics without an error (a re-check whose
        task was cancelled never publishes, so the first such is this text's), then idle()."""
        self.version += 1
        fut = self.c.expect(self.doc.uri)
        self.c.change(self.doc.uri, self.version, text)
        while True:
            _, diags = await asyncio.wait_for(fut, TIMEOUT)
            if not errors_of(diags):
                break
            fut = self.c.expect(self.doc.uri)
        await self.idle()

    async def idle(self) -> None:
        """A hover answered: the last check's index is built (the server builds it after publishing)."""
        await asyncio.wait_for(
            self.c.text_document_hover_async(
                L.HoverParams(
                    text_document=L.TextDocumentIdentifier(uri=self.doc.uri), position=self.doc.pos("drive(", 1)
                )
            ),
            TIMEOUT,
        )
        await asyncio.sleep(0.05)

    # ------------------------------------------------------------------ diagnostics
    async def keystrokes(self, n: int, idle: bool) -> None:
        kinds = ["digit" if i % 2 == 0 else "original" for i in range(n)]
        if n >= 2:
            kinds[(n // 2) & ~1] = "error"  # an even index: the next edit (original) fixes it
        lat, lat_all, shown, cleared = [], [], None, None
        for i, kind in enumerate(kinds):
            if idle:
                await self.idle()
            dt, dt_all, diags = await self.set_text(self.doc.edited(kind))
            lat.append(dt)
            lat_all.append(dt_all)
            errs = errors_of(diags)
            if kind == "error":
                shown = any(d.range.start.line == self.doc.flow for d in errs)
            elif i > 0 and kinds[i - 1] == "error":
                cleared = not errs
            if kind != "error" and errs:
                self.problems.append(f"keystroke {i} ({kind}): unexpected {[d.message for d in errs]}")
        how = "server idle" if idle else "back to back"
        note = f"the error shown: {shown}, then cleared: {cleared}" if shown is not None else ""
        self.row(f"keystroke → the document's diagnostics, {how}", lat, GOAL_DIAG, note)
        self.row(f"keystroke → all 25 files' diagnostics, {how}".replace("25", str(len(self.uris))), lat_all, GOAL_DIAG)
        if shown is False or cleared is False:
            self.problems.append(f"the error edit: shown {shown}, cleared {cleared}")

    async def typing(self, statement: str, interval: float, reps: int = 2) -> None:
        """Type a statement one character at a time; last keystroke → the final text's diagnostics
        (the only ones without an error: every shorter prefix is an unfinished statement)."""
        before, after = self.doc.around()
        finals = []
        for _ in range(reps):
            await self.settle(self.doc.text)
            t_last = 0.0
            for k in range(1, len(statement) + 1):
                self.version += 1
                t_last = self.c.change(self.doc.uri, self.version, before + statement[:k] + after)
                if k < len(statement):
                    await asyncio.sleep(interval)
            while True:
                t, diags = await asyncio.wait_for(self.c.expect(self.doc.uri), TIMEOUT)
                if not errors_of(diags):
                    break
            finals.append(t - t_last)
        await self.settle(self.doc.text)
        self.row(
            f"typing {len(statement)} chars {interval * 1000:.0f} ms apart: last key → its diagnostics",
            finals,
            GOAL_DIAG,
        )

    # ------------------------------------------------------------------ completion
    def completion_cases(self) -> list[tuple[str, str, int, str]]:
        """(name, a valid statement on a new line in the STATION body, the cursor's column in it,
        a label the list must hold)"""
        d = self.doc
        return [
            ("instance.", "  flow := pv_filter.y;", 20, "y"),
            ("instance.member.", "  i := drive.status.last_error;", 21, "state"),
            ("Type#", f"  alarm_level := E_ALARM{d.sfx}#{d.ep}_WARN;", 18 + len(f"E_ALARM{d.sfx}#"), f"{d.ep}_WARN"),
            ("identifier", "  pv_lin := pv;", 5, "pv_filter"),
        ]

    async def complete(self, line: int, col: int) -> tuple[float, list[str]]:
        pos = L.Position(line=line, character=col)
        t0 = time.perf_counter()
        got = await asyncio.wait_for(
            self.c.text_document_completion_async(
                L.CompletionParams(text_document=L.TextDocumentIdentifier(uri=self.doc.uri), position=pos)
            ),
            TIMEOUT,
        )
        dt = time.perf_counter() - t0
        items = got.items if isinstance(got, L.CompletionList) else list(got or [])
        return dt, [i.label for i in items]

    async def completions(self, n: int, mode: str, wait: float = 0.0) -> None:
        """idle: the statement is in the text, checked, its index built; the request alone.
        after / busy: from there a didChange cuts the statement at the cursor and the request
        follows at once / `wait` s later; the statement is then completed and checked again.
        pause: the statement cut one character before the cursor, checked (its diagnostics
        received), then `wait` s later the didChange of the next character and the request."""
        cases = self.completion_cases()
        times: dict[str, list[float]] = defaultdict(list)
        sizes: dict[str, int] = {}
        missed: dict[str, int] = defaultdict(int)
        per_case = max(1, -(-n // len(cases)))
        for name, stmt, col, want in cases:
            full = self.doc.with_line(stmt)
            await self.settle(full)
            for _ in range(per_case):
                if mode == "pause":
                    self.version += 1
                    fut = self.c.expect(self.doc.uri)
                    self.c.change(self.doc.uri, self.version, self.doc.with_line(stmt[: col - 1]))
                    await asyncio.wait_for(fut, TIMEOUT)
                    await asyncio.sleep(wait)
                if mode != "idle":
                    self.version += 1
                    self.c.change(self.doc.uri, self.version, self.doc.with_line(stmt[:col]))
                    if mode == "busy":
                        await asyncio.sleep(wait)
                dt, labels = await self.complete(self.doc.end, col)
                times[name].append(dt)
                sizes[name] = len(labels)
                missed[name] += want not in labels
                if mode != "idle":
                    await self.settle(full)
        await self.settle(self.doc.text)
        label = {
            "idle": "server idle",
            "after": "right after the didChange",
            "busy": f"{wait * 1000:.0f} ms after the didChange (its re-check running)",
            "pause": f"{wait * 1000:.0f} ms after the diagnostics of the text one key before",
        }[mode]
        every = [x for xs in times.values() for x in xs]
        wrong = sum(missed.values())
        self.row(f"completion, {label}", every, GOAL_COMPLETION, f"{wrong} without the expected item" if wrong else "")
        for name, xs in times.items():
            note = f"{missed[name]} of {len(xs)} without {cases[[c[0] for c in cases].index(name)][3]}"
            self.row(f"  · `{name}` ({sizes[name]} items)", xs, GOAL_COMPLETION, note if missed[name] else "")

    # ------------------------------------------------------------------ navigation
    async def navigation(self, n: int) -> None:
        d = self.doc
        spots = [
            d.pos("stats(x := pv_filter.y)", len("stats(x := ") + 2),  # an instance, a call's argument
            d.pos(f"FILTER_PT1{d.sfx}", 2),  # a function block type in a declaration
            d.pos("drive(start", 2),  # an instance called
            d.pos(f"RAW_TO_ENG{d.sfx}(", 3),  # a function's name in a call
        ]
        ident = L.TextDocumentIdentifier(uri=d.uri)
        hover, definition = [], []
        null: dict[str, set[str]] = defaultdict(set)
        for i in range(n):
            p = spots[i % len(spots)]
            text = d.lines[p.line]
            word = re.findall(r"\w+", text[: p.character])[-1] + re.match(r"\w*", text[p.character :]).group()
            where = f"{p.line + 1}:{p.character + 1} `{word}…`"
            t0 = time.perf_counter()
            h = await self.c.text_document_hover_async(L.HoverParams(text_document=ident, position=p))
            hover.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            g = await self.c.text_document_definition_async(L.DefinitionParams(text_document=ident, position=p))
            definition.append(time.perf_counter() - t0)
            if h is None:
                null["hover"].add(where)
            if g is None:
                null["definition"].add(where)
        self.row("hover", hover, None, "null at " + ", ".join(sorted(null["hover"])) if null["hover"] else "")
        self.row(
            "definition",
            definition,
            None,
            "null at " + ", ".join(sorted(null["definition"])) if null["definition"] else "",
        )


async def run(args: argparse.Namespace, folder: Path, paths: list[Path], gc_log: Path | None) -> Bench:
    full = [p for p in paths if re.search(r"^FUNCTION_BLOCK STATION_", p.read_text(), re.M)]
    doc = Doc(full[len(full) // 2])  # a complete module in the middle
    c = Client()
    env = dict(os.environ)
    if gc_log is not None:
        env["PYTHONPATH"] = os.pathsep.join(x for x in (str(gc_log.parent), env.get("PYTHONPATH", "")) if x)
        env["ST_BENCH_GC_LOG"] = str(gc_log)
    t0 = time.perf_counter()
    await c.start_io(sys.executable, "-m", "st.cli", "lsp", env=env)
    stderr = asyncio.create_task(c.drain_stderr())
    await c.initialize_async(
        L.InitializeParams(
            process_id=os.getpid(),
            root_uri=folder.as_uri(),
            workspace_folders=[L.WorkspaceFolder(uri=folder.as_uri(), name=folder.name)],
            capabilities=L.ClientCapabilities(
                text_document=L.TextDocumentClientCapabilities(
                    synchronization=L.TextDocumentSyncClientCapabilities(did_save=True),
                    completion=L.CompletionClientCapabilities(
                        completion_item=L.ClientCompletionItemOptions(snippet_support=True)
                    ),
                    hover=L.HoverClientCapabilities(content_format=[L.MarkupKind.Markdown]),
                    publish_diagnostics=L.PublishDiagnosticsClientCapabilities(),
                )
            ),
        )
    )
    c.initialized(L.InitializedParams())
    t_init = time.perf_counter() - t0
    b = Bench(c, doc, [p.as_uri() for p in paths], c._server.pid)
    b.row("start + initialize", [t_init], None)

    async def cold():
        futs = {u: c.expect(u) for u in b.uris}
        t0 = time.perf_counter()
        c.text_document_did_open(
            L.DidOpenTextDocumentParams(
                text_document=L.TextDocumentItem(uri=doc.uri, language_id="st", version=1, text=doc.text)
            )
        )
        t, diags = await asyncio.wait_for(futs[doc.uri], TIMEOUT)
        done = await asyncio.wait_for(asyncio.gather(*futs.values()), TIMEOUT)
        b.row("didOpen → first diagnostics (cold: the whole project parsed and checked)", [t - t0], None)
        b.row("didOpen → all files' diagnostics", [max(x for x, _ in done) - t0], None)
        if errors_of(diags):
            b.problems.append(f"cold: errors {[d.message for d in errors_of(diags)]}")
        t0 = time.perf_counter()
        await b.idle()
        b.row("then the first hover (waits for the index)", [time.perf_counter() - t0 - 0.05], None)

    statement = "  flow := flow + 1.5;"
    try:
        await b.phase("cold", cold())
        await b.phase("keystrokes, idle", b.keystrokes(args.edits, idle=True))
        await b.phase("keystrokes, back to back", b.keystrokes(args.edits, idle=False))
        for ms_apart in args.type_ms:
            await b.phase(f"typing, {ms_apart:.0f} ms apart", b.typing(statement, ms_apart / 1000))
        await b.phase("completion, idle", b.completions(args.edits, "idle"))
        await b.phase("completion, after didChange", b.completions(args.edits, "after"))
        await b.phase("completion, busy", b.completions(args.edits, "busy", args.busy_ms / 1000))
        await b.phase("completion, after a pause", b.completions(args.edits, "pause", args.pause_ms / 1000))
        await b.idle()
        await b.phase("hover + definition", b.navigation(args.edits))
        await b.phase("idle 3 s (the server's collection)", asyncio.sleep(3.0))
    except (TimeoutError, RuntimeError) as e:
        b.problems.append(f"stopped: {type(e).__name__}: {e}; server stderr: {c.stderr[-10:]}")
    finally:
        try:
            await asyncio.wait_for(c.shutdown_async(None), 30)
            c.exit(None)
            await asyncio.wait_for(c.stop(), 30)
        except (TimeoutError, RuntimeError):
            if c._server is not None and c._server.returncode is None:
                c._server.kill()
        stderr.cancel()
    return b


# ---------------------------------------------------------------------------- in-process split
def split_stages(doc: Doc, runs: int) -> list[tuple[str, float]]:
    """The re-check after a keystroke in this process, as the server's worker thread runs it:
    Analyzer.analyze, its parse and check (st/lsp/analysis.py's names, wrapped), the checker's
    passes (st/compiler/check's), the index built after it, and the full collections; medians."""
    import gc

    from st.compiler import check as checker
    from st.lsp import analysis
    from st.lsp.project import Overlays, project_of, sources_of

    stages: dict[str, list[float]] = defaultdict(list)
    wrapped: list[tuple[object, str, object]] = []

    def wrap(mod: object, name: str, label: str) -> None:
        f = getattr(mod, name, None)
        if not callable(f):
            return

        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return f(*a, **k)
            finally:
                stages[label].append(time.perf_counter() - t0)

        wrapped.append((mod, name, f))
        setattr(mod, name, timed)

    gc_s = [0.0, 0.0]
    ANALYZE, INDEX = "Analyzer.analyze (sources_of included)", "Analysis.index (built after publishing)"
    GC_ANALYZE, GC_INDEX = "  full collections in Analyzer.analyze", "  full collections in Analysis.index"

    def note(phase: str, info: dict) -> None:
        if info["generation"] == 2:
            if phase == "start":
                gc_s[1] = time.perf_counter()
            else:
                gc_s[0] += time.perf_counter() - gc_s[1]

    overlays = Overlays()
    key = project_of(str(doc.path), str(doc.path.parent), overlays)
    analyzer = analysis.Analyzer()
    _ = analyzer.analyze(sources_of(key, overlays, [])).index  # cold, and the first index
    wrap(analysis, "parse", "  parse (the edited file; the others' trees kept)")
    wrap(analysis, "check", "  check (the whole project)")
    passes = re.findall(r"^\s+\(?([a-z_]+)[(,] ?(?:ctx|sem)\b", Path(checker.__file__).read_text(), re.M)
    for name in passes:
        wrap(checker, name, f"    {name}")
    gc.callbacks.append(note)
    try:
        for i in range(runs):
            overlays.texts[str(doc.path)] = doc.edited("digit" if i % 2 == 0 else "original")
            gc_s[0] = 0.0
            t0 = time.perf_counter()
            a = analyzer.analyze(sources_of(key, overlays, []))
            t1 = time.perf_counter()
            stages[ANALYZE].append(t1 - t0)
            stages[GC_ANALYZE].append(gc_s[0])
            gc_s[0] = 0.0
            t1 = time.perf_counter()
            _ = a.index
            stages[INDEX].append(time.perf_counter() - t1)
            stages[GC_INDEX].append(gc_s[0])
    finally:
        gc.callbacks.remove(note)
        for mod, name, f in wrapped:
            setattr(mod, name, f)
    inner = [k for k in stages if k.startswith("  ") and k not in (GC_ANALYZE, GC_INDEX)]
    inner.sort(key=lambda k: (k.startswith("    "), -statistics.median(stages[k])))
    check = [k for k in inner if k.startswith("  check")]
    inner = [k for k in inner if k not in check]
    order = [ANALYZE, *[k for k in inner if not k.startswith("    ")], *check]
    order += [k for k in inner if k.startswith("    ")] + [GC_ANALYZE, INDEX, GC_INDEX]
    return [(k, statistics.median(stages[k])) for k in order if k in stages]


# ---------------------------------------------------------------------------- report
def q(xs: list[float], p: float) -> float:
    s = sorted(xs)
    return s[min(len(s) - 1, max(0, round(p * (len(s) - 1))))]


def ms(x: float) -> str:
    return f"{x * 1000:.0f}" if x >= 0.0095 else f"{x * 1000:.1f}"


def report(b: Bench, n_lines: int, n_files: int, check_ok: bool, gcs: list[tuple[float, float, str]]) -> None:
    print(f"\n`st lsp`, {n_lines} lines in {n_files} files, the document {b.doc.path.name} ({len(b.doc.lines)} lines)")
    print(f"`st check` of the split files: {'no error' if check_ok else 'ERRORS (see above)'}\n")
    print("| what | n | median ms | p90 ms | max ms | goal ms | median/goal | p90/goal | note |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for what, xs, goal, note in b.rows:
        if not xs:
            continue
        med, p90, mx = statistics.median(xs), q(xs, 0.9), max(xs)
        g = [ms(goal), f"{med / goal:.2f}", f"{p90 / goal:.2f}"] if goal else ["", "", ""]
        print(f"| {what} | {len(xs)} | {ms(med)} | {ms(p90)} | {ms(mx)} | {' | '.join(g)} | {note} |")
    print(
        "\n| phase | wall s | server CPU s | threads after | RSS MB after | full collections | their s | longest ms | in main thread |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for i, (name, w0, wall, cpu, n_threads, rss) in enumerate(b.phases):
        w1 = b.phases[i + 1][1] if i + 1 < len(b.phases) else float("inf")
        mine = [(d, who) for t, d, who in gcs if w0 <= t < w1]
        longest = ms(max(d for d, _ in mine)) if mine else ""
        main = sum(1 for _, who in mine if who == "MainThread")
        cpu_s = "" if cpu is None else f"{cpu:.2f}"
        gc_s = sum(d for d, _ in mine)
        print(
            f"| {name} | {wall:.2f} | {cpu_s} | {n_threads or ''} | {rss or ''} | {len(mine)} | {gc_s:.2f} | {longest} "
            f"| {main} |"
        )
    print("\ngoals (p90 against the goal):")
    for what, xs, goal, _ in b.rows:
        if goal and xs and not what.startswith("  "):
            p90 = q(xs, 0.9)
            print(
                f"  {'met   ' if p90 <= goal else 'MISSED'} {what}: p90 {ms(p90)} ms = {p90 / goal:.2f} × {ms(goal)} ms"
            )
    if b.problems:
        print("\nproblems:")
        for p in dict.fromkeys(b.problems):
            print("  -", p)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lines", type=int, default=20000)
    ap.add_argument("--edits", type=int, default=20, help="keystrokes, and requests per completion mode")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--type-ms", type=float, nargs="+", default=[120, 250], help="between keys when typing")
    ap.add_argument("--busy-ms", type=float, default=300, help="completion this long after the didChange")
    ap.add_argument("--pause-ms", type=float, default=200, help="completion this long after a check's diagnostics")
    ap.add_argument("--split", action="store_true", help="also time the re-check's stages in-process")
    ap.add_argument("--no-gc-log", action="store_true", help="no hook noting the server's full collections")
    args = ap.parse_args()
    text = generate(n_lines=args.lines, seed=args.seed)
    with tempfile.TemporaryDirectory(prefix="st-lsp-bench-") as tmp:
        folder = Path(tmp).resolve() / "project"
        folder.mkdir()
        paths = split_library(text, folder)
        print(f"{len(paths)} files, {text.count(chr(10))} lines in {folder}", flush=True)
        check_ok, out = st_check(paths)
        if not check_ok:
            print(out)
        gc_log = None
        if not args.no_gc_log:
            hook = Path(tmp).resolve() / "hook"
            hook.mkdir()
            (hook / "sitecustomize.py").write_text(GC_HOOK)
            gc_log = hook / "gc.log"
        b = asyncio.run(run(args, folder, paths, gc_log))
        report(b, text.count("\n"), len(paths), check_ok, gc_events(gc_log))
        if args.split:
            print("\nthe re-check after a keystroke, in this process (median of 6), ms:")
            for name, t in split_stages(b.doc, 6):
                print(f"  {name:48} {t * 1000:6.0f}")


if __name__ == "__main__":
    main()
