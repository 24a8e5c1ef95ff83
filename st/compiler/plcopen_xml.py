"""PLCopen XML projects (TC6 XML: the plc.xml of the OpenPLC Editor and Beremiz, CODESYS exports)
as ST sources.

`plcopen_source` turns one project into ST text with the XML's number of lines (layout.py): every
ST body (`<body><ST><xhtml:p><![CDATA[…]]>`) keeps its lines and columns, and what the XML says
in elements (types, variables, POU headers, configurations, SFC networks) is written as ST on the
line of the element it comes from (a variable's whole declaration on its `<variable>` line). So
every diagnostic names the XML file at the place the code or the element stands.

Bodies in FBD, LD or IL are not read (E050, at the `<body>`; the POU keeps its declarations); XML
that is malformed or not a PLCopen project is E051. `<documentation>` and `<addData>` are ignored.
The tool that wrote the file chooses the dialect preset with a `{dialect '…'}` pragma on the
`<fileHeader>` line: CODESYS → codesys, TwinCAT → twincat, Beremiz and the OpenPLC Editor (named,
or known by their `<xhtml:p>` text) → openplc. SFC networks: plcopen_sfc.py.
"""

from __future__ import annotations

import os
import re
from xml.parsers import expat

from ..diagnostics import Code, Diagnostic, Severity
from ..source import Span
from .layout import Layout
from .plcopen_sfc import Sfc
from .xmltree import Element, Unread, parse

NAMESPACES = (
    "http://www.plcopen.org/xml/tc6_0201",
    "http://www.plcopen.org/xml/tc6_0200",
    "http://www.plcopen.org/xml/tc6.xsd",  # TC6 XML 1.0 (older Beremiz and MatIEC files)
)
XHTML = "http://www.w3.org/1999/xhtml"

_ROOT = re.compile(r"\A\s*(?:<\?.*?\?>\s*|<!--.*?-->\s*)*<project\b[^>]*plcopen\.org/xml/tc6(?:_020[01]|\.xsd)", re.S)
_TOOLS = {"codesys": "codesys", "3s-smart": "codesys", "twincat": "twincat", "beckhoff": "twincat"}
_TOOLS |= {"beremiz": "openplc", "openplc": "openplc"}
_KINDS = {"function": "FUNCTION", "functionBlock": "FUNCTION_BLOCK", "program": "PROGRAM"}
_SECTIONS = {
    "inputVars": "VAR_INPUT",
    "outputVars": "VAR_OUTPUT",
    "inOutVars": "VAR_IN_OUT",
    "localVars": "VAR",
    "tempVars": "VAR_TEMP",
    "externalVars": "VAR_EXTERNAL",
    "globalVars": "VAR_GLOBAL",
    "accessVars": "VAR_ACCESS",
}
_QUALIFIERS = (
    ("constant", "CONSTANT"),
    ("retain", "RETAIN"),
    ("nonretain", "NON_RETAIN"),
    ("persistent", "PERSISTENT"),
)
_CLOCK = re.compile(r"(\d+):(\d+):(\d+(?:\.\d*)?)")
_ISO_DURATION = re.compile(r"P(?:(\d+)D)?(?:T(?:(\d+)H)?(?:(\d+)M)?(?:(\d+(?:\.\d*)?)S)?)?", re.I)


def handles(path: str, text: str) -> bool:
    """Is this file read by this module: an .xml file (a PLCopen project, or an error saying it is
    not one), or any file whose root element is a PLCopen project?"""
    return path.lower().endswith(".xml") or _ROOT.match(text[:4096]) is not None


