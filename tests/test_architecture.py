"""The package layering (docs/ARCHITECTURE.md): each stage imports only the stages below it.

Read from the source with `ast`, so imports inside functions count as much as those at the top
of a module: a function-level import may delay loading an optional dependency, never hide a cycle.
The compiler's own conventions are read the same way: diagnostics raised as `Code` members, one
rule per module under check/rules, call targets read by their class.
"""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "st"

# a package (or top-level module) of st → the ones it may import; the graph is a DAG, read bottom up
ALLOWED: dict[str, set[str]] = {
    "source": set(),
    "diagnostics": {"source"},
    "errors_doc": {"diagnostics"},
    "model": {"source", "diagnostics"},
    "grammar": {"source", "diagnostics"},
    "compiler": {"source", "diagnostics", "model", "grammar"},
    "runtime": {"source", "diagnostics", "model"},
    "stdlib": {"source", "diagnostics", "model", "compiler", "runtime"},
    "io": {"source", "diagnostics", "model", "runtime", "stdlib"},
    "api": {"source", "diagnostics", "model", "compiler", "runtime", "stdlib"},
    "facade": {"source", "diagnostics", "model", "compiler", "runtime", "stdlib", "api", "io", "opcua"},
    "testing": {"source", "diagnostics", "model", "compiler", "runtime", "stdlib", "api", "facade"},
    "web": {"source", "diagnostics", "model", "runtime", "stdlib", "io"},
    "opcua": {"source", "diagnostics", "model", "runtime", "stdlib", "io", "web"},  # web: one naming of types
    "lsp": {"source", "diagnostics", "errors_doc", "model", "grammar", "compiler", "stdlib", "api"},
    "app": {"source", "diagnostics", "model", "compiler", "runtime", "stdlib", "io", "api", "facade", "web", "opcua"},
    "experiments": {"source", "diagnostics", "model", "compiler", "runtime", "stdlib", "io", "api", "facade", "app"},
    "cli": {
        "source",
        "diagnostics",
        "errors_doc",
        "model",
        "compiler",
        "runtime",
        "stdlib",
        "io",
        "api",
        "facade",
        "app",
        "testing",
        "experiments",
        "opcua",
        "lsp",
    },
    "__init__": {"facade", "runtime", "diagnostics"},
    "__main__": {"cli"},
}


