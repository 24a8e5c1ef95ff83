"""A FOR loop's body may not write its own control variable: E052 under the presets whose
`writable_for_counter` is off (iec, openplc), nowhere else.

IEC 61131-3 (3rd edition, 7.3.3.4.2: the control variable "shall not be altered by any of the
repeated statements") and MatIEC forbid it: the checker reports each place the body's text shows.
CODESYS and TwinCAT allow it, and their loop tests the value the body left: the lowering
(lower/loops.py) then gives the loop the form that re-tests its counter, from `counter_writes`
here, adding what the text cannot show (other code reaching the variable during the body:
lower/writes.py).

Codes: E052.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ....source import Span
from ... import ast as A
from ..context import CheckContext
from ..targets import Binding, CallTarget, FbCall, FunctionCall, MethodCall, NativeCall, QueryItfCall, RefCall


def check_for_counter(ctx: CheckContext, s: A.For, library: str) -> None:
    """E052 at each place the body of `s` writes its control variable, under a dialect that
    forbids it (st's own libraries are written for every dialect)."""
    d = ctx.dialect
    sym = root_sym(s.var)
    if d is None or d.writable_for_counter or sym is None or library:
        return
    for span, how in counter_writes(s.body, sym):
        ctx.err(
            Code.FOR_COUNTER_WRITTEN,
            span,
            f"'{sym.name}' is the control variable of the FOR on line {s.span.line}: {how} in its body",
            f"IEC 61131-3 and MatIEC forbid it (the {d.name} dialect); count in another variable, or use WHILE",
        )


def root_sym(e):
    """The variable under `x`, `x.f`, `x[i]`, `x.3` (None for anything else)."""
    while isinstance(e, (A.Field, A.Index, A.Bit)):
        e = e.base
    return e.sym if isinstance(e, A.Name) and isinstance(e.sym, T.VarSym) else None


def counter_writes(body: list, sym: T.VarSym) -> list[tuple[Span, str]]:
    """(where, how) for each place of `body` that writes `sym` or lets a call write it: an
    assignment, a nested FOR's counter, an output (=>), VAR_IN_OUT, REFERENCE TO or ANY argument,
    its address or a reference taken (ADR, REF, REF=, __QUERYINTERFACE's result)."""
    found: list[tuple[Span, str]] = []
    for n in A.walk_nodes(body):
        if isinstance(n, A.Assign):
            if root_sym(n.target) is sym:
                found.append((n.target.span, "assigned"))
            if n.kind == "REF=" and root_sym(n.value) is sym:
                found.append((n.value.span, "a reference to it is taken"))
        elif isinstance(n, (A.For, A.CountedFor)) and root_sym(n.var) is sym:
            found.append((n.var.span, "the counter of a nested FOR"))
        elif isinstance(n, A.Call) and isinstance(n.target, CallTarget):
            found += _call_writes(n.target, sym)
    return found


def _call_writes(t: CallTarget, sym: T.VarSym) -> list[tuple[Span, str]]:
    match t:
        case FbCall(pou=pou, bind=bind) | FunctionCall(pou=pou, bind=bind) | MethodCall(pou=pou, bind=bind):
            return _bound_writes(pou, bind, sym)
        case NativeCall():
            return _native_writes(t, sym)
        case RefCall(arg=arg) if root_sym(arg) is sym:
            return [(arg.span, "a reference to it is taken")]
        case QueryItfCall(dst=dst) if root_sym(dst) is sym:
            return [(dst.span, "assigned by __QUERYINTERFACE")]
    return []


def _bound_writes(pou: T.POUType, bind: Binding, sym: T.VarSym) -> list[tuple[Span, str]]:
    """The arguments of a call of a POU that let it write `sym`."""
    out: list[tuple[Span, str]] = []
    for key, a in bind["params"].items():
        if root_sym(a.value) is not sym:
            continue
        how = _how_passed(a, pou.vars.get(key))
        if how:
            out.append((a.value.span, how))
    eno = bind.get("eno")
    if eno is not None and root_sym(eno.value) is sym:
        out.append((eno.value.span, "an output argument (ENO)"))
    return out


def _how_passed(a: A.Arg, p: T.VarSym | None) -> str:
    """How an argument lets the callee write the variable under it ('' if it does not)."""
    if a.output or (p is not None and p.section == "VAR_OUTPUT"):
        return "an output argument"
    if p is None:
        return ""
    if p.section == "VAR_IN_OUT":
        return f"passed to VAR_IN_OUT '{p.name}'"
    if T.is_reference(p.type):
        return f"bound to REFERENCE TO input '{p.name}'"
    if p.any_input:
        return f"passed by address to '{p.name}'"
    return ""


def _native_writes(t: NativeCall, sym: T.VarSym) -> list[tuple[Span, str]]:
    out: list[tuple[Span, str]] = []
    taking = t.sig.name.upper() in ("ADR", "REF")
    for a in t.args:
        if root_sym(a.value) is sym and (a.output or taking):
            out.append((a.value.span, "its address is taken" if taking else "an output argument"))
    for flag in (t.en, t.eno):
        if flag is not None and flag.output and root_sym(flag.value) is sym:
            out.append((flag.value.span, "an output argument"))
    return out
