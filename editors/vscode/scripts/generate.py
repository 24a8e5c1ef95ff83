"""Writes syntaxes/st.tmLanguage.json and language-configuration.json (edit this, not them).

    python3 scripts/generate.py            # rewrite both files
    python3 scripts/generate.py --check    # exit 1 when a file differs from what this writes

The keyword lists below are written once and used by the grammar (Oniguruma regexes, `(?i)` for
case-insensitive keywords) and by the folding and indentation rules (JavaScript regexes).
`npm test` checks that the two files are this script's output, then tokenizes a sample.
"""

import json
import re
import sys
from pathlib import Path

ID = r"[A-Za-z_][A-Za-z0-9_]*"
QID = ID + r"(?:\." + ID + r")*"
NB = r"(?<![\w.$#%])"  # not after a word, a '.', '$', '#' or '%' (fb.Set, E#Red, %X)


def words(ws):
    return "|".join(sorted(ws, key=lambda w: (-len(w), w)))


ELEMENTARY = """BOOL SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL BYTE WORD DWORD LWORD
TIME LTIME DATE LDATE TIME_OF_DAY TOD LTIME_OF_DAY LTOD DATE_AND_TIME DT LDATE_AND_TIME LDT
STRING WSTRING CHAR WCHAR BIT XINT UXINT XWORD __XINT __UXINT __XWORD PVOID""".split()
GENERIC = """ANY ANY_DERIVED ANY_ELEMENTARY ANY_MAGNITUDE ANY_NUM ANY_REAL ANY_INT ANY_SIGNED
ANY_UNSIGNED ANY_BIT ANY_STRING ANY_CHARS ANY_CHAR ANY_DATE ANY_DURATION""".split()
TYPED_NUM_PREFIX = """SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL BYTE WORD DWORD LWORD BOOL""".split()
STD_FB = """TON TOF TP LTON LTOF LTP TONR RTC SEMA R_TRIG F_TRIG SR RS
CTU CTD CTUD CTU_INT CTU_DINT CTU_LINT CTU_UDINT CTU_ULINT CTD_INT CTD_DINT CTD_LINT CTD_UDINT CTD_ULINT
CTUD_INT CTUD_DINT CTUD_LINT CTUD_UDINT CTUD_ULINT""".split()
STD_FUN = """ABS SQRT LN LOG EXP EXPT SIN COS TAN ASIN ACOS ATAN ATAN2 ADD SUB MUL DIV MOVE
SEL MAX MIN LIMIT MUX SHL SHR ROL ROR GT GE EQ LE LT NE LEN LEFT RIGHT MID CONCAT INSERT DELETE
REPLACE FIND TRUNC ROUND LOWER_BOUND UPPER_BOUND IS_VALID""".split()
INTRINSIC_FUN = """ADR BITADR SIZEOF XSIZEOF INDEXOF REF""".split()
INTRINSIC_KW = """__NEW __DELETE __QUERYINTERFACE __QUERYPOINTER __ISVALIDREF __VARINFO
__POSITION __POUNAME __CURRENTTASK""".split()
VAR_KW = """VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_TEMP VAR_GLOBAL VAR_EXTERNAL VAR_CONFIG
VAR_ACCESS VAR_INST VAR_STAT""".split()
MODIFIERS = """CONSTANT RETAIN NON_RETAIN PERSISTENT PUBLIC PRIVATE PROTECTED INTERNAL ABSTRACT
FINAL OVERRIDE AT R_EDGE F_EDGE READ_ONLY READ_WRITE""".split()
# words after ':' / OF / TO that are not a user type's name
NOT_A_TYPE = ELEMENTARY + GENERIC + STD_FB + """ARRAY POINTER REFERENCE REF_TO STRUCT UNION OF TO""".split()


def dump(value):
    """JSON with two-space indents and short lists of scalars on one line."""
    text = json.dumps(value, indent=2, ensure_ascii=False)
    return re.sub(
        r"\[\s*((?:\"(?:[^\"\\\\]|\\\\.)*\"\s*,?\s*)+)\]",
        lambda m: "[" + ", ".join(x.strip() for x in re.findall(r'"(?:[^"\\\\]|\\\\.)*"', m.group(1))) + "]",
        text,
    )


