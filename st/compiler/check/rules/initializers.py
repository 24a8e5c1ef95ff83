"""An initial value has a form its declared type takes: [...] for an array (a single value is no
array's), (...) for a structure or a block instance, FB_init arguments (`inst : FB(a := 1)`) for a
function block where an instance is declared (not in a TYPE); a UNION member has no initial value
of its own; an enumeration's default is one of its values. Under every preset.

Codes: E057.
"""

from __future__ import annotations

from ....diagnostics import Code
from ....model import types as T
from ... import ast as A
from ..context import CheckContext


def _bad(ctx: CheckContext, at, message: str) -> None:
    ctx.err(Code.BAD_INITIALIZER, at.span, message)


def check_union_member(ctx: CheckContext, d: A.VarDecl) -> None:
    """The declaration `d` of a UNION member."""
    if d.init is not None:
        _bad(ctx, d.init, "a UNION member cannot have an initial value (they share their bytes)")


def check_enum_default(ctx: CheckContext, init: A.Expr, spec: A.EnumType) -> None:
    """TYPE E : (A, B) := init;, where `init` is not a name: no default (unless the enumeration
    names one itself)."""
    if not spec.default:
        _bad(ctx, init, "an enumeration's default must be one of its values")


def check_type_has_no_arguments(ctx: CheckContext, spec: A.NamedType) -> None:
    """A named type used in a TYPE (or anywhere but an instance's declaration) takes no FB_init arguments."""
    if spec.ctor_args:
        _bad(ctx, spec, "FB_init arguments belong where an instance is declared (`inst : FB(a := 1);`), not in a type")


def check_constructed(ctx: CheckContext, init: A.CtorInit, t: T.Type) -> bool:
    """`inst : t(a := 1)`: `t` is a function block (reported: False if not)."""
    bt = T.unalias(t)
    if isinstance(bt, T.POUType) and bt.pou_kind == "FUNCTION_BLOCK":
        return True
    _bad(ctx, init, f"arguments in a declaration go to a function block's FB_init; {t} is not a function block")
    return False


def check_array_form(ctx: CheckContext, init, t: T.Type) -> bool:
    """An array initializer [...] for a value of type `t` (reported: False if not an array)."""
    if isinstance(T.unalias(t), T.ArrayType):
        return True
    _bad(ctx, init, f"an array initializer cannot initialize a {t}")
    return False


def check_structure_form(ctx: CheckContext, init: A.StructInit, t: T.Type) -> None:
    """A structure initializer (...) for a value of type `t`, which is neither a structure nor a block."""
    _bad(ctx, init, f"a structure initializer cannot initialize a {t}")


def check_single_value(ctx: CheckContext, init: A.Expr, t: T.Type) -> bool:
    """A single value `init` for a value of type `t`: no literal for an array (reported: False)."""
    if isinstance(T.unalias(t), T.ArrayType) and isinstance(init, A.Literal):
        # CODESYS-style: a single value initializes... no; IEC needs [..]
        _bad(ctx, init, f"an array needs an initializer in brackets, e.g. [{init.text}]")
        return False
    return True


def expand_array_ctor(ctx: CheckContext, init: A.ArrayCtorInit, t: T.Type) -> A.ArrayInit | None:
    """`ARRAY[..] OF FB(args)` / `ARRAY[..] OF FB[(args), (args)]` (CODESYS, TwinCAT): the array
    initializer it stands for, one CtorInit per element (with that element's value from the
    ordinary initializer, if any); None where its form is wrong (reported here)."""
    at = T.unalias(t)
    if not isinstance(at, T.ArrayType):
        _bad(ctx, init, f"FB_init arguments for each element need an array of function blocks, not {t}")
        return None
    inner = init.inner
    values: list = []
    if isinstance(inner, A.ArrayInit):
        for item in inner.items:
            values.extend(item.items * item.count if isinstance(item, A.RepeatInit) else [item])
    elif inner is not None:
        _bad(ctx, inner, "an array of function blocks takes an array initializer ([...]) besides its FB_init arguments")
        return None
    n = at.size
    lists = [init.each] * n if init.each is not None else list(init.elements or [])
    if len(lists) > n:
        _bad(ctx, init, f"{len(lists)} FB_init argument lists for an array of {n} elements")
        return None
    items: list = []
    for i in range(max(len(lists), len(values))):
        value = values[i] if i < len(values) else None
        items.append(A.CtorInit(init.span, list(lists[i]), value) if i < len(lists) else value)
    return A.ArrayInit(inner.span if isinstance(inner, A.ArrayInit) else init.span, items)
