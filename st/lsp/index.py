"""What every name in a checked project is: definitions and references by position.

Read off the checked syntax trees (the checker resolves each name to its symbol: `Name.sym`,
`Field.sym`) and the project's model: a *target* is one declared thing (a variable, a POU, a type,
a struct member, a method or property, an enumeration value) with where it is declared; an
*occurrence* is a place in a file that names a target (its declaration too). Positions are
0-based lines and columns of the text the compiler read (for a TwinCAT file: the XML's lines).
"""

from __future__ import annotations

import bisect
import os
import re
import threading
from dataclasses import dataclass, field
from typing import Any

from ..compiler import ast as A
from ..compiler.check import CheckCancelled, NativeCall
from ..compiler.check.intrinsics import INTRINSICS
from ..compiler.check.passes.collect import gvl_name
from ..compiler.check.passes.namespaces import NAMESPACE_PRAGMA
from ..compiler.library import FuncSig
from ..grammar.comments import strip_comments
from ..model import types as T
from ..model.program import Project
from ..source import SourceFile


@dataclass(eq=False)
class Target:
    name: str
    kind: str  # variable, constant, instance, function, function_block, program, method, property,
    # action, type, struct, enum, interface, member, enum_value, global
    file: str = ""  # where it is declared ("" when nowhere in a file: a native function)
    line: int = -1
    col: int = -1
    obj: Any = None  # the model's object (VarSym, POUType, Type, Member, …)
    owner: str = ""  # the POU or type it belongs to ("" for top-level things)
    library: bool = False
    detail: str = ""  # its type or signature, as hover shows it


@dataclass(frozen=True)
class Occurrence:
    line: int
    col: int
    length: int
    target: Target
    declaration: bool = False


@dataclass
class Scope:
    """A POU's lines in a file, and its model (for completion and hover of names in it)."""

    file: str
    first: int  # 0-based lines, inclusive
    last: int
    pou: T.POUType


@dataclass
class Index:
    occurrences: dict[str, list[Occurrence]] = field(default_factory=dict)  # file → sorted by position
    targets: list[Target] = field(default_factory=list)
    scopes: list[Scope] = field(default_factory=list)
    gvls: dict[str, Target] = field(default_factory=dict)  # named global variable lists, by lower name
    _keys: dict[int, Target] = field(default_factory=dict)
    _starts: dict[str, list[tuple[int, int]]] = field(default_factory=dict)

    def at(self, file: str, line: int, col: int) -> Occurrence | None:
        """The occurrence under (line, col), 0-based."""
        occ = self.occurrences.get(file)
        if not occ:
            return None
        starts = self._starts[file]
        k = bisect.bisect_right(starts, (line, col)) - 1
        while k >= 0 and starts[k][0] == line:
            o = occ[k]
            if o.col <= col <= o.col + o.length:
                return o
            k -= 1
        return None

    def references(self, target: Target) -> list[tuple[str, Occurrence]]:
        return [(f, o) for f, occ in self.occurrences.items() for o in occ if o.target is target]

    def scope_at(self, file: str, line: int) -> Scope | None:
        best = None
        for s in self.scopes:
            if s.file == file and s.first <= line <= s.last and (best is None or s.first >= best.first):
                best = s
        return best

    def target_of(self, obj: Any) -> Target | None:
        return self._keys.get(id(obj))


_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_STRING = re.compile(r"'(?:\$.|[^'$\n])*'|\"(?:\$.|[^\"$\n])*\"")


