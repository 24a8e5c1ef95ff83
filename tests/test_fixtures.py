"""Fixture tables: ST programs with their expected results, and ST files with marked errors.

tests/fixtures/run/**.st   header comments:  (* @scans N *)  (* @cycle T#10ms *)
                           (* @expect path = JSON *)   one per expectation
tests/fixtures/errors/*.st  a line that must report an error ends with (* @error E013 *), one that must
                           warn with (* @warn W005 *); nothing else may be reported unless the file says
                           (* @allow W005 *) or the line @cascade E013 (PLCopen XML projects, *.xml, mark
                           their lines the same way in XML comments: <!-- @error E050 -->)
tests/fixtures/ok/*.st      a passing example for each rule of the checker (st/compiler/check/rules/NAME.py
                           has ok/NAME.st): it compiles without any diagnostic
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from st import PLC
from st.api import compile_paths
from st.compiler.codegen import f32
from st.diagnostics import render_all
from st.model import types as T

HERE = Path(__file__).parent / "fixtures"
RUN = sorted((HERE / "run").rglob("*.st"))
ERRORS = sorted((HERE / "errors").rglob("*.st")) + sorted((HERE / "errors").rglob("*.xml"))
OK = sorted((HERE / "ok").rglob("*.st"))

_EXPECT = re.compile(r"@expect\s+([^=]+?)\s*=\s*(.+?)\s*\*\)")
_SCANS = re.compile(r"@scans\s+(\d+)")
_CYCLE = re.compile(r"@cycle\s+(\S+?)\s*\*\)")
_ERROR = re.compile(r"@error\s+([EW]\d{3})")
_WARN = re.compile(r"@warn\s+([EW]\d{3})")
_ALLOW = re.compile(r"@allow\s+([EW]\d{3})")
_CASCADE = re.compile(r"@cascade\s+([EW]\d{3})")


def _ids(paths, root):
    return [str(p.relative_to(root)) for p in paths]


def _resolve_type(plc: PLC, path: str):
    if path.strip().startswith("%"):
        return None
    return plc.ref(path).type


def _same(actual, expected, t) -> bool:
    b = T.base_of(t) if t is not None else None
    if isinstance(expected, float) or (isinstance(expected, int) and isinstance(actual, float)):
        if b is not None and b.is_real and b.bits == 32:
            return actual == f32(float(expected))
        return actual == float(expected)
    if isinstance(expected, list) and isinstance(actual, list):
        et = T.unalias(t).element if isinstance(T.unalias(t), T.ArrayType) else None
        if len(actual) != len(expected):
            return False
        inner = et
        if isinstance(T.unalias(t), T.ArrayType) and len(T.unalias(t).dims) > 1:
            sub = T.ArrayType(T.unalias(t).dims[1:], et)
            return all(_same(a, e, sub) for a, e in zip(actual, expected))
        return all(_same(a, e, inner) for a, e in zip(actual, expected))
    if isinstance(expected, dict) and isinstance(actual, dict):
        ut = T.unalias(t)
        if set(k.lower() for k in expected) != set(k.lower() for k in actual):
            return False
        amap = {k.lower(): v for k, v in actual.items()}
        for k, v in expected.items():
            mt = None
            if isinstance(ut, T.StructType) and k.lower() in ut.members:
                mt = ut.members[k.lower()].type
            if not _same(amap[k.lower()], v, mt):
                return False
        return True
    return actual == expected


@pytest.mark.parametrize("path", RUN, ids=_ids(RUN, HERE / "run"))
def test_run_fixture(path: Path):
    text = path.read_text()
    expects = _EXPECT.findall(text)
    assert expects, f"{path} has no @expect line"
    m = _SCANS.search(text)
    scans = int(m.group(1)) if m else 1
    m = _CYCLE.search(text)
    cycle = m.group(1) if m else None
    plc = PLC.from_files(str(path), cycle=cycle)
    plc.scan(scans)
    from st.runtime.values import to_json

    failures = []
    for var, raw in expects:
        expected = json.loads(raw)
        if var.strip().startswith("%"):
            actual = plc[var]
            t = None
        else:
            ref = plc.ref(var)
            t = ref.type
            actual = to_json(ref.get(), t)
        if not _same(actual, expected, t):
            failures.append(f"{var}: expected {expected!r}, got {actual!r}")
    assert not failures, "\n".join(failures)


def markers(text: str) -> set[tuple[int, str, str]]:
    """(line, code, severity) of each `@error` and `@warn` marker of a fixture."""
    lines = text.splitlines()
    return {
        (i + 1, m.group(1), severity)
        for i, line in enumerate(lines)
        for pattern, severity in ((_ERROR, "error"), (_WARN, "warning"))
        for m in pattern.finditer(line)
    }


@pytest.mark.parametrize("path", ERRORS, ids=_ids(ERRORS, HERE / "errors"))
def test_error_fixture(path: Path):
    """Exactly the marked diagnostics, each with its severity (`@error`, `@warn`): a missing one
    fails, and so does any other one (error or warning) unless the file allows its code with
    `(* @allow W005 *)`, or it is a known follow-on error of the line's own error, marked
    `@cascade E013` (tolerated, not required: a follow-on that goes away is an improvement)."""
    text = path.read_text()
    lines = text.splitlines()
    wanted = markers(text)
    assert wanted, f"{path} marks no @error or @warn"
    allowed = set(_ALLOW.findall(text))
    cascades = {(i + 1, m.group(1)) for i, line in enumerate(lines) for m in _CASCADE.finditer(line)}
    compiled = compile_paths([str(path)], use_cache=False, raise_on_error=False)
    diags = [d for d in compiled.diagnostics if d.span is not None and d.span.file == str(path)]
    got = {(d.span.line, str(d.code), d.severity.value) for d in diags}
    missing = wanted - got
    extra = {
        (line, code, sev) for line, code, sev in got - wanted if (line, code) not in cascades and code not in allowed
    }
    rendered = render_all(compiled.diagnostics, compiled.sources)
    assert not missing and not extra, f"missing {sorted(missing)}, unexpected {sorted(extra)}; reported:\n{rendered}"
    assert any(d.is_error for d in compiled.diagnostics) == any(sev == "error" for _, _, sev in wanted)
    assert "Traceback" not in rendered


@pytest.mark.parametrize("path", OK, ids=_ids(OK, HERE / "ok"))
def test_ok_fixture(path: Path):
    """A rule's passing example: what the rule allows compiles without any diagnostic."""
    compiled = compile_paths([str(path)], use_cache=False, raise_on_error=False)
    assert not compiled.diagnostics, render_all(compiled.diagnostics, compiled.sources)
