"""`st lsp` over real projects no one here wrote: every file opened, every name asked about.

    python bench/lsp_sweep.py CORPORA [--only NAME] [--max-names 4000]

CORPORA holds the public repositories (docs/conformance.md says how to fetch them; nothing of
them is committed). For each project below a server is started in the project's folder (with the
library projects it references on `--lib`, as `st check` is given them); every source file is
opened; then, for each name in its code (outside comments and strings; keywords and literals left
out): hover and go to definition; per file: document symbols, semantic tokens and completion after
the first instance of each block type followed by `.`. Before that, each project is checked twice
in-process with its trees kept, as the server re-checks (the second answer must be the first's).
Counted: answers, empty answers, errors (a
JSON-RPC error or a server that died: there must be none), diagnostics published per file beside
`st check`'s error count for the project, and the time of each request. The names hover leaves
unanswered are listed by how often they occur, the start of a to-do list.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import statistics
import subprocess
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from lsprotocol import types as L
from pygls.lsp.client import LanguageClient

from st.grammar.comments import strip_comments
from st.lsp.features import ELEMENTARY, KEYWORDS

TIMEOUT = 60.0


@dataclass
class Project:
    name: str
    root: str  # under CORPORA: the folder the server is started in (its workspace)
    files: tuple[str, ...]  # globs under root
    libs: tuple[str, ...] = ()  # under CORPORA: library projects (--lib)
    check: tuple[str, ...] = ()  # what `st check` is given (globs under root; none: not compared)


_TC = ("**/*.TcPOU", "**/*.TcGVL", "**/*.TcDUT", "**/*.TcIO")
_PROJ = ("**/*.plcproj",)  # `st check` is given the project (the .st projects: no comparison)

PROJECTS = (
    Project(
        "TcLog",
        "bengeisler-TcLog/src/TcLogProj/TcLog",
        _TC,
        ("tcunit-TcUnit/TcUnit",),
        _PROJ,
    ),
    Project(
        "TcLog's tests",
        "bengeisler-TcLog/src/TcLogProj/TcLogTEST",
        _TC,
        ("bengeisler-TcLog/src/TcLogProj/TcLog", "tcunit-TcUnit/TcUnit"),
        _PROJ,
    ),
    Project("struckig", "stefanbesler-struckig/Struckig", _TC, check=_PROJ),
    Project(
        "struckig's tests",
        "stefanbesler-struckig/tests",
        _TC,
        ("stefanbesler-struckig/Struckig", "tcunit-TcUnit/TcUnit"),
        _PROJ,
    ),
    Project("TcUnit", "tcunit-TcUnit/TcUnit", _TC, check=_PROJ),
    Project(
        "design patterns: State",
        "0w8States-PLC-Design-Patterns/Behavioral_Patterns/State/State_Pattern",
        _TC,
        check=_PROJ,
    ),
    Project(
        "design patterns: Observer",
        "0w8States-PLC-Design-Patterns/Behavioral_Patterns/Observer/Observer_Pattern",
        _TC,
        check=_PROJ,
    ),
    Project("OSCAT for OpenPLC", "wonka929-OSCAT_OpenPLC", ("**/*.st",)),
    Project("OpenPLC sample programs", "gracesrm-OpenPLC_Sample_Programs", ("**/*.st",)),
)

_SKIP = {w.lower() for w in KEYWORDS + ELEMENTARY} | {
    "end_function_block",
    "end_program",
    "end_function",
    "end_method",
    "end_property",
    "end_action",
    "end_interface",
    "end_struct",
    "end_type",
    "end_configuration",
    "end_resource",
    "end_namespace",
    "public",
    "private",
    "protected",
    "internal",
    "final",
    "abstract",
    "get",
    "set",
    "end_get",
    "end_set",
    "union",
    "end_union",
    "extends",
    "implements",
    "pointer",
    "reference",
    "to",
    "of",
    "var_inst",
    "var_config",
    "var_access",
    "non_retain",
}
_NAME = re.compile(r"(?<![\w#%.'\"])[A-Za-z_]\w*")
_STRING = re.compile(r"'(?:\$.|[^'$])*'|\"(?:\$.|[^\"$])*\"")
_CDATA = re.compile(r"<!\[CDATA\[(.*?)\]\]>", re.S)
_LITERAL_PREFIX = re.compile(r"\b(?:T|TIME|LT|LTIME|D|DATE|TOD|DT|TIME_OF_DAY|DATE_AND_TIME)#[\w.:-]+", re.I)


def code_regions(text: str, xml: bool) -> list[tuple[int, int]]:
    """(start, end) offsets of the code in a file: a TwinCAT file's CDATA sections, else all."""
    if not xml:
        return [(0, len(text))]
    return [(m.start(1), m.end(1)) for m in _CDATA.finditer(text)]


