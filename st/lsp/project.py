"""Which files make the project a document belongs to, with the editor's unsaved texts.

A document is checked with the files it is compiled with, as `st check` would be given them:
- a TwinCAT project: the nearest `.plcproj` in the document's folder or above it (within the
  workspace) — its files and the library projects it references (`--lib`/ST_LIBPATH as for
  `st check`), under the twincat preset;
- a PLCopen XML file (`plc.xml`, or any .xml PLCopen writes): that file alone;
- otherwise the `.st` files of the document's folder together, when they make one program: when
  they do not (two CONFIGURATIONs, or one POU name in two files: a folder of separate examples),
  the document alone.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..compiler.driver import load_files
from ..diagnostics import CompileError
from ..source import SourceFile

_CONFIG = re.compile(r"^\s*CONFIGURATION\s+(\w+)", re.I | re.M)
_POU = re.compile(
    r"^\s*(?:PROGRAM|FUNCTION_BLOCK|FUNCTION)\s+(?:ABSTRACT\s+|FINAL\s+|PUBLIC\s+|INTERNAL\s+)*(\w+)", re.I | re.M
)
TWINCAT_SUFFIXES = (".tcpou", ".tcgvl", ".tcdut", ".tcio", ".tctask")


@dataclass
class ProjectKey:
    """What identifies a project: its kind and its root file or folder (documents share a project
    when their keys are equal)."""

    kind: str  # "plcproj", "xml", "folder", "file"
    root: str

    def __hash__(self) -> int:
        return hash((self.kind, self.root))


@dataclass
class Overlays:
    """The editor's texts of open documents (path → text), which win over the files on disk."""

    texts: dict[str, str] = field(default_factory=dict)

    def read(self, path: str) -> str:
        got = self.texts.get(path)
        if got is not None:
            return got
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()


def project_of(path: str, workspace: str | None, overlays: Overlays) -> ProjectKey:
    p = Path(path)
    low = p.name.lower()
    if low.endswith(TWINCAT_SUFFIXES) or low.endswith(".plcproj"):
        found = _plcproj(p, workspace)
        if found is not None:
            return ProjectKey("plcproj", str(found))
        return ProjectKey("file", str(p))
    if low.endswith(".xml"):
        return ProjectKey("xml", str(p))
    folder = p.parent
    found = _plcproj(p, workspace)
    if found is not None and found.parent == folder:
        return ProjectKey("plcproj", str(found))
    if _one_program(folder, overlays):
        return ProjectKey("folder", str(folder))
    return ProjectKey("file", str(p))


def _plcproj(p: Path, workspace: str | None) -> Path | None:
    stop = Path(workspace).resolve() if workspace else None
    d = p.parent.resolve()
    if stop is not None and stop != d and stop not in d.parents:
        stop = None  # a document outside the workspace: its own folder only
    while True:
        try:
            projects = sorted(x for x in d.iterdir() if x.suffix.lower() == ".plcproj")
        except OSError:
            projects = []
        if projects:
            return projects[0]
        if d == stop or d.parent == d or stop is None:
            return None
        d = d.parent


def _st_files(folder: Path) -> list[Path]:
    try:
        return sorted(x for x in folder.iterdir() if x.suffix.lower() == ".st" and x.is_file())
    except OSError:
        return []


def _one_program(folder: Path, overlays: Overlays) -> bool:
    """The folder's .st files make one program: at most one CONFIGURATION, no POU name twice."""
    configs = 0
    names: set[str] = set()
    for f in _st_files(folder):
        try:
            text = overlays.read(str(f))
        except OSError:
            continue
        configs += len(_CONFIG.findall(text))
        for n in _POU.findall(text):
            if n.lower() in names:
                return False
            names.add(n.lower())
    return configs <= 1


def sources_of(key: ProjectKey, overlays: Overlays, lib_path: list[str]) -> list[SourceFile]:
    """The project's sources, each with the editor's text where the document is open."""
    if key.kind in ("folder", "file") and not twincat_file(key.root):
        paths = [str(f) for f in _st_files(Path(key.root))] if key.kind == "folder" else [key.root]
        if key.kind == "folder":  # a new file not saved yet is part of its folder too
            paths += [p for p in overlays.texts if Path(p).parent == Path(key.root) and p.lower().endswith(".st")]
        out = []
        for p in dict.fromkeys(paths):
            try:
                out.append(SourceFile(p, overlays.read(p)))
            except OSError:
                continue
        return out
    paths = [key.root]
    try:
        loaded = load_files(paths, lib_path, _provided())
    except CompileError as e:
        # a file that cannot be read: the others go on, the problem is a diagnostic of it
        return [SourceFile(d.span.file, "", load_diagnostics=[d]) for d in e.diagnostics]
    out = []
    for s in loaded:
        text = overlays.texts.get(s.path)
        if text is None:
            text = overlays.texts.get(os.path.abspath(s.path))
        if text is not None and text != _raw(s.path):
            s = _from_text(s.path, text)
        out.append(s)
    return out


def twincat_file(path: str) -> bool:
    return path.lower().endswith(TWINCAT_SUFFIXES)


def _raw(path: str) -> str | None:
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()
    except OSError:
        return None


def _from_text(path: str, text: str) -> SourceFile:
    """A source from the editor's text of a file, read as load_files reads the file."""
    from ..compiler import plcopen_xml, twincat

    if twincat.is_twincat(path):
        return SourceFile(path, twincat.twincat_source(text))
    if plcopen_xml.handles(path, text):
        st_text, problems = plcopen_xml.plcopen_source(text, path)
        return SourceFile(path, st_text, load_diagnostics=problems)
    return SourceFile(path, text)


def _provided() -> frozenset[str]:
    from ..api import provided_libraries

    return provided_libraries()