class _Builder:
    def __init__(self, project: Project, sources: dict[str, SourceFile], user_files: set[str]):
        self.project = project
        self.sources = sources
        self.user_files = user_files
        self.index = Index()
        self._lines: dict[str, list[str]] = {}
        self._enum_targets: dict[tuple[str, str], Target] = {}
        self.type_spans: dict[str, Any] = {}
        self.enum_spans: dict[tuple[str, str], Any] = {}
        self._natives: dict[tuple[str, str], Target] = {}
        self.gvls = self.index.gvls

    def lines(self, file: str) -> list[str]:
        got = self._lines.get(file)
        if got is None:
            src = self.sources.get(file)
            got = self._lines[file] = src.text.splitlines() if src is not None else []
        return got

    # ------------------------------------------------------------------ targets
    def target(self, obj: Any, name: str, kind: str, span: Any, owner: str = "", detail: str = "") -> Target:
        t = self.index._keys.get(id(obj))
        if t is not None:
            return t
        file, line, col = "", -1, -1
        if span is not None and getattr(span, "line", 0) > 0:
            file = span.file
            line, col = self.find(file, span.line - 1, span.col - 1, name)
        library = bool(file) and file not in self.user_files
        t = Target(name, kind, file, line, col, obj, owner, library, detail)
        self.index._keys[id(obj)] = t
        self.index.targets.append(t)
        if file and file in self.user_files and line >= 0:
            self.occur(file, line, col, len(name), t, True)
        return t

    def find(self, file: str, line: int, col: int, name: str) -> tuple[int, int]:
        """Where `name` is written at or after (line, col): its declaration's name, not the keyword
        before it."""
        lines = self.lines(file)
        low = name.lower()
        for k in range(line, min(line + 4, len(lines))):
            text = lines[k]
            start = col if k == line else 0
            for m in _WORD.finditer(text, max(start, 0)):
                if m.group().lower() == low:
                    return k, m.start()
        return line, col

    def occur(self, file: str, line: int, col: int, length: int, target: Target, decl: bool = False) -> None:
        if line < 0 or col < 0:
            return
        self.index.occurrences.setdefault(file, []).append(Occurrence(line, col, length, target, decl))

    # ------------------------------------------------------------------ the model
    def model(self, units: list[A.Unit]) -> None:
        p = self.project
        for u in units:  # where each type is declared: its TypeDecl (the model keeps no position)
            for item in u.items:
                if isinstance(item, A.TypeBlock):
                    for td in item.types:
                        self.type_spans.setdefault(td.name.lower(), td.span)
                        if isinstance(td.spec, A.EnumType):
                            for ev in td.spec.values:
                                self.enum_spans.setdefault((td.name.lower(), ev.name.lower()), ev.span)
        for pou in p.pous.values():
            self.pou(pou)
        for key, t in p.types.items():
            self.type_(t, key)
        for g in p.globals.values():
            if g.name.startswith("_") and g.pyname.startswith("_gs_"):
                continue
            self.var(g, "")
        owners = [*p.pous.values(), *(m for q in p.pous.values() for m in q.methods.values() if m.owner_fb is q)]
        for owner in [*owners, None]:  # the names in initializers: `(speed := 1.5, n := 2)`
            syms = owner.vars.values() if owner is not None else p.globals.values()
            for v in syms:
                if v.init is not None and v.span is not None and v.span.file in self.user_files:
                    self.init_names(v.span.file, v.init, v.type)
        for u in units:  # named global variable lists (a .TcGVL: `GVL_Main.x`)
            name = gvl_name(u)
            blocks = [x for x in u.items if isinstance(x, A.VarBlock)]
            if name and blocks:
                members = [g for g in p.globals.values() if g.span is not None and g.span.file == u.path]
                detail = f"VAR_GLOBAL list {name} ({len(members)} variables)"
                sp = blocks[0].span
                gt = Target(
                    name, "gvl", u.path, sp.line - 1, sp.col - 1, None, "", u.path not in self.user_files, detail
                )
                self.index.targets.append(gt)
                self.gvls[name.lower()] = gt

    def pou(self, pou: T.POUType, owner: str = "") -> Target:
        kind = {"FUNCTION_BLOCK": "function_block", "PROGRAM": "program", "FUNCTION": "function"}.get(
            pou.pou_kind, pou.pou_kind.lower()
        )
        if owner:
            kind = "method"
        decl = pou.decl
        t = self.target(pou, pou.name, kind, getattr(decl, "span", None), owner, signature(pou))
        for v in pou.vars.values():
            self.var(v, pou.name)
        for m in pou.methods.values():
            if m.owner_fb is pou or m.owner_fb is None:
                self.pou(m, pou.name)
        for name, a in pou.actions.items():
            span = getattr(a, "span", None)
            self.target(a, getattr(a, "name", name), "action", span, pou.name, f"ACTION {pou.name}.{name}")
        for ps in pou.properties.values():
            if ps.owner is pou:
                self.target(ps, ps.name, "property", ps.span, pou.name, f"PROPERTY {ps.name} : {type_name(ps.type)}")
        return t

    def var(self, v: T.VarSym, owner: str) -> Target | None:
        if v.section == "VAR_EXTERNAL" and v.global_ref is not None:
            g = self.var(v.global_ref, "")
            if g is not None:
                self.index._keys[id(v)] = g
                if v.span is not None and v.span.file in self.user_files:
                    line, col = self.find(v.span.file, v.span.line - 1, v.span.col - 1, v.name)
                    self.occur(v.span.file, line, col, len(v.name), g)
            return g
        ut = T.unalias(v.type)
        block = isinstance(ut, T.POUType) and ut.pou_kind in ("FUNCTION_BLOCK", "PROGRAM")
        kind = "constant" if v.constant else "instance" if block else "variable"
        if owner == "":
            kind = "constant" if v.constant else "global"
        return self.target(v, v.name, kind, v.span, owner, var_detail(v))

    def type_(self, t: T.Type, key: str) -> None:
        ut = t
        name = getattr(t, "name", key)
        span = self.type_spans.get(key) or getattr(t, "span", None)
        if isinstance(ut, T.StructType):
            self.target(t, name, "struct", span, "", f"TYPE {name} : STRUCT")
            for m in ut.members.values():
                self.target(m, m.name, "member", m.span, name, f"{m.name} : {type_name(m.type)}")
        elif isinstance(ut, T.EnumType):
            self.target(t, name, "enum", span, "", f"TYPE {name} : ({', '.join(n for n, _ in ut.members.values())})")
        elif isinstance(ut, T.POUType):
            return
        else:
            self.target(t, name, "type", span, "", f"TYPE {name} : {type_name(getattr(t, 'base', t))}")

    # ------------------------------------------------------------------ the syntax
    def units(self, units: list[A.Unit], stop: threading.Event | None = None) -> None:
        namespaces = self.namespaces(units)
        qualifier = (
            re.compile(r"(?<![\w.#'])(" + "|".join(map(re.escape, namespaces)) + r")(?=\s*\.\s*[A-Za-z_])", re.I)
            if namespaces
            else None
        )
        for u in units:
            if u.path not in self.user_files:
                continue
            if stop is not None and stop.is_set():
                raise CheckCancelled
            for item in u.items:
                self.scope(u.path, item)
                if isinstance(item, A.Configuration):
                    self.config_names(u.path, item)
            for node in A.walk_nodes(u.items):
                self.node(u.path, node)
            if qualifier is not None:
                self.qualifiers(u.path, qualifier, namespaces)

    def namespaces(self, units: list[A.Unit]) -> dict[str, Target]:
        """The namespaces code may qualify names with, lower name → target: st's libraries'
        (`Tc2_Standard.CONCAT`) and each referenced library project's (its .plcproj's pragma)."""
        out: dict[str, Target] = {}
        for lib in self.project.libraries:
            for n in getattr(lib, "namespaces", ()):
                detail = f"NAMESPACE {n}  (st's {lib.name} library)"
                out[n.lower()] = Target(n, "namespace", library=True, detail=detail)
        for u in units:
            for prag in getattr(u, "pragmas", ()):
                m = NAMESPACE_PRAGMA.fullmatch(prag.text.strip())
                if m and m.group(1).lower() not in out:
                    detail = f"NAMESPACE {m.group(1)}  (the library project {os.path.basename(u.path)})"
                    t = Target(m.group(1), "namespace", u.path, 0, 0, None, "", u.path not in self.user_files, detail)
                    out[m.group(1).lower()] = t
        self.index.targets.extend(out.values())
        return out

    def qualifiers(self, file: str, qualifier: re.Pattern, namespaces: dict[str, Target]) -> None:
        """`Tc2_Standard.` in a file's code: the namespace (the checker drops qualifiers from the
        tree, so they are found in the text, comments and strings left out)."""
        src = self.sources.get(file)
        if src is None:
            return
        taken = {(o.line, o.col) for o in self.index.occurrences.get(file, ())}  # a variable of that name
        for line, col, name in _qualifiers_in(file, src.text, qualifier):
            if (line, col) not in taken:
                self.occur(file, line, col, len(name), namespaces[name.lower()])

    def scope(self, file: str, item: Any) -> None:
        if isinstance(item, (A.POU, A.Interface)):
            pou = self.project.pous.get(item.name.lower())
            if pou is None:
                return
            end = item.end_span.line - 1 if item.end_span is not None else item.span.line - 1 + 10_000
            self.index.scopes.append(Scope(file, item.span.line - 1, end, pou))
            for m in getattr(item, "methods", []):
                method = pou.methods.get(m.name.lower())
                if method is not None and m.end_span is not None:
                    self.index.scopes.append(Scope(file, m.span.line - 1, m.end_span.line - 1, method))

    def node(self, file: str, n: Any) -> None:
        if isinstance(n, A.Name):
            if isinstance(n.sym, T.EnumType):  # a bare enumeration value (`mode := Idle`)
                t = self.enum_value(n.sym.name, n.name)
            else:
                t = self._sym_target(n.sym)
            if t is not None:
                self.occur(file, n.span.line - 1, n.span.col - 1, len(n.name), t)
        elif isinstance(n, A.Field):
            if isinstance(n.sym, T.EnumType):  # `E_State.Busy` (CODESYS): the type, then its value
                t = self.enum_value(n.sym.name, n.name)
                base = n.base
                if isinstance(base, A.Name) and base.sym is None:
                    tt = self._type_target(base.name)
                    if tt is not None:
                        self.occur(file, base.span.line - 1, base.span.col - 1, len(base.name), tt)
            else:
                t = self._sym_target(n.sym)
                base = n.base
                if isinstance(base, A.Name) and base.sym is None and base.name.lower() in self.gvls:
                    gt = self.gvls[base.name.lower()]
                    self.occur(file, base.span.line - 1, base.span.col - 1, len(base.name), gt)
            if t is not None and n.name_span is not None:
                self.occur(file, n.name_span.line - 1, n.name_span.col - 1, len(n.name), t)
        elif isinstance(n, A.NamedType):
            t = self._type_target(n.name)
            if t is not None:
                line, col = self.find(file, n.span.line - 1, n.span.col - 1, n.name.rsplit(".", 1)[-1])
                self.occur(file, line, col, len(n.name.rsplit(".", 1)[-1]), t)
        elif isinstance(n, A.EnumLit):
            tt = self._type_target(n.type_name) if n.type_name else None
            if tt is not None:
                self.occur(file, n.span.line - 1, n.span.col - 1, len(n.type_name), tt)
            mt = self.enum_value(n.type_name, n.member)
            if mt is not None:
                line, col = self.find(file, n.span.line - 1, n.span.col - 1 + len(n.type_name), n.member)
                self.occur(file, line, col, len(n.member), mt)
        elif isinstance(n, A.ProgramConfig):
            t = self._type_target(n.type_name)
            if t is not None:
                line, col = self.find(file, n.span.line - 1, n.span.col - 1 + len(n.instance), n.type_name)
                self.occur(file, line, col, len(n.type_name), t)
        elif isinstance(n, A.Call):
            if isinstance(n.target, NativeCall) and isinstance(n.callee, A.Name) and n.callee.sym is None:
                sig = n.target.sig
                t = self.native(sig, n.ty)  # a standard or vendor function implemented natively
                self.occur(file, n.callee.span.line - 1, n.callee.span.col - 1, len(n.callee.name), t)
                params = {p.name.lower(): p for p in sig.params}
                for arg in n.args:
                    p = params.get(sig.aliases.get(arg.name.lower(), arg.name.lower())) if arg.name else None
                    if p is not None:
                        pt = self.native_param(sig, p)
                        line, col = self.find(file, arg.span.line - 1, arg.span.col - 1, arg.name)
                        self.occur(file, line, col, len(arg.name), pt)
            elif (
                isinstance(n.callee, A.Name)
                and n.callee.sym is None
                and n.callee.name.lower() in INTRINSICS
                and n.target is not None
            ):  # ADR, REF, SIZEOF, __NEW, …: the operator and what it gives here
                t = self.intrinsic(n.callee.name.upper(), n.ty)
                self.occur(file, n.callee.span.line - 1, n.callee.span.col - 1, len(n.callee.name), t)
            pou = getattr(n.target, "pou", None)
            if isinstance(pou, T.POUType) and pou.pou_kind == "FUNCTION" and isinstance(n.callee, A.Name):
                if n.callee.sym is None:  # a function's name in its call (the checker binds no symbol to it)
                    t = self._sym_target(pou)
                    if t is not None:
                        self.occur(file, n.callee.span.line - 1, n.callee.span.col - 1, len(n.callee.name), t)
            if isinstance(pou, T.POUType):
                for arg in n.args:
                    v = pou.vars.get(arg.name.lower()) if arg.name else None
                    t = self._sym_target(v) if v is not None else None
                    if t is not None:
                        line, col = self.find(file, arg.span.line - 1, arg.span.col - 1, arg.name)
                        self.occur(file, line, col, len(arg.name), t)
        elif isinstance(n, A.TypeDecl) and isinstance(n.spec, A.EnumType):
            et = self.project.types.get(n.name.lower())
            for ev in n.spec.values:
                t = self.enum_value(n.name, ev.name, et, ev.span)
                if t is not None and ev.span is not None:
                    self.occur(file, ev.span.line - 1, ev.span.col - 1, len(ev.name), t, True)

    def init_names(self, file: str, init: Any, t: Any, depth: int = 0) -> None:
        """Occurrences of the members an initial value names: a structure's, a block instance's
        inputs (`otg : Otg(0.001, 3) := (MaxVelocity := [...])`), inside arrays and each other."""
        ut = T.unalias(t) if t is not None else None
        if ut is None or depth > 20:
            return
        if isinstance(init, A.CtorInit):
            self.init_names(file, init.inner, t, depth + 1)
        elif isinstance(init, A.ArrayInit) and isinstance(ut, T.ArrayType):
            for item in init.items:
                for x in item.items if isinstance(item, A.RepeatInit) else [item]:
                    self.init_names(file, x, ut.element, depth + 1)
        elif isinstance(init, A.StructInit):
            for name, span, value in init.fields:
                member: Any = None
                if isinstance(ut, T.StructType):
                    member = ut.members.get(name.lower())
                elif isinstance(ut, T.POUType):
                    p: T.POUType | None = ut
                    while p is not None and member is None:
                        member = p.vars.get(name.lower())
                        p = p.base
                if member is None:
                    continue
                target = self.index._keys.get(id(member)) or self._sym_target(member)
                if target is not None and span is not None:
                    line, col = self.find(file, span.line - 1, span.col - 1, name)
                    self.occur(file, line, col, len(name), target)
                self.init_names(file, value, getattr(member, "type", None), depth + 1)

    def native(self, sig: FuncSig, result: Any) -> Target:
        """A natively implemented library function: its signature (a result that depends on the
        arguments' types is shown as this call's)."""
        res = sig.result if isinstance(sig.result, str) else type_name(result)
        key = (sig.name.upper(), res)
        got = self._natives.get(key)
        if got is None:
            groups = {p.group: p.constraint for p in sig.params if p.group}
            params = "; ".join(f"{p.name} : {p.group or p.constraint}" for p in sig.params)
            if sig.extensible:
                params += "; …"
            where = ", ".join(f"{g} : {c}" for g, c in groups.items())
            detail = f"FUNCTION {sig.name}({params}) : {res}" + (f"  ({where})" if where else "")
            got = self._natives[key] = Target(sig.name, "function", obj=sig, library=True, detail=detail)
            self.index.targets.append(got)
        return got

    def intrinsic(self, name: str, result: Any) -> Target:
        res = type_name(result) if result is not None else ""
        if "literal" in res:  # a constant's type before it meets its use: nothing to show
            res = ""
        key = (name, res)
        got = self._natives.get(key)
        if got is None:
            detail = f"{name}(…)" + (f" : {res}" if res else "") + "  (an operator of the language)"
            got = self._natives[key] = Target(name, "function", library=True, detail=detail)
            self.index.targets.append(got)
        return got

    def native_param(self, sig: FuncSig, p: Any) -> Target:
        key = (f"{sig.name.upper()}.{p.name.upper()}", "")
        got = self._natives.get(key)
        if got is None:
            detail = f"VAR_INPUT {p.name} : {p.constraint}"
            got = self._natives[key] = Target(p.name, "variable", obj=p, owner=sig.name, library=True, detail=detail)
            self.index.targets.append(got)
        return got

    def config_names(self, file: str, c: A.Configuration) -> None:
        """A configuration's, its resources', tasks' and program instances' names (declarations);
        a program instance's task."""
        self.named(file, c, c.name, "configuration", f"CONFIGURATION {c.name}")
        for r in c.resources:
            self.named(file, r, r.name, "resource", f"RESOURCE {r.name} ON {r.target}")
            tasks = {}
            for td in r.tasks:
                params = ", ".join(f"{k} := …" for k in td.params)
                tasks[td.name.lower()] = self.named(file, td, td.name, "task", f"TASK {td.name}({params})")
            for pc in r.programs:
                detail = f"PROGRAM {pc.instance} WITH {pc.task} : {pc.type_name}"
                self.named(file, pc, pc.instance, "program_instance", detail)
                t = tasks.get(pc.task.lower()) if pc.task else None
                if t is not None:
                    line, col = self.find(file, pc.span.line - 1, pc.span.col - 1 + len(pc.instance), pc.task)
                    self.occur(file, line, col, len(pc.task), t)

    def named(self, file: str, node: Any, name: str, kind: str, detail: str) -> Target | None:
        if not name or node.span is None:
            return None
        t = self.target(node, name, kind, node.span, "", detail)
        return t

    def enum_value(self, type_name: str, member: str, et: Any = None, span: Any = None) -> Target | None:
        key = (type_name.lower(), member.lower())
        got = self._enum_targets.get(key)
        if got is not None:
            return got
        et = et or self.project.types.get(type_name.lower())
        enum = T.unalias(et) if et is not None else None
        if not isinstance(enum, T.EnumType):
            return None
        name, value = enum.members.get(member.lower(), (member, None))
        file, line, col = "", -1, -1
        span = span or self.enum_spans.get(key)
        if span is not None:
            file, line, col = span.file, span.line - 1, span.col - 1
        t = Target(
            name,
            "enum_value",
            file,
            line,
            col,
            None,
            type_name,
            file not in self.user_files,
            f"{type_name}#{name} = {value}",
        )
        self._enum_targets[key] = t
        self.index.targets.append(t)
        return t

    def _sym_target(self, sym: Any) -> Target | None:
        if sym is None:
            return None
        t = self.index._keys.get(id(sym))
        if t is not None:
            return t
        if isinstance(sym, T.POUType):
            return self.pou(sym)
        if isinstance(sym, T.VarSym):
            return self.var(sym, sym.owner.name if sym.owner is not None else "")
        return None

    def _type_target(self, name: str) -> Target | None:
        key = name.lower()
        t = self.project.types.get(key)
        if t is None and "." in key:
            t = self.project.types.get(key.rsplit(".", 1)[-1])
        if t is not None:
            return self.index._keys.get(id(t))
        pou = self.project.pous.get(key) or self.project.pous.get(key.rsplit(".", 1)[-1])
        if pou is not None:
            return self.pou(pou)
        return None


