"""The SFC networks of a PLCopen XML project as st's textual SFC (plcopen_xml.py reads the rest).

A graphical SFC is a set of elements joined by `connectionPointIn/connection refLocalId`; each
transition's source and target steps are found through the divergences and convergences between
(a jump is its target step). Each element becomes text on its own line:

    <step>             INITIAL_STEP s: a(N); b(D, T#2s); END_STEP   (the associations of the
                       action blocks joined to the step)
    <transition>       TRANSITION FROM (s1, s2) TO s3 := <its inline ST condition> ; END_TRANSITION
    <action> inline    ACTION _inline_<block>_<k>: <its ST> END_ACTION   (at the action block)

A transition whose condition names a transition of the POU (`<transitions>`, ST text `:= expr;`,
`T := expr;` or `expr`) is written where that transition's body stands; a second use of the same
transition is a copy of its condition, on one line. Macro steps and graphical conditions are not
read.
"""

from __future__ import annotations

import re
from collections import defaultdict
from typing import TYPE_CHECKING

from ..diagnostics import Code
from .xmltree import Element, Unread

if TYPE_CHECKING:
    from .plcopen_xml import Reader

_JOINS = ("selectionDivergence", "selectionConvergence", "simultaneousDivergence", "simultaneousConvergence")


def _refs(el: Element) -> list[str]:
    """The localIds an element is joined to above it."""
    return [c.get("refLocalId") for cp in el.all("connectionPointIn") for c in cp.all("connection")]


def _steps(names: list[str]) -> str:
    unique = list(dict.fromkeys(names))
    return unique[0] if len(unique) == 1 else "(" + ", ".join(unique) + ")"


def _expression(lang: Element, name: str) -> str:
    """The condition of a named transition's ST text (`:= e;`, `T := e;` or `e`), on one line."""
    text = "".join(t for _, _, t in lang.code()).strip()
    text = re.sub(r"^(?:" + re.escape(name) + r"\s*)?:=", "", text, flags=re.I).strip()
    return " ".join(text.removesuffix(";").split())


