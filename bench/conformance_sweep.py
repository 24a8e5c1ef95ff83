"""Measure st on real-world ST code: every file of each source checked alone, with no dialect and
with the dialect that fits the source, classified clean / refused / internal error.

    python bench/conformance_sweep.py CORPORA [--out DIR] [--timeout 60] [--jobs 1] [--only NAME]

CORPORA is a directory holding the public repositories (docs/conformance.md says how to fetch
them); nothing of theirs is in this repository. The report (markdown) goes to stdout and to
DIR/conformance.md, every file's result to DIR/results.json. A file is:

- clean: no error (warnings allowed);
- refused: an error other than E099, reported by its first error (code, message with names
  replaced by '…', file:line);
- internal: E099, an exception out of the compiler, or no answer within the timeout.

PLCopen XML (`plc.xml`, the OpenPLC Editor's library files) is compiled as it is (st reads its ST
and SFC bodies); a project with an FBD, LD or IL body (E050) is counted as skipped, not as refused.
TwinCAT's projects (.plcproj with their .TcPOU/.TcDUT/.TcGVL) listed as `plcprojs` are units of
their own, each compiled with the libraries it references found on its search path (the sweep's
`--lib`); a source's `project` files are counted as a project format unless --projects compiles
them (a source's projects as one unit).
"""

from __future__ import annotations

import argparse
import collections
import concurrent.futures
import hashlib
import json
import re
import signal
import sys
import time
import traceback
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path


@dataclass(frozen=True)
class Source:
    name: str
    dialect: str  # the preset that fits the code's compiler ("default": st's own, no preset)
    root: str  # directory under CORPORA
    st: tuple[str, ...] = ()  # globs of ST text files
    xml: tuple[str, ...] = ()  # globs of PLCopen XML projects
    project: tuple[str, ...] = ()  # globs of project files st does not read yet
    exclude: tuple[str, ...] = ()  # path fragments left out
    # units compiled together, as the source's own build does: (glob of directories, glob of files in
    # each); the files of a unit are not checked alone
    together: tuple[tuple[str, str], ...] = ()
    alone: tuple[str, ...] = ()  # path fragments of files checked alone even inside a unit
    pairs: bool = False  # test_X.st is compiled with X.st beside it (STruC++'s validation suite)
    # TwinCAT/CODESYS projects, each a unit with the libraries it references found on a search path:
    # (glob of .plcproj files under the root, the search path: paths under CORPORA given as --lib)
    plcprojs: tuple[tuple[str, tuple[str, ...]], ...] = ()


