"""Syntax error recovery: one run reports the syntax errors of every POU of a file, each with its
line and column, and no follow-on errors; the expected tokens of a message are ST words."""

from __future__ import annotations

import random
import re
import time

from click.testing import CliRunner

from st.api import compile_text
from st.cli import main
from st.compiler.driver import parse_source
from st.diagnostics import DiagnosticSink
from st.grammar.parser import StParser
from st.source import SourceFile


def errors(text: str, name: str = "t.st") -> list:
    r = compile_text(text, name, raise_on_error=False, use_cache=False)
    return [
        (d.code, d.span.line, d.span.col, d.message, d.hint)
        for d in r.diagnostics
        if d.is_error and d.span is not None and d.span.file == name
    ]


def where(text: str) -> list:
    return [(code, line, col) for code, line, col, _, _ in errors(text)]


# ---------------------------------------------------------------------- errors in several POUs

TWO_POUS = """PROGRAM first
VAR a : INT; END_VAR
a := a + * 2;
a := 1;
END_PROGRAM

FUNCTION_BLOCK Second
VAR_INPUT x : INT; END_VAR
VAR y : INT; END_VAR
y := x;
END_FUNCTION_BLOCK

FUNCTION Third : INT
VAR_INPUT v : INT; END_VAR
IF v > 0
  Third := 1;
END_IF;
END_FUNCTION
"""


def test_errors_in_the_first_and_the_third_pou_are_both_reported():
    assert errors(TWO_POUS) == [
        ("E001", 3, 10, "syntax error: unexpected '*'; expected an expression", ""),
        (
            "E001",
            16,
            3,
            "syntax error: unexpected 'Third'; expected '&', '*', '**', '+', '-', '/', '<', '<=', …",
            "THEN is missing before 'Third'",
        ),
    ]


FOUR_POUS = """PROGRAM first
VAR a : INT; END_VAR
a := (a + 2;
END_PROGRAM
FUNCTION_BLOCK Second
VAR x : INT; END_VAR
x := x + 1;
END_FUNCTION_BLOCK
FUNCTION Third : INT
VAR_INPUT v : INT; END_VAR
FOR v := 1 10 DO Third := v; END_FOR;
END_FUNCTION
TYPE Pair : STRUCT a : INT; b : ; END_STRUCT; END_TYPE
PROGRAM fifth
VAR s : INT; END_VAR
WHILE s < 10 DO s := s + 1; END_IF;
END_PROGRAM
"""


def test_errors_in_four_of_five_pous_are_all_reported_with_their_hints():
    assert errors(FOUR_POUS) == [
        ("E001", 3, 12, "syntax error: unexpected ';'; expected ')'", "')' is missing before ';'"),
        (
            "E001",
            11,
            12,
            "syntax error: unexpected '10'; expected '&', '*', '**', '+', '-', '/', '<', '<=', …",
            "TO is missing before '10'",
        ),
        (
            "E001",
            13,
            33,
            "syntax error: unexpected ';'; expected an identifier, '(', 'ARRAY', 'POINTER', 'REFERENCE', 'REF_TO', "
            "'STRING'",
            "a type is missing before ';'",
        ),
        (
            "E001",
            16,
            29,
            "syntax error: unexpected 'END_IF'; expected a located address, an identifier, '(', ';', 'CASE', "
            "'CONTINUE', 'END_WHILE', 'EXIT', …",
            "did you mean END_WHILE?",
        ),
    ]


def test_st_check_lists_the_errors_of_every_pou_with_file_line_and_column(tmp_path):
    f = tmp_path / "four.st"
    f.write_text(FOUR_POUS)
    r = CliRunner().invoke(main, ["check", str(f)])
    assert r.exit_code == 1
    located = [line.split(": error[")[0] for line in r.output.splitlines() if ": error[" in line]
    assert located == [f"{f}:3:12", f"{f}:11:12", f"{f}:13:33", f"{f}:16:29"]
    assert "4 error(s), 0 warning(s)" in r.output
    assert "Traceback" not in r.output


METHODS = """FUNCTION_BLOCK FB
VAR x : INT; END_VAR
METHOD M1 : INT
VAR_INPUT a : INT; END_VAR
M1 := a * ;
x := a;
END_METHOD
METHOD M2 : INT
M2 := x;
END_METHOD
x := x + 1;
END_FUNCTION_BLOCK
PROGRAM main
VAR f : FB; r : INT; END_VAR
r := f.M1(a := 1) +;
END_PROGRAM
"""


