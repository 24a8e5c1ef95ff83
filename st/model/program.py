"""The checked program: what the checker produces, code generation consumes and the runtime reads.

Fields marked "syntax" hold the compiler's AST while it compiles; in the compiled artefact
(st.compiler.artefact) they hold the AST-free values of st.model.summaries, or None.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..source import Span
from .types import POUType


@dataclass(eq=False)
class TaskModel:
    name: str
    interval: int = 0           # ns; 0 for an event task
    priority: int = 0
    single: str = ""            # the name of the BOOL global that triggers an event task
    span: Any = None


@dataclass(eq=False)
class InstanceModel:
    name: str
    type: POUType
    task: str                   # task name ("" = runs every base tick)
    resource: str = ""
    args: list = field(default_factory=list)   # connections [(param, syntax: Expr | None, is_output)]
    span: Any = None


@dataclass(eq=False)
class ConfigModel:
    name: str
    tasks: list = field(default_factory=list)          # [TaskModel]
    instances: list = field(default_factory=list)      # [InstanceModel]
    var_config: list = field(default_factory=list)     # [(path list, location, syntax: init (InitialValue),
    #                                                     syntax: declared type (None), span)]
    implicit: bool = False      # made up for a file with only a PROGRAM


@dataclass(eq=False)
class StepModel:
    name: str
    index: int
    initial: bool
    actions: list               # [(action name, qualifier, syntax: time Expr | None)]
    span: Any = None


@dataclass(eq=False)
class TransitionModel:
    index: int
    sources: list               # step indices
    targets: list
    cond: Any                   # syntax: Expr (BOOL) | None
    priority: int = 0
    span: Any = None


@dataclass(eq=False)
class SfcModel:
    steps: list
    transitions: list
    actions: list               # action names in use (lower)
    action_index: dict          # lower name → index


@dataclass(eq=False)
class Project:
    types: dict = field(default_factory=dict)          # lower → Type
    pous: dict = field(default_factory=dict)           # lower → POUType
    globals: dict = field(default_factory=dict)        # unique key → VarSym
    global_names: dict = field(default_factory=dict)   # lower name → [VarSym]
    configs: list = field(default_factory=list)        # [ConfigModel]
    enum_members: dict = field(default_factory=dict)   # lower member → [(EnumType, name, value)]
    direct_vars: dict = field(default_factory=dict)    # "%QX0.0" → (pyname, Type)
    sfc: dict = field(default_factory=dict)            # pou lower → SfcModel
    test_blocks: list = field(default_factory=list)    # syntax: ast.TestBlock as parsed ([] in the artefact)
    tests: list = field(default_factory=list)          # [TestModel], checked
    test_asserts: list = field(default_factory=list)   # [AssertInfo], index = id in generated code
    libraries: list = field(default_factory=list)      # compiler: Library; artefact: LibraryInfo

    def user_pous(self):
        return [p for p in self.pous.values() if not p.library]


@dataclass(eq=False)
class TestModel:
    """One TEST block: generated as the function `pyname` (SETUP, the TEST, then TEARDOWN)."""

    name: str
    span: Span
    pyname: str
    pou: Any = None             # the pseudo-POU holding SETUP + TEST variables (None in the artefact)
    setup: list = field(default_factory=list)      # syntax: statements ([] in the artefact)
    body: list = field(default_factory=list)
    teardown: list = field(default_factory=list)


@dataclass(eq=False)
class AssertInfo:
    """What a failure report of one test statement needs: its kind, place, source text and types."""

    kind: str                   # ASSERT_EQ, ADVANCE_TIME, MOCK_VERIFY_CALLED, ...
    span: Span
    text: str = ""              # the statement's source text, filled by the driver
    types: list = field(default_factory=list)
    index: int = -1