SOURCES = (
    Source("OpenPLC v3 runtime", "openplc", "thiagoralves-OpenPLC_v3", st=("webserver/**/*.st",)),
    Source(
        "OpenPLC Editor (examples, block libraries)",
        "openplc",
        "thiagoralves-editor",
        st=("**/*.st",),
        xml=("**/plc.xml", "plcopen/*_Blocks.xml", "plcopen/*Cards.xml", "plcopen/MQTT.xml", "plcopen/P1AM.xml"),
    ),
    Source(
        "OpenPLC sample programs (gracesrm)",
        "openplc",
        "gracesrm-OpenPLC_Sample_Programs",
        st=("**/*.st",),
        xml=("**/plc.xml",),
    ),
    Source("OpenPLC user project: CybICS", "openplc", "mniedermaier-CybICS", st=("**/*.st",), xml=("**/plc.xml",)),
    Source(
        "OpenPLC user project: OpenPLC_Tutorials (LD, as generated ST)",
        "openplc",
        "virajdesai0309-OpenPLC_Tutorials",
        st=("**/*.st",),
        xml=("**/plc.xml",),
    ),
    Source("OSCAT as OpenPLC generates it", "openplc", "wonka929-OSCAT_OpenPLC", st=("**/*.st",), xml=("**/plc.xml",)),
    Source(
        "MatIEC lib and Annex F (OpenPLC's fork)",
        "openplc",
        "thiagoralves-matiec",
        st=("lib/*.txt", "AnnexF/*.txt"),
        # MatIEC reads its library as one text (ieclib.txt includes the rest) and the Annex F examples
        # use each other's blocks; the {#include} wrappers themselves are left out, and the
        # declarations of MatIEC's built-in functions (not ST: `IN 1 .. : REAL`) are checked alone
        exclude=("lib/ieclib.txt", "lib/standard_FB.txt"),
        alone=("lib/standard_functions.txt",),
        together=(("lib", "*.txt"), ("AnnexF", "*_st.txt")),
    ),
    Source("Beremiz projects", "openplc", "beremiz-beremiz", xml=("**/plc.xml",)),
    Source(  # STruC++ reads IEC 61131-3 3rd edition and CODESYS's extensions both, as st's default does
        "STruC++ validation programs",
        "default",
        "Autonomy-Logic-STruCpp",
        st=("**/*.st",),
        together=(("libs/sources/*", "**/*.st"), ("tests/fixtures/smart-traffic-light", "**/*.st")),
        pairs=True,
    ),
    # TwinCAT projects as TwinCAT builds them: each .plcproj with the libraries it references, found
    # as library projects on the search path (--lib); Tc2_*/Tc3_* are st's own vendor library
    Source(
        "TwinCAT: TcUnit and its verifier",
        "twincat",
        "tcunit-TcUnit",
        plcprojs=(("TcUnit/**/TcUnit.plcproj", ()), ("TcUnit-Verifier/**/*.plcproj", ("tcunit-TcUnit/TcUnit",))),
    ),
    Source(
        "TwinCAT: struckig (library, tests, example, benchmark)",
        "twincat",
        "stefanbesler-struckig",
        plcprojs=(
            ("Struckig/**/Struckig.plcproj", ()),
            ("tests/**/*.plcproj", ("stefanbesler-struckig/Struckig", "tcunit-TcUnit/TcUnit")),
            ("examples/**/*.plcproj", ("stefanbesler-struckig/Struckig",)),
            ("benchmark/**/*.plcproj", ("stefanbesler-struckig/Struckig",)),
        ),
    ),
    Source(
        "TwinCAT: TcLog and its tests",
        "twincat",
        "bengeisler-TcLog",
        plcprojs=(
            ("src/**/TcLog.plcproj", ("tcunit-TcUnit/TcUnit",)),
            ("src/**/TcLogTEST.plcproj", ("tcunit-TcUnit/TcUnit", "bengeisler-TcLog/src/TcLogProj/TcLog")),
        ),
    ),
    Source(
        "TwinCAT: PLC design patterns course (0w8States)",
        "twincat",
        "0w8States-PLC-Design-Patterns",
        plcprojs=(("**/*.plcproj", ()),),
    ),
    Source(
        "TwinCAT: blark's samples",
        "twincat",
        "klauer-blark",
        st=("blark/tests/source/*.st", "blark/tests/POUs/*.TcPOU"),
    ),
)


@dataclass
class Outcome:
    status: str  # clean | refused | internal
    code: str = ""
    message: str = ""  # normalised
    where: str = ""  # file:line of the first error
    raw: str = ""  # the message as given
    others: list[list[str]] = field(default_factory=list)  # every error's [code, message, file:line], one per reason
    run: str = ""  # --scans: "ok", "fault: …", "not started: …" or "internal: …" (a clean unit run on virtual time)
    languages: list[str] = field(default_factory=list)  # PLCopen XML: the languages of its bodies st does not read


@dataclass
class FileResult:
    source: str
    path: str  # relative to CORPORA
    kind: str  # st | xml | skipped-xml | project | duplicate
    note: str = ""  # the ST file compiled (its first file), or why it is not
    paths: list[str] = field(default_factory=list)  # every file compiled (a unit has several)
    libs: list[str] = field(default_factory=list)  # a project's library search path (--lib)
    outcomes: dict[str, Outcome] = field(default_factory=dict)  # "default" / dialect name → outcome