def test_an_error_in_a_method_leaves_the_other_methods_and_the_block_body_alone():
    assert errors(METHODS) == [
        ("E001", 5, 11, "syntax error: unexpected ';'; expected an expression", "an expression is missing before ';'"),
        ("E001", 15, 20, "syntax error: unexpected ';'; expected an expression", "an expression is missing before ';'"),
    ]


CONFIGURATION = """PROGRAM main
VAR x : INT; END_VAR
x := x + 1;
END_PROGRAM
CONFIGURATION c
RESOURCE r ON PLC
TASK t (INTERVAL := T#10ms, PRIORITY := );
PROGRAM inst WITH t : main;
END_RESOURCE
END_CONFIGURATION
"""


def test_an_error_in_a_task_of_a_configuration_is_one_error():
    assert errors(CONFIGURATION) == [
        ("E001", 7, 41, "syntax error: unexpected ')'; expected an expression", "an expression is missing before ')'")
    ]


# ---------------------------------------------------------------------- statements and declarations

STATEMENTS = """PROGRAM p
VAR a, b : INT; c : BOOL; END_VAR
a := (b + ;
b := 2;
IF c THEN
  a := b +;
  b := a;
END_IF;
WHILE a < 10 DO
  a := a + 1;
END_WHILE;
END_PROGRAM
"""


def test_an_error_inside_a_statement_brings_no_follow_on_errors():
    # the statements after each error, the END_IF of the IF around the second, are read as they are
    assert errors(STATEMENTS) == [
        ("E001", 3, 11, "syntax error: unexpected ';'; expected an expression", ""),
        ("E001", 6, 11, "syntax error: unexpected ';'; expected an expression", "an expression is missing before ';'"),
    ]


def test_a_statement_skipped_inside_nested_blocks_resumes_in_the_innermost_one():
    src = "PROGRAM p\nVAR x : INT; END_VAR\n" + "IF x > 0 THEN\n" * 30 + "x := ;\n" + "END_IF;\n" * 30
    src += "x := 1;\nEND_PROGRAM\n"
    assert where(src) == [("E001", 33, 6)]


def test_a_wrong_end_keyword_is_one_error():
    src = "PROGRAM p\nVAR x : INT; END_VAR\nWHILE x < 10 DO\n  x := x + 1;\nEND_IF;\nx := 0;\nEND_PROGRAM\n"
    assert errors(src) == [
        (
            "E001",
            5,
            1,
            "syntax error: unexpected 'END_IF'; expected a located address, an identifier, '(', ';', 'CASE', "
            "'CONTINUE', 'END_WHILE', 'EXIT', …",
            "did you mean END_WHILE?",
        )
    ]


CASES = """PROGRAM p
VAR i, x : INT; END_VAR
CASE i OF
  1 x := 1;
  2: x := 2 +;
  3: x := 3;
END_CASE;
REPEAT x := x + 1 UNTIL x > 5 END_REPEAT;
END_PROGRAM
"""


def test_errors_in_case_labels_case_bodies_and_a_repeat_are_each_reported_once():
    assert errors(CASES) == [
        ("E001", 4, 5, "syntax error: unexpected 'x'; expected ',', '..', ':'", "':' is missing before 'x'"),
        ("E001", 5, 14, "syntax error: unexpected ';'; expected an expression", "an expression is missing before ';'"),
        (
            "E001",
            8,
            18,
            "syntax error: unexpected 'UNTIL'; expected '&', '*', '**', '+', '-', '/', ';', '<', …",
            "a ';' is missing here",
        ),
    ]


DECLARATIONS = """FUNCTION_BLOCK F
VAR_INPUT a : INT := ; b : BOOL; END_VAR
VAR c : ARRAY[1..] OF INT; d : INT; END_VAR
c[1] := a;
END_FUNCTION_BLOCK
TYPE
  T : STRUCT x : INT; y : ; END_STRUCT;
END_TYPE
"""


def test_errors_in_declaration_sections_and_types_resume_at_the_next_declaration():
    assert errors(DECLARATIONS) == [
        (
            "E001",
            2,
            22,
            "syntax error: unexpected ';'; expected an expression, '['",
            "an expression is missing before ';'",
        ),
        ("E001", 3, 18, "syntax error: unexpected ']'; expected an expression", "an expression is missing before ']'"),
        (
            "E001",
            7,
            27,
            "syntax error: unexpected ';'; expected an identifier, '(', 'ARRAY', 'POINTER', 'REFERENCE', 'REF_TO', "
            "'STRING'",
            "a type is missing before ';'",
        ),
    ]