def build_index(
    project: Project,
    units: list[A.Unit],
    sources: dict[str, SourceFile],
    user_files: set[str],
    stop: threading.Event | None = None,
) -> Index:
    """Every name's definition and occurrences. `stop`: set when the index is no longer wanted
    (an edit came): CheckCancelled is raised between files."""
    b = _Builder(project, sources, user_files)
    b.model(units)
    b.units(units, stop)
    idx = b.index
    for file, occ in idx.occurrences.items():
        unique = {(o.line, o.col): o for o in sorted(occ, key=lambda o: (o.line, o.col, not o.declaration))}
        occ[:] = sorted(unique.values(), key=lambda o: (o.line, o.col))
        idx._starts[file] = [(o.line, o.col) for o in occ]
    return idx


_FOUND: dict[str, tuple[str, str, list[tuple[int, int, str]]]] = {}  # file → (pattern, text, qualifiers)


def _qualifiers_in(file: str, text: str, qualifier: re.Pattern) -> list[tuple[int, int, str]]:
    """(line, column, namespace) of each qualifier in a file's code; kept while its text is the
    same (a file not edited is not searched again at the next index)."""
    got = _FOUND.get(file)
    if got is not None and got[0] == qualifier.pattern and got[1] == text:
        return got[2]
    code = strip_comments(text, True)[0]
    code = _STRING.sub(lambda m: " " * len(m.group()), code)
    starts = [0] + [m.end() for m in re.finditer("\n", code)]
    found = []
    for m in qualifier.finditer(code):
        line = bisect.bisect_right(starts, m.start()) - 1
        found.append((line, m.start() - starts[line], m.group(1)))
    _FOUND[file] = (qualifier.pattern, text, found)
    return found