# The judgement of docs/conformance.md, reason by reason: (code, start of the normalised message,
# fragment of the unit's path or of the error's file:line, verdict, why). Verdicts: "a" wrongly refused
# (the compiler the code was written for accepts it), "b" rightly refused (invalid as written, a
# missing vendor library, another language), "?" not decided yet. First match wins; a reason that
# matches none is "unjudged" and shows in the report until someone judges it.
JUDGED = [
    ("E048", "", "", "a", "own VAR_INPUT written (rule 1)"),
    ("E001", "unexpected character '}'", "", "a", "{{ }} C block (rule 1)"),
    ("E013", "type mismatch: cannot assign integer literal to BOOL", "", "a", "0/1 as BOOL (rule 2)"),
    ("E013", "type mismatch: cannot pass integer literal to BOOL", "symbextest", "b", "user SEL : BOOL"),
    ("E013", "type mismatch: cannot pass integer literal to BOOL", "", "a", "0/1 as BOOL (rule 2)"),
    ("E002", "", "", "a", "comments do not nest (rule 1)"),
    ("E001", "syntax error: unexpected end of file", "OSCAT", "a", "comments do not nest (rule 1)"),
    ("E001", "syntax error: unexpected '…'", "_il.txt", "b", "IL"),
    ("E001", "syntax error: unexpected '…'", "AnnexF", "b", "Annex F draft: %B6"),
    ("E001", "syntax error: unexpected '…'", "PLCPython", "b", "prose in the body"),
    ("E012", "unknown type '…'", "PT_Motor_PID", "a", "OpenPLC's PID (rule 3)"),
    ("E020", "", "PT_Motor_PID", "a", "OpenPLC's PID (rule 3)"),
    ("E023", "'INT' is not", "PT_Motor_PID", "a", "OpenPLC's PID (rule 3)"),
    ("E012", "unknown type '…'", "AnnexF", "b", "cascade of Annex F typos"),
    ("E020", "", "AnnexF", "b", "cascade of Annex F typos"),
    ("E023", "'INT' is not", "AnnexF", "b", "cascade of Annex F typos"),
    ("E012", "unknown type '…'", "FT_AVG", "b", "OSCAT's DELAY missing (file alone)"),
    ("E020", "", "FT_AVG", "b", "OSCAT's DELAY missing"),
    ("E023", "'INT' is not", "FT_AVG", "b", "OSCAT's DELAY missing"),
    ("E012", "unknown type '…'", "strings", "b", "cascade of 'it''s'"),
    ("E020", "", "strings", "b", "cascade"),
    ("E023", "'INT' is not", "strings", "b", "cascade"),
    ("E023", "'…' is not a structure", "smart-traffic", "a", "variable named as its enum type (new)"),
    ("E029", "", "smart-traffic", "a", "variable named as its enum type (new)"),
    ("E023", "'…' is not a structure", "fb_", "a", "THIS.x without ^ (IEC ed. 3; new)"),
    ("E010", "undeclared function or function block '…'", "Estun", "b", "vendor C functions"),
    ("E010", "undeclared identifier '…'", "plcopen/Arduino_", "b", "C block's placeholder body: undeclared name"),
    ("E010", "undeclared identifier '…'", "plcopen/CAN_", "b", "C block's placeholder body: undeclared name"),
    ("E010", "undeclared function or function block '…'", "time_types", "b", "TIME_TO_US: STruC++ only"),
    ("E010", "undeclared function or function block 'TIME'", "", "a", "TIME() (rule 4)"),
    ("E058", "'%…' is N bit(s) wide", "", "b", "%ML as DWORD: MatIEC refuses it too (location size)"),
    ("E017", "… takes N argument(s), not N", "String Functions", "b", "MatIEC did not build it"),
    ("E017", "… takes one argument", "", "a", "__NEW(T, n) (new, CODESYS)"),
    ("E026", "", "fb_", "a", "THIS.M() (IEC ed. 3; new)"),
    ("E023", "'…' is not an array", "", "a", "POINTER indexing (rule 4)"),
    ("E010", "undeclared identifier", "softmotion", "a", "user type over st's PLCopen (new)"),
    ("E011", "", "softmotion", "a", "user type over st's PLCopen (new)"),
    ("E027", "implicit conversion from UINT to USINT", "", "b", "MatIEC: no implicit narrowing"),
    ("E027", "implicit conversion from BYTE to INT", "", "a", "BYTE into INT (rules 4, 7)"),
    ("E014", "", "", "a", "ANY_BIT arithmetic (rule 4)"),
    ("E001", "'…' is a reserved keyword", "", "a", "R_EDGE as a name (rule 4)"),
    ("E013", "type mismatch: cannot assign BOOL to INT", "symbextest", "b", "user SEL : BOOL"),
    ("E013", "type mismatch: cannot pass INT to BOOL", "symbextest", "b", "user SEL : BOOL"),
    ("E001", "syntax error: unexpected 'END_VAR'", "delay_st", "b", "Annex F typo"),
    ("E001", "syntax error: unexpected 'VAR_OUTPUT'", "delay_st", "b", "Annex F typo"),
    ("E001", "syntax error: unexpected ']'", "diffeq", "b", "Annex F ARRAY[1..]"),
    ("E001", "syntax error: unexpected '1'", "standard_functions", "b", "MatIEC-internal declarations"),
    ("E012", "ARRAY[*]", "", "b", "ARRAY[*] only in VAR_IN_OUT (IEC, CODESYS)"),
    ("E013", "type mismatch: cannot pass ARRAY", "", "b", "cascade of ARRAY[*]"),
    ("E004", "%…: only bit addresses", "", "a", "%IW0.0 read as %IW0 (OpenPLC's glue; new)"),
    ("E004", "%… is outside the process image", "", "a", "%ML1024+ special functions (new)"),
    ("E001", "syntax error: unexpected ''s working''", "", "b", "'' is not an escape ($')"),
    # TwinCAT (issue 34): what is still refused, and why that is right
    ("E003", "this METHOD is outside any", "klauer-blark", "b", "a METHOD alone, cut from its block's .TcPOU"),
    ("E012", "", "klauer-blark", "b", "a parser sample naming declarations it does not hold"),
    ("E010", "", "klauer-blark", "b", "a parser sample naming declarations it does not hold"),
    ("E013", "", "klauer-blark", "b", "cascade of an undeclared name"),
    ("E020", "", "klauer-blark", "b", "cascade of an undeclared name"),
    ("E022", "", "klauer-blark", "b", "cascade of an undeclared constant"),
    ("E023", "", "klauer-blark", "b", "cascade of an undeclared name"),
    ("E029", "", "klauer-blark", "b", "cascade of an undeclared constant"),
    ("E057", "", "klauer-blark", "b", "cascade of an undeclared type or constant"),
    ("E012", "unknown type '…'", "Command_Pattern", "b", "Tc2_MC2's NC axis blocks (MC_Jog)"),
    ("E016", "", "Command_Pattern", "b", "Tc2_MC2's MC_* parameters"),
    ("E020", "", "Command_Pattern", "b", "cascade of Tc2_MC2"),
    ("E023", "", "Command_Pattern", "b", "Tc2_MC2's AXIS_REF (NcToPlc)"),
    ("E012", "unknown type '…'", "Visitor", "b", "Tc3_XML_Utility (FB_XmlDomParser)"),
    ("E023", "", "Visitor", "b", "cascade of Tc3_XML_Utility"),
    ("E047", "", "Abstract_Factory", "b", "an override that does not match, in a block nothing uses"),
    ("E010", "undeclared identifier '…'", "Abstract_Factory", "b", "the same unused block's body"),
]


