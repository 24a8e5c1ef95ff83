"""Diagnostic codes: every code the source emits is a `Code`, every `Code` is documented in
docs/diagnostics.md, every documented code is a `Code`, and the docs are generated from the enum."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from st.diagnostics import Code
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