# ---------------------------------------------------------------------- how things are shown
def type_name(t: Any) -> str:
    if t is None:
        return "?"
    name = getattr(t, "name", None)
    if isinstance(name, str) and name:
        return name
    return str(t)


def var_detail(v: T.VarSym) -> str:
    out = f"{v.name} : {type_name(v.type)}"
    if v.location:
        out = f"{v.name} AT {v.location} : {type_name(v.type)}"
    init: Any = v.init
    shown = getattr(init, "text", None) or (repr(init.value) if hasattr(init, "value") else None)
    if v.const_value is not None and not isinstance(v.const_value, (list, dict)):
        shown = shown or str(v.const_value)
    if shown:
        out += f" := {shown}"
    return out


def signature(pou: T.POUType) -> str:
    """`FUNCTION_BLOCK TON (IN : BOOL; PT : TIME) => (Q : BOOL; ET : TIME)`, a function's result type."""
    ins = [v for v in pou.vars.values() if v.section == "VAR_INPUT"]
    outs = [v for v in pou.vars.values() if v.section == "VAR_OUTPUT"]
    inouts = [v for v in pou.vars.values() if v.section == "VAR_IN_OUT"]
    kind = pou.pou_kind if pou.owner_fb is None else "METHOD"
    text = f"{kind} {pou.name}("
    text += "; ".join(f"{v.name} : {type_name(v.type)}" for v in ins)
    if inouts:
        text += ("; " if ins else "") + "; ".join(f"VAR_IN_OUT {v.name} : {type_name(v.type)}" for v in inouts)
    text += ")"
    if outs:
        text += " => (" + "; ".join(f"{v.name} : {type_name(v.type)}" for v in outs) + ")"
    if pou.return_type is not None:
        text += f" : {type_name(pou.return_type)}"
    return text
