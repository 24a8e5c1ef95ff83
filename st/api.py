"""The public Python API: compile ST (`compile_text`, `compile_paths`, the libraries they use).
`st.PLC`, the runtime's PLC with constructors that compile first, is st/facade.py's:

    from st import PLC
    plc = PLC.from_source(text, cycle="10ms")
    plc.scan(); plc.advance("2.5s"); plc["main.x"]

Compiling loads no runtime (`st check` starts at once).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

from .compiler.driver import compile_sources, load_files
from .compiler.options import CompileOptions
from .diagnostics import CompileError
from .model.compiled import CompiledProgram
from .model.program import Project
from .source import SourceFile
from .stdlib.iec import default_library
from .stdlib.plcopen import library as plcopen_library
from .stdlib.vendor import library as vendor_library


def libraries(options: CompileOptions | None = None) -> list:
    """The libraries of a compilation: the standard library (its time unit and F_TRIG behaviour
    are the options'), PLCopen motion, and the vendor compatibility library under codesys, twincat
    and the default (not under iec and openplc, whose programs know none of its names)."""
    options = options or CompileOptions()
    matiec = options.dialect is not None and options.dialect.matiec_errors
    p0 = options.dialect is not None and options.dialect.position_zero
    libs = [default_library(options.f_trig_first_scan, options.time_unit, matiec, p0), plcopen_library()]
    if options.dialect is None or options.dialect.vendor_library:
        libs.append(vendor_library())
    return libs


def provided_libraries() -> frozenset[str]:
    """The lower-case names of the system libraries st stands in for (the namespaces its libraries
    answer to: Tc2_Standard, Tc2_System, SysFile, ...): a project's references to them are not
    searched for."""
    return frozenset(n.lower() for lib in (default_library(), vendor_library()) for n in lib.namespaces)


def _refused(e: CompileError, raise_on_error: bool) -> CompiledProgram:
    """A compile that stopped before the pipeline (an unknown dialect pragma), as the pipeline
    reports one: raised, or returned with its diagnostics."""
    if raise_on_error:
        raise e
    return CompiledProgram([], Project(), e.diagnostics, e.sources)


def compile_text(
    text: str,
    name: str = "<source>.st",
    *,
    f_trig_first_scan: bool = False,
    time_unit: str = "ms",
    use_cache: bool = True,
    emit_python: bool = False,
    raise_on_error: bool = True,
    coverage: bool = False,
    dialect: str | None = None,
    native: bool = False,
) -> CompiledProgram:
    src = SourceFile(name, text.replace("\r\n", "\n"))
    return _compile(
        [src],
        raise_on_error,
        dialect=dialect,
        time_unit=time_unit,
        f_trig_first_scan=f_trig_first_scan,
        use_cache=use_cache,
        emit_python=emit_python,
        coverage=coverage,
        native=native,
    )


def compile_paths(
    paths: list,
    *,
    f_trig_first_scan: bool = False,
    time_unit: str = "ms",
    use_cache: bool = True,
    emit_python: bool = False,
    raise_on_error: bool = True,
    coverage: bool = False,
    dialect: str | None = None,
    native: bool = False,
    lib_path: Sequence[str | os.PathLike] = (),
) -> CompiledProgram:
    """Compile ST files (.st, TwinCAT's .TcPOU/.../.plcproj, PLCopen XML). A .plcproj's library
    references are looked up in `lib_path` (library .plcproj files or folders holding them), then
    in $ST_LIBPATH (compiler/libpath.py)."""
    sources = load_files([str(p) for p in paths], [str(p) for p in lib_path], provided_libraries())
    return _compile(
        sources,
        raise_on_error,
        dialect=dialect,
        time_unit=time_unit,
        f_trig_first_scan=f_trig_first_scan,
        use_cache=use_cache,
        emit_python=emit_python,
        coverage=coverage,
        native=native,
    )


def _compile(sources: list[SourceFile], raise_on_error: bool, **options) -> CompiledProgram:
    """The options from the keyword arguments and the sources' pragmas, then the pipeline."""
    try:
        chosen = CompileOptions.for_sources(sources, **options)
    except CompileError as e:
        return _refused(e, raise_on_error)
    return compile_sources(sources, libraries(chosen), chosen, raise_on_error=raise_on_error)


def own_sources(compiled: CompiledProgram) -> list[SourceFile]:
    """The source texts `compiled` was made from (its libraries' left out), as they were then."""
    library_paths = {path for lib in compiled.project.libraries for path, _text in lib.sources}
    return [s for path, s in compiled.sources.items() if path not in library_paths]


def compile_sources_again(sources: list[SourceFile], **options) -> CompiledProgram:
    """Source texts already read (`own_sources`) compiled with `options`, without raising (see the
    result's diagnostics): the same cache entry as any other compile of those texts."""
    return _compile(sources, False, **options)


def compile_again(compiled: CompiledProgram, **options) -> CompiledProgram:
    """The program `compiled` was made from, compiled again with other `options` (native=True): its
    own source texts, as they were then (not the files as they are now: an edit since is not in
    it), without raising (see the result's diagnostics)."""
    return compile_sources_again(own_sources(compiled), **options)