def test_statements_in_a_section_without_end_var_are_one_error():
    src = "PROGRAM p\nVAR\n  x : INT;\n  y : INT;\nx := 1;\ny := x + 1;\nEND_PROGRAM\nFUNCTION f : INT\nf := 1 +;\n"
    src += "END_FUNCTION\n"
    assert errors(src) == [
        (
            "E001",
            5,
            3,
            "syntax error: unexpected ':='; expected ',', '.', ':', 'AT'",
            "END_VAR is missing before this statement",
        ),
        ("E001", 9, 9, "syntax error: unexpected ';'; expected an expression", "an expression is missing before ';'"),
    ]


def test_declarations_without_var_are_one_error():
    src = "PROGRAM p\n  x : INT;\n  y : BOOL;\nEND_VAR\nx := 1;\nEND_PROGRAM\n"
    assert errors(src) == [
        (
            "E001",
            2,
            5,
            "syntax error: unexpected ':'; expected '(', '.', ':=', '?=', 'R=', 'REF=', 'S=', '[', …",
            "VAR is missing before this line",
        )
    ]


# ---------------------------------------------------------------------- POU boundaries

UNCLOSED = """PROGRAM a
VAR x : INT; END_VAR
x := 1;

FUNCTION_BLOCK F
VAR y : INT; END_VAR
IF y > 0 THEN
  y := 0;

PROGRAM b
VAR z : INT; END_VAR
z := 2 +;
END_PROGRAM
"""


def test_an_unclosed_pou_ends_where_the_next_one_begins():
    assert errors(UNCLOSED) == [
        (
            "E001",
            5,
            1,
            "syntax error: unexpected 'FUNCTION_BLOCK'; expected a located address, an identifier, '(', ';', "
            "'ACTION', 'CASE', 'CONTINUE', 'END_PROGRAM', …",
            "END_PROGRAM is missing before 'FUNCTION_BLOCK'",
        ),
        (
            "E001",
            10,
            1,
            "syntax error: unexpected 'PROGRAM'; expected a located address, an identifier, '(', ';', 'CASE', "
            "'CONTINUE', 'ELSE', 'ELSIF', …",
            "END_FUNCTION_BLOCK is missing before 'PROGRAM'",
        ),
        ("E001", 12, 9, "syntax error: unexpected ';'; expected an expression", "an expression is missing before ';'"),
    ]


def test_an_unclosed_pou_at_the_end_of_the_file():
    assert errors("PROGRAM a\nVAR x : INT; END_VAR\nx := 1;\n") == [
        (
            "E001",
            4,
            1,
            "syntax error: unexpected end of file; expected a located address, an identifier, '(', ';', 'ACTION', "
            "'CASE', 'CONTINUE', 'END_PROGRAM', …",
            "END_PROGRAM is missing",
        )
    ]


def test_a_broken_pou_header_skips_that_pou_and_what_the_builder_would_say_about_the_gap():
    # the METHOD after the skipped block is not reported as outside any block; the reserved name of
    # the next POU, and its stray character, are
    src = (
        "FUNCTION_BLOCK 'FB'\nVAR x : INT; END_VAR\nx := 1;\nEND_FUNCTION_BLOCK\nMETHOD M : INT\nM := 1;\n"
        "END_METHOD\nPROGRAM p\nVAR then : INT; END_VAR\nthen := 16#;\nEND_PROGRAM\n"
    )
    assert errors(src) == [
        (
            "E001",
            1,
            16,
            "syntax error: unexpected string 'FB'; expected an identifier, 'ABSTRACT', 'FINAL', 'INTERNAL', 'PUBLIC'",
            "",
        ),
        ("E001", 9, 5, "'then' is a reserved keyword and cannot be a name", ""),
        ("E001", 10, 11, "unexpected character '#'", ""),
    ]


# ---------------------------------------------------------------------- the ';' repair


def test_missing_semicolons_alone_are_repaired_and_the_program_is_still_checked():
    src = "PROGRAM p\nVAR a : INT; END_VAR\na := 1\na := 2\nb := 3;\nEND_PROGRAM\n"
    assert errors(src) == [
        (
            "E001",
            3,
            7,
            "syntax error: unexpected 'a'; expected '&', '*', '**', '+', '-', '/', ';', '<', …",
            "a ';' is missing at the end of line 3",
        ),
        (
            "E001",
            4,
            7,
            "syntax error: unexpected 'b'; expected '&', '*', '**', '+', '-', '/', ';', '<', …",
            "a ';' is missing at the end of line 4",
        ),
        ("E010", 5, 1, "undeclared identifier 'b'", ""),
    ]


