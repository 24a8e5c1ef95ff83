"""An XML file as a tree of elements that know where they stand: expat reports the line and column
of every start tag, end tag and piece of character data, so text taken from the tree can be put
back at its place (layout.py)."""

from __future__ import annotations

from dataclasses import dataclass, field
from xml.parsers import expat

_NOT_CODE = ("documentation", "addData")  # PLCopen's comments and tool data, never a type or a body


@dataclass(eq=False)
class Element:
    """One XML element: its local name, attributes, 0-based position of its start tag and of its end
    (the `</`, or just after an empty element), children and character data at their positions."""

    tag: str
    ns: str
    attrs: dict[str, str]
    line: int
    col: int
    end_line: int = 0
    end_col: int = 0
    kids: list[Element] = field(default_factory=list)
    texts: list[tuple[int, int, str]] = field(default_factory=list)

    def get(self, name: str, default: str = "") -> str:
        return self.attrs.get(name, default)

    def kid(self, tag: str) -> Element | None:
        return next((k for k in self.kids if k.tag == tag), None)

    def all(self, tag: str) -> list[Element]:
        return [k for k in self.kids if k.tag == tag]

    def first(self) -> Element | None:
        """The first child that is not documentation or tool data (a type's, a value's, a body's)."""
        return next((k for k in self.kids if k.tag not in _NOT_CODE), None)

    def code(self) -> list[tuple[int, int, str]]:
        """The character data of this element and all inside it, in document order."""
        out = list(self.texts)
        for k in self.kids:
            out += k.code()
        return sorted(out, key=lambda t: (t[0], t[1]))

    def walk(self):
        yield self
        for k in self.kids:
            yield from k.walk()


def parse(xml: str) -> Element:
    """The element tree with positions (expat: every event knows its line and column); raises
    expat.ExpatError for malformed XML."""
    parser = expat.ParserCreate(encoding="utf-8", namespace_separator=" ")
    parser.buffer_text = False
    stack: list[Element] = []
    roots: list[Element] = []

    def start(name: str, attrs: dict[str, str]) -> None:
        ns, _, tag = name.rpartition(" ")
        el = Element(tag, ns, attrs, parser.CurrentLineNumber - 1, parser.CurrentColumnNumber)
        (stack[-1].kids if stack else roots).append(el)
        stack.append(el)

    def end(_name: str) -> None:
        el = stack.pop()
        el.end_line, el.end_col = parser.CurrentLineNumber - 1, parser.CurrentColumnNumber

    def chars(data: str) -> None:
        if stack:
            stack[-1].texts.append((parser.CurrentLineNumber - 1, parser.CurrentColumnNumber, data))

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.Parse(xml.encode("utf-8"), True)
    return roots[0]


class Unread(Exception):
    """A part of the file its reader does not turn into text: (code, element, message, and the
    language it is written in when that is why)."""

    def __init__(self, code: str, el: Element, message: str, language: str = ""):
        super().__init__(message)
        self.code, self.el, self.message, self.language = code, el, message, language