def verdict(code: str, message: str, where: str) -> tuple[str, str]:
    for c, m, fragment, v, why in JUDGED:
        if c == code and message.startswith(m) and fragment in where:
            return v, why
    return "unjudged", ""


def judged(f: FileResult, key: str) -> str:
    """A refused unit: "wrong" if every reason is judged wrongly refused, "right" if one is judged
    rightly refused (it stays refused whatever else is fixed), otherwise "open"."""
    o = f.outcomes[key]
    kinds = {verdict(c, m, f"{f.path} {w}")[0] for c, m, w in o.others}
    return "right" if "b" in kinds else "wrong" if kinds == {"a"} else "open"


# ---------------------------------------------------------------- normalising messages

_QUOTED = re.compile(r"'([^']*)'|\"([^\"]*)\"|`([^`]*)`")
_WORD = re.compile(r"(?<![%#\w])[A-Za-z_]\w*")
_PATH = re.compile(r"(?<![\w.])/[^\s:)]+|%[IQM][XBWDL]?[\d.]+")
_NUMBER = re.compile(r"(?<![\w#%.])\d+(\.\d+)?(?![\w#])")
# words kept as they are: the IEC types and keywords a message names as words, not as user names
KEEP = set(
    """BOOL BYTE WORD DWORD LWORD SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL TIME LTIME DATE
    TIME_OF_DAY TOD DATE_AND_TIME DT LDATE LTOD LDT STRING WSTRING CHAR WCHAR ARRAY OF STRUCT POINTER TO
    REF_TO REFERENCE ANY ANY_INT ANY_NUM ANY_BIT ANY_REAL ANY_ELEMENTARY IF THEN ELSE ELSIF END_IF CASE
    FOR WHILE REPEAT UNTIL DO BY RETURN EXIT VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_GLOBAL VAR_EXTERNAL
    VAR_TEMP VAR_CONFIG VAR_ACCESS END_VAR CONSTANT RETAIN AT FUNCTION FUNCTION_BLOCK PROGRAM METHOD
    PROPERTY INTERFACE TYPE END_TYPE CONFIGURATION RESOURCE TASK ON WITH EN ENO TRUE FALSE AND OR XOR
    NOT MOD THIS SUPER EXTENDS IMPLEMENTS ACTION STEP TRANSITION IL LD FBD SFC ST IEC OpenPLC MatIEC
    CODESYS TwinCAT REF_ASSIGN RESET_ASSIGN SET_ASSIGN""".split()
)


