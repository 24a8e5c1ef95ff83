"""FB_init (CODESYS): the chain of a block's FB_init methods as one explicit constructor.

An instance of a block whose chain is not empty is constructed after its declared initial
values are in place: each block's own FB_init runs, the base's first. The implicit call gives
`bInitRetains` TRUE (a cold start: retained values are restored afterwards), `bInCopyCode`
FALSE and every other input the declaration's argument of that name (`inst : FB(nId := 5)`)
or its default; the arguments are checked against the most derived FB_init's inputs.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...model import types as T

FIXED = {"binitretains": True, "bincopycode": False}


@dataclass(slots=True)
class InitCall:
    method: T.POUType  # one block's own FB_init
    args: list  # per input, in order: a fixed bool, or the input (its declared argument or default)


@dataclass(slots=True)
class Constructor:
    calls: list  # [InitCall], base first
    inputs: dict  # lower-case name → VarSym: what a declaration's arguments are checked against


def constructor(pou: T.POUType) -> Constructor | None:
    chain = T.fb_init_chain(pou)
    if not chain:
        return None
    calls = [InitCall(mt, [FIXED.get(p.name.lower(), p) for p in mt.params()]) for mt in chain]
    return Constructor(calls, {p.name.lower(): p for p in pou.methods["fb_init"].params()})
