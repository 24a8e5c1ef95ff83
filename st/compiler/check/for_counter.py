"""Where a FOR loop's body writes its own control variable, as far as the body's text shows it.

IEC 61131-3 (3rd edition, 7.3.3.4.2: the control variable "shall not be altered by any of the
repeated statements") and MatIEC forbid it: the checker reports each place under the iec and
openplc presets (E052). CODESYS and TwinCAT allow it, and their loop tests the value the body left:
the lowering (lower/loops.py) then gives the loop the form that re-tests its counter, adding what
the text cannot show (other code reaching the variable during the body: lower/writes.py).
"""

from __future__ import annotations

from ...model import types as T
from ...source import Span
from .. import ast as A
from .targets import CallTarget, FbCall, FunctionCall, MethodCall, NativeCall, QueryItfCall, RefCall


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
            found += _call_writes(n, n.target, sym)
    return found


def _call_writes(call: A.Call, t: CallTarget, sym: T.VarSym) -> list[tuple[Span, str]]:
    out: list[tuple[Span, str]] = []
    match t:
        case FbCall(pou=pou, bind=bind) | FunctionCall(pou=pou, bind=bind) | MethodCall(pou=pou, bind=bind):
            for key, a in bind["params"].items():
                if root_sym(a.value) is not sym:
                    continue
                p = pou.vars.get(key)
                if a.output or (p is not None and p.section == "VAR_OUTPUT"):
                    out.append((a.value.span, "an output argument"))
                elif p is not None and p.section == "VAR_IN_OUT":
                    out.append((a.value.span, f"passed to VAR_IN_OUT '{p.name}'"))
                elif p is not None and T.is_reference(p.type):
                    out.append((a.value.span, f"bound to REFERENCE TO input '{p.name}'"))
                elif p is not None and p.any_input:
                    out.append((a.value.span, f"passed by address to '{p.name}'"))
            eno = bind.get("eno")
            if eno is not None and root_sym(eno.value) is sym:
                out.append((eno.value.span, "an output argument (ENO)"))
        case NativeCall(sig=sig, args=args, en=en, eno=eno):
            taking = sig.name.upper() in ("ADR", "REF")
            for a in args:
                if root_sym(a.value) is sym and (a.output or taking):
                    out.append((a.value.span, "its address is taken" if taking else "an output argument"))
            for flag in (en, eno):
                if flag is not None and flag.output and root_sym(flag.value) is sym:
                    out.append((flag.value.span, "an output argument"))
        case RefCall(arg=arg) if root_sym(arg) is sym:
            out.append((arg.span, "a reference to it is taken"))
        case QueryItfCall(dst=dst) if root_sym(dst) is sym:
            out.append((dst.span, "assigned by __QUERYINTERFACE"))
    return out
