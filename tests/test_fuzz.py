"""The fuzzer (st/testing/fuzz.py): a seeded, time-bounded run over mutated example programs finds
no defect (no traceback, no internal error, no raw fault, no hang); and the fuzzer's own parts
do what they say. The long run is bench/fuzz_programs.py (bench/README.md)."""

import random
import threading
import time

import pytest

from st.testing import fuzz
from st.testing.fuzz import Outcome, Worker, corpus, mutant, run_one, shrink

# the suite's run: mutants 0..MUTANTS-1 of SEED, two worker processes (about 7 s on 2 cores;
# bench/fuzz_programs.py sweeps tens of thousands); a failure lists each defect signature with
# its mutant and a shrunk reproducer
SEED, MUTANTS, WORKERS = 2026, 150, 2


@pytest.mark.slow
def test_mutated_example_programs_never_crash_the_compiler_or_the_runtime():
    programs = corpus()
    counts, defects = {}, {}
    lock = threading.Lock()
    todo = iter(range(MUTANTS))

    def work():
        w = Worker(timeout=20)
        try:
            while True:
                with lock:
                    i = next(todo, None)
                if i is None:
                    return
                base, src = mutant(SEED, i, programs)
                o = w.classify(src)
                with lock:
                    counts[o.cls] = counts.get(o.cls, 0) + 1
                    if o.defect and o.signature not in defects:
                        defects[o.signature] = (i, base, src, o)
        finally:
            w.close()

    threads = [threading.Thread(target=work) for _ in range(WORKERS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if defects:
        reports = []
        w = Worker(timeout=20)
        try:
            for sig, (i, base, src, o) in sorted(defects.items()):
                small = shrink(src, sig, w.classify, budget=40 if o.cls != "timeout" else 4)
                reports.append(f"mutant({SEED}, {i}) of {base}: {o.cls}: {sig}\n  {o.detail}\n--- shrunk:\n{small}")
        finally:
            w.close()
        pytest.fail(
            f"{len(defects)} defect signature(s) in {MUTANTS} mutants of seed {SEED} "
            f"(outcomes {counts}):\n\n" + "\n\n".join(reports),
            pytrace=False,
        )
    assert sum(counts.values()) == MUTANTS
    assert counts.get("diagnostics", 0) > 0 and counts.get("ok", 0) > 0  # both sides were reached
    assert sum(n for c, n in counts.items() if c.startswith("fault:")) > 0


# ---------------------------------------------------------------------- the mutator


def test_mutants_are_a_pure_function_of_seed_and_index():
    programs = corpus()
    assert mutant(1, 5, programs) == mutant(1, 5, programs) == mutant(1, 5)
    assert len({mutant(1, i, programs)[1] for i in range(30)}) == 30
    assert mutant(1, 5, programs) != mutant(2, 5, programs)
    bases = dict(programs)
    assert sum(mutant(1, i, programs)[1] != bases[mutant(1, i, programs)[0]] for i in range(30)) >= 28


def test_the_corpus_is_every_example_program_with_test_files_joined_to_their_subject():
    names = [n for n, _ in corpus()]
    assert "programs/thesis/single_axis.st" in names and "programs/blink.st" in names
    joined = dict(corpus())["programs/test_traffic_light.st"]
    assert "CONFIGURATION" in joined and "TEST " in joined


def test_the_tokenizer_gives_the_text_back():
    for _, text in corpus():
        assert "".join(fuzz.tokens(text)) == text
    assert fuzz.tokens("x := 16#FF + T#1s5ms;") == ["x", " ", ":=", " ", "16#FF", " ", "+", " ", "T#1s5ms", ";"]


@pytest.mark.parametrize("kind", list(fuzz.MUTATIONS))
def test_each_mutation_changes_the_program_and_is_seeded(kind):
    text = dict(corpus())["programs/traffic_light.st"]
    toks = fuzz.tokens(text)
    changed = set()
    for j in range(5):
        a = "".join(fuzz._mutate_once(list(toks), random.Random(j), kind))
        assert a == "".join(fuzz._mutate_once(list(toks), random.Random(j), kind))
        changed.add(a != text)
    assert True in changed


def test_a_fault_statement_comes_with_its_variables():
    text = dict(corpus())["programs/blink.st"]
    m = "".join(fuzz._mutate_once(fuzz.tokens(text), random.Random(3), "fault-statement"))
    k = next(w for w in fuzz.tokens(m) if w.startswith("x_f"))[3:]
    assert f"x_f{k} : DINT := 7" in m
    assert run_one(m).cls in (
        "ok",
        "fault:DIV0",
        "fault:INDEX",
        "fault:RANGE",
        "fault:CONVERSION",
        "fault:NULL",
        "fault:WATCHDOG",
        "fault:LOOP",
    )


def test_literals_are_replaced_by_extremes_of_their_kind_most_of_the_time():
    assert fuzz._lit_kind("16#FF") == fuzz._lit_kind("42") == "int"
    assert fuzz._lit_kind("1.5E3") == fuzz._lit_kind("LREAL#2.0") == "real"
    assert fuzz._lit_kind("T#1s") == "time" and fuzz._lit_kind("DT#1970-01-01-00:00:00") == "date"
    assert fuzz._lit_kind("'abc'") == "string" and fuzz._lit_kind("TRUE") == "bool"
    assert max(len(v) for v in fuzz.ALL_EXTREMES) < 10_000


# ---------------------------------------------------------------------- the classifier

PROGRAM = (
    "PROGRAM main\nVAR x : DINT := 1; d : DINT; a : ARRAY[0..3] OF INT; r : LREAL := 1.0E30; "
    "p : REF_TO DINT; w : WORD := 1; END_VAR\n{}\nEND_PROGRAM\n"
)
RECURSIVE = (
    "FUNCTION_BLOCK FB_r\nMETHOD m : DINT\nVAR_INPUT n : DINT; END_VAR\nm := THIS^.m(n + 1);\n"
    "END_METHOD\nEND_FUNCTION_BLOCK\n"
    "PROGRAM main\nVAR f : FB_r; x : DINT; END_VAR\nx := f.m(0);\nEND_PROGRAM\n"
)
SELF_CALL = (
    "FUNCTION F : DINT\nVAR_INPUT n : DINT; END_VAR\nF := F(n + 1);\nEND_FUNCTION\n"
    "PROGRAM main\nVAR x : DINT; END_VAR\nx := F(0);\nEND_PROGRAM\n"
)


@pytest.mark.parametrize(
    "source, cls",
    [
        (PROGRAM.format("x := x + 1;"), "ok"),
        (PROGRAM.format("x := x + ;"), "diagnostics"),
        (PROGRAM.format("x := y;"), "diagnostics"),
        (PROGRAM.format("x := x / d;"), "fault:DIV0"),
        (PROGRAM.format("WHILE TRUE DO x := x + 1; END_WHILE;"), "fault:WATCHDOG"),
        (PROGRAM.format("a[x + 10] := 1;"), "fault:INDEX"),
        (PROGRAM.format("x := p^;"), "fault:NULL"),
        (PROGRAM.format("x := LREAL_TO_DINT(r);"), "fault:CONVERSION"),
        (PROGRAM.format("w := SHL(w, d - 1);"), "fault:RANGE"),
        (PROGRAM.format("FOR x := 0 TO 10 BY d DO END_FOR;"), "fault:LOOP"),
        (RECURSIVE, "fault:RECURSION"),
        (SELF_CALL, "fault:RECURSION"),  # W013: it runs, as in CODESYS, until it goes too deep
        ("PROGRAM main\nVAR x : DINT; END_VAR\nx := 1;\n", "diagnostics"),  # cut short
    ],
)
def test_the_classifier_names_each_outcome(source, cls):
    assert run_one(source).cls == cls


def test_an_exception_out_of_the_compiler_is_an_internal_defect(monkeypatch):
    import st.api

    def broken(*a, **k):
        raise KeyError("boom")

    monkeypatch.setattr(st.api, "compile_text", broken)
    o = run_one(PROGRAM.format("x := 1;"))
    assert (o.cls, o.defect) == ("internal", True)
    assert o.signature == "compile: KeyError"  # no frame of st/ below run_one


def test_an_error_without_a_location_is_an_internal_defect(monkeypatch):
    import st.api
    from st.diagnostics import Diagnostic, Severity
    from st.source import Span

    real = st.api.compile_text

    def unlocated(*a, **k):
        c = real(*a, **k)
        c.diagnostics = [Diagnostic("E013", Severity.ERROR, Span("fuzz.st", 0, 0), "type mismatch 'x'")]
        return c

    monkeypatch.setattr(st.api, "compile_text", unlocated)
    o = run_one(PROGRAM.format("x := x + ;"))
    assert (o.cls, o.signature) == ("internal", "unlocated E013 type mismatch '…'")


def test_python_text_in_a_fault_is_a_raw_fault_defect(monkeypatch):
    from st.stdlib.iec import default_library

    def leaky(x):
        raise ValueError("math domain error")

    monkeypatch.setitem(default_library(False, "ms", False, False).helpers, "_std_sin", leaky)  # the one compiles use
    o = run_one(PROGRAM.format("x := LREAL_TO_DINT(SIN(DINT_TO_LREAL(x)));"))
    assert (o.cls, o.signature) == ("raw-fault", "[FAULT] ValueError: math domain error")


@pytest.mark.slow
def test_a_mutant_that_outlasts_the_timeout_is_a_timeout_and_the_worker_is_replaced():
    endless = PROGRAM.format("WHILE TRUE DO x := x + 1; END_WHILE;")
    worker = Worker(timeout=60, watchdog="60s")  # the PLC's own watchdog would come too late
    try:
        # warm (its first compile builds the parser), so the endless mutant reaches its scan within
        # the 3 s however loaded the machine; the fresh worker then has as long as it needs to answer
        assert worker.classify(PROGRAM.format("x := 1;")).cls == "ok"
        worker.timeout = 3
        assert worker.classify(endless) == Outcome("timeout", "timeout in scan", "more than 3 s")
        worker.timeout = 60
        assert worker.classify(PROGRAM.format("x := 2;")).cls == "ok"  # a fresh worker answers
        assert worker.restarts == 1
    finally:
        worker.close()
    assert run_one(endless, timeout=20).cls == "fault:WATCHDOG"  # the usual 100 ms watchdog


@pytest.mark.slow
def test_a_worker_that_dies_is_a_crash_and_is_replaced():
    worker = Worker(timeout=30, watchdog="60s")
    try:
        assert worker.classify(PROGRAM.format("x := 2;")).cls == "ok"
        proc = worker.proc
        assert proc is not None

        def kill_in_the_scan(phase):  # once the worker says it scans: no fixed wait for it to get there
            if phase == "scan":
                proc.kill()

        t0 = time.monotonic()
        o = worker.classify(PROGRAM.format("WHILE TRUE DO x := x + 1; END_WHILE;"), on_phase=kill_in_the_scan)
        assert (o.cls, o.signature) == ("crash", "worker died in scan (exit -9)")
        assert time.monotonic() - t0 < 20
        assert worker.classify(PROGRAM.format("x := x / d;")).cls == "fault:DIV0"
    finally:
        worker.close()


def test_shrinking_keeps_the_signature_and_drops_the_rest():
    def check(text):
        return Outcome("internal", "boom") if "BOOM" in text else Outcome("ok")

    src = "line one;\nline two;\nx := BOOM + 1;\nline four;\n"
    assert shrink(src, "boom", check) == "BOOM"
    calls = []

    def counted(text):
        calls.append(text)
        return check(text)

    shrink(src * 50, "boom", counted, budget=25)
    assert len(calls) <= 25
