"""What the editor asks, answered from the last analysis and the document's current text.

Each function takes plain values (file, 0-based line and column, the document's text) and an
Analysis, and returns plain values; server.py turns them into LSP messages. Completion reads the
text left of the cursor (a half-typed statement does not parse; the names around it are the last
analysis's).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from typing import Any

from ..compiler.check.passes.namespaces import NAMESPACE_PRAGMA
from ..model import types as T
from ..source import comment_beside
from .analysis import Analysis
from .index import Occurrence, Target, signature, type_name

KEYWORDS = (
    "IF THEN ELSIF ELSE END_IF CASE OF END_CASE FOR TO BY DO END_FOR WHILE END_WHILE REPEAT UNTIL "
    "END_REPEAT EXIT CONTINUE RETURN AND OR XOR NOT MOD TRUE FALSE VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT "
    "VAR_GLOBAL VAR_EXTERNAL VAR_TEMP VAR_STAT CONSTANT RETAIN PERSISTENT END_VAR AT PROGRAM END_PROGRAM "
    "FUNCTION END_FUNCTION FUNCTION_BLOCK END_FUNCTION_BLOCK METHOD END_METHOD PROPERTY END_PROPERTY "
    "INTERFACE END_INTERFACE EXTENDS IMPLEMENTS THIS SUPER TYPE END_TYPE STRUCT END_STRUCT ARRAY "
    "REF_TO REFERENCE POINTER CONFIGURATION END_CONFIGURATION RESOURCE END_RESOURCE TASK WITH ON"
).split()
ELEMENTARY = (
    "BOOL SINT INT DINT LINT USINT UINT UDINT ULINT BYTE WORD DWORD LWORD REAL LREAL TIME LTIME DATE "
    "TIME_OF_DAY TOD DATE_AND_TIME DT STRING WSTRING CHAR WCHAR"
).split()
SNIPPETS = {
    "IF": "IF ${1:condition} THEN\n\t$0\nEND_IF;",
    "IF … ELSE": "IF ${1:condition} THEN\n\t$2\nELSE\n\t$0\nEND_IF;",
    "CASE": "CASE ${1:selector} OF\n\t${2:0}:\n\t\t$0\nEND_CASE;",
    "FOR": "FOR ${1:i} := ${2:0} TO ${3:10} DO\n\t$0\nEND_FOR;",
    "WHILE": "WHILE ${1:condition} DO\n\t$0\nEND_WHILE;",
    "REPEAT": "REPEAT\n\t$0\nUNTIL ${1:condition}\nEND_REPEAT;",
    "FUNCTION_BLOCK": "FUNCTION_BLOCK ${1:Name}\nVAR_INPUT\n\t$2\nEND_VAR\nVAR_OUTPUT\nEND_VAR\n$0\nEND_FUNCTION_BLOCK",
}


@dataclass
class Item:
    """A completion item: label, kind (as Target.kind, or keyword/snippet/type), detail, text to insert."""

    label: str
    kind: str
    detail: str = ""
    insert: str = ""
    snippet: bool = False


# ---------------------------------------------------------------------- hover, definition, references
def occurrence(a: Analysis, file: str, line: int, col: int) -> Occurrence | None:
    return a.index.at(file, line, col)


def hover(a: Analysis, file: str, line: int, col: int) -> str | None:
    o = occurrence(a, file, line, col)
    if o is None:
        return None
    return describe(a, o.target)


def describe(a: Analysis, t: Target) -> str:
    """Markdown: the declaration in a code block, then what it is, where, and its comment."""
    what = {
        "variable": "variable",
        "instance": "function block instance",
        "constant": "constant",
        "global": "global variable",
        "member": "structure member",
        "enum_value": "enumeration value",
        "function": "function",
        "function_block": "function block",
        "program": "program",
        "method": "method",
        "property": "property",
        "action": "action",
        "struct": "structure",
        "enum": "enumeration",
        "type": "type",
        "gvl": "global variable list",
        "namespace": "namespace",
        "program_instance": "program instance",
    }.get(t.kind, t.kind)
    head = t.detail or t.name
    obj = t.obj
    if isinstance(obj, T.VarSym):
        head = f"{obj.section} {t.detail}" if obj.section else t.detail
        ut = T.unalias(obj.type)
        if isinstance(ut, T.POUType) and ut.pou_kind in ("FUNCTION_BLOCK", "INTERFACE"):
            head += "\n" + signature(ut)
    parts = [f"```st\n{head}\n```", f"*{what}*" + (f" of `{t.owner}`" if t.owner else "")]
    if isinstance(obj, T.VarSym) and obj.location:
        parts.append(f"located at `{obj.location}`")
    if t.library:
        parts.append("from a library")
    comment = _comment(a, t)
    if comment:
        parts.append(comment)
    return "\n\n".join(parts)


def _comment(a: Analysis, t: Target) -> str:
    if not t.file or t.line < 0:
        return ""
    src = a.sources.get(t.file)
    if src is None:
        try:
            with open(t.file, encoding="utf-8", errors="replace") as f:
                text = f.read()
        except OSError:
            return ""
    else:
        text = src.text
    return comment_beside(text.splitlines(), t.line + 1, t.col + 1)


def definition(a: Analysis, file: str, line: int, col: int) -> Target | None:
    o = occurrence(a, file, line, col)
    if o is None or not o.target.file or o.target.line < 0:
        return None
    return o.target


def references(a: Analysis, file: str, line: int, col: int, declaration: bool) -> list[tuple[str, Occurrence]]:
    o = occurrence(a, file, line, col)
    if o is None:
        return []
    return [(f, x) for f, x in a.index.references(o.target) if declaration or not x.declaration]


# ---------------------------------------------------------------------- rename
class RenameRefused(ValueError):
    pass


_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def rename(a: Analysis, file: str, line: int, col: int, new: str) -> dict[str, list[tuple[int, int, int, str]]]:
    """{file: [(line, col, length, new text)]} for every occurrence of the name under the cursor."""
    o = occurrence(a, file, line, col)
    if o is None:
        raise RenameRefused("no symbol here to rename")
    t = o.target
    if t.library or not t.file:
        raise RenameRefused(f"{t.name} is declared in a library")
    if not _IDENT.match(new) or new.upper() in KEYWORDS or new.upper() in ELEMENTARY:
        raise RenameRefused(f"{new!r} is not a name ST allows")
    clash = _clash(a, t, new)
    if clash:
        raise RenameRefused(clash)
    out: dict[str, list[tuple[int, int, int, str]]] = {}
    for f, x in a.index.references(t):
        out.setdefault(f, []).append((x.line, x.col, x.length, new))
    return out


def _clash(a: Analysis, t: Target, new: str) -> str:
    low = new.lower()
    if t.kind in ("function", "function_block", "program", "struct", "enum", "type") and a.project is not None:
        if low in a.project.pous or low in a.project.types:
            return f"{new} is declared already"
    if isinstance(t.obj, T.VarSym) and t.obj.owner is not None and low in t.obj.owner.vars:
        return f"{t.obj.owner.name} has a variable {new} already"
    return ""


# ---------------------------------------------------------------------- symbols
def document_symbols(a: Analysis, file: str) -> list[tuple[Target, list[Target]]]:
    """The file's POUs, types and globals, each with its variables, methods, properties and actions."""
    tops = [t for t in a.index.targets if t.file == file and not t.owner and t.kind != "enum_value"]
    kids: dict[str, list[Target]] = {}
    for t in a.index.targets:
        if t.file == file and t.owner:
            kids.setdefault(t.owner.lower(), []).append(t)
    out = []
    for t in sorted(tops, key=lambda t: (t.line, t.col)):
        out.append((t, sorted(kids.get(t.name.lower(), []), key=lambda k: (k.line, k.col))))
    return out


