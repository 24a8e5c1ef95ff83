"""The checked program: what the checker produces, code generation consumes and the runtime reads.

Fields typed `Syntax` hold the compiler's AST while it compiles (st.model.syntax); in the
compiled artefact (st.compiler.artefact) they hold the AST-free values of st.model.summaries, or
None.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from ..source import Span
from .summaries import InitialValue
from .syntax import Syntax
from .types import EnumType, POUType, Type, VarSym


class LibrarySources(Protocol):
    """A library as the model sees it (the compiler's Library, the artefact's LibraryInfo)."""

    @property
    def name(self) -> str: ...

    @property
    def sources(self) -> Sequence[tuple[str, str]]: ...


@dataclass(eq=False)
class TaskModel:
    name: str
    interval: int = 0  # ns; 0 for an event task
    priority: int = 0
    single: str = ""  # the name of the BOOL global that triggers an event task
    span: Span | None = None


@dataclass(eq=False)
class InstanceModel:
    name: str
    type: POUType
    task: str  # task name ("" = runs every base tick)
    resource: str = ""
    # connections [(parameter, its connection (compiler: an expression; artefact: None), is output)]
    args: list[tuple[VarSym, Syntax | None, bool]] = field(default_factory=list)
    span: Span | None = None
    # the global holding the PROGRAM's one instance when code uses the program by its name
    # (CODESYS, TwinCAT): the task runs that instance; "" for an instance of its own
    singleton: str = ""


@dataclass(eq=False)
class ConfigModel:
    name: str
    tasks: list[TaskModel] = field(default_factory=list)
    instances: list[InstanceModel] = field(default_factory=list)
    # [(path, location, initial value (compiler: its syntax; artefact: a value or None), declared type
    # (compiler: its syntax; artefact: None), span)]
    var_config: list[tuple[list[str], str, Syntax | InitialValue | None, Syntax | None, Span]] = field(
        default_factory=list
    )
    implicit: bool = False  # made up for a file with only a PROGRAM


@dataclass(eq=False)
class AccessPath:
    """A VAR_ACCESS entry: `name` reaches the variable at `target` (a path the runtime resolves,
    "inst.x", "g_count.field", or a %address), of `type`; READ_ONLY refuses writes from outside."""

    name: str
    target: str
    type: Type
    read_only: bool
    span: Span | None = None


@dataclass(eq=False)
class StepModel:
    name: str
    index: int
    initial: bool
    actions: list[tuple[str, str, Syntax | None]]  # [(action name, qualifier, its time (compiler) | None)]
    span: Span | None = None


@dataclass(eq=False)
class TransitionModel:
    index: int
    sources: list[int]  # step indices
    targets: list[int]
    cond: Syntax | None  # compiler: the BOOL expression; artefact: None
    priority: int = 0
    span: Span | None = None


@dataclass(eq=False)
class SfcModel:
    steps: list[StepModel]
    transitions: list[TransitionModel]
    actions: list[str]  # action names in use (lower)
    action_index: dict[str, int]  # lower name → index


@dataclass(eq=False)
class Project:
    types: dict[str, Type] = field(default_factory=dict)  # lower name → Type
    pous: dict[str, POUType] = field(default_factory=dict)  # lower name → POUType
    globals: dict[str, VarSym] = field(default_factory=dict)  # unique key → VarSym
    global_names: dict[str, list[VarSym]] = field(default_factory=dict)  # lower name → [VarSym]
    configs: list[ConfigModel] = field(default_factory=list)
    enum_members: dict[str, list[tuple[EnumType, str, int]]] = field(default_factory=dict)  # lower member → …
    direct_vars: dict[str, tuple[str, Type]] = field(default_factory=dict)  # "%QX0.0" → (pyname, Type)
    sfc: dict[str, SfcModel] = field(default_factory=dict)  # pou lower → SfcModel
    test_blocks: list[Syntax] = field(default_factory=list)  # ast.TestBlock as parsed ([] in the artefact)
    tests: list[TestModel] = field(default_factory=list)  # checked
    test_asserts: list[AssertInfo] = field(default_factory=list)  # index = id in generated code
    libraries: Sequence[LibrarySources] = field(default_factory=list)  # compiler: Library; artefact: LibraryInfo
    access_paths: dict[str, AccessPath] = field(default_factory=dict)  # lower name → VAR_ACCESS entry

    def user_pous(self) -> list[POUType]:
        return [p for p in self.pous.values() if not p.library]


@dataclass(eq=False)
class TestModel:
    """One TEST block: generated as the function `pyname` (SETUP, the TEST, then TEARDOWN)."""

    name: str
    span: Span
    pyname: str
    pou: POUType | None = None  # the pseudo-POU holding SETUP + TEST variables (None in the artefact)
    setup: list[Syntax] = field(default_factory=list)  # statements ([] in the artefact)
    body: list[Syntax] = field(default_factory=list)
    teardown: list[Syntax] = field(default_factory=list)


@dataclass(eq=False)
class AssertInfo:
    """What a failure report of one test statement needs: its kind, place, source text and types."""

    kind: str  # ASSERT_EQ, ADVANCE_TIME, MOCK_VERIFY_CALLED, ...
    span: Span
    text: str = ""  # the statement's source text, filled by the driver
    types: list[Type] = field(default_factory=list)
    index: int = -1
