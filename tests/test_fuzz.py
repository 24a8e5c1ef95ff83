"""The fuzzer (st/testing/fuzz.py): a seeded, time-bounded run over mutated example programs finds
no defect (no traceback, no internal error, no raw fault, no hang); and the fuzzer's own parts
do what they say. The long run is bench/fuzz_programs.py (bench/README.md)."""
import pytest

from st.testing import fuzz
from st.testing.fuzz import Outcome, Worker, classify, corpus, mutant, shrink

SEED, MUTANTS = 2026, 150


def test_mutated_example_programs_never_crash_the_compiler_or_the_runtime():
    programs = corpus()
    worker = Worker(timeout=20)
    counts, defects = {}, []
    try:
        for i in range(MUTANTS):
            base, src = mutant(SEED, i, programs)
            o = worker.classify(src)
            counts[o.cls] = counts.get(o.cls, 0) + 1
            if o.defect:
                small = shrink(src, o.signature, worker.classify, budget=60)
                defects.append(f"mutant {i} of {base}: {o.cls}: {o.signature}\n{o.detail}\n--- shrunk:\n{small}")
    finally:
        worker.close()
    assert not defects, "\n\n".join(defects)
    assert counts.get("diagnostics", 0) > 0 and counts.get("ok", 0) > 0      # both sides were reached
    assert sum(n for c, n in counts.items() if c.startswith("fault:")) > 0


def test_mutants_are_a_pure_function_of_seed_and_index():
    programs = corpus()
    assert mutant(1, 5, programs) == mutant(1, 5, programs)
    assert len({mutant(1, i, programs)[1] for i in range(20)}) == 20
    assert mutant(1, 5, programs) != mutant(2, 5, programs)


def test_the_tokenizer_gives_the_text_back():
    for _, text in corpus():
        assert "".join(fuzz.tokens(text)) == text


PROGRAM = "PROGRAM main\nVAR x : DINT := 1; d : DINT; END_VAR\n{}\nEND_PROGRAM\n"


@pytest.mark.parametrize("body, cls", [
    ("x := x + 1;", "ok"),
    ("x := x + ;", "diagnostics"),
    ("x := x / d;", "fault:DIV0"),
    ("WHILE TRUE DO x := x + 1; END_WHILE;", "fault:WATCHDOG"),
    ("x := SHL(DINT_TO_DWORD(x), -1);", "diagnostics"),          # SHL takes ANY_BIT: DWORD result into DINT
])
def test_the_classifier_names_each_outcome(body, cls):
    assert classify(PROGRAM.format(body)).cls == cls


def test_an_exception_out_of_the_compiler_is_an_internal_defect(monkeypatch):
    import st.api

    def broken(*a, **k):
        raise KeyError("boom")
    monkeypatch.setattr(st.api, "compile_text", broken)
    o = classify(PROGRAM.format("x := 1;"))
    assert (o.cls, o.defect) == ("internal", True)
    assert o.signature.startswith("compile: KeyError")


def test_python_text_in_a_fault_is_a_raw_fault_defect(monkeypatch):
    from st.stdlib.iec import default_library

    def leaky(x):
        raise ValueError("math domain error")
    monkeypatch.setitem(default_library(False, "ms").helpers, "_std_sin", leaky)   # the one compiles use
    o = classify(PROGRAM.format("x := LREAL_TO_DINT(SIN(DINT_TO_LREAL(x)));"))
    assert (o.cls, o.signature) == ("raw-fault", "[FAULT] ValueError: math domain error")


def test_a_mutant_that_outlasts_the_timeout_is_a_timeout_and_the_worker_is_replaced():
    endless = PROGRAM.format("WHILE TRUE DO x := x + 1; END_WHILE;")
    worker = Worker(timeout=3, watchdog="60s")        # the PLC's own watchdog would come too late
    try:
        assert worker.classify(endless).cls == "timeout"
        assert worker.classify(PROGRAM.format("x := 2;")).cls == "ok"             # a fresh worker answers
    finally:
        worker.close()
    quick = Worker(timeout=20)                          # with the usual 100 ms watchdog: a located fault
    try:
        assert quick.classify(endless).cls == "fault:WATCHDOG"
    finally:
        quick.close()


def test_shrinking_keeps_the_signature_and_drops_the_rest():
    def check(text):
        return Outcome("internal", "boom") if "BOOM" in text else Outcome("ok")
    src = "line one;\nline two;\nx := BOOM + 1;\nline four;\n"
    assert shrink(src, "boom", check) == "BOOM"
