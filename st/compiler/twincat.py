"""TwinCAT 3 project files as ST sources: .TcPOU, .TcDUT, .TcGVL, .TcIO and the .plcproj that
lists them.

A TwinCAT file is XML whose CDATA sections hold the ST: a POU's declaration and body, each
method's, property accessor's and action's. `twincat_source` turns one file into ST text that
has every CDATA character at the same line and column as in the XML, everything else blanked,
and the keywords TwinCAT leaves implicit (END_FUNCTION_BLOCK, END_METHOD, GET … END_GET,
ACTION … END_ACTION, …) written on lines of the file that hold only XML. So the file is compiled
as it is and every diagnostic names the .TcPOU itself, at the line and column of the code.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import PureWindowsPath

from .layout import Layout

SUFFIXES = (".tcpou", ".tcdut", ".tcgvl", ".tcio")
PROJECT_SUFFIX = ".plcproj"

_TOKEN = re.compile(
    r"<!\[CDATA\[(.*?)\]\]>|<(/?)([A-Za-z_][\w.]*)((?:[^>\"']|\"[^\"]*\"|'[^']*')*?)(/?)>|<\?.*?\?>|<!--.*?-->", re.S
)
COMPILE_ITEM = re.compile(r"<Compile\s+Include\s*=\s*\"([^\"]+)\"")
_NAME_ATTR = re.compile(r"\bName\s*=\s*\"([^\"]*)\"")
_KIND = re.compile(
    r"^\s*(?:\{[^}]*\}\s*|\(\*.*?\*\)\s*|//[^\n]*\n\s*)*"
    r"(FUNCTION_BLOCK|FUNCTION|PROGRAM|INTERFACE)\b",
    re.I | re.S,
)
_CONTAINERS = {"Method": "METHOD", "Property": "PROPERTY", "Get": "GET", "Set": "SET", "Action": "ACTION"}


def is_twincat(path: str) -> bool:
    return path.lower().endswith(SUFFIXES + (PROJECT_SUFFIX,))


def project_namespaces(xml: str) -> str:
    """The project's own namespaces as pragmas (`{namespace 'TcUnit'}`): its Name, Title and
    DefaultNamespace, which its code may qualify its own names with (`TcUnit.FB_TestSuite`)."""
    names = dict.fromkeys(
        m.group(1) for m in re.finditer(r"<(?:Name|Title|DefaultNamespace)>\s*([A-Za-z_]\w*)\s*</", xml)
    )
    return "".join("{namespace '" + n + "'}\n" for n in names)


@dataclass(frozen=True)
class CompileItem:
    """One `<Compile Include="…"/>` of a .plcproj that st reads: the file and where it is named."""

    include: str  # as written: 'POUs\\FB_Test.TcPOU'
    path: str  # the file: the exact path, else one whose names match case-insensitively
    found: bool  # False: no such file, even ignoring case
    line: int  # 1-based line and column of the <Compile element in the .plcproj
    col: int


def compile_items(project_path: str, xml: str) -> list[CompileItem]:
    """The ST files a .plcproj compiles (its `<Compile Include="…"/>` items of .TcPOU/.TcDUT/
    .TcGVL/.TcIO). TwinCAT runs on Windows, where names are case-insensitive: an Include whose
    exact path does not exist is looked up component by component ignoring case."""
    base = os.path.dirname(project_path)
    out = []
    for m in COMPILE_ITEM.finditer(xml):
        rel = PureWindowsPath(m.group(1)).as_posix()
        if not rel.lower().endswith(SUFFIXES):
            continue
        exact = os.path.join(base, rel)
        path = exact if os.path.exists(exact) else find_ignoring_case(base, rel)
        line = xml.count("\n", 0, m.start()) + 1
        col = m.start() - (xml.rfind("\n", 0, m.start()) + 1) + 1
        out.append(CompileItem(m.group(1), path or exact, path is not None, line, col))
    return out


def project_files(project_path: str, xml: str) -> list[str]:
    """The ST files a .plcproj compiles, as paths (see `compile_items`)."""
    return [item.path for item in compile_items(project_path, xml)]


def find_ignoring_case(base: str, rel: str) -> str | None:
    """The path under `base` whose components match `rel`'s ignoring case (an exact match first,
    else the first in sorted order), or None."""
    path = base
    for part in (p for p in rel.split("/") if p and p != "."):
        if part == "..":
            path = os.path.join(path, part)
            continue
        exact = os.path.join(path, part)
        if os.path.exists(exact):
            path = exact
            continue
        try:
            names = sorted(os.listdir(path or "."))
        except OSError:
            return None
        match = next((n for n in names if n.lower() == part.lower()), None)
        if match is None:
            return None
        path = os.path.join(path, match)
    return path


def project_source(xml: str, namespaces: str, lines: Iterable[int] = ()) -> str:
    """The ST a .plcproj stands for in the compilation: its namespace pragmas (`project_namespaces`),
    and, at each line in `lines` (where a diagnostic about the project points: a <Compile> whose file
    is missing, a library reference not found), the XML of that line in a `//` comment at its own
    columns, so that the diagnostic shows it. Every other line is blank."""
    out = Layout(xml)
    if namespaces:
        out.keyword(0, namespaces.replace("\n", " ").strip())
    text_lines = xml.split("\n")
    for n in sorted(set(lines)):
        if 1 < n <= len(text_lines):
            shown = text_lines[n - 1]
            start = len(shown) - len(shown.lstrip())
            if start >= 3:  # room for the '//' before the element
                out.code(out.starts[n - 1], "//")
                out.code(out.starts[n - 1] + start, shown.strip())
    return out.text()


def twincat_source(xml: str) -> str:
    """The ST of one TwinCAT file, laid out at the XML's lines and columns (see the module doc)."""
    out = Layout(xml)
    stack: list[str] = []
    pou_end = ""  # END_FUNCTION_BLOCK etc. of the file's POU, until it is written
    itf = False
    for m in _TOKEN.finditer(xml):
        cdata, closing, tag, attrs, selfclosing = m.groups()
        if cdata is not None:
            out.code(m.start(1), cdata)
            if stack and stack[-1] == "Declaration" and len(stack) >= 2 and stack[-2] in ("POU", "Itf"):
                kind = _KIND.match(cdata)
                if kind is not None:
                    pou_end = "END_" + kind.group(1).upper()
                    itf = kind.group(1).upper() == "INTERFACE"
            continue
        if tag is None:
            continue  # <?xml ?>, comments
        if not closing:
            if tag in ("Method", "Property", "Action") and len(stack) >= 1 and stack[-1] in ("POU", "Itf"):
                if pou_end and not itf:  # members follow the block's END_, as CODESYS writes them in text
                    out.keyword(m.start(), pou_end)
                    pou_end = ""
            if tag == "GVL":  # the list's name: GVL_Main.x reaches its variables (compiler/check)
                name = _NAME_ATTR.search(attrs or "")
                if name:
                    out.keyword(m.start(), "{gvl '" + name.group(1) + "'}")
            if tag in ("Get", "Set"):
                out.keyword(m.start(), _CONTAINERS[tag])
            elif tag == "Action":
                name = _NAME_ATTR.search(attrs or "")
                out.keyword(m.start(), f"ACTION {name.group(1) if name else ''} :")
            if not selfclosing:
                stack.append(tag)
            continue
        # a closing tag
        while stack and stack[-1] != tag:
            stack.pop()
        if not stack:
            continue
        stack.pop()
        parent = stack[-1] if stack else ""
        if tag == "Implementation" and parent == "POU" and pou_end and not itf:
            out.keyword(m.start(), pou_end)
            pou_end = ""
        elif tag in ("Method", "Property", "Get", "Set", "Action"):
            out.keyword(m.start(), "END_" + _CONTAINERS[tag])
        elif tag in ("POU", "Itf") and pou_end:
            out.keyword(m.start(), pou_end)
            pou_end = ""
    return out.text()
