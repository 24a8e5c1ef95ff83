"""CompileOptions: built from the API's keyword arguments and the sources' pragmas, part of the
cache key; diagnostics a dialect makes moot are dropped by code and data, not by message text."""

from __future__ import annotations

from st import PLC
from st.api import compile_text
from st.compiler.dialect import PRESETS
from st.compiler.options import CompileOptions
from st.source import SourceFile


def test_options_from_keywords_and_pragmas():
    src = SourceFile("a.st", "{dialect 'openplc'}\n{attribute 'strict'}\nTYPE Mode : (A, B); END_TYPE\n")
    assert CompileOptions.for_sources([src]) == CompileOptions(PRESETS["openplc"], "s", True, frozenset({"mode"}))
    assert CompileOptions.for_sources([src], dialect="codesys", coverage=True).dialect is PRESETS["codesys"]
    assert CompileOptions.for_sources([], time_unit="s") == CompileOptions(time_unit="s")


def test_the_cache_key_includes_the_options(tmp_path, monkeypatch):
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path))
    src = "PROGRAM main\nVAR t : TIME := T#1500ms; n : DINT; END_VAR\nn := TIME_TO_DINT(t);\nEND_PROGRAM\n"
    runs = [
        compile_text(src, "o.st", **kw)
        for kw in ({}, {"time_unit": "s"}, {"dialect": "openplc"}, {"emit_python": True}, {}, {"dialect": "openplc"})
    ]
    assert [r.from_cache for r in runs] == [False, False, False, False, True, True]
    assert [_scan_n(r) for r in runs] == [1500, 1, 1, 1500, 1500, 1]
    assert runs[3].python_source and not runs[0].python_source


def _scan_n(compiled) -> int:
    plc = PLC(compiled)
    plc.scan()
    return plc["main.n"]


def test_pragmas_a_dialect_knows_are_not_reported_as_ignored():
    src = (
        "{dialect 'codesys'}\n{ attribute 'qualified_only' }\n{warning 'x'}\n"
        "PROGRAM main\nVAR a : INT; END_VAR\na := 1;\nEND_PROGRAM\n"
    )
    w = [d for d in compile_text(src, "p.st", use_cache=False).diagnostics if d.code == "W001"]
    assert [(d.span.line, d.datum("pragma")) for d in w] == [(3, "warning")]
    w = [d for d in compile_text(src, "p.st", use_cache=False, dialect="iec").diagnostics if d.code == "W001"]
    assert [(d.span.line, d.datum("pragma")) for d in w] == [(2, "attribute"), (3, "warning")]