def workspace_symbols(a: Analysis, query: str) -> list[Target]:
    q = query.lower()
    return [
        t
        for t in a.index.targets
        if t.file and not t.library and t.kind != "enum_value" and (not q or q in t.name.lower())
    ]


# ---------------------------------------------------------------------- completion
_MEMBER = re.compile(r"((?:[A-Za-z_]\w*\^?\s*(?:\[[^\]]*\])?\s*\.\s*)*[A-Za-z_]\w*\^?(?:\s*\[[^\]]*\])?)\s*\.\s*(\w*)$")
_ENUM = re.compile(r"([A-Za-z_]\w*)#(\w*)$")
_CALL = re.compile(r"([A-Za-z_][\w.]*)\s*\(([^()]*)$")


def completion(a: Analysis, file: str, line: int, col: int, text: str) -> list[Item]:
    lines = text.splitlines()
    prefix = lines[line][:col] if line < len(lines) else ""
    scope = a.scope_at(file, line)
    pou = scope.pou if scope is not None else None
    m = _ENUM.search(prefix)
    if m:
        return _enum_members(a, m.group(1))
    m = _MEMBER.search(prefix)
    if m:
        return _members(a, pou, m.group(1))
    m = _CALL.search(prefix)
    if m and not re.search(r":=\s*\w*$|=>\s*\w*$", prefix):
        pins = _pins(a, pou, m.group(1), m.group(2))
        if pins:
            return pins + _in_scope(a, pou)
    return _in_scope(a, pou) + _keywords()


