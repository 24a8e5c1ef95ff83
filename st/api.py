"""The public Python API: compile ST and get a PLC.

    from st import PLC
    plc = PLC.from_source(text, cycle="10ms")
    plc.scan(); plc.advance("2.5s"); plc["main.x"]
"""
from __future__ import annotations

from .compiler.driver import CompiledProgram, compile_sources, load_files
from .source import SourceFile
from .stdlib.iec import default_library


def libraries(f_trig_first_scan: bool = False, time_unit: str = "ms") -> list:
    from .stdlib.plcopen import library as plcopen_library
    return [default_library(f_trig_first_scan, time_unit), plcopen_library()]


def compile_text(text: str, name: str = "<source>.st", *, f_trig_first_scan: bool = False,
                 time_unit: str = "ms", use_cache: bool = True, emit_python: bool = False,
                 raise_on_error: bool = True, coverage: bool = False) -> CompiledProgram:
    src = SourceFile(name, text.replace("\r\n", "\n"))
    return compile_sources([src], libraries(f_trig_first_scan, time_unit), use_cache=use_cache,
                           emit_python=emit_python, raise_on_error=raise_on_error, coverage=coverage)


def compile_paths(paths: list, *, f_trig_first_scan: bool = False, time_unit: str = "ms",
                  use_cache: bool = True, emit_python: bool = False, raise_on_error: bool = True,
                  coverage: bool = False) -> CompiledProgram:
    return compile_sources(load_files([str(p) for p in paths]), libraries(f_trig_first_scan, time_unit),
                           use_cache=use_cache, emit_python=emit_python, raise_on_error=raise_on_error,
                           coverage=coverage)
