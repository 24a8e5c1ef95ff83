"""A compiled program names its native module by the hash of the module's contents, never by a
path: it finds the module in the build cache wherever the cache is when it runs, and a cached
compile whose module is gone is compiled (and built) again (issue 33)."""

from __future__ import annotations

import shutil

import pytest

from st import PLC
from st.api import compile_text
from st.compiler.native import toolchain
from st.model.compiled import CompiledProgram, native_dir

needs_toolchain = pytest.mark.skipif(toolchain.missing() is not None, reason=f"native tier: {toolchain.missing()}")

# a program of this test alone: its module is loaded into this process by this test only
MOVED = """\
PROGRAM moved
VAR a : ARRAY[1..8] OF DINT; i : INT; n : DINT; END_VAR
FOR i := 1 TO 8 DO
  a[i] := a[i] + i * 7919;
END_FOR;
n := n + a[8];
END_PROGRAM
"""


@pytest.mark.slow  # a native build in a fresh cache
@needs_toolchain
def test_an_artefact_finds_its_module_by_hash_after_the_cache_moves(tmp_path, monkeypatch):
    first, second = tmp_path / "first", tmp_path / "second"
    monkeypatch.setenv("ST_CACHE_DIR", str(first))
    compiled = compile_text(MOVED, "moved.st", native=True)
    (module,) = compiled.native
    assert module.file == first / "compiled" / "native" / module.file.name and module.file.exists()
    assert module.name == toolchain.module_name(module.file.with_name(module.pyx).read_text())
    data = compiled.to_bytes()
    assert str(tmp_path).encode() not in data  # no path in the artefact

    shutil.move(first, second)
    monkeypatch.setenv("ST_CACHE_DIR", str(second))
    assert native_dir() == second / "compiled" / "native"
    loaded = CompiledProgram.from_bytes(data, sources=compiled.sources, helpers=compiled.helpers)
    plc = PLC(loaded)
    assert type(plc.instances["moved"][1])._body.__module__ == module.name  # the compiled body
    plc.scan(2)
    assert plc["moved.n"] == (1 + 2) * 8 * 7919  # a[8] after the first scan, then the second
    assert not [e for e in plc.log.entries if "not used" in e.text]
    # the compile cache moved with it: the same program is a hit, its module found there
    again = compile_text(MOVED, "moved.st", native=True)
    assert again.from_cache and again.native == compiled.native


@pytest.mark.slow  # two native builds in a fresh cache
@needs_toolchain
def test_a_cached_compile_whose_module_is_gone_is_built_again(tmp_path, monkeypatch):
    monkeypatch.setenv("ST_CACHE_DIR", str(tmp_path))
    text = MOVED.replace("7919", "7907")
    compiled = compile_text(text, "gone.st", native=True)
    (module,) = compiled.native
    assert compile_text(text, "gone.st", native=True).from_cache
    shutil.rmtree(module.file.parent)  # the native build directory, not the compile cache
    again = compile_text(text, "gone.st", native=True)
    assert not again.from_cache and again.native == compiled.native and module.file.exists()
