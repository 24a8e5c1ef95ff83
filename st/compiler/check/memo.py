"""What a check works out from a syntax tree alone, kept for the next check of the same tree.

The language server checks a project again after every edit and keeps the trees of the files
that did not change (st/lsp/analysis.py); a tree is stable once checked (a re-check gives the same
answers, tests/test_lsp.py). Answers that depend on nothing but the nodes under a tree's part (the
names a body mentions, the nodes a body holds) are then looked up instead of walked again. A
compilation has no memo: every answer is worked out, as before.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

V = TypeVar("V")


class TreeMemo:
    """Answers keyed by (what, the syntax objects they come from); an entry holds its objects, so
    their ids stay theirs. `sweep()` after a check drops what that check did not ask for (the
    trees of an edited file are new objects: their old answers go)."""

    def __init__(self) -> None:
        self._got: dict[tuple, tuple[tuple, Any]] = {}
        self._used: set[tuple] = set()

    def get(self, what: str, nodes: tuple, compute: Callable[[], V]) -> V:
        key = (what, *map(id, nodes))
        hit = self._got.get(key)
        if hit is None or any(a is not b for a, b in zip(hit[0], nodes, strict=True)):
            hit = self._got[key] = (nodes, compute())
        self._used.add(key)
        return hit[1]

    def sweep(self) -> None:
        self._got = {k: v for k, v in self._got.items() if k in self._used}
        self._used = set()

    def __len__(self) -> int:
        return len(self._got)


def remembered(memo: TreeMemo | None, what: str, nodes: tuple, compute: Callable[[], V]) -> V:
    """compute(), through memo when there is one."""
    return compute() if memo is None else memo.get(what, nodes, compute)