def _keywords() -> list[Item]:
    out = [Item(k, "keyword") for k in KEYWORDS]
    out += [Item(k, "type") for k in ELEMENTARY]
    out += [Item(k, "snippet", f"{k.split()[0]} … statement", body, True) for k, body in SNIPPETS.items()]
    return out


def _in_scope(a: Analysis, pou: T.POUType | None) -> list[Item]:
    out: list[Item] = []
    seen: set[str] = set()

    def add(item: Item) -> None:
        if item.label.lower() not in seen:
            seen.add(item.label.lower())
            out.append(item)

    chain = []
    p = pou
    while p is not None:
        chain.append(p)
        if p.owner_fb is not None:
            chain.append(p.owner_fb)
        p = p.base if p.owner_fb is None else p.owner_fb.base
    for p in chain:
        for v in p.vars.values():
            if not v.name.startswith("_"):
                add(Item(v.name, _var_kind(v), f"{v.section} {v.name} : {type_name(v.type)}"))
    if a.project is not None:
        for gs in a.project.global_names.values():
            for g in gs:
                if not g.name.startswith("_"):
                    add(Item(g.name, "global", f"VAR_GLOBAL {g.name} : {type_name(g.type)}"))
        for q in a.project.pous.values():
            if q.owner_fb is None and q.pou_kind in ("FUNCTION", "FUNCTION_BLOCK", "PROGRAM", "INTERFACE"):
                add(Item(q.name, q.pou_kind.lower(), signature(q)))
        for key, t in a.project.types.items():
            if not isinstance(t, T.POUType):
                add(Item(getattr(t, "name", key), "type", f"TYPE {getattr(t, 'name', key)}"))
    return out


def _var_kind(v: T.VarSym) -> str:
    if v.constant:
        return "constant"
    ut = T.unalias(v.type)
    return "instance" if isinstance(ut, T.POUType) and ut.pou_kind in ("FUNCTION_BLOCK", "PROGRAM") else "variable"


def _enum_members(a: Analysis, type_name_: str) -> list[Item]:
    if a.project is None:
        return []
    found = a.project.types.get(type_name_.lower())
    t = T.unalias(found) if found is not None else None
    if not isinstance(t, T.EnumType):
        return []
    return [Item(n, "enum_value", f"{t.name}#{n} = {v}") for n, v in t.members.values()]


def _resolve_chain(a: Analysis, pou: T.POUType | None, chain: str) -> Any:
    """The type the expression `a.b[1].c^` has, read from the declarations (None if unknown)."""
    parts = [p.strip() for p in re.split(r"\.", re.sub(r"\[[^\]]*\]", "[]", chain))]
    first = parts[0]
    indexed = first.endswith("[]") or first.endswith("^[]")
    name = first.replace("[]", "").replace("^", "").strip()
    t: Any = None
    if name.upper() == "THIS" and pou is not None:
        t = pou.owner_fb or pou
    else:
        p = pou
        while p is not None and t is None:
            v = p.vars.get(name.lower())
            if v is None and p.owner_fb is not None:
                v = p.owner_fb.vars.get(name.lower())
            if v is not None:
                t = v.type
            p = p.base if p.owner_fb is None else p.owner_fb.base
        if t is None and a.project is not None:
            gs = a.project.global_names.get(name.lower())
            if gs:
                t = gs[0].type
            elif name.lower() in a.project.types:
                return ("type", a.project.types[name.lower()])
            elif name.lower() in a.project.pous:
                return ("type", a.project.pous[name.lower()])
    t = _step(t, indexed)
    for part in parts[1:]:
        indexed = part.endswith("[]")
        key = part.replace("[]", "").replace("^", "").strip().lower()
        ut = T.unalias(t) if t is not None else None
        if isinstance(ut, T.StructType):
            m = ut.members.get(key)
            t = m.type if m is not None else None
        elif isinstance(ut, T.POUType):
            v = _pou_member(ut, key)
            t = v
        else:
            return None
        t = _step(t, indexed)
    return t