class Reader:
    """One project's ST (`out`) and the problems met on the way (`diags`)."""

    def __init__(self, xml: str, path: str):
        self.out = Layout(xml)
        self.path = path
        self.diags: list[Diagnostic] = []

    # ---------------------------------------------------------------- placing and reporting
    def at(self, el: Element, text: str) -> None:
        self.out.place(el.line, el.col, text)

    def at_end(self, el: Element, text: str) -> None:
        self.out.place(el.end_line, el.end_col, text)

    def code(self, el: Element) -> None:
        for line, col, text in el.code():
            self.out.place(line, col, text, code=True)

    def problem(self, code: str, el: Element, message: str, hint: str = "", language: str = "") -> None:
        """An error at `el`; an E050 names the `language` it does not read (a fact for tools)."""
        data = (("language", language),) if language else ()
        span = Span(self.path, el.line + 1, el.col + 1)
        self.diags.append(Diagnostic(code, Severity.ERROR, span, message, hint, data))

    def unread(self, e: Unread) -> None:
        self.problem(e.code, e.el, e.message, language=e.language)

    # ---------------------------------------------------------------- the project
    def project(self, root: Element) -> None:
        header = root.kid("fileHeader")
        preset = _preset(root)
        if preset is not None:
            self.at(header or root, "{dialect '" + preset + "'}")
        types = root.kid("types")
        if types is not None:
            data_types = types.kid("dataTypes")
            if data_types is not None and data_types.all("dataType"):
                self.at(data_types, "TYPE")
                for dt in data_types.all("dataType"):
                    self.data_type(dt)
                self.at_end(data_types, "END_TYPE")
            pous = types.kid("pous")
            for pou in pous.all("pou") if pous is not None else ():
                self.pou(pou)
        configurations = (root.kid("instances") or root).kid("configurations")
        for conf in configurations.all("configuration") if configurations is not None else ():
            self.configuration(conf)

    # ---------------------------------------------------------------- types and values
    def type_of(self, holder: Element) -> str:
        """A `<type>`, `<baseType>` or `<returnType>` as ST (Unread if st cannot say it)."""
        t = holder.first()
        if t is None:
            raise Unread(Code.XML_FILE, holder, f"<{holder.tag}> names no type")
        if t.tag in ("string", "wstring"):
            length = t.get("length")
            return t.tag.upper() + (f"[{length}]" if length else "")
        if t.tag == "derived":
            return t.get("name")
        if t.tag == "array":
            dims = ", ".join(f"{d.get('lower')}..{d.get('upper')}" for d in t.all("dimension"))
            return f"ARRAY [{dims}] OF {self.type_of(_need(t, 'baseType'))}"
        if t.tag in ("subrangeSigned", "subrangeUnsigned"):
            rng = _need(t, "range")
            return f"{self.type_of(_need(t, 'baseType'))} ({rng.get('lower')}..{rng.get('upper')})"
        if t.tag == "enum":
            return _enum(t, self)
        if t.tag == "pointer":
            return f"REF_TO {self.type_of(_need(t, 'baseType'))}"
        if re.fullmatch(r"[A-Z][A-Z0-9_]*", t.tag):
            return t.tag  # an elementary type: <INT/>, <TIME/>, <DT/>, …
        raise Unread(
            Code.XML_FILE,
            t,
            f"a <{t.tag}> type: st reads elementary, string, derived, array, "
            "subrange, enumerated and pointer types here (a structure only as a data type)",
        )

    def value_of(self, holder: Element, typ: Element | None) -> str:
        """An `<initialValue>` (or an array's or structure's `<value>`) as ST; `typ` is the
        `<type>` it initialises, if known (a string's text is quoted when the XML left it bare)."""
        v = holder.first()
        if v is None:
            raise Unread(Code.XML_FILE, holder, f"<{holder.tag}> holds no value")
        if v.tag == "simpleValue":
            return _quoted(v.get("value"), typ)
        if v.tag == "arrayValue":
            base = None
            if typ is not None and typ.first() is not None and typ.first().tag == "array":  # type: ignore[union-attr]
                base = typ.first().kid("baseType")  # type: ignore[union-attr]
            parts = []
            for item in v.all("value"):
                inner = self.value_of(item, base)
                rep = item.get("repetitionValue")
                parts.append(f"{rep}({inner})" if rep else inner)
            return "[" + ", ".join(parts) + "]"
        if v.tag == "structValue":
            return "(" + ", ".join(f"{m.get('member')} := {self.value_of(m, None)}" for m in v.all("value")) + ")"
        raise Unread(Code.XML_FILE, v, f"a <{v.tag}> initial value: st reads simple, array and structure values")

    def data_type(self, dt: Element) -> None:
        name = dt.get("name")
        try:
            base = _need(dt, "baseType")
            kind = base.first()
            if kind is not None and kind.tag == "struct":
                self.at(dt, f"{name} : STRUCT")
                for var in kind.all("variable"):
                    self.variable(var)
                self.at_end(kind, "END_STRUCT;")
                return
            text = f"{name} : {self.type_of(base)}"
            init = dt.kid("initialValue")
            if init is not None:
                text += f" := {self.value_of(init, base)}"
            self.at(dt, text + ";")
        except Unread as e:
            self.unread(e)

    # ---------------------------------------------------------------- variables
    def variable(self, var: Element) -> None:
        """`name AT address : type := value;` on the `<variable>` line."""
        try:
            typ = _need(var, "type")
            text = var.get("name")
            if var.get("address"):
                text += " AT " + var.get("address")
            text += " : " + self.type_of(typ)
            init = var.kid("initialValue")
            if init is not None:
                text += " := " + self.value_of(init, typ)
            self.at(var, text + ";")
        except Unread as e:
            self.unread(e)

    def section(self, sec: Element) -> None:
        keyword = _SECTIONS[sec.tag]
        qualifiers = [q for attr, q in _QUALIFIERS if sec.get(attr) == "true"]
        self.at(sec, " ".join([keyword, *qualifiers]))
        for var in sec.all("variable"):
            self.variable(var)
        self.at_end(sec, "END_VAR")

    # ---------------------------------------------------------------- POUs
    def pou(self, pou: Element) -> None:
        name = pou.get("name")
        kind = _KINDS.get(pou.get("pouType"))
        if kind is None:
            self.problem(
                Code.XML_FILE,
                pou,
                f"POU {name} is a '{pou.get('pouType')}': st reads functions, function blocks and programs",
            )
            return
        itf = pou.kid("interface")
        header = f"{kind} {name}"
        ret = itf.kid("returnType") if itf is not None else None
        if ret is not None and kind == "FUNCTION":
            try:
                if itf is not None and itf.first() is ret:
                    self.at(ret, ": " + self.type_of(ret))
                else:
                    header += " : " + self.type_of(ret)
            except Unread as e:
                self.unread(e)
        self.at(pou, header)
        for sec in itf.kids if itf is not None else ():
            if sec.tag in _SECTIONS:
                self.section(sec)
        bodies = pou.all("body")
        transitions = pou.kid("transitions")
        named = {t.get("name").lower(): t for t in (transitions.all("transition") if transitions is not None else ())}
        langs = [b.first() for b in bodies]
        sfcs = [Sfc(self, name, lang, named) for lang in langs if lang is not None and lang.tag == "SFC"]
        actions = pou.kid("actions")
        for action in actions.all("action") if actions is not None else ():
            self.action(name, action)
        for tr in named.values():
            for sfc in sfcs:
                sfc.named_transition(tr)
        for body in bodies:
            lang = body.first()
            if lang is None:
                continue
            if lang.tag == "ST":
                self.code(lang)
            elif lang.tag == "SFC":
                next(s for s in sfcs if s.el is lang).emit()
            else:
                self.language(body, f"POU {name}", lang)
        self.at_end(pou, "END_" + kind)

    def action(self, pou_name: str, action: Element) -> None:
        """An action of a POU: ACTION name: body END_ACTION at the `<action>` element."""
        self.at(action, f"ACTION {action.get('name')}:")
        body = action.kid("body")
        lang = body.first() if body is not None else None
        if lang is not None and lang.tag == "ST":
            self.code(lang)
        elif lang is not None and body is not None:
            self.language(body, f"action {action.get('name')} of POU {pou_name}", lang)
        self.at_end(action, "END_ACTION")

    def language(self, body: Element, what: str, lang: Element) -> None:
        """A body in a language st does not read: E050 at the `<body>`."""
        if lang.tag in ("FBD", "LD", "IL"):
            self.problem(
                Code.XML_LANGUAGE,
                body,
                f"{what} is written in {lang.tag}: st reads ST and SFC bodies",
                "rewrite the body in ST (the editor can show the ST it generates), or leave this POU out",
                lang.tag,
            )
        else:
            self.problem(Code.XML_FILE, lang, f"{what} has a <{lang.tag}> body: st reads ST and SFC bodies")

    # ---------------------------------------------------------------- configurations
    def configuration(self, conf: Element) -> None:
        self.at(conf, f"CONFIGURATION {conf.get('name')}")
        for kid in conf.kids:
            if kid.tag == "resource":
                self.resource(kid)
            elif kid.tag == "globalVars":
                self.section(kid)
        self.at_end(conf, "END_CONFIGURATION")

    def resource(self, res: Element) -> None:
        self.at(res, f"RESOURCE {res.get('name')} ON PLC")
        for kid in res.kids:
            if kid.tag == "task":
                self.task(kid)
            elif kid.tag == "globalVars":
                self.section(kid)
            elif kid.tag == "pouInstance":
                self.at(kid, f"PROGRAM {kid.get('name')} : {_type_name(kid)};")
        self.at_end(res, "END_RESOURCE")

    def task(self, task: Element) -> None:
        params = []
        if task.get("single"):
            params.append(f"SINGLE := {task.get('single')}")
        if task.get("interval"):
            params.append(f"INTERVAL := {_interval(task.get('interval'))}")
        params.append(f"PRIORITY := {task.get('priority') or '0'}")
        name = task.get("name")
        self.at(task, f"TASK {name}({', '.join(params)});")
        for inst in task.all("pouInstance"):
            self.at(inst, f"PROGRAM {inst.get('name')} WITH {name} : {_type_name(inst)};")