class Sfc:
    """One `<SFC>` body of a POU."""

    def __init__(self, reader: Reader, pou: str, el: Element, transitions: dict[str, Element]):
        self.reader, self.pou, self.el = reader, pou, el
        self.transitions = transitions  # the POU's named transitions: lower name → <transition>
        self.nodes = {k.get("localId"): k for k in el.kids if k.get("localId")}
        self.below: dict[str, list[Element]] = defaultdict(list)
        for k in el.kids:
            for ref in _refs(k):
                self.below[ref].append(k)
        self.named: dict[str, str] = {}  # transition name (lower) → FROM … TO … of its first use
        self.copies: dict[int, str] = {}  # id of a later use → the name (lower) it uses
        self.inline: dict[int, str] = {}  # id of an inline <action> → its ACTION's name
        for k in el.all("transition"):
            cond = k.kid("condition")
            use = cond.first() if cond is not None else None
            if use is None or use.tag != "reference":
                continue
            key = use.get("name").lower()
            try:
                if key not in transitions:
                    raise Unread(Code.XML_FILE, k, f"transition {use.get('name')} is not a transition of {pou}")
                if key in self.named:
                    self.copies[id(k)] = key
                else:
                    self.named[key] = self.arc(k)
            except Unread as e:
                reader.unread(e)

    # ---------------------------------------------------------------- the graph
    def up(self, ref: str, at: Element, seen: set[str]) -> list[str]:
        """The steps above the element `ref` (through divergences and convergences)."""
        el = self.nodes.get(ref)
        if el is None:
            raise Unread(
                Code.XML_FILE, at, f"an SFC element of {self.pou} is joined to element {ref}, which is not there"
            )
        if ref in seen:
            return []
        seen.add(ref)
        if el.tag == "step":
            return [el.get("name")]
        if el.tag in _JOINS:
            return [n for r in _refs(el) for n in self.up(r, el, seen)]
        raise Unread(
            Code.XML_FILE,
            el,
            f"an SFC transition of {self.pou} follows a <{el.tag}>: st reads steps, divergences and convergences there",
        )

    def down(self, ref: str, seen: set[str]) -> list[str]:
        """The steps below the element `ref` (a jump: its target)."""
        out = []
        for el in self.below.get(ref, ()):
            if el.tag == "step":
                out.append(el.get("name"))
            elif el.tag == "jumpStep":
                out.append(el.get("targetName"))
            elif el.tag in _JOINS and el.get("localId") not in seen:
                seen.add(el.get("localId"))
                out += self.down(el.get("localId"), seen)
            elif el.tag == "macroStep":
                raise Unread(Code.XML_FILE, el, f"an SFC macro step in {self.pou}: st does not read macro steps")
        return out

    def arc(self, tr: Element) -> str:
        """`FROM sources TO targets` of a transition."""
        sources = [n for r in _refs(tr) for n in self.up(r, tr, set())]
        targets = self.down(tr.get("localId"), set())
        if not sources or not targets:
            raise Unread(
                Code.XML_FILE,
                tr,
                f"an SFC transition of {self.pou} is not joined to a step {'above' if not sources else 'below'} it",
            )
        prio = f" (PRIORITY := {tr.get('priority')})" if tr.get("priority") else ""
        return f"{prio} FROM {_steps(sources)} TO {_steps(targets)}"

    # ---------------------------------------------------------------- the text
    def emit(self) -> None:
        blocks: dict[str, list[Element]] = defaultdict(list)
        for k in self.el.all("actionBlock"):
            for ref in _refs(k):
                blocks[ref].append(k)
            for i, act in enumerate(k.all("action"), 1):
                if act.kid("inline") is not None:
                    self.inline[id(act)] = f"_inline_{k.get('localId')}_{i}"
        for k in self.el.kids:
            try:
                if k.tag == "step":
                    self.step(k, blocks.get(k.get("localId"), []))
                elif k.tag == "transition":
                    self.transition(k)
                elif k.tag == "actionBlock":
                    self.inline_actions(k)
                elif k.tag == "macroStep":
                    raise Unread(Code.XML_FILE, k, f"an SFC macro step in {self.pou}: st does not read macro steps")
            except Unread as e:
                self.reader.unread(e)

    def step(self, el: Element, blocks: list[Element]) -> None:
        text = ("INITIAL_STEP" if el.get("initialStep") == "true" else "STEP") + f" {el.get('name')}:"
        for block in blocks:
            for act in block.all("action"):
                ref = act.kid("reference")
                name = self.inline.get(id(act)) or (ref.get("name") if ref is not None else "")
                if not name:
                    raise Unread(Code.XML_FILE, act, f"an action of step {el.get('name')} names no action")
                args = act.get("qualifier") or "N"
                if act.get("duration"):
                    args += ", " + act.get("duration")
                text += f" {name}({args});"
        self.reader.at(el, text + " END_STEP")

    def transition(self, el: Element) -> None:
        cond = el.kid("condition")
        kind = cond.first() if cond is not None else None
        if kind is None:
            raise Unread(Code.XML_FILE, el, f"an SFC transition of {self.pou} has no condition")
        if kind.tag == "reference":  # the first use is written with the named transition's body
            key = self.copies.get(id(el))
            body = self.transitions[key].kid("body") if key is not None else None
            lang = body.first() if body is not None else None
            if key is not None and lang is not None and lang.tag == "ST":  # a later use: its text copied
                self.reader.at(el, f"TRANSITION{self.arc(el)} := {_expression(lang, key)} ; END_TRANSITION")
            return
        lang = kind.first() if kind.tag == "inline" else None
        if lang is None or lang.tag != "ST":
            what = lang.tag if lang is not None else "a graphical network"
            raise Unread(
                Code.XML_LANGUAGE,
                el,
                f"the condition of an SFC transition of {self.pou} is {what}: st reads ST conditions",
                lang.tag if lang is not None else "FBD",
            )
        self.reader.at(el, f"TRANSITION{self.arc(el)} :=")
        code = lang.code()
        last = max((i for i, c in enumerate(code) if c[2].strip()), default=-1)
        if last >= 0 and code[last][2].rstrip().endswith(";"):  # `a AND b;`: the ';' is written below
            line, col, text = code[last]
            code[last] = (line, col, text.rstrip()[:-1])
        for line, col, text in code:
            self.reader.out.place(line, col, text, code=True)
        self.reader.at_end(el, "; END_TRANSITION")

    def named_transition(self, tr: Element) -> None:
        """A transition of the POU's `<transitions>`, written where its body stands if this SFC uses it."""
        arc = self.named.get(tr.get("name").lower())
        if arc is None:
            return
        body = tr.kid("body")
        lang = body.first() if body is not None else None
        if lang is None or body is None or lang.tag != "ST":
            if lang is not None and body is not None:
                self.reader.language(body, f"transition {tr.get('name')} of POU {self.pou}", lang)
            return
        self.reader.at(tr, f"TRANSITION {tr.get('name')}{arc}")
        code = lang.code()
        first = next((i for i, c in enumerate(code) if c[2].strip()), None)
        text = code[first][2].lstrip() if first is not None else ""
        name = tr.get("name")
        if text[: len(name)].lower() == name.lower() and text[len(name) :].lstrip().startswith(":="):
            line, col, raw = code[first]  # type: ignore[index]  # `T := expr;`: the name blanked
            cut = raw.index(text) + len(name)
            code[first] = (line, col, " " * cut + raw[cut:])  # type: ignore[index]
        elif not text.startswith(":="):
            self.reader.at(tr, ":=")  # a bare expression
        for line, col, piece in code:
            self.reader.out.place(line, col, piece, code=True)
        if not "".join(c[2] for c in code).rstrip().endswith(";"):
            self.reader.at_end(tr, ";")
        self.reader.at_end(tr, "END_TRANSITION")

    def inline_actions(self, block: Element) -> None:
        """The inline ST actions of an action block, each an ACTION at its `<action>` element."""
        for act in block.all("action"):
            name = self.inline.get(id(act))
            if name is None:
                continue
            self.reader.at(act, f"ACTION {name}:")
            inline = act.kid("inline")
            lang = inline.first() if inline is not None else None
            if lang is not None and lang.tag == "ST":
                self.reader.code(lang)
            elif lang is not None and inline is not None:
                self.reader.language(inline, f"an action of POU {self.pou}", lang)
            self.reader.at_end(act, "END_ACTION")