def names_in(text: str, xml: bool) -> list[tuple[int, int, str]]:
    """(line, column, name) of every name in the code, 0-based."""
    starts = [0] + [m.end() for m in re.finditer("\n", text)]
    out = []
    for a, b in code_regions(text, xml):
        code = strip_comments(text[a:b], True)[0]
        code = _STRING.sub(lambda m: " " * len(m.group()), code)
        code = _LITERAL_PREFIX.sub(lambda m: " " * len(m.group()), code)
        for m in _NAME.finditer(code):
            word = m.group()
            if word.lower() in _SKIP or re.fullmatch(r"(?i)(16|8|2)", word):
                continue
            pos = a + m.start()
            line = _bisect(starts, pos)
            out.append((line, pos - starts[line], word))
    return out


def _bisect(starts: list[int], pos: int) -> int:
    lo, hi = 0, len(starts) - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if starts[mid] <= pos:
            lo = mid
        else:
            hi = mid - 1
    return lo


@dataclass
class Result:
    name: str
    files: int = 0
    lines: int = 0
    names: int = 0
    hover: int = 0
    definition: int = 0
    errors: list[str] = field(default_factory=list)
    diag_errors: int = 0
    diag_warnings: int = 0
    check_errors: int | None = None
    times: dict[str, list[float]] = field(default_factory=dict)
    unanswered: Counter = field(default_factory=Counter)
    empty_after: Counter = field(default_factory=Counter)  # x of an `x.` completion without items
    completions: int = 0
    completion_empty: int = 0
    alive: bool = True
    cold: float = 0.0
    recheck_differs: int = 0  # projects whose second check (of the same trees) answered otherwise
    projects: int = 0

    def time(self, what: str, dt: float) -> None:
        self.times.setdefault(what, []).append(dt)


def st_check_errors(paths: list[Path], libs: list[str]) -> int | None:
    args = [sys.executable, "-m", "st.cli", "check"]
    for lib in libs:
        args += ["--lib", lib]
    r = subprocess.run(args + [str(p) for p in paths], capture_output=True, text=True, check=False)
    found = re.findall(r"(\d+) errors?", r.stdout + r.stderr)
    if found:
        return int(found[-1])
    return 0 if r.returncode == 0 else None


