"""Golden tests of generated Python: tests/golden/<name>.st compiles to exactly <name>.py.

A change to code generation shows here as a diff of the Python it prints. When the change is
meant, rewrite the files with `ST_UPDATE_GOLDEN=1 pytest tests/test_golden.py` and review the
diff in version control.
"""

from __future__ import annotations

import difflib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from st.api import compile_paths

GOLDEN = Path(__file__).with_name("golden")
CASES = sorted(p.stem for p in GOLDEN.glob("*.st"))


def emitted(st_path: Path) -> str:
    r = compile_paths([str(st_path)], emit_python=True, use_cache=False)
    return r.python_source[str(st_path)] + "\n"


@pytest.mark.parametrize("name", CASES)
def test_generated_python_is_the_golden_one(name):
    st_path, py_path = GOLDEN / f"{name}.st", GOLDEN / f"{name}.py"
    got = emitted(st_path)
    if os.environ.get("ST_UPDATE_GOLDEN") == "1":
        py_path.write_text(got)
        return
    want = py_path.read_text() if py_path.exists() else ""
    if got != want:
        diff = "".join(
            difflib.unified_diff(
                want.splitlines(True), got.splitlines(True), f"golden/{name}.py", f"generated from golden/{name}.st"
            )
        )
        pytest.fail(
            f"the generated Python of golden/{name}.st changed (ST_UPDATE_GOLDEN=1 rewrites it):\n{diff}", pytrace=False
        )


def test_there_are_golden_programs():
    assert len(CASES) >= 4


@pytest.mark.slow
def test_emit_python_marks_each_statement_with_its_st_line(tmp_path):
    f = tmp_path / "e.st"
    f.write_text(
        "FUNCTION Twice : INT\n"
        "VAR_INPUT x : INT; END_VAR\n"
        "IF x > 10 THEN\n"
        "  Twice := 0;\n"
        "ELSIF x > 5 THEN\n"
        "  Twice := 1;\n"
        "ELSE\n"
        "  Twice := x * 2;\n"
        "END_IF;\n"
        "END_FUNCTION\n"
        "PROGRAM p\n"
        "VAR y : INT; i : INT; END_VAR\n"
        "FOR i := 1 TO 3 DO\n"
        "  y := Twice(y + 1);\n"
        "END_FOR;\n"
        "END_PROGRAM\n"
    )
    r = subprocess.run(
        [sys.executable, "-m", "st", "compile", str(f), "--emit", "python"], capture_output=True, text=True, timeout=120
    )
    assert r.returncode == 0, r.stderr
    assert (
        r.stdout
        == f"""\
# ---- generated from {f}
def _fn_Twice(x):  # st:1
    Twice = 0  # st:1
    if x > 10:  # st:3
        Twice = 0  # st:4
    elif x > 5:  # st:5
        Twice = 1  # st:6
    else:
        Twice = (x * 2 + 32768 & 65535) - 32768  # st:8
    return Twice  # st:10

class _prg_p(_FB):  # st:11
    __slots__ = ('y', 'i')  # st:11
    _kinds = ('p',)  # st:11

    def __init__(self):  # st:11
        self.y = 0  # st:12
        self.i = 0  # st:12

    def _body(self):  # st:11
        i = self.i  # st:11
        y = self.y  # st:11
        try:  # st:11
            i = 1 - 1  # st:13
            for i in _range(1, 4):  # st:13
                if _wd_armed:  # st:13
                    _wd_check()  # st:13
                y = _fn_Twice((y + 1 + 32768 & 65535) - 32768)  # st:14
            else:
                i = (i + 1 + 32768 & 65535) - 32768  # st:13
        finally:
            self.i = i  # st:16
            self.y = y  # st:16
"""
    )
