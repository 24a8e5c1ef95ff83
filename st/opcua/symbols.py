"""What the OPC UA server publishes: the symbol configuration applied to the running program.

Built in the PLC's process (and again after an online change) and handed to the server as one
JSON document: a tree of nodes (folders, objects for program and block instances and
structures, variables) with each variable's IEC type, its OPC UA type, its access and the comment
written beside its declaration.

Which variables are published, and how (first that says):
1. the map file (`--opcua-map`): TOML, `[symbols]` with `"pattern" = "read" | "readwrite" | "none"`,
   patterns over instance paths (`gantry.auto`, `gantry.move1.*`), case-insensitive, the last
   matching pattern wins;
2. `{attribute 'symbol' := '…'}` written before the variable's declaration;
3. what the enclosing variable got (a block instance passes it to its inputs and outputs, a
   structure to all its members);
4. `{attribute 'symbol' := '…'}` written before the POU that declares the variable;
5. the default: located variables, globals and a program's inputs and outputs are `read`,
   anything else is not published. Nothing is writable unless 1, 2 or 4 says `readwrite`.
"""

from __future__ import annotations

import fnmatch
import re
import tomllib
from pathlib import Path
from typing import Any

from ..model import types as T
from ..source import comment_beside

READ, READWRITE, NONE = "read", "readwrite", "none"
ACCESS = (READ, READWRITE, NONE)
MAX_NODES = 50_000  # nodes in one address space (an enormous array of blocks is cut there)
MAX_ELEMENTS = 1_000  # objects made for the elements of one array of blocks or structures
_STDLIB = str(Path(__file__).resolve().parents[1] / "stdlib")

_SYMBOL = re.compile(r"\{\s*attribute\s+'symbol'\s*:=\s*'([^']*)'\s*\}", re.I)

# IEC elementary type → the OPC UA built-in type its value is published as
UA_TYPES = {
    "BOOL": "Boolean",
    "SINT": "SByte",
    "INT": "Int16",
    "DINT": "Int32",
    "LINT": "Int64",
    "USINT": "Byte",
    "UINT": "UInt16",
    "UDINT": "UInt32",
    "ULINT": "UInt64",
    "BYTE": "Byte",
    "WORD": "UInt16",
    "DWORD": "UInt32",
    "LWORD": "UInt64",
    "REAL": "Float",
    "LREAL": "Double",
}
_BY_KIND = {"time": "Duration", "tod": "Duration", "date": "DateTime", "dt": "DateTime", "char": "String"}


class MapError(ValueError):
    """A map file that cannot be used: the message names the file and what is wrong."""


def load_map(path: str) -> list[tuple[str, str]]:
    """[(pattern, access)] of a TOML map file, in the file's order."""
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except OSError as e:
        raise MapError(f"error: {path}: cannot read the OPC UA map: {e.strerror}") from None
    except tomllib.TOMLDecodeError as e:
        raise MapError(f"error: {path}: {e}") from None
    table = doc.get("symbols")
    if not isinstance(table, dict):
        raise MapError(f'error: {path}: expected a [symbols] table of "pattern" = "read" | "readwrite" | "none"')
    out = []
    for pattern, access in table.items():
        if access not in ACCESS:
            raise MapError(f"error: {path}: {pattern!r} = {access!r}: the access is one of read, readwrite, none")
        out.append((pattern.lower(), access))
    return out


def ua_type(t: T.Type) -> str | None:
    """The OPC UA built-in type of an elementary, enumerated or string IEC type (None: not one)."""
    ut = T.unalias(t)
    if isinstance(ut, T.EnumType):
        return "Int32"
    if isinstance(ut, T.StringType):
        return "String"
    bt = T.base_of(t)
    name = getattr(bt, "name", "")
    if name in UA_TYPES:
        return UA_TYPES[name]
    return _BY_KIND.get(getattr(bt, "kind", ""))


