"""A POU does not call itself, directly or through others: E032 under the presets whose
`recursion_allowed` is off (iec, openplc: IEC 61131-3 and MatIEC do not allow recursion), W013
under codesys, twincat and the default (CODESYS warns and runs it; a recursion that goes too deep
faults with RECURSION at run time). Checked once the bodies are (each call knows its target).

The call graph has a node for every body that runs: a FUNCTION, a function block's or program's
body, a METHOD, a property's GET and SET, an ACTION. An edge is a call whose body is known from
the declarations (see `_Graph.targets`): a function; a method, property or action of the running
instance (every body that can run there: the block's own or inherited one, and the overrides in the
blocks that extend it); SUPER^'s; an instance held by value (a variable, a field, an array
element: its declared type's); and a call through an interface, a pointer, a reference or a
VAR_IN_OUT where the program has one body it can run. Where it has several, the body depends on
what the variable refers to at run time: not an edge (the runtime's RECURSION fault covers it).

Codes: E032, W013.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ...syntax import decl_of, declared
from ..common import SUPER, THIS
from ..context import CheckContext
from ..memo import TreeMemo, remembered
from ..targets import ActionCall, FbCall, FunctionCall, MethodCall


class _Graph:
    """The bodies of the program and the calls between them whose target the declarations show."""

    def __init__(self, pous, memo: TreeMemo | None = None) -> None:
        self.memo = memo
        self.names: dict[int, str] = {}  # node → what a message calls it ("method FB_A.M")
        self.bodies: list[tuple[Any, list, Any]] = []  # (node, what runs, the block THIS is)
        self.blocks = [p for p in pous if p.pou_kind in ("FUNCTION_BLOCK", "PROGRAM")]
        self._kin: dict[int, list] = {}
        for pou in pous:
            d = declared(pou)
            if d is None or pou.pou_kind in ("INTERFACE", "TEST"):
                continue
            block = pou if pou.pou_kind in ("FUNCTION_BLOCK", "PROGRAM") else None
            kind = {"FUNCTION": "", "PROGRAM": "program ", "FUNCTION_BLOCK": "function block "}.get(pou.pou_kind)
            if kind is None:
                continue
            self._add(pou, f"{kind}{pou.name}", [d.body, getattr(d, "transitions", [])], block)
            for mt in pou.methods.values():
                if mt.owner_fb is pou and mt.decl is not None:
                    self._add(mt, f"method {pou.name}.{mt.name}", [decl_of(mt).body], pou)
            for ps in pou.properties.values():
                if ps.owner is not pou:
                    continue
                for acc, which in ((ps.get, "GET"), (ps.set, "SET")):
                    if acc is not None and acc.decl is not None:
                        self._add(acc, f"property {pou.name}.{ps.name} ({which})", [decl_of(acc).body], pou)
            for act in getattr(d, "actions", ()):
                self._add(act, f"action {pou.name}.{act.name}", [act.body], block or pou)

    def _add(self, node, name: str, body: list, block) -> None:
        self.names[id(node)] = name
        self.bodies.append((node, body, block))

    def kin(self, t: T.POUType) -> list:
        """The blocks an instance of static type t may be: t's implementations or extensions."""
        got = self._kin.get(id(t))
        if got is None:
            got = self._kin[id(t)] = [b for b in self.blocks if T.implements(b, t)]
        return got

    def edges(self) -> dict[int, list[tuple[int, Span]]]:
        out: dict[int, list[tuple[int, Span]]] = {}
        for node, body, block in self.bodies:
            calls = out.setdefault(id(node), [])
            sites = remembered(self.memo, "calls", tuple(body), partial(_call_sites, body))
            for x, written in sites:
                for target in self.targets(x, block, written):
                    if id(target) in self.names:
                        calls.append((id(target), x.span))
        return out

    def targets(self, x, block, written: bool) -> list:
        """The bodies that node x (a call, a property read or written) runs, as far as the
        declarations show them."""
        if isinstance(x, A.Call) and x.target is not None:
            match x.target:
                case FunctionCall(pou=pou):
                    return [pou]
                case MethodCall(pou=mt, obj=obj):
                    name = mt.name.lower()
                    return self._on(obj, block, lambda t: t.methods.get(name))
                case FbCall():
                    return self._on(x.callee, block, lambda t: t)
                case ActionCall(name=act, inst=inst):
                    return self._on(inst, block, lambda t: t.actions.get(act))
            return []
        if isinstance(x, (A.Name, A.Field)) and isinstance(x.sym, T.PropSym):
            name = x.sym.name.lower()

            def accessor(t):
                ps = t.properties.get(name)
                return None if ps is None else (ps.set if written else ps.get)

            return self._on(x.base if isinstance(x, A.Field) else None, block, accessor)
        return []

    def _on(self, obj, block, member) -> list:
        """The bodies `member(block type)` of a call on the instance `obj` (None: the running one)."""
        if obj is None or _is(obj, THIS):
            if block is None:
                return []
            every = (member(t) for t in self.kin(block))  # THIS: the block or one that extends it
            return list({id(b): b for b in every if b is not None}.values())
        if _is(obj, SUPER):
            base = block.base if block is not None else None
            got = member(base) if base is not None else None
            return [got] if got is not None else []
        t = T.unalias(obj.ty) if obj.ty is not None else None
        if not isinstance(t, T.POUType) or t.pou_kind == "FUNCTION":
            return []
        if t.pou_kind != "INTERFACE" and _held_by_value(obj):
            got = member(t)
            return [got] if got is not None else []
        # through an interface, a pointer, a reference, a VAR_IN_OUT: known when only one body can run
        bodies = {id(b): b for b in (member(k) for k in self.kin(t)) if b is not None and id(b) in self.names}
        return list(bodies.values()) if len(bodies) == 1 else []


