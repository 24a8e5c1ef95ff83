"""Lowering: the checked AST → a smaller AST that code generation prints without semantic choices.

Runs after the checks, before code generation (compiler/codegen). Each lowering is one module
and rewrites the bodies in place (the checked project is built for one compilation):

- qualified.py: `GVL_Main.x` (a named global variable list's variable) → the global's name;
- properties.py: property reads and writes → `AccessorCall` (GET, or SET as a target);
- loops.py: FOR → `CountedFor` (its form decided), a `LoopGuard` first in every loop;
- writes.py: who else may write an instance's variables while its body runs (a FOR's form and
  codegen's cached variables depend on it);
- inheritance.py: each block's flattened member set and what its instances are (`Block`),
  with fb_init.py's explicit constructor for its FB_init chain; which implementation each
  method or block call runs (SUPER^ calls are the base's);
- initial_values.py: the order of initialisation of the POUs whose initial values name variables;
  which VAR_IN_OUTs of blocks start unbound (those __ISVALIDREF tests).
"""

from __future__ import annotations

from dataclasses import dataclass

from ...model.program import Project
from . import inheritance, initial_values, loops, properties, qualified
from .walk import bodies, rewrite_exprs, rewrite_outside_bodies
from .writes import Writes


@dataclass(slots=True)
class LowerOptions:
    loop_guards: bool = True  # the watchdog's check in every loop (off only to measure its cost)


@dataclass(slots=True)
class LoweredProgram:
    """What code generation prints: the project with lowered bodies, each block's class, and who
    else may write an instance's variables while its body runs (writes.py)."""

    project: Project
    blocks: dict  # POUType → inheritance.Block
    writes: Writes
    initial_orders: dict  # POUType → [initialization_order.Step]: initial values that name variables
    unbound_in_outs: set  # VarSym: a block's VAR_IN_OUT that __ISVALIDREF tests, unbound at first


def lower(project: Project, options: LowerOptions | None = None) -> LoweredProgram:
    options = options or LowerOptions()
    listed = list(bodies(project))
    unbound: set = set()

    def expression(e):
        initial_values.note_unbound_in_out(e, unbound)
        return _expression(e)

    for body, _block in listed:
        properties.property_targets(body)
        rewrite_exprs(body, expression)
    initial_values.rewrite_initializers(project, _expression)
    writes = Writes(project)  # on the rewritten bodies: property uses are accessor calls now
    for body, block in listed:
        loops.count_fors(body, writes, block)
        if options.loop_guards:
            loops.guard_loops(body)
    rewrite_outside_bodies(project, _expression)  # SFC conditions, configuration arguments
    return LoweredProgram(
        project,
        inheritance.blocks(project),
        writes,
        initial_values.initial_orders(project),
        unbound,
    )


def _expression(e):
    """The expression rewrites, in one walk of each body (innermost first): a GVL's or a located
    variable's plain name, a property read's GET call, and which implementation a call runs. They
    touch different nodes and none reads what a later one changes below it, so one walk gives
    what three would."""
    return inheritance.dispatch(properties.property_read(qualified.plain_name(e)))
