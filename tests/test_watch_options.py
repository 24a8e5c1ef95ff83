"""--watch compiles each change with the command line's --dialect and --lib (issue 34: they were
dropped, so an online change of a TwinCAT project compiled under no preset and without its
libraries)."""

from __future__ import annotations

from st import PLC
from st.api import compile_paths
from st.app.options import RunOptions
from st.app.watch import Watcher

OLD = "PROGRAM main\nVAR n : DINT; END_VAR\nn := 0;\nEND_PROGRAM\n"
NEW = "PROGRAM main\nVAR n : DINT; END_VAR\nn := TIME_TO_DINT(T#2s);\nEND_PROGRAM\n"


def test_an_online_change_is_compiled_with_the_dialect_of_the_command_line(tmp_path):
    f = tmp_path / "w.st"
    f.write_text(OLD)
    plc = PLC(compile_paths([str(f)], dialect="openplc", use_cache=False))
    plc.scan(1)
    f.write_text(NEW)
    watcher = Watcher(plc, RunOptions(files=[str(f)], dialect="openplc"))
    watcher._prepare_change()  # what the background thread does, here in the test's thread
    assert watcher.result is not None
    watcher._swap(watcher.result)
    plc.scan(1)
    assert plc["main.n"] == 2  # openplc's TIME_TO_DINT counts seconds (the default: 2000)