def _word(m: re.Match) -> str:
    w = m.group(0)
    if w in KEEP or w.upper() in KEEP and w.isupper():
        return w
    if w.islower() and "_" not in w and not any(c.isdigit() for c in w):
        return w  # an English word of the message
    return "…"


def _quoted(m: re.Match) -> str:
    inner = next(g for g in m.groups() if g is not None)
    if not re.search(r"[A-Za-z_]", inner):
        return f"'{inner}'"  # punctuation: the token itself says what is wrong
    if inner.upper() in KEEP:
        return f"'{inner.upper()}'"
    return "'…'"


def normalise(message: str) -> str:
    """The message with the names and numbers it quotes replaced, so that one rule gives one reason;
    a syntax error keeps the token it met, not the list of tokens it expected."""
    message = _PATH.sub(lambda m: "%…" if m.group(0).startswith("%") else "…", message.split("; expected", 1)[0])
    pieces = []
    last = 0
    for m in _QUOTED.finditer(message):
        pieces.append(_NUMBER.sub("N", _WORD.sub(_word, message[last : m.start()])))
        pieces.append(_quoted(m))
        last = m.end()
    pieces.append(_NUMBER.sub("N", _WORD.sub(_word, message[last:])))
    return "".join(pieces).strip()


# ---------------------------------------------------------------- checking one file


class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout


def run_scans(result, scans: int) -> str:
    """A clean unit's program run for `scans` scans of 10 ms: ok, a PLC fault, or an internal error."""
    from st import PLC, PLCFaultError, PLCStartError

    try:
        plc = PLC(result, "10ms")
        for _ in range(scans):
            plc.scan()
    except PLCFaultError as e:
        return f"fault: {e}"
    except PLCStartError as e:
        return f"not started: {e}"
    except _Timeout:
        raise
    except Exception as e:  # anything else out of the runtime is an internal error
        tb = traceback.extract_tb(e.__traceback__)[-1]
        return f"internal: {type(e).__name__}: {e} at {Path(tb.filename).name}:{tb.lineno}"
    return "ok"


def check_file(
    paths: list[str], dialect: str | None, timeout: int, scans: int = 0, libs: list[str] | None = None
) -> Outcome:
    """One file (or unit) compiled alone, without the cache, and its outcome (and, with `scans`, what
    running a clean one does); `libs`: a project's library search path."""
    from st.api import compile_paths

    signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(timeout)
    try:
        result = compile_paths(paths, raise_on_error=False, use_cache=False, dialect=dialect, lib_path=libs or ())
    except _Timeout:
        return Outcome("internal", "timeout", f"no answer within {timeout} s", paths[0])
    except RecursionError:
        return Outcome("internal", "RecursionError", "RecursionError", paths[0])
    except Exception as e:  # an exception out of the compiler is an internal error
        tb = traceback.extract_tb(e.__traceback__)[-1]
        where = f"{Path(tb.filename).name}:{tb.lineno}"
        return Outcome("internal", type(e).__name__, normalise(str(e))[:160], where, f"{e} at {where}")
    finally:
        signal.alarm(0)
    errors = [d for d in result.diagnostics if d.is_error]
    if not errors:
        if not scans:
            return Outcome("clean")
        signal.alarm(timeout)
        try:
            return Outcome("clean", run=run_scans(result, scans))
        except _Timeout:
            return Outcome("clean", run=f"internal: no answer within {timeout} s")
        finally:
            signal.alarm(0)
    first = errors[0]
    internal = first.code == "E099" or any(d.code == "E099" for d in errors)
    if internal:
        first = next(d for d in errors if d.code == "E099")
    where = f"{first.span.file}:{first.span.line}"
    others: dict[tuple[str, str], str] = {}
    for d in errors:
        others.setdefault((d.code, normalise(d.message)), f"{d.span.file}:{d.span.line}")
    status = "internal" if internal else "refused"
    listed = [[c, m, w] for (c, m), w in others.items()]
    languages = sorted({d.datum("language") for d in errors if d.code == "E050"})
    return Outcome(status, first.code, normalise(first.message), where, first.message, listed, languages=languages)


