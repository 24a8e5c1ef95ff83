"""The libraries a TwinCAT or CODESYS project references, found as library projects on a search path.

A .plcproj names the libraries it uses: `<PlaceholderReference Include="TcUnit">` (resolved by its
`<DefaultResolution>TcUnit, * (www.tcunit.org)</DefaultResolution>`) or `<LibraryReference
Include="TcUnit, * (www.tcunit.org)">`. st compiles a library from its source project: each reference
is looked up, by name (the Include's first part), among the projects named on the command line and
then in the search path: `--lib PATH` (repeatable: a library .plcproj, or a folder searched
recursively for .plcproj files), then the folders and projects of the environment variable
`ST_LIBPATH` (os.pathsep-separated). A library project matches when its <Name>, <Title>,
<DefaultNamespace> or file stem is the name, case-insensitively. Its files join the compilation as if
it had been named, and its own references are followed (each library once).

System libraries are not searched for: the ones st stands in for with its own libraries (their
namespaces: Tc2_Standard, Tc2_System, Tc2_Utilities, SysFile, ...; the caller passes them) and the
vendors' system libraries (Beckhoff's Tc2_*/Tc3_*, CODESYS's "System" ones, `Base Interfaces`).
A reference that is found nowhere is a warning (W014) at the reference's line of the .plcproj that
names the search path; the uses of the library's names then fail as before ("no library 'X'").

A .plcproj is read once per process while its file is unchanged (path, mtime and size): its
names, references and files (`read_project`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from ..diagnostics import Code, Diagnostic, Severity
from ..source import Span

ENV = "ST_LIBPATH"
PROJECT_SUFFIX = ".plcproj"

# the vendors whose libraries are the runtime's own (TwinCAT: Tc2_Standard, Tc3_Module, ...;
# CODESYS: SysFile, Base Interfaces, ...): never searched for, never reported missing
SYSTEM_VENDORS = frozenset({"beckhoff automation gmbh", "system", "3s - smart software solutions gmbh", "codesys"})

_REFERENCE = re.compile(r"<(PlaceholderReference|LibraryReference)\s+Include\s*=\s*\"([^\"]*)\"[^>]*?(/?)>")
_CHILD = re.compile(r"<(DefaultResolution|Namespace)>\s*([^<]*?)\s*</\1>")
_OWN_NAME = re.compile(r"<(Name|Title|DefaultNamespace)>\s*([^<]*?)\s*</\1>")
_VENDOR = re.compile(r"\(([^()]*)\)\s*$")


@dataclass(frozen=True)
class Reference:
    """One library reference of a project: the library's name, as written, and where."""

    name: str  # 'TcUnit': the Include's first part
    include: str  # the Include attribute as written
    resolution: str  # <DefaultResolution> ('' if none): 'TcUnit, * (www.tcunit.org)'
    namespace: str  # <Namespace> ('' if none): what the project's code qualifies its names with
    line: int  # 1-based line and column of the element in the .plcproj
    col: int

    @property
    def vendor(self) -> str:
        """The vendor in parentheses ('www.tcunit.org'), or the Include's third part
        ('Base Interfaces,newest,System' → 'System'); '' if it names none."""
        for text in (self.resolution, self.include):
            m = _VENDOR.search(text)
            if m:
                return m.group(1).strip()
        parts = [p.strip() for p in self.include.split(",")]
        return parts[2] if len(parts) >= 3 else ""

    @property
    def names(self) -> tuple[str, ...]:
        """The names the library may be found by: the Include's, then its resolution's."""
        second = library_name(self.resolution) if self.resolution else ""
        return tuple(dict.fromkeys(n for n in (self.name, second) if n))


@dataclass(frozen=True)
class Project:
    """What st reads of a .plcproj: the names it is known by and the libraries it references."""

    path: str
    names: frozenset[str]  # lower case: <Name>, <Title>, <DefaultNamespace>, the file stem
    references: tuple[Reference, ...] = field(default=())


def library_name(include: str) -> str:
    """'TcUnit, * (www.tcunit.org)' → 'TcUnit'; 'Base Interfaces,newest,System' → 'Base Interfaces'."""
    return include.split(",", 1)[0].strip()