def plcopen_source(xml: str, path: str) -> tuple[str, list[Diagnostic]]:
    """The ST of one PLCopen XML file, laid out at its lines (see the module doc), and the problems
    of reading it (E050, E051) as diagnostics of `path`."""
    reader = Reader(xml, path)
    try:
        root = parse(xml)
    except expat.ExpatError as e:
        span = Span(path, e.lineno, e.offset + 1)
        message = f"malformed XML: {expat.ErrorString(e.code)}"
        reader.diags.append(Diagnostic(Code.XML_FILE, Severity.ERROR, span, message))
        return reader.out.text(), reader.diags
    if root.tag != "project" or root.ns not in NAMESPACES:
        shown = f"{{{root.ns}}}{root.tag}" if root.ns else root.tag
        reader.problem(
            Code.XML_FILE,
            root,
            f"this XML file is not a PLCopen XML project: its root element is <{shown}>",
            'a PLCopen project (plc.xml) starts with <project xmlns="http://www.plcopen.org/xml/tc6_0201">',
        )
        return reader.out.text(), reader.diags
    try:
        reader.project(root)
    except Exception as exc:  # a reader bug must still not show the user a traceback
        if os.environ.get("ST_DEBUG"):
            raise
        message = f"internal compiler error while reading PLCopen XML: {type(exc).__name__}: {exc}"
        hint = "please report this with the file; set ST_DEBUG=1 to see the traceback"
        reader.diags.append(Diagnostic(Code.INTERNAL, Severity.ERROR, Span(path, 1, 1), message, hint))
    return reader.out.text(), reader.diags


