"""The native build's own process (`python -m st.app.native_build`, app/native_upgrade.py): the
program's source texts and compile options arrive pickled on stdin, the build compiled to C goes
into st's compile cache, and the exit status says whether it is there. Cython and the C compiler
then run beside the PLC's process, not in it: the scan never waits for them to hand back the
interpreter."""

from __future__ import annotations

import pickle
import sys


def main() -> int:
    from ..api import compile_sources_again
    from ..source import SourceFile

    texts, options = pickle.load(sys.stdin.buffer)
    compiled = compile_sources_again([SourceFile(path, text) for path, text in texts], **options)
    return 0 if compiled.native else 1


if __name__ == "__main__":
    sys.exit(main())
