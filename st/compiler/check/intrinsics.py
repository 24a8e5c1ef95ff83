"""Intrinsics: the calls the compiler itself answers, by name → handler (`INTRINSICS`): REF and
ADR (a reference to a variable), SIZEOF, LOWER_BOUND and UPPER_BOUND, __NEW and __DELETE,
__ISVALIDREF, __QUERYINTERFACE, and the unit-test statements (ASSERT_EQ, ..., tests.py). Each
handler checks its arguments, sets the call's target and returns the call's type."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ...diagnostics import Code
from ...model import types as T
from .. import ast as A
from .common import Scope, names_constant, take_address
from .part import Part
from .rules import abstract, call_without_value
from .targets import BoundCall, DeleteCall, IsValidRefCall, NewCall, QueryItfCall, RefCall, SizeofCall
from .tests import TEST_CALLS

Handler = Callable[[Part, A.Call, str, Scope, bool], T.Type | None]


@dataclass(frozen=True)
class Intrinsic:
    handler: Handler
    """(the part, the call, its lower-case name, the scope, whether it is a statement) → its type."""
    vendor: bool = False
    """A vendor extension: E044 outside the presets that have them."""
    pou_first: bool = True
    """A user POU of this name is called instead."""
    vendor_beside_pou: bool = True
    """E044 is reported even where a user POU has the name (for those that are not `pou_first`)."""


def _ref(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """REF(x): a reference to a variable (IEC 61131-3 3rd edition); ADR(x): a POINTER TO it (no
    arithmetic). ADR of a CONSTANT is its address (CODESYS): reading through it gives the
    constant's value; a write through it changes that memory, not the uses of the constant, which
    are its value wherever the compiler folds them (as CODESYS's 'Replace constants' does)."""
    if len(c.args) != 1 or c.args[0].name:
        part.err(Code.ARGUMENT_COUNT, c.span, "REF takes exactly one variable")
        return None
    arg = c.args[0].value
    if not isinstance(arg, (A.Name, A.Field, A.Index, A.Deref)):  # (p^, THIS^: what p points at)
        part.err(Code.NOT_A_VARIABLE, arg.span, "REF needs a variable")
        return None
    if key == "adr" and names_constant(part, arg, scope):
        t = part.exprs.expr(arg, scope)  # read through the pointer, never written as a variable
    else:
        t = part.stmts.lvalue(arg, scope)
    take_address(arg)
    if isinstance(arg, A.Name) and isinstance(arg.sym, T.POUType):  # ADR(F) inside F: its result
        arg.sym.result_address_taken = True
    c.target = RefCall(arg)
    return T.RefType(t) if t is not None else None


def _sizeof(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """SIZEOF(variable or type): its size in bytes, a constant (natural alignment, as a 64-bit target)."""
    if len(c.args) != 1 or c.args[0].name:
        part.err(Code.ARGUMENT_COUNT, c.span, "SIZEOF takes one variable or type")
        return T.LIT_INT
    arg = c.args[0].value
    t = None
    if isinstance(arg, A.Name) and part.exprs.lookup(arg.name.lower(), scope) is None:
        t = _named_type(part, arg)
        if t is None:
            part.err(Code.UNDECLARED, arg.span, f"'{arg.name}' is neither a variable nor a type")
            return T.LIT_INT
    else:
        t = part.exprs.expr(arg, scope)
    if t is None:
        return T.LIT_INT
    size, _align = T.size_of(t)
    c.target = SizeofCall(size)
    c.const = size
    return T.LIT_INT


def _named_type(part: Part, arg: A.Name) -> T.Type | None:
    """The type `arg` names: elementary, declared, or a block's."""
    return (
        T.ELEMENTARY.get(arg.name.upper())
        or part.decls.resolve_named_type(arg.name.lower(), arg.span)
        or part.p.pous.get(arg.name.lower())
    )


def _bound(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """LOWER_BOUND(arr, dim) / UPPER_BOUND(arr, dim): a DINT; a constant unless arr is ARRAY[*]."""
    what = key.upper()
    if len(c.args) != 2 or any(a.name or a.output for a in c.args):
        part.err(Code.ARGUMENT_COUNT, c.span, f"{what} takes an array and a dimension: {what}(arr, 1)")
        return T.DINT
    at = part.exprs.expr(c.args[0].value, scope)
    dim = part.consts.value(c.args[1].value, scope)
    part.exprs.expr(c.args[1].value, scope, T.DINT)
    u = T.unalias(at) if at is not None else None
    if at is None:
        return T.DINT
    if not isinstance(u, T.ArrayType):
        part.err(Code.TYPE_MISMATCH, c.args[0].value.span, f"{what} needs an array, not {at}")
        return T.DINT
    if not isinstance(dim, int) or not 1 <= dim <= len(u.dims):
        part.err(Code.NOT_CONSTANT, c.args[1].value.span, f"the dimension must be a constant from 1 to {len(u.dims)}")
        return T.DINT
    lo, hi = u.dims[dim - 1]
    value = None if T.is_conformant(u) else (hi if key == "upper_bound" else lo)
    c.target = BoundCall(c.args[0].value, dim, key == "upper_bound", value)
    return T.DINT


def _new(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """__NEW(type): a POINTER TO a fresh value of that type; __NEW(type, n): to the first of n
    (NULL if n < 1); __NEW(FB(a := v)): a fresh instance whose FB_init gets these arguments, any
    expressions, evaluated where __NEW runs (CODESYS)."""
    if not 1 <= len(c.args) <= 2 or any(a.name for a in c.args):
        part.err(Code.ARGUMENT_COUNT, c.span, "__NEW takes a type and an optional count")
        return None
    arg = c.args[0].value
    ctor, outputs = None, False
    if isinstance(arg, A.Call) and isinstance(arg.callee, A.Name) and arg.callee.name:  # __NEW(FB(a := 1))
        ctor = A.CtorInit(arg.span, [(a.name, a.span, a.value) for a in arg.args])
        outputs = any(a.output for a in arg.args)
        arg = arg.callee
    t = _named_type(part, arg) if isinstance(arg, A.Name) and arg.name else None
    if t is None or (isinstance(t, T.POUType) and t.pou_kind not in ("FUNCTION_BLOCK",)):
        part.err(Code.BAD_TYPE, arg.span, "__NEW needs a data type or a FUNCTION_BLOCK type")
        return None
    abstract.check_new_instance(part.ctx, t, arg.span)
    if ctor is not None:
        if outputs:
            part.err(Code.BAD_PARAMETER, ctor.span, "FB_init takes inputs only")
        part.decls.check_ctor_args(ctor, t, scope, at_run_time=True)
    count = c.args[1].value if len(c.args) == 2 else None
    if count is not None:
        if isinstance(t, T.POUType):  # as CODESYS: a count only for data types
            part.err(
                Code.ARGUMENT_COUNT,
                count.span,
                f"__NEW of a FUNCTION_BLOCK makes one instance; '{t.name}' takes no count",
            )
        ct = part.exprs.expr(count, scope, T.DINT)
        if ct is not None and not (T.base_of(ct).is_int or T.base_of(ct) is T.LIT_INT):
            part.err(Code.TYPE_MISMATCH, count.span, f"the count of __NEW must be an integer, not {ct}")
    c.target = NewCall(t, count, ctor)
    return T.RefType(t, "POINTER")


def _delete(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """__DELETE(p): p becomes NULL (the value is freed when nothing refers to it any more, so a
    dangling pointer cannot happen)."""
    if len(c.args) != 1 or any(a.name for a in c.args):
        part.err(Code.ARGUMENT_COUNT, c.span, "__DELETE takes one argument")
        return None
    arg = c.args[0].value
    call_without_value.check_statement_call(part.ctx, c, statement, "__DELETE(p) is a statement; it has no value")
    if isinstance(arg, A.Name) and arg.name.upper() == "THIS" and scope.fb is not None:
        # __DELETE(THIS) (CODESYS: an instance made by __NEW releasing itself): nothing to set to
        # NULL here; the instance is freed once nothing refers to it any more
        part.exprs.expr(arg, scope)
        c.target = DeleteCall(arg, itself=True)
        return None
    t = part.stmts.lvalue(arg, scope)
    u = T.unalias(t) if t is not None else None
    if t is not None and not (isinstance(u, T.RefType) and u.ref_kind == "POINTER"):
        part.err(Code.TYPE_MISMATCH, arg.span, f"__DELETE needs a POINTER, not {t}")
    c.target = DeleteCall(arg)
    return None


def _is_valid_ref(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """__ISVALIDREF(r): is the REFERENCE TO r bound? r may be a variable, a block's member
    (`THIS^.refX`, `inst.refX`: the reference itself, not what it refers to) or a VAR_IN_OUT (bound
    by a call: always in a FUNCTION or METHOD, once the block was called with it in a block)."""
    if len(c.args) != 1 or c.args[0].name:
        part.err(Code.ARGUMENT_COUNT, c.span, "__ISVALIDREF takes one reference")
        return T.BOOL
    t = part.exprs.expr(c.args[0].value, scope)
    arg = c.args[0].value
    sym = arg.sym if isinstance(arg, (A.Name, A.Field)) else None
    is_ref = isinstance(sym, T.VarSym) and (
        T.is_reference(sym.type) or (sym.section == "VAR_IN_OUT" and isinstance(arg, A.Name))
    )
    if not is_ref and not isinstance(T.unalias(t) if t is not None else None, T.RefType):
        part.err(Code.TYPE_MISMATCH, arg.span, f"__ISVALIDREF needs a reference, not {t}")
        return T.BOOL
    c.target = IsValidRefCall(arg)
    return T.BOOL


def _query_interface(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """__QUERYINTERFACE(source, dest): does the instance behind `source` provide dest's
    interface? If so dest refers to it and the result is TRUE (CODESYS)."""
    if len(c.args) != 2 or any(a.name for a in c.args):
        part.err(
            Code.ARGUMENT_COUNT,
            c.span,
            "__QUERYINTERFACE takes two arguments: an interface (or instance) and an interface variable",
        )
        return T.BOOL
    st = part.exprs.expr(c.args[0].value, scope)
    dt = part.stmts.lvalue(c.args[1].value, scope)
    s, d = (T.unalias(x) if x is not None else None for x in (st, dt))
    if not (isinstance(s, T.POUType) and s.pou_kind in ("INTERFACE", "FUNCTION_BLOCK")):
        part.err(Code.TYPE_MISMATCH, c.args[0].span, f"__QUERYINTERFACE needs an interface or an instance, not {st}")
    if not (isinstance(d, T.POUType) and d.pou_kind == "INTERFACE"):
        part.err(Code.TYPE_MISMATCH, c.args[1].span, f"__QUERYINTERFACE needs an interface variable to fill, not {dt}")
        return T.BOOL
    c.target = QueryItfCall(c.args[0].value, c.args[1].value, d)
    return T.BOOL


def _test_statement(part: Part, c: A.Call, key: str, scope: Scope, statement: bool) -> T.Type | None:
    """ASSERT_*, ADVANCE_TIME, MOCK_VERIFY_*: tests.py."""
    return part.tests.test_call(c, key, scope, statement)


INTRINSICS: dict[str, Intrinsic] = {
    "ref": Intrinsic(_ref),
    "adr": Intrinsic(_ref, vendor=True),
    "sizeof": Intrinsic(_sizeof, vendor=True),
    "lower_bound": Intrinsic(_bound),
    "upper_bound": Intrinsic(_bound),
    "__new": Intrinsic(_new, vendor=True, pou_first=False),
    "__delete": Intrinsic(_delete, vendor=True, pou_first=False),
    "__isvalidref": Intrinsic(_is_valid_ref, vendor=True, pou_first=False, vendor_beside_pou=False),
    "__queryinterface": Intrinsic(_query_interface, vendor=True, pou_first=False, vendor_beside_pou=False),
    **{key: Intrinsic(_test_statement) for key in TEST_CALLS},
}