# ---------------------------------------------------------------- helpers


def _preset(root: Element) -> str | None:
    """The dialect preset of the tool that wrote the project, if it is known."""
    header = root.kid("fileHeader")
    names = (header.get("companyName") + " " + header.get("productName")).lower() if header is not None else ""
    for word, preset in _TOOLS.items():
        if word in names:
            return preset
    if any(el.ns == XHTML and el.tag == "p" for el in root.walk()):
        return "openplc"  # Beremiz's writer (and so the OpenPLC Editor's) puts text in <xhtml:p>
    return None


def _need(el: Element, tag: str) -> Element:
    kid = el.kid(tag)
    if kid is None:
        raise Unread(Code.XML_FILE, el, f"<{el.tag}> has no <{tag}>")
    return kid


def _enum(t: Element, reader: Reader) -> str:
    values = t.kid("values")
    names = []
    for v in values.all("value") if values is not None else ():
        names.append(v.get("name") + (f" := {v.get('value')}" if v.get("value") else ""))
    base = t.kid("baseType")
    listed = "(" + ", ".join(names) + ")"
    return f"{reader.type_of(base)} {listed}" if base is not None and base.first() is not None else listed


def _quoted(value: str, typ: Element | None) -> str:
    """A string's initial value in quotes (Beremiz writes the text bare); other values as they are."""
    kind = typ.first() if typ is not None else None
    if kind is None or kind.tag not in ("string", "wstring"):
        return value
    q = "'" if kind.tag == "string" else '"'
    if len(value) >= 2 and value[0] == q and value[-1] == q:
        return value
    return q + value.replace("$", "$$").replace(q, "$" + q) + q


def _type_name(inst: Element) -> str:
    return inst.get("typeName") or inst.get("type")  # `type` in TC6 XML 1.0


def _interval(text: str) -> str:
    """A task interval as a TIME literal: T#20ms as it is, an XML duration (PT0.02S) or time of day
    (00:00:00.02, TC6 XML 1.0) converted."""
    m = _ISO_DURATION.fullmatch(text.strip()) or _CLOCK.fullmatch(text.strip())
    if m is None or not any(m.groups()):
        return text
    d, h, mi, s = m.groups() if len(m.groups()) == 4 else (None, *m.groups())
    ms = ((int(d or 0) * 24 + int(h or 0)) * 60 + int(mi or 0)) * 60000 + float(s or 0) * 1000
    return f"T#{ms:g}ms"
