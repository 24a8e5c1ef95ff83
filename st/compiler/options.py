"""How a program is compiled: one value, chosen once and passed down explicitly.

`st.api` builds the options from its keyword arguments and the sources' pragmas; the driver hands
them to the checker and to code generation, and the compile cache keys on them.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

from ..source import SourceFile
from .dialect import Dialect, pragma_preset, preset, strict_types
from .twincat import is_twincat


@dataclass(frozen=True)
class CompileOptions:
    dialect: Dialect | None = None  # a preset (st.compiler.dialect); None: everything accepted
    time_unit: str = "ms"  # what TIME_TO_<int> counts: ms, or s as MatIEC
    f_trig_first_scan: bool = False  # F_TRIG pulses on the first scan (MatIEC)
    strict_types: frozenset[str] = frozenset()  # types declared {attribute 'strict'} (lower-case names)
    emit_python: bool = False  # keep the generated Python text (CompiledProgram.python_source)
    coverage: bool = False  # line and branch probes (never cached)
    use_cache: bool = True
    native: bool = False  # block bodies compiled to C by Cython (compiler/native, docs/native.md)

    @classmethod
    def for_sources(
        cls,
        sources: Iterable[SourceFile],
        *,
        dialect: str | None = None,
        time_unit: str = "ms",
        f_trig_first_scan: bool = False,
        emit_python: bool = False,
        coverage: bool = False,
        use_cache: bool = True,
        native: bool = False,
    ) -> CompileOptions:
        """The options of a compile of `sources`. The preset is `dialect` (an unknown name is a
        ValueError) or else the one a `{dialect '…'}` pragma names (an unknown one is a CompileError,
        E045), or else twincat when every source is a TwinCAT file; a preset decides the time unit and
        the F_TRIG behaviour. (A PLCopen XML file names the preset of the tool that wrote it with a
        pragma in its laid-out ST: plcopen_xml.py.)"""
        sources = list(sources)
        chosen = preset(dialect) if dialect is not None else pragma_preset(sources)
        if chosen is None and sources and all(is_twincat(s.path) for s in sources):
            chosen = preset("twincat")
        if chosen is not None:
            time_unit, f_trig_first_scan = chosen.time_unit, chosen.f_trig_first_scan
        native = native or os.environ.get("ST_NATIVE", "") not in ("", "0")  # the whole suite on the native tier
        return cls(
            chosen,
            time_unit,
            f_trig_first_scan,
            frozenset(strict_types(s.text for s in sources)),
            emit_python,
            coverage,
            use_cache,
            native,
        )

    def cache_token(self) -> str:
        """The options that decide the compiled output, as text for the cache key."""
        return repr(
            (
                self.dialect,
                self.time_unit,
                self.f_trig_first_scan,
                sorted(self.strict_types),
                self.emit_python,
                self.coverage,
                self.native,
            )
        )