def _check_job(job: tuple[list[str], str, int, int, list[str]]) -> dict[str, dict]:
    """A unit with no dialect and with its source's preset ("default" when that is st's default);
    only the preset's outcome is run."""
    paths, preset, timeout, scans, libs = job
    keys = ["default"] if preset == "default" else ["default", preset]
    return {
        k: asdict(check_file(paths, None if k == "default" else k, timeout, scans if k == preset else 0, libs))
        for k in keys
    }


# ---------------------------------------------------------------- the sweep


def collect(corpora: Path, only: str | None, projects: bool = False) -> list[FileResult]:
    """Every file of every source, its outcomes still to fill."""
    files: list[FileResult] = []
    seen: dict[str, str] = {}
    for src in SOURCES:
        if only and only.lower() not in src.name.lower():
            continue
        root = corpora / src.root
        if not root.is_dir():
            print(f"warning: {root} missing, source '{src.name}' skipped", file=sys.stderr)
            continue

        def excluded(p: Path, src=src) -> bool:
            return any(x in str(p) for x in src.exclude)

        def matches(globs, root=root):
            return [p for p in sorted({p for g in globs for p in root.glob(g) if p.is_file()}) if not excluded(p)]

        units: list[list[Path]] = []
        grouped: set[Path] = set()
        for dirs, pattern in src.together:
            for d in sorted(q for q in root.glob(dirs) if q.is_dir()):
                unit = [
                    p
                    for p in sorted(d.glob(pattern))
                    if p.is_file() and not excluded(p) and not any(x in str(p) for x in src.alone)
                ]
                if unit:
                    units.append(unit)
                    grouped.update(unit)
        singles = [p for p in matches(src.st) if p not in grouped]
        if src.pairs:
            paired = {p.with_name(p.name[5:]) for p in singles if p.name.startswith("test_")}
            for p in singles:
                if p in paired:
                    continue
                base = p.with_name(p.name[5:])
                units.append([base, p] if p.name.startswith("test_") and base.is_file() else [p])
        else:
            units += [[p] for p in singles]
        for unit in units:
            rel = str(unit[0].relative_to(corpora)) + (f" (+{len(unit) - 1} files)" if len(unit) > 1 else "")
            digest = hashlib.sha1(b"".join(p.read_bytes() for p in unit)).hexdigest()
            if digest in seen:
                files.append(FileResult(src.name, rel, "duplicate", f"same text as {seen[digest]}"))
                continue
            seen[digest] = rel
            files.append(FileResult(src.name, rel, "st", str(unit[0]), [str(p) for p in unit]))
        for p in matches(src.xml):
            rel = str(p.relative_to(corpora))
            digest = hashlib.sha1(p.read_bytes()).hexdigest()
            if digest in seen:
                files.append(FileResult(src.name, rel, "duplicate", f"same text as {seen[digest]}"))
                continue
            seen[digest] = rel
            files.append(FileResult(src.name, rel, "xml", str(p), [str(p)]))
        for pattern, libs in src.plcprojs:
            for p in matches((pattern,)):
                rel = str(p.relative_to(corpora))
                search = [str(corpora / lib) for lib in libs]
                note = "with --lib " + ", ".join(libs) if libs else ""
                files.append(FileResult(src.name, rel, "st", note, [str(p)], search))
        found = matches(src.project)
        if projects and found:
            rel = str(found[0].relative_to(corpora)) + f" (+{len(found) - 1} files)"
            files.append(FileResult(src.name, rel, "st", str(found[0]), [str(p) for p in found]))
        for p in found:
            files.append(FileResult(src.name, str(p.relative_to(corpora)), "project", "project format not read yet"))
    return files


