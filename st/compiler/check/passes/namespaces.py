"""Pass 0, namespaces: `Lib.X` where Lib is a library the compilation loads (Tc2_Standard,
Tc2_System, …) or the project's own namespace (`{namespace 'TcUnit'}`, from a .plcproj) names X
itself. Every library's names share one scope here, so the qualifier is dropped before anything
is resolved: in type names, EXTENDS/IMPLEMENTS, calls, enumeration values and variables
(`SysFile.SysTypes.X`: nested qualifiers too). A name declared as a variable anywhere is never
taken for a namespace. What stays dotted with an unknown first part is reported where the type or
block is looked up (`unknown_namespace`)."""

from __future__ import annotations

import dataclasses
import re
from typing import Any

from ... import ast as A
from ..context import CheckContext

NAMESPACE_PRAGMA = re.compile(r"\{\s*namespace\s+'([A-Za-z_][A-Za-z0-9_]*)'\s*\}", re.I)
_SKIP = frozenset({"span", "ty", "const", "sym", "name_span", "end_span"})  # (a call's target: not set yet)
_KEEP = frozenset({"__system.iqueryinterface"})  # CODESYS's root interface: known by its full name
_fields: dict[type, tuple[str, ...]] = {}


def resolve_namespaces(ctx: CheckContext, units: list[A.Unit]) -> None:
    for lib in ctx.libraries:
        ctx.namespaces.update((n.lower(), n) for n in lib.namespaces)
    for u in units:
        for p in u.pragmas:
            m = NAMESPACE_PRAGMA.fullmatch(p.text)
            if m:
                ctx.namespaces[m.group(1).lower()] = m.group(1)
    if not ctx.namespaces:
        return
    variables: set[str] = set()
    for u in units:
        _variables(u, variables)
    known = frozenset(k for k in ctx.namespaces if k not in variables)
    if known:
        for u in units:
            if u.unqualified_for != known:  # (a tree checked again, by the language server: done)
                _Rewrite(set(known)).node(u)
                u.unqualified_for = known


def unqualified(name: str, namespaces: set[str] | dict[str, str]) -> str:
    """`Lib.Sub.X` → `X` while the leading parts are namespaces; other names unchanged."""
    if "." not in name or name.lower() in _KEEP:
        return name
    parts = name.split(".")
    while len(parts) > 1 and parts[0].lower() in namespaces:
        parts.pop(0)
    return ".".join(parts)


def unknown_namespace(name: str, namespaces: dict[str, str]) -> str:
    """The message for a dotted type or block name whose qualifier is no library: '' if not dotted."""
    if "." not in name:
        return ""
    first = name.split(".")[0]
    known = ", ".join(sorted(namespaces.values(), key=str.lower)) or "none"
    return f"'{name}': no library '{first}' is available (namespaces here: {known})"


def _variables(node: Any, out: set[str]) -> None:
    if isinstance(node, A.VarDecl):
        out.update(n.lower() for n, _ in node.names)
        return
    if isinstance(node, list):
        for x in node:
            _variables(x, out)
        return
    for name in ("items", "var_blocks", "decls", "methods", "properties", "get", "set", "resources"):
        sub = getattr(node, name, None)
        if sub is not None:
            _variables(sub, out)


class _Rewrite:
    def __init__(self, namespaces: set[str]):
        self.ns = namespaces

    def node(self, n: Any) -> Any:
        if isinstance(n, list):
            for i, x in enumerate(n):
                n[i] = self.node(x)
            return n
        if isinstance(n, tuple):
            return tuple(self.node(x) for x in n)
        if type(n).__module__ != A.__name__:
            return n
        for f in _field_names(type(n)):
            v = getattr(n, f)
            if v is None or isinstance(v, (int, float, bool)):
                continue
            setattr(n, f, self.node(v))
        if isinstance(n, A.Field) and isinstance(n.base, A.Name) and n.base.name.lower() in self.ns:
            return A.Name(n.span, n.name)
        if isinstance(n, A.NamedType):
            n.name = unqualified(n.name, self.ns)
        elif isinstance(n, A.POU):
            n.extends = unqualified(n.extends, self.ns)
            n.implements = [unqualified(x, self.ns) for x in n.implements]
        elif isinstance(n, A.Interface):
            n.extends = [unqualified(x, self.ns) for x in n.extends]
        return n


def _field_names(cls: type) -> tuple[str, ...]:
    names = _fields.get(cls)
    if names is None:
        names = tuple(f.name for f in dataclasses.fields(cls) if f.name not in _SKIP)
        _fields[cls] = names
    return names