def test_missing_semicolons_are_repaired_next_to_other_syntax_errors():
    src = "PROGRAM p\nVAR a, b : INT; END_VAR\na := 1\nb := 2\na := b +;\nb := 3\nEND_PROGRAM\n"
    assert errors(src) == [
        (
            "E001",
            3,
            7,
            "syntax error: unexpected 'b'; expected '&', '*', '**', '+', '-', '/', ';', '<', …",
            "a ';' is missing at the end of line 3",
        ),
        (
            "E001",
            4,
            7,
            "syntax error: unexpected 'a'; expected '&', '*', '**', '+', '-', '/', ';', '<', …",
            "a ';' is missing at the end of line 4",
        ),
        ("E001", 5, 9, "syntax error: unexpected ';'; expected an expression", ""),
        (
            "E001",
            6,
            7,
            "syntax error: unexpected 'END_PROGRAM'; expected '&', '*', '**', '+', '-', '/', ';', '<', …",
            "a ';' is missing at the end of line 6",
        ),
    ]


def test_a_file_that_needed_more_than_semicolons_is_not_checked_further():
    # the AST after a guess is not the program: no checker error comes from it (f's undeclared name)
    src = "PROGRAM p\nVAR x : INT; END_VAR\nx := (1 + 2;\nEND_PROGRAM\nFUNCTION f : INT\nf := undeclared;\n"
    src += "END_FUNCTION\n"
    assert where(src) == [("E001", 3, 12)]


# ---------------------------------------------------------------------- garbage in, clean E001 out


def test_stray_characters_are_each_one_error():
    src = "PROGRAM p\nVAR x, y : INT; END_VAR\nx := 1 § ;\ny := x ? 2;\nx := (y;\nEND_PROGRAM\n"
    assert errors(src) == [
        ("E001", 3, 8, "unexpected character '§'", ""),
        ("E001", 4, 8, "unexpected character '?'", ""),
        ("E001", 5, 8, "syntax error: unexpected ';'; expected ')'", "')' is missing before ';'"),
    ]


def test_a_file_of_only_end_if_is_one_error():
    assert errors("END_IF\n" * 200) == [
        (
            "E001",
            1,
            1,
            "syntax error: unexpected 'END_IF'; expected end of file, 'ACTION', 'CLASS', 'CONFIGURATION', "
            "'FUNCTION', 'FUNCTION_BLOCK', 'INTERFACE', 'METHOD', …",
            "",
        )
    ]


def test_deeply_nested_parentheses_are_one_error():
    open_only = "PROGRAM p\nVAR x : INT; END_VAR\nx := " + "(" * 5000 + "1;\nx := 2;\nEND_PROGRAM\n"
    assert errors(open_only) == [("E001", 3, 5007, "syntax error: unexpected ';'; expected ')'", "")]
    broken = "PROGRAM p\nVAR x : INT; END_VAR\nx := " + "(" * 3000 + "1 +* 2" + ")" * 3000 + ";\nEND_PROGRAM\n"
    assert where(broken) == [("E001", 3, 3009)]


def test_the_number_of_syntax_errors_is_bounded():
    src = "PROGRAM p\nVAR x : INT; END_VAR\n" + "x := x + * 1;\n" * 2000 + "END_PROGRAM\n"
    got = where(src)
    assert len(got) == 50
    assert got[0] == ("E001", 3, 10) and got[-1] == ("E001", 52, 10)


def test_garbage_gives_located_e001_diagnostics_in_bounded_time():
    rnd = random.Random(61131)
    words = ["IF", "THEN", "END_IF", "PROGRAM", "END_PROGRAM", "VAR", "END_VAR", "x", ":=", "1", ";", "(", ")"]
    inputs = [
        bytes(rnd.randrange(256) for _ in range(20000)).decode("latin-1"),
        "".join(rnd.choice("abcXYZ;:=()[]+-*/ \n'\"#%.,<>") for _ in range(20000)),
        " ".join(rnd.choice(words) for _ in range(20000)),
        ")" * 50000,  # (a run of ";" is nothing now: stray semicolons between declarations)
        "PROGRAM p\n" + "x := 'abc\n" * 2000 + "END_PROGRAM\n",
        "PROGRAM p\nVAR x : INT; END_VAR\n" + "IF x THEN\n" * 3000 + "x := ;\n" + "END_IF;\n" * 3000 + "END_PROGRAM\n",
    ]
    for text in inputs:
        start = time.perf_counter()
        r = compile_text(text, "g.st", raise_on_error=False, use_cache=False)
        assert time.perf_counter() - start < 30
        syntax = [d for d in r.diagnostics if d.code == "E001"]
        assert 1 <= len(syntax) <= 50
        assert all(d.span.file == "g.st" and d.span.line >= 1 and d.span.col >= 1 for d in syntax)
        assert not [d for d in r.diagnostics if d.code in ("E099", "E041")]