def _pou_member(pou: T.POUType, key: str) -> Any:
    p: T.POUType | None = pou
    while p is not None:
        v = p.vars.get(key)
        if v is not None:
            return v.type
        ps = p.properties.get(key)
        if ps is not None:
            return ps.type
        p = p.base
    return None


def _step(t: Any, indexed: bool) -> Any:
    ut = T.unalias(t) if t is not None else None
    if isinstance(ut, T.RefType):
        ut = T.unalias(ut.target) if getattr(ut, "target", None) is not None else ut
    if indexed and isinstance(ut, T.ArrayType):
        ut = T.unalias(ut.element)
    return ut


def _members(a: Analysis, pou: T.POUType | None, chain: str) -> list[Item]:
    t = _resolve_chain(a, pou, chain)
    if t is None and re.fullmatch(r"[A-Za-z_]\w*", chain.strip()):
        gvl = a.index.gvls.get(chain.strip().lower())
        if gvl is not None and a.project is not None:  # `GVL_Main.`: the list's variables
            return [
                Item(g.name, "constant" if g.constant else "global", f"VAR_GLOBAL {g.name} : {type_name(g.type)}")
                for g in a.project.globals.values()
                if g.span is not None and g.span.file == gvl.file and not g.name.startswith("_")
            ]
        return _namespace_members(a, chain.strip())
    if isinstance(t, tuple):  # `Color.` (a qualified enumeration value), a POU's name
        inner = T.unalias(t[1])
        if isinstance(inner, T.EnumType):
            return [Item(n, "enum_value", f"{inner.name}#{n} = {v}") for n, v in inner.members.values()]
        return []
    if isinstance(t, T.StructType):
        return [Item(m.name, "member", f"{m.name} : {type_name(m.type)}") for m in t.members.values()]
    if isinstance(t, T.POUType):
        own = pou is not None and (pou is t or pou.owner_fb is t)
        out: list[Item] = []
        seen: set[str] = set()
        p: T.POUType | None = t
        while p is not None:
            for v in p.vars.values():
                if v.name.startswith("_") or v.name.lower() in seen:
                    continue
                if own or v.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"):
                    seen.add(v.name.lower())
                    out.append(Item(v.name, _var_kind(v), f"{v.section} {v.name} : {type_name(v.type)}"))
            for m in p.methods.values():
                if m.name.lower() not in seen:
                    seen.add(m.name.lower())
                    out.append(Item(m.name, "method", signature(m)))
            for ps in p.properties.values():
                if ps.name.lower() not in seen:
                    seen.add(ps.name.lower())
                    out.append(Item(ps.name, "property", f"PROPERTY {ps.name} : {type_name(ps.type)}"))
            for name in p.actions:
                if name.lower() not in seen:
                    seen.add(name.lower())
                    out.append(Item(name, "action", f"ACTION {p.name}.{name}"))
            p = p.base
        return out
    return []


_TOP_KINDS = ("FUNCTION", "FUNCTION_BLOCK", "PROGRAM", "INTERFACE")


