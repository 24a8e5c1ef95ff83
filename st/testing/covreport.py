"""ST coverage: the data (probes and hits) and its reports, in the terminal and as HTML.

A coverage build (`compile_*(..., coverage=True)`) has one probe per statement line and one per
arm of every IF/ELSIF/ELSE and CASE (implicit ELSE arms included). Reports follow coverage.py's
conventions: `Stmts Miss Branch BrPart Cover Missing`, percent = (lines run + arms taken) /
(lines + arms), rounded down, "12-14, 17->ELSE" for what did not run.
"""

from __future__ import annotations

import html
import os
import sys
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Point:
    """One probe: a statement line, or one arm of the decision at `line`."""

    file: str
    line: int
    kind: str  # "line" or "branch"
    label: str = ""  # branches: "THEN", "ELSIF (line 14)", "ELSE", "implicit ELSE", "CASE 1, 2", "CASE ELSE"
    target: int = 0  # branches: the line of the arm's first statement (0: an empty or implicit arm)


class CoverageData:
    def __init__(self, points=None, hits=None):
        self.points: list = list(points or [])
        self.hits = bytearray(hits) if hits is not None else bytearray(len(self.points))

    def merge(self, other: CoverageData) -> None:
        if other.points == self.points:
            for i, h in enumerate(other.hits):
                if h:
                    self.hits[i] = 1
            return
        index = {p: i for i, p in enumerate(self.points)}
        for p, h in zip(other.points, other.hits):
            k = index.get(p)
            if k is None:
                index[p] = k = len(self.points)
                self.points.append(p)
                self.hits.append(0)
            if h:
                self.hits[k] = 1

    def to_json(self) -> dict:
        return {"points": [[p.file, p.line, p.kind, p.label, p.target] for p in self.points], "hits": list(self.hits)}

    @classmethod
    def from_json(cls, d: dict) -> CoverageData:
        return cls([Point(*p) for p in d["points"]], bytearray(d["hits"]))

    def files(self) -> list:
        by_file: dict = {}
        for p, h in zip(self.points, self.hits):
            by_file.setdefault(p.file, []).append((p, h))
        return [FileCoverage(path, items) for path, items in sorted(by_file.items())]


class FileCoverage:
    def __init__(self, path: str, items: list):
        self.path = path
        lines: dict = {}
        self.arms: list = []  # [(Point, hit)]
        for p, h in items:
            if p.kind == "line":
                lines[p.line] = lines.get(p.line, False) or bool(h)
            else:
                self.arms.append((p, bool(h)))
        self.statements = sorted(lines)
        self.run_lines = {n for n, h in lines.items() if h}
        self.missed = [n for n in self.statements if n not in self.run_lines]
        self.branches = len(self.arms)
        self.branches_taken = sum(1 for _, h in self.arms if h)
        decisions: dict = {}
        for p, h in self.arms:
            decisions.setdefault(p.line, []).append((p, h))
        self.decisions = decisions
        self.partial = sorted(
            n for n, arms in decisions.items() if any(h for _, h in arms) and not all(h for _, h in arms)
        )

    @property
    def percent(self) -> float:
        total = len(self.statements) + self.branches
        if total == 0:
            return 100.0
        return 100.0 * (len(self.run_lines) + self.branches_taken) / total

    def missed_arms(self, line: int) -> list:
        return [p.label for p, h in self.decisions.get(line, []) if not h]

    def missing_ranges(self) -> str:
        """Missed statement lines as ranges of consecutive statements, then the arms never taken of
        decisions that did run ("12-14, 20, 17->ELSE")."""
        parts = []
        stmts = self.statements
        i = 0
        while i < len(stmts):
            if stmts[i] in self.run_lines:
                i += 1
                continue
            j = i
            while j + 1 < len(stmts) and stmts[j + 1] not in self.run_lines:
                j += 1
            parts.append(str(stmts[i]) if i == j else f"{stmts[i]}-{stmts[j]}")
            i = j + 1
        for line in sorted(self.decisions):
            if line in self.run_lines:
                parts += [f"{line}->{label}" for label in self.missed_arms(line)]
        return ", ".join(parts)


def _floor_percent(v: float) -> str:
    n = int(v)
    if n == 100 and v < 100.0:
        n = 99
    return f"{n}%"


