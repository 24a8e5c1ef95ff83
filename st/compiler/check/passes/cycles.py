"""Self-containment and recursion, once the bodies are checked (each call knows its target): a type
may not contain itself (rules/self_containment.py), a POU that calls itself is E032 or W013
(rules/recursion.py), initial values do not need each other's values
(rules/initialization_order.py)."""

from __future__ import annotations

from ..context import CheckContext
from ..rules.initialization_order import check_initialization_order
from ..rules.recursion import check_recursion
from ..rules.self_containment import check_self_containment


def check_cycles(ctx: CheckContext) -> None:
    check_self_containment(ctx)
    check_recursion(ctx)
    check_initialization_order(ctx)