class _Sources:
    """Pragmas and comments around declarations, read from the program's source texts."""

    def __init__(self, compiled: Any):
        self.compiled = compiled
        self._lines: dict[str, list[str]] = {}

    def lines(self, file: str) -> list[str]:
        got = self._lines.get(file)
        if got is None:
            src = self.compiled.sources.get(file)
            got = self._lines[file] = src.text.splitlines() if src is not None else []
        return got

    def symbol_attribute(self, span: Any) -> str | None:
        """The 'symbol' attribute written on the declaration's line before it, or on the lines
        just above it (pragmas and comments only)."""
        if span is None:
            return None
        lines = self.lines(span.file)
        if not 0 < span.line <= len(lines):
            return None
        m = _SYMBOL.search(lines[span.line - 1][: max(span.col - 1, 0)])
        if m:
            return m.group(1).lower()
        k = span.line - 2
        while k >= 0:
            text = lines[k].strip()
            if not text.startswith(("{", "(*", "//")):
                break
            m = _SYMBOL.search(text)
            if m:
                return m.group(1).lower()
            k -= 1
        return None

    def comment(self, span: Any) -> str:
        """The comment beside the declaration (st.source.comment_beside)."""
        if span is None:
            return ""
        return comment_beside(self.lines(span.file), span.line, span.col)


class _Walk:
    def __init__(self, plc: Any, rules: list[tuple[str, str]]):
        self.plc = plc
        self.rules = rules
        self.src = _Sources(plc.compiled)
        self.nodes: list[dict] = []
        self.count = 0

    def decide(self, path: str, sym: Any, inherited: str | None, pou: Any, default: str) -> str:
        low = path.lower()
        for pattern, access in reversed(self.rules):
            if fnmatch.fnmatchcase(low, pattern):
                return access
        own = self.src.symbol_attribute(getattr(sym, "span", None)) if sym is not None else None
        if own in ACCESS:
            return own
        if inherited is not None:
            return inherited
        decl = getattr(pou, "decl", None) if pou is not None else None
        at_pou = self.src.symbol_attribute(getattr(decl, "span", None)) if decl is not None else None
        if at_pou in ACCESS:
            return at_pou
        return default

    def add(self, node: dict) -> bool:
        if self.count >= MAX_NODES:
            return False
        self.count += 1
        self.nodes.append(node)
        return True

    # ------------------------------------------------------------------ one variable, any type
    def variable(
        self, parent: str, name: str, path: str, t: T.Type, sym: Any, access: str | None, pou: Any, default: str
    ) -> bool:
        """Publish `path` (and what it holds) under `parent`; True when anything was published."""
        ut = T.unalias(t)
        decided = self.decide(path, sym, access, pou, default)
        desc = self.src.comment(getattr(sym, "span", None)) if sym is not None else ""
        ua = ua_type(t)
        if ua is not None:
            if decided == NONE:
                return False
            return self.add(_var(parent, name, path, t, ua, decided, desc, None))
        if isinstance(ut, T.ArrayType):
            el = T.unalias(ut.element)
            eua = ua_type(ut.element)
            if any(hi < lo for lo, hi in ut.dims):
                return False  # ARRAY[*]: its bounds are the caller's
            if eua is not None:
                if decided == NONE:
                    return False
                dims = [hi - lo + 1 for lo, hi in ut.dims]
                node = _var(parent, name, path, ut.element, eua, decided, desc, dims)
                node["lo"] = [lo for lo, _hi in ut.dims]
                return self.add(node)
            if not isinstance(el, (T.StructType, T.POUType)):
                return False
            obj = self._object(parent, name, path, t, desc)
            published = False
            for k, index in enumerate(_indices(ut.dims)):
                if k >= MAX_ELEMENTS:
                    break
                sub = f"[{', '.join(map(str, index))}]"
                published |= self.variable(
                    obj["id"], name + sub, path + sub, ut.element, None, decided if decided != NONE else None, pou, NONE
                )
            return self._keep(obj, published)
        if isinstance(ut, T.StructType):
            obj = self._object(parent, name, path, t, desc)
            inherit = decided if decided != default or access is not None else None
            published = False
            for m in ut.members.values():
                published |= self.variable(obj["id"], m.name, f"{path}.{m.name}", m.type, m, inherit, None, default)
            return self._keep(obj, published)
        if isinstance(ut, T.POUType) and ut.pou_kind == "FUNCTION_BLOCK":
            obj = self._object(parent, name, path, t, desc)
            inherit = decided if decided != default or access is not None else None
            published = self.members(obj["id"], path, ut, inherit)
            return self._keep(obj, published)
        return False  # references, pointers, interfaces: not values a client reads

    def members(self, parent: str, path: str, pou: T.POUType, inherit: str | None) -> bool:
        """The variables of a program or block instance."""
        published = False
        for v in pou.vars.values():
            if v.section in ("VAR_TEMP", "VAR_EXTERNAL") or v.name.startswith("_"):
                continue
            interface = v.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")
            if v.section == "VAR_IN_OUT":
                continue  # the caller's variable: published where it is declared
            passed = inherit if interface else None
            default = READ if v.location else (READ if interface and pou.pou_kind == "PROGRAM" else NONE)
            published |= self.variable(parent, v.name, f"{path}.{v.name}", v.type, v, passed, pou, default)
        return published

    def _object(self, parent: str, name: str, path: str, t: T.Type, desc: str) -> dict:
        node = {"kind": "object", "id": path, "parent": parent, "name": name, "iec": _type_text(t), "desc": desc}
        self.nodes.append(node)
        return node

    def _keep(self, obj: dict, published: bool) -> bool:
        if not published:
            self.nodes.remove(obj)
        else:
            self.count += 1
        return published