def _line_col(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def references(xml: str) -> list[Reference]:
    """The library references of a .plcproj's text, in the order written."""
    out = []
    for m in _REFERENCE.finditer(xml):
        tag, include, selfclosing = m.groups()
        body = ""
        if not selfclosing:
            end = xml.find(f"</{tag}>", m.end())
            body = xml[m.end() : end if end >= 0 else len(xml)]
        children = dict(_CHILD.findall(body))
        line, col = _line_col(xml, m.start())
        ns = children.get("Namespace", "")
        out.append(Reference(library_name(include), include, children.get("DefaultResolution", ""), ns, line, col))
    return out


def own_names(path: str, xml: str) -> frozenset[str]:
    """The names a project is known by, lower case: <Name>, <Title>, <DefaultNamespace>, file stem."""
    names = {v.lower() for _k, v in _OWN_NAME.findall(xml) if v}
    names.add(os.path.splitext(os.path.basename(path))[0].lower())
    return frozenset(names)


def is_system(ref: Reference, provided: Collection[str] = ()) -> bool:
    """Is this a system library (never searched for)? One st stands in for (`provided`: lower-case
    namespaces of st's libraries) or one of a runtime vendor's."""
    if any(n.lower() in provided for n in ref.names):
        return True
    return ref.vendor.lower() in SYSTEM_VENDORS


# ---------------------------------------------------------------- reading projects, cached

_projects: dict[str, tuple[tuple[int, int], Project]] = {}


def _stamp(path: str) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_mtime_ns, st.st_size


def read_project(path: str, xml: str | None = None) -> Project | None:
    """The project at `path` (its text `xml` if the caller has read it), once per process while the
    file is unchanged; None if it cannot be read."""
    key = os.path.abspath(path)
    stamp = _stamp(key)
    if stamp is None:
        return None
    got = _projects.get(key)
    if got is not None and got[0] == stamp:
        return got[1]
    if xml is None:
        try:
            with open(key, encoding="utf-8-sig", errors="replace") as f:
                xml = f.read()
        except OSError:
            return None
    project = Project(key, own_names(key, xml), tuple(references(xml)))
    _projects[key] = (stamp, project)
    return project


def projects_in(entry: str) -> list[str]:
    """The .plcproj files a search-path entry gives: itself, or a folder's, recursively (hidden
    folders left out), in sorted order."""
    if os.path.isfile(entry):
        return [os.path.abspath(entry)] if entry.lower().endswith(PROJECT_SUFFIX) else []
    found = []
    for root, dirs, files in os.walk(entry):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        found += [os.path.abspath(os.path.join(root, f)) for f in sorted(files) if f.lower().endswith(PROJECT_SUFFIX)]
    return found


def search_path(lib_path: Iterable[str] = (), environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The search path: the given entries (--lib, lib_path=), then ST_LIBPATH's."""
    env = (os.environ if environ is None else environ).get(ENV, "")
    entries = [str(p) for p in lib_path] + [p for p in env.split(os.pathsep) if p]
    return tuple(dict.fromkeys(entries))


def find(ref: Reference, candidates: Sequence[Project]) -> Project | None:
    """The first candidate known by one of the reference's names."""
    for name in ref.names:
        low = name.lower()
        for p in candidates:
            if low in p.names:
                return p
    return None


# ---------------------------------------------------------------- resolution


@dataclass
class Resolution:
    """The library projects a compilation adds, in the order found, and what could not be found."""

    libraries: list[str] = field(default_factory=list)  # .plcproj paths, each once
    warnings: dict[str, list[Diagnostic]] = field(default_factory=dict)  # .plcproj path → its W014s
    namespaces: dict[str, list[str]] = field(default_factory=dict)  # .plcproj path → namespaces of its references


def resolve(named: Sequence[str], lib_path: Iterable[str] = (), provided: Collection[str] = ()) -> Resolution:
    """The libraries the projects `named` (their .plcproj paths, as given) reference, transitively,
    found among `named` themselves and then in the search path (`lib_path`, ST_LIBPATH)."""
    out = Resolution()
    search = search_path(lib_path)
    provided = {n.lower() for n in provided}
    pairs = [(p, n) for n in named if (p := read_project(n)) is not None]
    given = [p for p, _n in pairs]
    path_of = {p.path: n for p, n in pairs}  # a named project's diagnostics use its name as given
    candidates: list[Project] | None = None  # the search path's projects, read when first needed
    done = {p.path for p in given}
    todo = list(given)
    while todo:
        project = todo.pop(0)
        shown = path_of.get(project.path, project.path)
        for ref in project.references:
            if is_system(ref, provided):
                continue
            lib = find(ref, [p for p in given if p.path != project.path])
            if lib is None:
                if candidates is None:
                    candidates = [p for e in search for f in projects_in(e) if (p := read_project(f)) is not None]
                lib = find(ref, [p for p in candidates if p.path != project.path])
            if lib is None:
                out.warnings.setdefault(shown, []).append(_not_found(shown, ref, search))
                continue
            if ref.namespace:
                out.namespaces.setdefault(shown, []).append(ref.namespace)
            if lib.path not in done:
                done.add(lib.path)
                out.libraries.append(lib.path)
                todo.append(lib)
    return out


def _not_found(project: str, ref: Reference, search: Sequence[str]) -> Diagnostic:
    where = ", ".join(search) if search else f"nothing (no --lib given, {ENV} unset)"
    return Diagnostic(
        Code.LIBRARY_NOT_FOUND,
        Severity.WARNING,
        Span(project, ref.line, ref.col),
        f"library '{ref.name}' not found: no project named here and no library project in the search path "
        f"is named so (searched: {where})",
        f"give its .plcproj, or a folder holding it, with --lib PATH or in {ENV}",
    )