async def sweep(p: Project, corpora: Path, max_names: int) -> Result:
    root = corpora / p.root
    files = sorted({f for g in p.files for f in root.glob(g)})
    libs = [str(corpora / lib) for lib in p.libs]
    res = Result(p.name, files=len(files))
    if p.check:
        res.check_errors = st_check_errors(sorted({f for g in p.check for f in root.glob(g)}), libs)
    res.projects, res.recheck_differs = recheck(root, files, libs)
    client = LanguageClient("st-lsp-sweep", "1")
    published: dict[str, list] = {}

    last = [time.perf_counter()]

    @client.feature(L.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
    def _diags(params: L.PublishDiagnosticsParams) -> None:
        published[params.uri] = params.diagnostics
        last[0] = time.perf_counter()

    @client.feature(L.WINDOW_LOG_MESSAGE)
    def _log(params: L.LogMessageParams) -> None:
        pass

    cmd = [sys.executable, "-m", "st.cli", "lsp"]
    for lib in libs:
        cmd += ["--lib", lib]
    await client.start_io(*cmd)
    try:
        await client.initialize_async(
            L.InitializeParams(
                process_id=os.getpid(),
                root_uri=root.as_uri(),
                capabilities=L.ClientCapabilities(),
            )
        )
        client.initialized(L.InitializedParams())
        t0 = time.perf_counter()
        texts = {}
        for f in files:
            text = f.read_text(encoding="utf-8-sig", errors="replace")
            texts[f] = text
            res.lines += text.count("\n") + 1
            client.text_document_did_open(
                L.DidOpenTextDocumentParams(
                    text_document=L.TextDocumentItem(uri=f.as_uri(), language_id="st", version=1, text=text)
                )
            )
        while len(published) < len(files) and time.perf_counter() - t0 < TIMEOUT:
            await asyncio.sleep(0.05)
        res.cold = time.perf_counter() - t0
        while time.perf_counter() - last[0] < 2.0 and time.perf_counter() - t0 < 5 * TIMEOUT:
            await asyncio.sleep(0.1)  # each didOpen checks the project again: its last diagnostics
        for f in files:
            for d in published.get(f.as_uri(), []):
                if d.severity == L.DiagnosticSeverity.Error:
                    res.diag_errors += 1
                elif d.severity == L.DiagnosticSeverity.Warning:
                    res.diag_warnings += 1
        per_file = max(1, max_names // max(1, len(files)))
        for f in files:
            uri = f.as_uri()
            ident = L.TextDocumentIdentifier(uri=uri)
            names = names_in(texts[f], f.suffix.lower() != ".st")
            if len(names) > per_file:  # spread over the file
                step = len(names) / per_file
                names = [names[int(i * step)] for i in range(per_file)]
            await _timed(
                res, "documentSymbol", client.text_document_document_symbol_async(L.DocumentSymbolParams(ident))
            )
            await _timed(
                res, "semanticTokens", client.text_document_semantic_tokens_full_async(L.SemanticTokensParams(ident))
            )
            for line, col, word in names:
                res.names += 1
                pos = L.Position(line=line, character=col + 1)
                h = await _timed(res, "hover", client.text_document_hover_async(L.HoverParams(ident, pos)))
                if h is not None and not isinstance(h, Exception):
                    res.hover += 1
                elif h is None:
                    res.unanswered[word] += 1
                g = await _timed(
                    res, "definition", client.text_document_definition_async(L.DefinitionParams(ident, pos))
                )
                if g and not isinstance(g, Exception):
                    res.definition += 1
            # completion after `name.` where the name is the first word of a code line
            lines = texts[f].splitlines()
            for line, col, word in names[:: max(1, len(names) // 20)]:
                end = col + len(word)
                if end < len(lines[line]) and lines[line][end] == ".":
                    got = await _timed(
                        res,
                        "completion",
                        client.text_document_completion_async(
                            L.CompletionParams(ident, L.Position(line=line, character=end + 1))
                        ),
                    )
                    res.completions += 1
                    items = getattr(got, "items", got) or []
                    if isinstance(got, Exception) or not items:
                        res.completion_empty += 1
                        res.empty_after[word] += 1
    except Exception as e:  # noqa: BLE001 - counted: the sweep goes on with the next project
        res.errors.append(f"{type(e).__name__}: {e}")
    finally:
        server = client._server
        res.alive = server is not None and server.returncode is None
        try:
            await asyncio.wait_for(client.shutdown_async(None), 10)
            client.exit(None)
            await asyncio.wait_for(client.stop(), 10)
        except Exception:  # noqa: BLE001
            if server is not None and server.returncode is None:
                server.kill()
    return res


def recheck(root: Path, files: list[Path], libs: list[str]) -> tuple[int, int]:
    """In this process, as the server does: each project the files make checked twice with its
    trees kept; (projects, how many answered otherwise the second time)."""
    from st.lsp.analysis import Analyzer
    from st.lsp.project import Overlays, project_of, sources_of

    def answer(a) -> list:
        return sorted((p, d.code, d.span.line, d.span.col, d.message) for p, ds in a.diagnostics.items() for d in ds)

    overlays = Overlays()
    keys = {project_of(str(f), str(root), overlays) for f in files}
    differ = 0
    for key in keys:
        an = Analyzer()
        first = answer(an.analyze(sources_of(key, overlays, libs)))
        differ += first != answer(an.analyze(sources_of(key, overlays, libs)))
    return len(keys), differ


async def _timed(res: Result, what: str, coro):
    t0 = time.perf_counter()
    try:
        got = await asyncio.wait_for(coro, TIMEOUT)
    except Exception as e:  # noqa: BLE001 - a JSON-RPC error: counted
        res.errors.append(f"{what}: {type(e).__name__}: {e}"[:200])
        got = e
    res.time(what, time.perf_counter() - t0)
    return got


def report(results: list[Result]) -> None:
    print(
        "| project | files | lines | diagnostics E / W (st check's E) | re-check differs | cold s | names | hover |"
        " definition | completion after `x.` | errors | p50 / p99 ms |"
    )
    print("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in results:
        every = sorted(t for ts in r.times.values() for t in ts) or [0.0]
        p99 = every[min(len(every) - 1, int(0.99 * len(every)))]
        hv = f"{r.hover / r.names:.0%}" if r.names else ""
        df = f"{r.definition / r.names:.0%}" if r.names else ""
        comp = f"{r.completions - r.completion_empty}/{r.completions}" if r.completions else ""
        errors = str(len(r.errors)) + ("" if r.alive else ", server died")
        print(
            f"| {r.name} | {r.files} | {r.lines} | {r.diag_errors} / {r.diag_warnings} ({r.check_errors}) | "
            f"{r.recheck_differs} of {r.projects} | "
            f"{r.cold:.1f} | {r.names} | {hv} | {df} | {comp} | {errors} | "
            f"{statistics.median(every) * 1000:.1f} / {p99 * 1000:.0f} |"
        )
    print()
    for r in results:
        if r.errors:
            print(f"{r.name}: errors: {r.errors[:5]}")
        top = ", ".join(f"{w} {n}" for w, n in r.unanswered.most_common(12))
        print(f"{r.name}: hover unanswered most: {top}")
        if r.empty_after:
            top = ", ".join(f"{w} {n}" for w, n in r.empty_after.most_common(12))
            print(f"{r.name}: no completion after: {top}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("corpora", type=Path)
    ap.add_argument("--only", help="projects whose name contains this")
    ap.add_argument("--max-names", type=int, default=4000, help="names asked about per project")
    args = ap.parse_args()
    results = []
    for p in PROJECTS:
        if args.only and args.only.lower() not in p.name.lower():
            continue
        if not (args.corpora / p.root).is_dir():
            print(f"{p.name}: {p.root} not under {args.corpora}, skipped", file=sys.stderr)
            continue
        print(f"{p.name} …", file=sys.stderr, flush=True)
        results.append(asyncio.run(sweep(p, args.corpora, args.max_names)))
    report(results)


if __name__ == "__main__":
    main()
