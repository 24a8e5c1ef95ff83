"""Diagnostic codes: every code the source emits is a `Code`, every `Code` is documented in
docs/diagnostics.md, every documented code is a `Code`, and the docs are generated from the enum;
every `Code` has a failing fixture (tests/fixtures/errors) and `st explain` shows it; every rule of
the checker (st/compiler/check/rules) has a passing fixture and a failing one per code it raises."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from st.api import compile_paths
from st.cli import main
from st.diagnostics import Code, CompileError
from st.errors_doc import explain, markdown

ROOT = Path(__file__).resolve().parent.parent
CODE = re.compile(r"[EW]\d{3}")


def _codes_in_source() -> dict[str, set[str]]:
    """Every string constant of st/ that looks like a code (what err/warning/Diagnostic are given),
    with the files it appears in."""
    found: dict[str, set[str]] = {}
    for path in sorted((ROOT / "st").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and CODE.fullmatch(node.value):
                found.setdefault(node.value, set()).add(str(path.relative_to(ROOT)))
    return found


def _documented() -> list[str]:
    text = (ROOT / "docs" / "diagnostics.md").read_text()
    return re.findall(r"^\| ([EW]\d{3}) \|", text, re.M)


def test_every_emitted_code_is_a_member():
    members = {c.value for c in Code}
    unknown = {code: files for code, files in _codes_in_source().items() if code not in members}
    assert not unknown, f"codes used in st/ but missing from st.diagnostics.Code: {unknown}"


def test_the_source_emits_codes():
    assert {"E001", "E013", "W002"} <= set(_codes_in_source())


def test_every_member_is_documented_and_every_documented_code_is_a_member():
    documented = _documented()
    assert len(documented) == len(set(documented)), "a code is documented twice"
    assert set(documented) == {c.value for c in Code}


def test_docs_are_generated_from_the_enum():
    assert (ROOT / "docs" / "diagnostics.md").read_text() == markdown()


def test_codes_compare_as_strings():
    assert Code.TYPE_MISMATCH == "E013"
    assert f"[{Code.TYPE_MISMATCH}]" == "[E013]"
    assert {"E013": 1}[Code.TYPE_MISMATCH] == 1
    assert Code("E013") is Code.TYPE_MISMATCH


def test_explain():
    assert explain("e027").startswith("An implicit narrowing conversion")
    assert explain("E999") is None
    assert all(c.explanation for c in Code)


# ------------------------------------------------------------------ a fixture for every code, a rule per module

FIXTURES = ROOT / "tests" / "fixtures"
RULES = ROOT / "st" / "compiler" / "check" / "rules"
MARKER = re.compile(r"@(error|warn)\s+([EW]\d{3})")
# the codes no fixture file can produce, and where each is tested instead
WITHOUT_FIXTURE = {
    "E000": "a file that cannot be read: test_an_unreadable_file_is_e000 below",
    "E099": "an internal compiler error (a bug): test_hardening_compiler.py, test_compiled_model.py",
    "W012": "the native tier's toolchain missing or failing: test_native.py",
    "W014": "a .plcproj's library reference not found: test_twincat_projects.py",
}


def _markers() -> dict[str, set[tuple[str, str]]]:
    """code → {(fixture file, error/warn)} of every marker in tests/fixtures/errors."""
    found: dict[str, set[tuple[str, str]]] = {}
    for path in sorted((FIXTURES / "errors").rglob("*")):
        if path.suffix in (".st", ".xml"):
            for kind, code in MARKER.findall(path.read_text()):
                found.setdefault(code, set()).add((path.name, kind))
    return found


def _rule_codes() -> dict[str, set[str]]:
    """rule module name → the codes its docstring names (`Codes: E052.`)."""
    out = {}
    for path in sorted(RULES.glob("*.py")):
        if path.name == "__init__.py":
            continue
        doc = ast.get_docstring(ast.parse(path.read_text())) or ""
        m = re.search(r"^Codes: (.+)\.$", doc, re.M)
        assert m, f"{path.name}: its docstring names no 'Codes: ...'"
        out[path.stem] = set(CODE.findall(m.group(1)))
    return out


def test_every_code_has_a_failing_fixture():
    markers = _markers()
    missing = [c.value for c in Code if c.value not in markers and c.value not in WITHOUT_FIXTURE]
    assert not missing, f"codes without a fixture in tests/fixtures/errors: {missing}"
    assert not set(WITHOUT_FIXTURE) & set(markers), "a code with a fixture need not be listed in WITHOUT_FIXTURE"
    assert set(WITHOUT_FIXTURE) <= {c.value for c in Code}


def test_every_marker_names_a_code_with_its_severity():
    members = {c.value for c in Code}
    for code, uses in _markers().items():
        assert code in members, f"{sorted(uses)} mark {code}, which is no Code"
        for name, kind in uses:
            assert kind == ("error" if code.startswith("E") else "warn"), f"{name}: @{kind} {code}"


def test_every_rule_has_its_fixtures():
    """Each rule module: a passing example (tests/fixtures/ok/<rule>.st) and, for each code it
    raises, a failing fixture."""
    markers = _markers()
    rules = _rule_codes()
    assert len(rules) >= 30
    for rule, codes in rules.items():
        assert (FIXTURES / "ok" / f"{rule}.st").is_file(), f"rule {rule} has no tests/fixtures/ok/{rule}.st"
        assert codes, f"rule {rule} names no code"
        assert not [c for c in codes if c not in markers], f"rule {rule}: a code without a failing fixture"
    assert {p.stem for p in (FIXTURES / "ok").glob("*.st")} == set(rules), "an ok fixture of no rule"


def test_an_unreadable_file_is_e000(tmp_path):
    with pytest.raises(CompileError) as info:
        compile_paths([str(tmp_path / "missing.st")], use_cache=False)
    assert [str(d.code) for d in info.value.diagnostics] == ["E000"]


def test_st_explain_shows_every_code():
    for c in Code:
        r = CliRunner().invoke(main, ["explain", c.value.lower()])
        assert r.exit_code == 0 and r.output == f"{c.value}: {c.explanation}\n", r.output