def ci(word):
    """A case-insensitive JavaScript regex for one word, without flags ([Ee][Nn][Dd]_[Ii][Ff])."""
    return "".join(f"[{c.upper()}{c.lower()}]" if c.isalpha() else c for c in word)


def kw(name, ws, after=""):
    return {"name": name, "match": rf"(?i){NB}\b({words(ws)})\b{after}"}


grammar = {
    "$schema": "https://raw.githubusercontent.com/martinring/tmlanguage/master/tmlanguage.json",
    "name": "Structured Text (IEC 61131-3)",
    "scopeName": "source.st",
    "fileTypes": ["st", "TcPOU", "TcGVL", "TcDUT", "TcIO"],
    "patterns": [{"include": "#xml-wrapper"}, {"include": "#declarations"}, {"include": "#code"}],
    "repository": {
        # ----------------------------------------------------------------- TwinCAT's XML files
        "xml-wrapper": {
            "comment": "TwinCAT's .TcPOU/.TcGVL/.TcDUT/.TcIO are XML with the ST in CDATA sections: "
            "the tags (at the start of a line, where ST never has a '<') and the CDATA brackets",
            "patterns": [
                {
                    "name": "meta.tag.preprocessor.xml.st",
                    "match": r"^\s*<\?xml\b.*?\?>",
                },
                {
                    "name": "meta.tag.xml.st",
                    "match": r"(?:^\s*|(?<=\]\]>))(?:</?[A-Za-z][\w:.\-]*(?:\s+[\w:.\-]+\s*=\s*(?:\"[^\"]*\"|'[^']*'))*\s*/?>\s*)+",
                    "captures": {"0": {"patterns": [{"include": "#xml-tag"}]}},
                },
                {"name": "punctuation.definition.cdata.begin.xml.st", "match": r"<!\[CDATA\["},
                {"name": "punctuation.definition.cdata.end.xml.st", "match": r"\]\]>"},
            ],
        },
        "xml-tag": {
            "patterns": [
                {
                    "match": r"(</?)([A-Za-z][\w:.\-]*)",
                    "captures": {
                        "1": {"name": "punctuation.definition.tag.xml.st"},
                        "2": {"name": "entity.name.tag.xml.st"},
                    },
                },
                {
                    "match": r"([\w:.\-]+)\s*(=)\s*(\"[^\"]*\"|'[^']*')",
                    "captures": {
                        "1": {"name": "entity.other.attribute-name.xml.st"},
                        "2": {"name": "punctuation.separator.key-value.xml.st"},
                        "3": {"name": "string.quoted.xml.st"},
                    },
                },
                {"name": "punctuation.definition.tag.xml.st", "match": r"/?>"},
            ]
        },
        # ----------------------------------------------------------------- comments and pragmas
        "comments": {
            "patterns": [
                {"include": "#comment-paren"},
                {"include": "#comment-slash-star"},
                {
                    "name": "comment.line.double-slash.st",
                    "begin": r"//",
                    "beginCaptures": {"0": {"name": "punctuation.definition.comment.st"}},
                    "end": r"$",
                },
            ]
        },
        "comment-paren": {
            "comment": "(* … *) comments nest (CODESYS, TwinCAT)",
            "name": "comment.block.st",
            "begin": r"\(\*",
            "end": r"\*\)",
            "captures": {"0": {"name": "punctuation.definition.comment.st"}},
            "patterns": [{"include": "#comment-paren"}],
        },
        "comment-slash-star": {
            "name": "comment.block.st",
            "begin": r"/\*",
            "end": r"\*/",
            "captures": {"0": {"name": "punctuation.definition.comment.st"}},
            "patterns": [{"include": "#comment-slash-star"}],
        },
        "pragmas": {
            "patterns": [
                {
                    "comment": "{{ … }}: C code embedded in an OpenPLC program",
                    "name": "meta.embedded.block.c.st",
                    "begin": r"\{\{",
                    "end": r"\}\}",
                    "captures": {"0": {"name": "punctuation.section.embedded.st"}},
                    "patterns": [{"include": "source.c"}],
                },
                {
                    "comment": "{attribute 'x'}, {dialect 'iec'}, {warning '…'}, {IF defined(x)}, {region …}",
                    "name": "meta.preprocessor.pragma.st",
                    "begin": r"\{",
                    "end": r"\}",
                    "captures": {"0": {"name": "punctuation.definition.pragma.st"}},
                    "patterns": [
                        {
                            "comment": "the pragma's first word: attribute, dialect, warning, IF, region, …",
                            "match": r"(?<=\{)\s*(\w+)",
                            "captures": {"1": {"name": "keyword.control.directive.pragma.st"}},
                        },
                        {
                            "name": "keyword.operator.pragma.st",
                            "match": r"(?i)\b(defined|hasattribute|hastype|hasvalue|hasconstanttype|hasconstantvalue|project_defined)\b|:=|=|<>|\bAND\b|\bOR\b|\bNOT\b",
                        },
                        {"include": "#strings"},
                        {"include": "#numbers"},
                    ],
                },
            ]
        },
        # ----------------------------------------------------------------- literals
        "strings": {
            "patterns": [
                {
                    "name": "string.quoted.single.st",
                    "begin": r"'",
                    "end": r"'|$",
                    "beginCaptures": {"0": {"name": "punctuation.definition.string.begin.st"}},
                    "endCaptures": {"0": {"name": "punctuation.definition.string.end.st"}},
                    "patterns": [
                        {"name": "constant.character.escape.st", "match": r"\$(?:[$'\"LlNnPpRrTt]|[0-9A-Fa-f]{2})"},
                        {"name": "invalid.illegal.escape.st", "match": r"\$."},
                    ],
                },
                {
                    "name": "string.quoted.double.st",
                    "begin": r"\"",
                    "end": r"\"|$",
                    "beginCaptures": {"0": {"name": "punctuation.definition.string.begin.st"}},
                    "endCaptures": {"0": {"name": "punctuation.definition.string.end.st"}},
                    "patterns": [
                        {"name": "constant.character.escape.st", "match": r"\$(?:[$'\"LlNnPpRrTt]|[0-9A-Fa-f]{4})"},
                        {"name": "invalid.illegal.escape.st", "match": r"\$."},
                    ],
                },
            ]
        },
        "numbers": {
            "patterns": [
                {"name": "constant.numeric.integer.binary.st", "match": r"\b2#[01_]+\b"},
                {"name": "constant.numeric.integer.octal.st", "match": r"\b8#[0-7_]+\b"},
                {"name": "constant.numeric.integer.hexadecimal.st", "match": r"\b16#[0-9A-Fa-f_]+\b"},
                {
                    "name": "constant.numeric.float.st",
                    "match": r"\b[0-9][0-9_]*(?:\.[0-9][0-9_]*(?:[eE][+-]?[0-9]+)?|[eE][+-]?[0-9]+)\b",
                },
                {"name": "constant.numeric.integer.decimal.st", "match": r"\b[0-9][0-9_]*\b"},
            ]
        },
        "typed-literals": {
            "patterns": [
                {
                    "name": "constant.numeric.date-and-time.st",
                    "match": r"(?i)\b(?:LDATE_AND_TIME|DATE_AND_TIME|LDT|DT)#[0-9]+-[0-9]+-[0-9]+-[0-9]+:[0-9]+(?::[0-9]+(?:\.[0-9]+)?)?",
                },
                {
                    "name": "constant.numeric.time-of-day.st",
                    "match": r"(?i)\b(?:LTIME_OF_DAY|TIME_OF_DAY|LTOD|TOD)#[0-9]+:[0-9]+(?::[0-9]+(?:\.[0-9]+)?)?",
                },
                {"name": "constant.numeric.date.st", "match": r"(?i)\b(?:LDATE|DATE|LD|D)#[0-9]+-[0-9]+-[0-9]+"},
                {"name": "constant.numeric.time.st", "match": r"(?i)\b(?:LTIME|TIME|LT|T)#[+-]?[0-9][0-9_.a-z]*"},
                {
                    "comment": "INT#5, BYTE#16#FF, REAL#-1.5E3, BOOL#TRUE",
                    "match": rf"(?i)\b({words(TYPED_NUM_PREFIX)})(#)([+-]?(?:(?:2|8|16)#[0-9A-F_]+|[0-9][0-9_]*(?:\.[0-9][0-9_]*)?(?:E[+-]?[0-9]+)?)\b)",
                    "captures": {
                        "1": {"name": "support.type.primitive.st"},
                        "2": {"name": "punctuation.separator.type.st"},
                        "3": {"patterns": [{"include": "#numbers"}]},
                    },
                },
                {
                    "match": r"(?i)\b(BOOL)(#)(TRUE|FALSE)\b",
                    "captures": {
                        "1": {"name": "support.type.primitive.st"},
                        "2": {"name": "punctuation.separator.type.st"},
                        "3": {"name": "constant.language.boolean.st"},
                    },
                },
                {
                    "comment": "STRING#'abc', WCHAR#\"x\": the string follows",
                    "match": r"(?i)\b(STRING|WSTRING|CHAR|WCHAR)(#)(?=['\"])",
                    "captures": {
                        "1": {"name": "support.type.primitive.st"},
                        "2": {"name": "punctuation.separator.type.st"},
                    },
                },
                {
                    "comment": "an enumeration value with its type: Color#Red",
                    "match": rf"\b({ID})(#)({ID})\b",
                    "captures": {
                        "1": {"name": "entity.name.type.enum.st"},
                        "2": {"name": "punctuation.separator.type.st"},
                        "3": {"name": "variable.other.enummember.st"},
                    },
                },
            ]
        },
        "addresses": {
            "patterns": [
                {"name": "constant.other.address.st", "match": r"(?i)%[IQM][XBWDL]?(?:\*|[0-9]+(?:\.[0-9]+)*)"},
                {
                    "comment": "a partial access: word.%X3, dw.%B1",
                    "name": "constant.other.address.partial.st",
                    "match": r"(?i)(?<=\.)%[XBWDL][0-9]+",
                },
            ]
        },
        "language-constants": {
            "patterns": [
                kw("constant.language.boolean.st", ["TRUE", "FALSE"]),
                kw("constant.language.null.st", ["NULL"]),
                kw("variable.language.st", ["THIS", "SUPER"]),
            ]
        },
        # ----------------------------------------------------------------- declarations
        "declarations": {
            "patterns": [
                {"include": "#comments"},
                {"include": "#pragmas"},
                {"include": "#var-block"},
                {"include": "#type-block"},
                {"include": "#pou-header"},
            ]
        },
        "pou-header": {
            "patterns": [
                {
                    "comment": "in a CONFIGURATION: PROGRAM instance WITH task : Type(…)",
                    "match": rf"(?i){NB}\b(PROGRAM)\s+(?:(RETAIN|NON_RETAIN)\s+)?({ID})\s*(?:(WITH)\s+({ID})\s*)?(:)(?!=)\s*({ID})",
                    "captures": {
                        "1": {"name": "storage.type.pou.st"},
                        "2": {"name": "storage.modifier.st"},
                        "3": {"name": "variable.other.instance.st"},
                        "4": {"name": "keyword.other.configuration.st"},
                        "5": {"name": "variable.other.task.st"},
                        "6": {"name": "punctuation.separator.colon.st"},
                        "7": {"name": "entity.name.type.program.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(FUNCTION_BLOCK|CLASS)\b((?:\s+(?:ABSTRACT|FINAL|PUBLIC|INTERNAL))*)\s+({ID})",
                    "captures": {
                        "1": {"name": "storage.type.pou.st"},
                        "2": {"name": "storage.modifier.st"},
                        "3": {"name": "entity.name.type.class.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(PROGRAM)\b((?:\s+(?:ABSTRACT|FINAL|PUBLIC|INTERNAL))*)\s+({ID})",
                    "captures": {
                        "1": {"name": "storage.type.pou.st"},
                        "2": {"name": "storage.modifier.st"},
                        "3": {"name": "entity.name.type.program.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(INTERFACE)\b((?:\s+(?:PUBLIC|INTERNAL))*)\s+({ID})",
                    "captures": {
                        "1": {"name": "storage.type.pou.st"},
                        "2": {"name": "storage.modifier.st"},
                        "3": {"name": "entity.name.type.interface.st"},
                    },
                },
                {
                    "comment": "FUNCTION F : INT, METHOD PUBLIC M : BOOL, PROPERTY P : REAL",
                    "match": rf"(?i){NB}\b(FUNCTION|METHOD|PROPERTY)\b((?:\s+(?:ABSTRACT|FINAL|PUBLIC|PRIVATE|PROTECTED|INTERNAL|OVERRIDE))*)\s+({ID})(?:\s*(:)(?!=)\s*(?!(?:POINTER|REFERENCE|ARRAY|REF_TO)\b)({QID}))?",
                    "captures": {
                        "1": {"name": "storage.type.pou.st"},
                        "2": {"name": "storage.modifier.st"},
                        "3": {"name": "entity.name.function.st"},
                        "4": {"name": "punctuation.separator.colon.st"},
                        "5": {"patterns": [{"include": "#elementary-types"}, {"include": "#type-name"}]},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(ACTION)\s+({ID})\s*(?=:(?!=)|$|\(\*|//)",
                    "captures": {
                        "1": {"name": "storage.type.pou.st"},
                        "2": {"name": "entity.name.function.action.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(CONFIGURATION|RESOURCE)\s+({ID})(?:\s+(ON)\s+({ID}))?",
                    "captures": {
                        "1": {"name": "storage.type.configuration.st"},
                        "2": {"name": "entity.name.section.st"},
                        "3": {"name": "keyword.other.configuration.st"},
                        "4": {"name": "entity.name.type.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(TASK)\s+({ID})\s*(?=\()",
                    "captures": {
                        "1": {"name": "keyword.other.configuration.st"},
                        "2": {"name": "entity.name.section.task.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(INITIAL_STEP|STEP)\s+({ID})\s*(?=:(?!=))",
                    "captures": {
                        "1": {"name": "keyword.other.sfc.st"},
                        "2": {"name": "entity.name.label.step.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(EXTENDS)\s+({QID}(?:\s*,\s*{QID})*)",
                    "captures": {
                        "1": {"name": "storage.modifier.extends.st"},
                        "2": {"name": "entity.other.inherited-class.st"},
                    },
                },
                {
                    "match": rf"(?i){NB}\b(IMPLEMENTS)\s+({QID}(?:\s*,\s*{QID})*)",
                    "captures": {
                        "1": {"name": "storage.modifier.implements.st"},
                        "2": {"name": "entity.other.inherited-class.st"},
                    },
                },
            ]
        },
        "var-block": {
            "name": "meta.block.var.st",
            "begin": rf"(?i){NB}\b({words(VAR_KW)})\b",
            "beginCaptures": {"1": {"name": "storage.type.var.st"}},
            "end": rf"(?i){NB}\b(END_VAR)\b",
            "endCaptures": {"1": {"name": "storage.type.var.st"}},
            "patterns": [
                {"include": "#xml-wrapper"},
                {"include": "#comments"},
                {"include": "#pragmas"},
                {"include": "#var-names"},
                {"include": "#type-reference"},
                {"include": "#code"},
            ],
        },
        "var-names": {
            "comment": "the names a declaration declares: a, b AT %IX0.0 : BOOL;",
            "match": rf"(?i)(?<![\w.$#%])({ID}(?:\s*,\s*{ID})*)(?=\s*(?:AT\s+%\S+\s*)?:(?!=))",
            "captures": {"1": {"patterns": [{"include": "#var-name"}]}},
        },
        "var-name": {"patterns": [{"name": "variable.other.declaration.st", "match": ID}]},
        "type-reference": {
            "comment": "a user type's name after ':' (not ':='), OF or TO in a declaration",
            "match": rf"(?i)(?:(?<=:)|(?<=\bOF\s)|(?<=\bTO\s)|(?<=\bREF_TO\s))\s*(?!(?:{words(NOT_A_TYPE)})\b)({QID})\b(?!\s*#)",
            "captures": {"1": {"patterns": [{"include": "#type-name"}]}},
        },
        "type-name": {"name": "entity.name.type.st", "match": QID},
        "type-block": {
            "name": "meta.block.type.st",
            "begin": rf"(?i){NB}\b(TYPE)\b",
            "beginCaptures": {"1": {"name": "storage.type.st"}},
            "end": rf"(?i){NB}\b(END_TYPE)\b",
            "endCaptures": {"1": {"name": "storage.type.st"}},
            "patterns": [
                {"include": "#xml-wrapper"},
                {"include": "#comments"},
                {"include": "#pragmas"},
                {"include": "#struct-block"},
                {
                    "comment": "the name of a type: Name : STRUCT …, Name EXTENDS Base : STRUCT, Name : (A, B);",
                    "match": rf"(?i)(?:^|(?<=\bTYPE))\s*(?:(PUBLIC|INTERNAL)\s+)?({ID})\s*(?:(EXTENDS)\s+({QID})\s*)?(?=:(?!=))",
                    "captures": {
                        "1": {"name": "storage.modifier.st"},
                        "2": {"name": "entity.name.type.st"},
                        "3": {"name": "storage.modifier.extends.st"},
                        "4": {"name": "entity.other.inherited-class.st"},
                    },
                },
                {"include": "#type-reference"},
                {"include": "#code"},
            ],
        },
        "struct-block": {
            "name": "meta.block.struct.st",
            "begin": rf"(?i){NB}\b(STRUCT|UNION)\b",
            "beginCaptures": {"1": {"name": "storage.type.st"}},
            "end": rf"(?i){NB}\b(END_STRUCT|END_UNION)\b",
            "endCaptures": {"1": {"name": "storage.type.st"}},
            "patterns": [
                {"include": "#xml-wrapper"},
                {"include": "#comments"},
                {"include": "#pragmas"},
                {"include": "#var-names"},
                {"include": "#type-reference"},
                {"include": "#code"},
            ],
        },
        # ----------------------------------------------------------------- code
        "code": {
            "patterns": [
                {"include": "#comments"},
                {"include": "#pragmas"},
                {"include": "#strings"},
                {"include": "#typed-literals"},
                {"include": "#numbers"},
                {"include": "#addresses"},
                {"include": "#pou-header"},
                {"include": "#keywords"},
                {"include": "#language-constants"},
                {"include": "#elementary-types"},
                {"include": "#standard-blocks"},
                {"include": "#functions"},
                {"include": "#operators"},
                {"include": "#punctuation"},
            ]
        },
        "keywords": {
            "patterns": [
                {
                    "name": "storage.type.pou.st",
                    "match": rf"(?i){NB}\b(END_PROGRAM|END_FUNCTION_BLOCK|END_FUNCTION|END_METHOD|END_PROPERTY|END_INTERFACE|END_CLASS|END_ACTION|END_GET|END_SET|FUNCTION_BLOCK|FUNCTION|PROGRAM|METHOD|PROPERTY|INTERFACE|CLASS)\b",
                },
                {
                    "comment": "a property's accessors in a text export, at the start of a line: GET … END_GET (not Set := …)",
                    "match": r"(?i)^\s*(GET|SET)\b(?!\s*(?::=|\.|\[|\(|\^|,|;|=>|:))",
                    "captures": {"1": {"name": "storage.type.pou.st"}},
                },
                {"name": "storage.type.st", "match": rf"(?i){NB}\b(TYPE|END_TYPE|STRUCT|END_STRUCT|UNION|END_UNION)\b"},
                {"name": "storage.type.var.st", "match": rf"(?i){NB}\b({words(VAR_KW + ['END_VAR'])})\b"},
                {
                    "name": "storage.type.reference.st",
                    "match": rf"(?i){NB}\b(ARRAY|REF_TO|POINTER\s+TO|REFERENCE\s+TO)\b",
                },
                {
                    "name": "keyword.control.conditional.st",
                    "match": rf"(?i){NB}\b(IF|THEN|ELSIF|ELSE|END_IF|CASE|OF|END_CASE)\b",
                },
                {
                    "name": "keyword.control.loop.st",
                    "match": rf"(?i){NB}\b(FOR|TO|BY|DO|END_FOR|WHILE|END_WHILE|REPEAT|UNTIL|END_REPEAT)\b",
                },
                {"name": "keyword.control.flow.st", "match": rf"(?i){NB}\b(EXIT|CONTINUE|RETURN|JMP)\b"},
                {
                    "name": "keyword.control.exception.st",
                    "match": rf"(?i){NB}\b(__TRY|__CATCH|__FINALLY|__ENDTRY)\b",
                },
                {
                    "name": "storage.modifier.st",
                    "match": rf"(?i){NB}\b({words(MODIFIERS + ['EXTENDS', 'IMPLEMENTS'])})\b",
                },
                {"name": "keyword.other.intrinsic.st", "match": rf"(?i){NB}\b({words(INTRINSIC_KW)})\b"},
                {
                    "name": "keyword.other.sfc.st",
                    "match": rf"(?i){NB}\b(END_STEP|END_TRANSITION|INITIAL_STEP)\b|{NB}\b(TRANSITION)\b(?!\s*(?::=|\.|\[|\(|\^|,|;))|{NB}\b(FROM)\b(?=\s*[A-Za-z_(])",
                },
                {
                    "name": "storage.type.pou.st",
                    "match": rf"(?i){NB}\b(ACTION)\b(?=\s*$)",
                },
                {
                    "name": "storage.type.configuration.st",
                    "match": rf"(?i){NB}\b(END_CONFIGURATION|END_RESOURCE|CONFIGURATION|RESOURCE)\b",
                },
                {
                    "comment": "unit tests (STruC++): TEST 'name' … END_TEST, SETUP, TEARDOWN, MOCK",
                    "name": "keyword.other.test.st",
                    "match": rf"(?i){NB}\b(END_TEST|END_SETUP|END_TEARDOWN|MOCK_FUNCTION|RETURNS(?=\s))\b|{NB}\b(TEST)\b(?=\s*['\"])|^\s*(SETUP|TEARDOWN)\b(?=\s*(?:$|\(\*|//))|{NB}\b(MOCK)\b(?=\s+[A-Za-z_])",
                },
                {"name": "keyword.operator.logical.st", "match": rf"(?i){NB}\b(AND_THEN|OR_ELSE|AND|OR|XOR|NOT)\b"},
                {"name": "keyword.operator.arithmetic.st", "match": rf"(?i){NB}\b(MOD)\b"},
            ]
        },
        "elementary-types": {
            "patterns": [
                {"name": "support.type.primitive.st", "match": rf"(?i){NB}\b({words(ELEMENTARY)})\b(?!#)"},
                {"name": "support.type.generic.st", "match": rf"(?i){NB}\b({words(GENERIC)})\b"},
            ]
        },
        "standard-blocks": {
            "comment": "the standard function blocks (IEC 61131-3 2.5.2.3)",
            "name": "support.class.st",
            "match": rf"(?i){NB}\b({words(STD_FB)})\b",
        },
        "functions": {
            "patterns": [
                {
                    "comment": "conversions: INT_TO_REAL, TO_DINT, TRUNC_INT, …",
                    "name": "support.function.conversion.st",
                    "match": rf"(?i){NB}\b(?:[A-Z]+_TO_[A-Z_]+|TO_[A-Z_]+|TRUNC_[A-Z]+|BCD_TO_[A-Z]+)\b(?=\s*\()",
                },
                {"name": "support.function.st", "match": rf"(?i){NB}\b({words(STD_FUN)})\b(?=\s*\()"},
                {"name": "support.function.intrinsic.st", "match": rf"(?i){NB}\b({words(INTRINSIC_FUN)})\b(?=\s*\()"},
                {
                    "match": rf"(?<![\w$#%])({ID})\s*(?=\()",
                    "captures": {"1": {"name": "entity.name.function.call.st"}},
                },
            ]
        },
        "operators": {
            "patterns": [
                {"name": "keyword.operator.assignment.st", "match": r":=|\?="},
                {
                    "comment": "set, reset and reference assignments: x S= b; p REF= v;",
                    "name": "keyword.operator.assignment.st",
                    "match": r"(?i)(?<=\s)(?:S|R|REF)=(?=[\s(])",
                },
                {"name": "keyword.operator.output.st", "match": r"=>"},
                {"name": "keyword.operator.comparison.st", "match": r"<>|<=|>=|=|<|>"},
                {"name": "keyword.operator.arithmetic.st", "match": r"\*\*|\+|-|\*|/"},
                {"name": "keyword.operator.logical.st", "match": r"&"},
                {"name": "keyword.operator.range.st", "match": r"\.\."},
                {"name": "keyword.operator.dereference.st", "match": r"\^"},
            ]
        },
        "punctuation": {
            "patterns": [
                {"name": "punctuation.terminator.statement.st", "match": ";"},
                {"name": "punctuation.separator.comma.st", "match": ","},
                {"name": "punctuation.accessor.st", "match": r"\."},
                {"name": "punctuation.separator.colon.st", "match": ":"},
                {"name": "punctuation.brackets.round.st", "match": r"[()]"},
                {"name": "punctuation.brackets.square.st", "match": r"[\[\]]"},
            ]
        },
    },
}

# folding: the start and end of a block (JavaScript regexes; VS Code drops their flags, so each
# letter is a class). A start line that also ends its block (IF a THEN b; END_IF) is no start.
FOLD_START = (
    """PROGRAM FUNCTION_BLOCK FUNCTION METHOD PROPERTY INTERFACE CLASS CONFIGURATION RESOURCE
TYPE STRUCT UNION IF CASE FOR WHILE REPEAT __TRY""".split()
    + VAR_KW
)
# soft keywords that are also names: only when not followed by an assignment, a dot, a call, …
FOLD_SOFT = """ACTION TRANSITION STEP INITIAL_STEP GET SET TEST SETUP TEARDOWN""".split()
FOLD_END = (
    ["END_" + w for w in FOLD_START if not w.startswith(("VAR", "__"))]
    + ["END_VAR", "__ENDTRY"]
    + ["END_ACTION", "END_TRANSITION", "END_STEP", "END_GET", "END_SET", "END_TEST", "END_SETUP", "END_TEARDOWN"]
)
hard = "|".join(ci(w) for w in sorted(set(FOLD_START), key=lambda w: (-len(w), w)))
soft = "|".join(ci(w) for w in sorted(FOLD_SOFT, key=lambda w: (-len(w), w)))
end = "|".join(ci(w) for w in sorted(set(FOLD_END), key=lambda w: (-len(w), w)))
never_end = r"(?!.*\b[Ee][Nn][Dd]_)"
fold_start = (
    rf"^\s*(?:(?:{hard})\b|(?:{soft})\b(?!\s*(?::=|\.|\[|\(|\^|,|;|=>|:\s*[A-Za-z_]+\s*;))){never_end}"
    rf"|^\s*\{{\s*{ci('region')}\b"
)
fold_end = rf"^\s*(?:{end})\b|^\s*\{{\s*{ci('endregion')}\b"

INCREASE = (
    r"^\s*(?:(?:PROGRAM|FUNCTION_BLOCK|FUNCTION|METHOD|PROPERTY|INTERFACE|CLASS|CONFIGURATION|RESOURCE|"
    r"TYPE|STRUCT|UNION|VAR(?:_\w+)?|REPEAT|__TRY|INITIAL_STEP|SETUP|TEARDOWN)\b|STEP\s+\w+\s*:|"
    r"ACTION\s+\w+\s*:?\s*$|TRANSITION\b(?!\s*:?=)|TEST\s*['\"]|(?:GET|SET)\s*$)(?!.*\bEND_)"
    r"|.*\b(?:THEN|DO|OF|ELSE|__CATCH(?:\s*\(\s*\w+\s*\))?|__FINALLY)\s*(?:(?://.*|\(\*.*\*\))\s*)?$"
)
DECREASE = r"^\s*(?:END_\w+|ELSE|ELSIF|UNTIL|__CATCH|__FINALLY|__ENDTRY)\b"

config = {
    "comments": {"lineComment": "//", "blockComment": ["(*", "*)"]},
    "brackets": [["(", ")"], ["[", "]"], ["{", "}"]],
    "autoClosingPairs": [
        {"open": "(", "close": ")"},
        {"open": "[", "close": "]"},
        {"open": "{", "close": "}"},
        {"open": "(*", "close": "*)", "notIn": ["string", "comment"]},
        {"open": "'", "close": "'", "notIn": ["string", "comment"]},
        {"open": '"', "close": '"', "notIn": ["string", "comment"]},
    ],
    "autoCloseBefore": ";:.,=}])>*+-/ \n\t",
    "surroundingPairs": [["(", ")"], ["[", "]"], ["{", "}"], ["'", "'"], ['"', '"']],
    "folding": {"markers": {"start": fold_start, "end": fold_end}},
    "indentationRules": {
        "increaseIndentPattern": {"pattern": INCREASE, "flags": "i"},
        "decreaseIndentPattern": {"pattern": DECREASE, "flags": "i"},
    },
}


def main(argv: list[str]) -> int:
    root = Path(__file__).resolve().parent.parent
    outputs = {
        root / "syntaxes" / "st.tmLanguage.json": dump(grammar) + "\n",
        root / "language-configuration.json": dump(config) + "\n",
    }
    if "--check" in argv:
        stale = [p for p, text in outputs.items() if not p.exists() or p.read_text(encoding="utf-8") != text]
        for p in stale:
            print(f"{p.relative_to(root)} is not what scripts/generate.py writes: run python3 scripts/generate.py")
        return 1 if stale else 0
    for p, text in outputs.items():
        p.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