def _namespace_members(a: Analysis, name: str) -> list[Item]:
    """What `NS.` may name: a library's (st's own: Tc2_Standard, Tc2_System, …) POUs and functions,
    or a referenced library project's (its namespace pragma comes from its .plcproj) POUs, types and
    globals, the ones declared under that project's folder."""
    key = name.lower()
    project = a.project
    if project is None:
        return []
    out: list[Item] = []
    for lib in project.libraries:
        if key in (n.lower() for n in getattr(lib, "namespaces", ())):
            paths = {path for path, _ in getattr(lib, "sources", ())}
            for q in project.pous.values():
                span = getattr(q.decl, "span", None)
                if span is not None and span.file in paths and q.owner_fb is None and q.pou_kind in _TOP_KINDS:
                    out.append(Item(q.name, q.pou_kind.lower(), signature(q)))
            for sig in getattr(lib, "functions", {}).values():
                out.append(Item(sig.name, "function", f"FUNCTION {sig.name}"))
            return out
    folders = [
        os.path.dirname(u.path) + os.sep
        for u in a.units
        if any((m := NAMESPACE_PRAGMA.fullmatch(p.text.strip())) and m.group(1).lower() == key for p in u.pragmas)
    ]
    if not folders:
        return []

    def inside(span: Any) -> bool:
        return span is not None and any(str(span.file).startswith(f) for f in folders)

    for q in project.pous.values():
        if q.owner_fb is None and q.pou_kind in _TOP_KINDS and inside(getattr(q.decl, "span", None)):
            out.append(Item(q.name, q.pou_kind.lower(), signature(q)))
    for k, t in project.types.items():
        if not isinstance(t, T.POUType) and inside(getattr(t, "span", None)):
            out.append(Item(getattr(t, "name", k), "type", f"TYPE {getattr(t, 'name', k)}"))
    for gs in project.global_names.values():
        for g in gs:
            if inside(g.span) and not g.name.startswith("_"):
                out.append(Item(g.name, "global", f"VAR_GLOBAL {g.name} : {type_name(g.type)}"))
    return out


def _pins(a: Analysis, pou: T.POUType | None, callee: str, inside: str) -> list[Item]:
    t = _resolve_chain(a, pou, callee)
    target = t[1] if isinstance(t, tuple) else t
    if not isinstance(target, T.POUType):
        return []
    given = {m.lower() for m in re.findall(r"(\w+)\s*(?::=|=>)", inside)}
    out = []
    for v in target.vars.values():
        if v.name.startswith("_") or v.name.lower() in given:
            continue
        if v.section in ("VAR_INPUT", "VAR_IN_OUT"):
            out.append(Item(f"{v.name} :=", "pin", f"{v.section} {v.name} : {type_name(v.type)}", f"{v.name} := "))
        elif v.section == "VAR_OUTPUT":
            out.append(Item(f"{v.name} =>", "pin", f"VAR_OUTPUT {v.name} : {type_name(v.type)}", f"{v.name} => "))
    return out


# ---------------------------------------------------------------------- semantic tokens
TOKEN_TYPES = ["namespace", "type", "class", "enum", "interface", "struct", "parameter", "variable", "property",
               "enumMember", "function", "method"]  # fmt: skip
TOKEN_MODIFIERS = ["declaration", "readonly", "defaultLibrary", "instance"]  # instance: of a function block
_TOKEN_OF = {
    "function_block": "class",
    "program": "class",
    "interface": "interface",
    "struct": "struct",
    "enum": "enum",
    "type": "type",
    "enum_value": "enumMember",
    "function": "function",
    "method": "method",
    "action": "method",
    "property": "property",
    "member": "property",
    "constant": "variable",
    "global": "variable",
    "variable": "variable",
    "instance": "variable",
    "gvl": "namespace",
    "namespace": "namespace",
    "configuration": "namespace",
    "resource": "namespace",
    "task": "variable",
    "program_instance": "variable",
}


def semantic_tokens(a: Analysis, file: str) -> list[int]:
    """The LSP's relative encoding: for every occurrence (line delta, start delta, length, type, modifiers)."""
    data: list[int] = []
    last_line = last_col = 0
    for o in a.index.occurrences.get(file, []):
        t = o.target
        kind = _TOKEN_OF.get(t.kind)
        if kind is None:
            continue
        if isinstance(t.obj, T.VarSym) and t.obj.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and t.owner:
            kind = "parameter"
        mods = 0
        if o.declaration:
            mods |= 1
        if t.kind in ("constant", "enum_value"):
            mods |= 2
        if t.library:
            mods |= 4
        if t.kind == "instance":
            mods |= 8
        dl = o.line - last_line
        dc = o.col - last_col if dl == 0 else o.col
        data += [dl, dc, o.length, TOKEN_TYPES.index(kind), mods]
        last_line, last_col = o.line, o.col
    return data