def run(files: list[FileResult], timeout: int, jobs: int, scans: int = 0) -> None:
    dialect_of = {s.name: s.dialect for s in SOURCES}
    todo = [f for f in files if f.kind in ("st", "xml")]
    work = [(f.paths, dialect_of[f.source], timeout, scans, f.libs) for f in todo]
    started = time.monotonic()
    if jobs <= 1:
        answers = map(_check_job, work)
        for i, (f, ans) in enumerate(zip(todo, answers, strict=True), 1):
            f.outcomes = {k: Outcome(**v) for k, v in ans.items()}
            _progress(i, len(todo), started)
    else:
        with concurrent.futures.ProcessPoolExecutor(jobs) as pool:
            for i, (f, ans) in enumerate(zip(todo, pool.map(_check_job, work, chunksize=4), strict=True), 1):
                f.outcomes = {k: Outcome(**v) for k, v in ans.items()}
                _progress(i, len(todo), started)
    print(file=sys.stderr)
    for f in todo:
        languages = sorted({lang for o in f.outcomes.values() for lang in o.languages})
        if f.kind == "xml" and languages:  # a body st does not read: skipped, whatever else it has
            f.kind, f.note, f.outcomes = "skipped-xml", " and ".join(languages) + " body", {}


def _progress(i: int, n: int, started: float) -> None:
    print(f"\r{i}/{n} files, {time.monotonic() - started:.0f} s", end="", file=sys.stderr, flush=True)


# ---------------------------------------------------------------- the report


def _shown(where: str, corpora: Path) -> str:
    """file:line relative to the corpora."""
    return where.removeprefix(str(corpora) + "/")


