"""What starting st loads (issue 36: the CLI starts at once): `st --version`/`--help` load no
compiler and no runtime, and a compile answered from the cache loads neither the grammar nor the
checker, the code generator or the runtime. Times are in bench/bench_cli.py, not here."""

from __future__ import annotations

import json
import subprocess
import sys

HEAVY = ("lark", "st.compiler.build", "st.compiler.check", "st.compiler.lower", "st.compiler.codegen.module")
RUNTIME = ("st.runtime.plc", "st.runtime.engine")


def _loaded(code: str, env: dict | None = None) -> list[str]:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


REPORT = "import sys, json; print(json.dumps(sorted(m for m in sys.modules if m.startswith({prefixes!r}))))"


def test_the_command_line_loads_no_compiler_and_no_runtime_to_start():
    code = "import st.cli; " + REPORT.format(prefixes=HEAVY + RUNTIME)
    assert _loaded(code) == []


def test_a_compile_from_the_cache_loads_neither_grammar_nor_checker_nor_runtime(tmp_path):
    import os

    src = tmp_path / "p.st"
    src.write_text("PROGRAM p\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n")
    env = {**os.environ, "ST_CACHE_DIR": str(tmp_path / "cache")}
    compile_it = f"from st.api import compile_paths; r = compile_paths([{str(src)!r}]); "
    first = _loaded(compile_it + REPORT.format(prefixes=HEAVY), env)
    assert "st.compiler.check" in first  # (a miss: the whole pipeline)
    again = _loaded(compile_it + "assert r.from_cache; " + REPORT.format(prefixes=HEAVY + RUNTIME), env)
    assert again == []