def _call_sites(body: list) -> list[tuple[Any, bool]]:
    """The nodes of a body that may run another body (calls, names and fields: a property),
    each with whether it is written (an assignment's target, an output argument's variable)."""
    out = []
    written = set()  # (an assignment or an argument comes before its target in the walk)
    for x in A.walk_nodes(body):
        if isinstance(x, A.Assign):
            written.add(id(x.target))
        elif isinstance(x, A.Arg):
            if x.output:
                written.add(id(x.value))
        elif isinstance(x, (A.Call, A.Name, A.Field)):
            out.append((x, id(x) in written))
    return out


def _is(obj, which) -> bool:
    """Is obj THIS (THIS^, THIS) or SUPER (SUPER^)?"""
    if isinstance(obj, A.Deref):
        obj = obj.base
    return isinstance(obj, A.Name) and obj.sym is which


def _held_by_value(obj) -> bool:
    """Is obj an instance itself (a variable, a field, an array element), not reached through a
    pointer, a reference, a VAR_IN_OUT or a function's result?"""
    if isinstance(obj, A.Index):
        return True
    if isinstance(obj, (A.Name, A.Field)):
        sym = obj.sym
        sym = getattr(sym, "global_ref", None) or sym
        if getattr(sym, "section", "") == "VAR_IN_OUT":
            return False
        t = getattr(sym, "type", None)
        return t is not None and not T.is_reference(t) and isinstance(T.unalias(t), T.POUType)
    return False


def check_recursion(ctx: CheckContext) -> None:
    """Every body that calls itself, directly or through others: E032 (or W013) where the call that
    closes the circle stands (one per body in a circle)."""
    graph = _Graph(list(ctx.project.pous.values()), ctx.memo)
    edges = graph.edges()
    circled = _in_circles(edges)
    for node, _body, _block in graph.bodies:
        start = id(node)
        if start not in circled:
            continue
        seen: set[int] = set()
        came: dict[int, int] = {}
        stack = [(target, span, start) for target, span in reversed(edges.get(start, ()))]
        while stack:
            target, span, frm = stack.pop()
            if target == start:
                _report(ctx, graph.names, span, start, frm, came)
                break
            if target in seen or circled.get(target) != circled[start]:
                continue
            seen.add(target)
            came[target] = frm
            stack.extend((t, s, target) for t, s in reversed(edges.get(target, ())))


def _report(ctx: CheckContext, names: dict[int, str], span: Span, start: int, last: int, came: dict[int, int]) -> None:
    """E032 where the dialect forbids recursion, else W013."""
    if ctx.dialect is not None and not ctx.dialect.recursion_allowed:
        ctx.err(Code.RECURSION, span, _message(names, start, last, came, "is not allowed in IEC 61131-3"))
    else:
        ctx.warn(
            Code.RECURSIVE_CALL,
            span,
            _message(names, start, last, came, "runs as in CODESYS; IEC 61131-3 does not allow it"),
            "a recursion that goes too deep faults with RECURSION",
        )


def _message(names: dict[int, str], start: int, last: int, came: dict[int, int], verdict: str) -> str:
    path = []
    x = last
    while x != start:
        path.append(names[x])
        x = came[x]
    via = f" through {', '.join(reversed(path))}" if path else ""
    return f"{names[start]} calls itself{via} (recursion {verdict})"


def _in_circles(edges: dict[int, list[tuple[int, Span]]]) -> dict[int, int]:
    """The nodes on a circle of calls, each with its strongly connected component's number
    (Tarjan's algorithm, without recursion)."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    on_stack: set[int] = set()
    stack: list[int] = []
    comp: dict[int, int] = {}
    counter = 0
    for root in edges:
        if root in index:
            continue
        work = [(root, 0)]
        while work:
            v, i = work.pop()
            if i == 0:
                index[v] = low[v] = counter
                counter += 1
                stack.append(v)
                on_stack.add(v)
            succ = edges.get(v, ())
            for j in range(i, len(succ)):
                w = succ[j][0]
                if w not in index:
                    work.append((v, j + 1))
                    work.append((w, 0))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                if low[v] == index[v]:
                    members = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        members.append(w)
                        if w == v:
                            break
                    if len(members) > 1 or any(t == v for t, _ in succ):
                        for w in members:
                            comp[w] = v
                if work:
                    u = work[-1][0]
                    low[u] = min(low[u], low[v])
    return comp