def _indices(dims: list[tuple[int, int]]):
    if not dims:
        yield ()
        return
    lo, hi = dims[0]
    for i in range(lo, hi + 1):
        for rest in _indices(dims[1:]):
            yield (i, *rest)


def _var(parent: str, name: str, path: str, t: T.Type, ua: str, access: str, desc: str, dims: list | None) -> dict:
    ut = T.unalias(t)
    node: dict[str, Any] = {
        "kind": "var",
        "id": path,
        "parent": parent,
        "name": name,
        "path": path,
        "ua": ua,
        "iec": _type_text(t) if dims is None else f"ARRAY OF {_type_text(t)}",
        "access": access,
        "desc": desc,
        "dims": dims,
    }
    bt = T.base_of(t)
    node["time"] = getattr(bt, "kind", "") if getattr(bt, "kind", "") in ("time", "tod", "date", "dt") else ""
    if isinstance(ut, T.EnumType):
        node["enum"] = sorted([v, n] for n, v in ut.members.values())
    elif isinstance(ut, T.SubrangeType):
        node["range"] = [ut.lo, ut.hi]
    elif isinstance(bt, T.ElemType) and bt.kind in ("int", "bit"):
        node["range"] = [bt.lo, bt.hi]
    if isinstance(ut, T.StringType):
        node["length"] = ut.length
    return node


def _type_text(t: T.Type) -> str:
    from ..web.describe import type_text  # noqa: PLC0415 - one naming of types for both servers

    return type_text(t)


def describe(plc: Any, name: str, rules: list[tuple[str, str]] | None = None) -> dict:
    """The address space of the running program: {"name", "nodes": [...]} (parents before children)."""
    w = _Walk(plc, rules or [])
    w.nodes.append({"kind": "folder", "id": "Programs", "parent": "", "name": "Programs", "desc": "program instances"})
    for display, _obj, pou in plc.instances.values():
        w._object("Programs", display, display, pou, "")  # shown even with nothing published in it
        w.count += 1
        w.members(display, display, pou, None)
    w.nodes.append({"kind": "folder", "id": "Globals", "parent": "", "name": "Globals", "desc": "global variables"})
    for g in plc.project.globals.values():
        if g.name.startswith("_") or g.span is None or g.span.file.startswith(_STDLIB):
            continue
        try:
            plc.ref(g.name)
        except (KeyError, ValueError):
            continue  # a member of a qualified list, reached by its list's name only
        w.variable("Globals", g.name, g.name, g.type, g, None, None, READ)
    located = [n for n in w.nodes if n["kind"] == "var" and _location(plc, n["path"])]
    if located:
        w.nodes.append(
            {"kind": "folder", "id": "Located", "parent": "", "name": "Located", "desc": "located variables"}
        )
        for n in located:
            addr = _location(plc, n["path"])
            w.add({**n, "id": addr, "parent": "Located", "name": addr})
    return {"name": name, "nodes": w.nodes, "cut": w.count >= MAX_NODES}


def _location(plc: Any, path: str) -> str:
    try:
        b = plc.ref(path).binding
    except (KeyError, ValueError):
        return ""
    return b.addr if b is not None else ""