def _modules() -> dict[str, Path]:
    out = {}
    for f in sorted(PACKAGE.rglob("*.py")):
        parts = list(f.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = f
    return out


MODULES = _modules()


def _type_checking_only(tree: ast.Module) -> set[int]:
    """The import nodes under `if TYPE_CHECKING:` (annotations only: never run, no cycle)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            out |= {id(n) for n in ast.walk(node)}
    return out


def _imports(name: str, path: Path) -> list[tuple[str, list[str], int, bool]]:
    """(imported module, names imported from it, line, runs when the module or a function runs)
    for each st import."""
    tree = ast.parse(path.read_text(), str(path))
    is_pkg = path.name == "__init__.py"
    annotations_only = _type_checking_only(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name == "st" or a.name.startswith("st."):
                    found.append((a.name, [], node.lineno, id(node) not in annotations_only))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_pkg else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            elif node.module and (node.module == "st" or node.module.startswith("st.")):
                target = node.module
            else:
                continue
            names = [a.name for a in node.names]
            # `from . import x` / `from st.compiler import types`: a submodule, not a name
            subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
            if subs:
                found += [(s, [], node.lineno, id(node) not in annotations_only) for s in subs]
                names = [n for n in names if f"{target}.{n}" not in MODULES]
                if not names:
                    continue
            found.append((target, names, node.lineno, id(node) not in annotations_only))
    return found


def _layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


GRAPH = {m: _imports(m, p) for m, p in MODULES.items()}


def test_every_package_is_placed_in_the_layering():
    assert {_layer(m) for m in MODULES} <= set(ALLOWED), "a new package: give it its place in ALLOWED"


def test_the_layering_itself_has_no_cycle():
    seen, stack = set(), set()

    def visit(n):
        assert n not in stack, f"ALLOWED has a cycle through {n}"
        if n in seen:
            return
        stack.add(n)
        for m in ALLOWED[n]:
            visit(m)
        stack.discard(n)
        seen.add(n)

    for n in ALLOWED:
        visit(n)


def test_each_stage_imports_only_the_stages_below_it():
    wrong = [
        f"{MODULES[m].relative_to(ROOT)}:{line}: {_layer(m)} imports {target}"
        for m, imports in GRAPH.items()
        for target, _, line, _ in imports
        if _layer(target) != _layer(m) and _layer(target) not in ALLOWED[_layer(m)]
    ]
    assert not wrong, "\n".join(wrong)


def test_no_private_name_is_imported_from_another_package():
    wrong = [
        f"{MODULES[m].relative_to(ROOT)}:{line}: from {target} import {n}"
        for m, imports in GRAPH.items()
        for target, names, line, _ in imports
        for n in names
        if n.startswith("_") and not n.startswith("__") and _layer(target) != _layer(m)
    ]
    assert not wrong, "\n".join(wrong)


def test_no_module_outside_the_runtime_imports_a_private_runtime_name():
    wrong = []
    for f in sorted((ROOT / "tests").glob("*.py")) + sorted((ROOT / "bench").glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("st.runtime"):
                wrong += [
                    f"{f.relative_to(ROOT)}:{node.lineno}: {a.name}" for a in node.names if a.name.startswith("_")
                ]
    assert not wrong, "\n".join(wrong)


def test_imports_inside_functions_hide_no_cycle():
    """The module graph with every import, wherever it is written, has no cycle."""
    edges = defaultdict(set)
    for m, imports in GRAPH.items():
        for target, _, _, runs in imports:
            if not runs:
                continue
            t = target
            while t not in MODULES and "." in t:
                t = t.rsplit(".", 1)[0]
            if t != m and t in MODULES:
                edges[m].add(t)
    # a package's __init__ importing its own submodules is how packages export: not a cycle
    for m in list(edges):
        edges[m] = {t for t in edges[m] if not (m.startswith(t + ".") and MODULES[t].name == "__init__.py")}
    state: dict[str, int] = {}
    cycles = []

    def visit(n, path):
        state[n] = 1
        for t in sorted(edges[n]):
            if state.get(t) == 1:
                cycles.append(" → ".join(path[path.index(t) :] + [t]) if t in path else f"{n} → {t}")
            elif t not in state:
                visit(t, path + [t])
        state[n] = 2

    for m in sorted(MODULES):
        if m not in state:
            visit(m, [m])
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


@pytest.mark.parametrize("layer", ["model", "runtime"])
def test_the_lower_layers_import_no_optional_dependency_at_module_level(layer):
    """The model and the runtime load with the standard library alone (plus what the README installs)."""
    third_party_ok = {"numpy"}
    wrong = []
    for m, p in MODULES.items():
        if _layer(m) != layer:
            continue
        tree = ast.parse(p.read_text())
        for node in tree.body:
            mods = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom) and not node.level
                else []
            )
            wrong += [
                f"{p.relative_to(ROOT)}: {x}"
                for x in mods
                if x.split(".")[0] in ("matplotlib", "pysoem", "ruckig", "pymodbus", "lark", "click", "rich")
                and x.split(".")[0] not in third_party_ok
            ]
    assert not wrong, "\n".join(wrong)


# ------------------------------------------------------------------ the compiler's conventions

COMPILER = PACKAGE / "compiler"
RAW_CODE = re.compile(r"[EW]\d{3}")


def _string_constants(path: Path) -> list[tuple[int, str]]:
    """(line, value) of the string constants of a module that are not docstrings."""
    tree = ast.parse(path.read_text())
    docs = {
        id(n.body[0].value)
        for n in ast.walk(tree)
        if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and n.body
        and isinstance(n.body[0], ast.Expr)
        and isinstance(n.body[0].value, ast.Constant)
    }
    return [
        (n.lineno, n.value)
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
    ]


def test_the_compiler_raises_diagnostics_as_code_members():
    """No raw code string ("E013", "W002") in st/compiler: every code is `Code.X` (st/diagnostics.py)."""
    found: dict[str, set[str]] = {}
    for path in sorted(COMPILER.rglob("*.py")):
        for _line, value in _string_constants(path):
            if RAW_CODE.fullmatch(value):
                found.setdefault(str(path.relative_to(ROOT)), set()).add(value)
    assert not found, f"raw code strings in st/compiler: {found}"


def _codes_used(path: Path) -> set[str]:
    """The `Code` members a module names (Code.X), as their values."""
    from st.diagnostics import Code

    names = {
        n.attr
        for n in ast.walk(ast.parse(path.read_text()))
        if isinstance(n, ast.Attribute) and isinstance(n.value, ast.Name) and n.value.id == "Code"
    }
    return {Code[name].value for name in names}


RULE_MODULES = sorted(p for p in (COMPILER / "check" / "rules").glob("*.py") if p.name != "__init__.py")


@pytest.mark.parametrize("path", RULE_MODULES, ids=[p.stem for p in RULE_MODULES])
def test_each_rule_module_raises_the_codes_its_docstring_names(path):
    """One rule per module: its docstring says what it enforces and ends with `Codes: E0xx, ...`,
    and the module raises exactly those codes."""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    m = re.search(r"^Codes: (.+)\.$", doc, re.M)
    assert m, f"{path.name}: the docstring names no 'Codes: ...'"
    assert len(doc.split("\n\n")[0]) > 40, f"{path.name}: the docstring does not say what the rule enforces"
    assert set(RAW_CODE.findall(m.group(1))) == _codes_used(path)


def test_the_rules_are_modules_of_their_own():
    """A rule module imports no other rule module (the parts and passes call the rules)."""
    wrong = [
        f"{m} imports {target}"
        for m, imports in GRAPH.items()
        if m.startswith("st.compiler.check.rules.")
        for target, _, _, _ in imports
        if target.startswith("st.compiler.check.rules.") and target != m
    ]
    assert not wrong, "\n".join(wrong)


def test_no_call_target_is_read_by_a_kind_string():
    """Call targets are one class per kind (check/targets.py), read with match or isinstance: none
    has a `kind`, and no module compares `<target>.kind`."""
    from st.compiler.check import targets

    kinds = [
        c.__name__
        for c in vars(targets).values()
        if isinstance(c, type) and issubclass(c, targets.CallTarget) and hasattr(c, "kind")
    ]
    assert not kinds, f"call targets with a kind: {kinds}"
    wrong = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for n in ast.walk(ast.parse(path.read_text())):
            if isinstance(n, ast.Attribute) and n.attr == "kind":
                base = n.value
                named = base.attr if isinstance(base, ast.Attribute) else base.id if isinstance(base, ast.Name) else ""
                if named in ("target", "tgt"):
                    wrong.append(f"{path.relative_to(ROOT)}:{n.lineno}")
    assert not wrong, "\n".join(wrong)