def report(files: list[FileResult], top: int, corpora: Path) -> str:
    lines = ["# st on real-world ST code", ""]
    lines += [
        "Each unit (a file, or the files its own build compiles together) compiled alone; *default* is no",
        "dialect, *preset* the one that fits the source. Outcomes count units.",
        "",
        "| source | preset | files | units | clean (default) | clean (preset) | refused (preset): rightly / "
        "wrongly / open | internal | XML skipped | duplicates | not read (project format) |",
        "|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|",
    ]
    by_source = collections.defaultdict(list)
    for f in files:
        by_source[f.source].append(f)
    totals = collections.Counter()
    for src in SOURCES:
        group = by_source.get(src.name)
        if not group:
            continue
        checked = [f for f in group if f.outcomes]
        row = collections.Counter(
            paths=sum(len(f.paths) for f in checked),
            files=len(checked),
            clean_default=sum(f.outcomes["default"].status == "clean" for f in checked),
            clean=sum(f.outcomes[src.dialect].status == "clean" for f in checked),
            refused=sum(f.outcomes[src.dialect].status == "refused" for f in checked),
            **collections.Counter(
                judged(f, src.dialect) for f in checked if f.outcomes[src.dialect].status == "refused"
            ),
            internal=sum(any(o.status == "internal" for o in f.outcomes.values()) for f in checked),
            skipped=sum(f.kind == "skipped-xml" for f in group),
            dup=sum(f.kind == "duplicate" for f in group),
            project=sum(f.kind == "project" for f in group),
        )
        totals.update(row)
        lines.append(
            f"| {src.name} | {src.dialect} | {row['paths']} | {row['files']} | {row['clean_default']} | {row['clean']} | "
            f"{row['refused']}: {row['right']} / {row['wrong']} / {row['open']} | {row['internal']} | {row['skipped']} | {row['dup']} | {row['project']} |"
        )
    t = totals
    lines.append(
        f"| **all** | | {t['paths']} | {t['files']} | {t['clean_default']} | {t['clean']} | "
        f"{t['refused']}: {t['right']} / {t['wrong']} / {t['open']} | {t['internal']} | "
        f"{t['skipped']} | {t['dup']} | {t['project']} |"
    )
    lines += ["", f"## Top {top} refusal reasons (first error of each refused file)", ""]
    lines += ["| # | code | message (names as '…') | preset | default | example |", "|---:|---|---|---:|---:|---|"]
    reasons: dict[tuple[str, str], list] = collections.defaultdict(lambda: [0, 0, ""])
    dialect_of = {s.name: s.dialect for s in SOURCES}
    for f in files:
        for key, o in f.outcomes.items():
            if o.status != "refused":
                continue
            r = reasons[(o.code, o.message)]
            if key == dialect_of[f.source]:
                r[0] += 1
            if key == "default":
                r[1] += 1
            if not r[2]:
                r[2] = _shown(o.where, corpora)
    ranked = sorted(reasons.items(), key=lambda kv: (-max(kv[1][0], kv[1][1]), kv[0]))
    for i, ((code, msg), (n_preset, n_default, example)) in enumerate(ranked[:top], 1):
        msg = msg.replace("|", "\\|")[:140]
        lines.append(f"| {i} | {code} | {msg} | {n_preset} | {n_default} | `{example}` |")
    lines += ["", "## Every reason (all errors of each refused file, a reason counted once per file)", ""]
    lines += ["| # | code | message | files (preset) | judged | example |", "|---:|---|---|---:|---|---|"]
    every: dict[tuple[str, str], list] = collections.defaultdict(lambda: [0, "", collections.Counter()])
    for f in files:
        o = f.outcomes.get(dialect_of[f.source])
        for code, msg, where in o.others if o else ():
            r = every[(code, msg)]
            r[0] += 1
            r[1] = r[1] or _shown(where, corpora)
            r[2][verdict(code, msg, f"{f.path} {where}")] += 1
    ranked_all = sorted(every.items(), key=lambda kv: (-kv[1][0], kv[0]))
    for i, ((code, msg), (n, example, verdicts)) in enumerate(ranked_all[:top], 1):
        shown = msg.replace("|", "\\|")[:140]
        judgement = "; ".join(f"{v} {k}: {why}" if why else f"{v} {k}" for (v, why), k in verdicts.most_common())
        lines.append(f"| {i} | {code} | {shown} | {n} | {judgement} | `{example}` |")
    internal = [(f, k, o) for f in files for k, o in f.outcomes.items() if o.status == "internal"]
    lines += ["", f"## Internal errors ({len(internal)})", ""]
    for f, k, o in internal:
        lines.append(f"- `{f.path}` ({k}): {o.code} {o.raw or o.message} at {o.where}")
    runs = [(f, o.run) for f in files for k, o in f.outcomes.items() if o.run]
    if runs:
        counted = collections.Counter(r.split(":", 1)[0] for _, r in runs)
        lines += ["", f"## Clean units run ({', '.join(f'{n} {k}' for k, n in counted.most_common())})", ""]
        lines += [f"- `{f.path}`: {r.replace(str(corpora) + '/', '')}" for f, r in runs if r != "ok"]
    skipped = collections.Counter(f.note for f in files if f.kind == "skipped-xml")
    if skipped:
        lines += ["", "## PLCopen XML skipped (a body in a language st does not read, E050)", ""]
        lines += [f"- {n} × {why}" for why, n in skipped.most_common()]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("corpora", type=Path, help="directory with the fetched repositories")
    ap.add_argument("--out", type=Path, default=Path("/tmp/st-conformance"), help="results directory")
    ap.add_argument("--timeout", type=int, default=60, help="seconds per file and dialect")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes")
    ap.add_argument("--top", type=int, default=30, help="refusal reasons listed")
    ap.add_argument("--only", help="only the sources whose name contains this")
    ap.add_argument("--scans", type=int, default=0, help="also run each clean unit (its preset) for this many scans")
    ap.add_argument(
        "--projects",
        action="store_true",
        help="also compile TwinCAT project files (.plcproj), each source's together as one unit",
    )
    ap.add_argument("--preset", help="this preset for every source instead of its own (to look behind a rule)")
    args = ap.parse_args(argv)
    if args.preset:
        global SOURCES
        SOURCES = tuple(replace(s, dialect=args.preset) for s in SOURCES)
    args.out.mkdir(parents=True, exist_ok=True)
    files = collect(args.corpora.resolve(), args.only, args.projects)
    run(files, args.timeout, args.jobs, args.scans)
    text = report(files, args.top, args.corpora.resolve())
    (args.out / "conformance.md").write_text(text)
    (args.out / "results.json").write_text(json.dumps([asdict(f) for f in files], indent=1))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