def _display(path: str) -> str:
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return path
    return path if rel.startswith("..") else rel


def terminal_report(data: CoverageData, file=None, show_missing: bool = True) -> float:
    """A coverage.py-style table; returns the total percent."""
    file = file or sys.stdout
    files = data.files()
    rows = [
        (
            _display(f.path),
            len(f.statements),
            len(f.missed),
            f.branches,
            len(f.partial),
            _floor_percent(f.percent),
            f.missing_ranges(),
        )
        for f in files
    ]
    n_st = sum(len(f.statements) for f in files)
    n_run = sum(len(f.run_lines) for f in files)
    n_br = sum(f.branches for f in files)
    n_taken = sum(f.branches_taken for f in files)
    total = 100.0 if n_st + n_br == 0 else 100.0 * (n_run + n_taken) / (n_st + n_br)
    rows.append(("TOTAL", n_st, n_st - n_run, n_br, sum(len(f.partial) for f in files), _floor_percent(total), ""))
    width = max([len("Name")] + [len(r[0]) for r in rows])
    head = f"{'Name':<{width}}  {'Stmts':>5}  {'Miss':>5}  {'Branch':>6}  {'BrPart':>6}  {'Cover':>5}"
    if show_missing:
        head += "   Missing"
    print(head, file=file)
    print("-" * len(head), file=file)
    for i, (name, st, miss, br, part, cover, missing) in enumerate(rows):
        if i == len(rows) - 1:
            print("-" * len(head), file=file)
        line = f"{name:<{width}}  {st:>5}  {miss:>5}  {br:>6}  {part:>6}  {cover:>5}"
        if show_missing and missing:
            line += "   " + missing
        print(line.rstrip(), file=file)
    return total


_CSS = """body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse}
td,th{padding:2px 10px;text-align:right}td.name,th.name{text-align:left}
pre{margin:0}.src td{text-align:left;padding:0 6px;font-family:monospace;white-space:pre}
.run{background:#dfd}.miss{background:#fdd}.part{background:#ffc}.n{color:#888;text-align:right}
.note{color:#850;font-style:italic}"""


def html_report(data: CoverageData, directory) -> str:
    """index.html (the table) and one page per ST file; returns the index path."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for k, f in enumerate(data.files()):
        page = f"file_{k}.html"
        (out / page).write_text(_file_page(f), encoding="utf-8")
        rows.append(
            f"<tr><td class='name'><a href='{page}'>{html.escape(_display(f.path))}</a></td>"
            f"<td>{len(f.statements)}</td><td>{len(f.missed)}</td><td>{f.branches}</td>"
            f"<td>{len(f.partial)}</td><td>{_floor_percent(f.percent)}</td></tr>"
        )
    index = out / "index.html"
    index.write_text(
        _page(
            "ST coverage",
            "<h1>ST coverage</h1><table><tr><th class='name'>File</th>"
            "<th>Stmts</th><th>Miss</th><th>Branch</th><th>BrPart</th><th>Cover</th></tr>" + "".join(rows) + "</table>",
        ),
        encoding="utf-8",
    )
    return str(index)


def _file_page(f: FileCoverage) -> str:
    title = html.escape(_display(f.path))
    try:
        lines = Path(f.path).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as e:
        return _page(title, f"<h1>{title}</h1><p>The source cannot be read: {html.escape(str(e))}</p>")
    body = []
    for n, text in enumerate(lines, 1):
        cls, note = "", ""
        if n in f.partial:
            cls = "part"
            note = "; ".join(f"{label} never taken" for label in f.missed_arms(n))
        elif n in f.run_lines:
            cls = "run"
        elif n in f.missed:
            cls = "miss"
        note_html = f" <span class='note'>({html.escape(note)})</span>" if note else ""
        body.append(f"<tr class='{cls}'><td class='n'>{n}</td><td>{html.escape(text)}{note_html}</td></tr>")
    head = (
        f"<h1>{title}</h1><p>{len(f.statements)} statements, {len(f.missed)} missed; {f.branches} "
        f"branches, {f.branches_taken} taken; {_floor_percent(f.percent)}</p>"
    )
    return _page(title, head + "<table class='src'>" + "".join(body) + "</table>")


def _page(title: str, body: str) -> str:
    return (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{title}</title>"
        f"<style>{_CSS}</style></head><body>{body}</body></html>\n"
    )