def test_a_program_with_any_one_token_deleted_gives_one_error_at_most():
    # every token of a program deleted in turn: one syntax error, or none where the token may go
    text = (
        "PROGRAM p\nVAR i, s : INT; b : BOOL; a : ARRAY[1..3] OF INT; END_VAR\n"
        "FOR i := 1 TO 3 DO a[i] := i * 2; END_FOR;\nIF s > 10 THEN s := 0; ELSIF b THEN s := 1; ELSE s := s + 1; "
        "END_IF;\nCASE i OF 1: b := TRUE; 2, 3: b := FALSE; END_CASE;\nWHILE s < 5 DO s := s + 1; END_WHILE;\n"
        "END_PROGRAM\n"
    )
    spans = [(m.start(), m.end()) for m in re.finditer(r"[A-Za-z_][A-Za-z0-9_]*|\d+|:=|\.\.|\S", text)]
    counts = []
    for start, end in spans:
        sink = DiagnosticSink()
        parse_source(SourceFile("m.st", text[:start] + text[end:]), sink)
        assert not [d for d in sink.items if d.code in ("E099", "E041")]
        counts.append(len([d for d in sink.items if d.code == "E001"]))
    # the 7 that still parse: the ';' after END_IF, END_CASE, END_WHILE and after `a[i] := i * 2` (an
    # empty statement remains), ELSE, and the `s` of two `s := s + 1` (a '+' sign remains)
    assert (len(counts), counts.count(0), max(counts)) == (101, 7, 1)


# ---------------------------------------------------------------------- the expected tokens in ST


def test_expected_assignments_are_spelled_as_in_st():
    src = "PROGRAM p\nVAR x : INT; r : REF_TO INT; END_VAR\nx = 5;\nr REF= x x;\nEND_PROGRAM\n"
    assert errors(src) == [
        (
            "E001",
            3,
            3,
            "syntax error: unexpected '='; expected '(', '.', ':=', '?=', 'R=', 'REF=', 'S=', '[', …",
            "use ':=' to assign a value; '=' compares",
        ),
        ("E001", 4, 10, "syntax error: unexpected 'x'; expected '&', '(', '*', '**', '+', '-', '.', '/', …", ""),
    ]


def test_every_terminal_of_the_grammar_has_an_st_spelling():
    parser = StParser(None)
    described = {
        "WS": "white space",
        "VAR_KIND": "'VAR'",
        "SET_ASSIGN": "'S='",
        "RESET_ASSIGN": "'R='",
        "REF_ASSIGN": "'REF='",
        "STRING_KW": "'STRING'",
        "PARTIAL_ACCESS": "a partial access such as %X0",
        "IDENT": "an identifier",
        "INTEGER": "an integer",
        "BASED_INT": "an integer",
        "REAL_LIT": "a real number",
        "TIME_LIT": "a time literal",
        "DATE_LIT": "a date literal",
        "TOD_LIT": "a time-of-day literal",
        "DT_LIT": "a date-and-time literal",
        "TYPED_PREFIX": "a typed literal",
        "STRING_LIT": "a string",
        "WSTRING_LIT": "a wide string",
        "DIRECT_VAR": "a located address",
        "ACCESS_DIRECTION": "'READ_ONLY'",
    }
    for t in parser.lark.terminals:
        if t.pattern.type == "str":
            assert parser.spelling(t.name) == f"'{t.pattern.value}'", t.name
        else:
            assert parser.spelling(t.name) == described[t.name], t.name  # a new regex terminal: name it in _PRETTY
    assert parser.spelling("$END") == "end of file"


def test_a_subrange_with_a_star_is_a_located_error_not_an_internal_one():
    sink = DiagnosticSink()
    parse_source(SourceFile("t.st", "TYPE T : INT( * ); END_TYPE\n"), sink)
    assert [(d.code, d.span.line, d.span.col, d.message) for d in sink.sorted()] == [
        ("E001", 1, 10, "a subrange of INT needs its bounds: INT(lo..hi)")
    ]
