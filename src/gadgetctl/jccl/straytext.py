"""Stray text: non-whitespace text directly inside an element that holds child elements.

JCCL elements hold either text (a property value) or child elements, never both; the
schemas allow any content inside ``<elements>`` and embedded elements, and VR Juggler
ignores such text without a word (a generator that wrote a count between two elements,
a value typed one line too low). The parsed tree tells whether a file has any; only then
is the source scanned again with positions (expat reports where each run of text starts,
which lxml does not keep).
"""

from __future__ import annotations

from xml.parsers import expat

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.xmlload import XmlDocument


def _local(tag: str) -> str:
    return tag.rpartition("}")[2]


#: The elements holding elements and text that is not XML white space (a superset: Python's
#: strip() also removes other white space), compiled once rather than for every document.
_HOLDING_TEXT = etree.XPath("descendant-or-self::*[*][text()[normalize-space()]]")


def has_stray_text(root: etree._Element) -> bool:
    # XPath finds the candidates; each is then confirmed.
    for element in _HOLDING_TEXT(root):
        children = [c for c in element if isinstance(c.tag, str)]
        if not children:
            continue
        if (element.text or "").strip() or any((c.tail or "").strip() for c in element):
            return True
    return False


class _Run:
    """A run of text: where it starts and what it holds."""

    __slots__ = ("column", "line", "text")

    def __init__(self, line: int, column: int, text: str) -> None:
        self.line = line
        self.column = column  # 0-based, as expat gives it
        self.text = text


class _Open:
    """An element whose end is still to come."""

    __slots__ = ("has_children", "name", "runs")

    def __init__(self, name: str) -> None:
        self.name = name
        self.has_children = False
        self.runs: list[_Run] | None = None


class _Scanner:
    """Collects, per element, the runs of text between markup; reports the non-blank runs
    of elements that turned out to hold child elements."""

    def __init__(self) -> None:
        self.stack: list[_Open] = []
        self.found: list[tuple[int, int, str, str]] = []  # line, column (1-based), element, text
        self.current: _Run | None = None
        self.parser = expat.ParserCreate(namespace_separator="}")
        self.parser.StartElementHandler = self.start
        self.parser.EndElementHandler = self.end
        self.parser.CharacterDataHandler = self.data
        for name in (
            "CommentHandler",
            "ProcessingInstructionHandler",
            "StartCdataSectionHandler",
            "EndCdataSectionHandler",
        ):
            setattr(self.parser, name, self.markup)
        # Never load or expand anything: the file has already been parsed without a DTD.
        self.parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)

    def markup(self, *_args) -> None:
        self.current = None

    def start(self, name: str, _attrs) -> None:
        self.current = None
        if self.stack:
            self.stack[-1].has_children = True
        self.stack.append(_Open(_local(name)))

    def end(self, _name: str) -> None:
        self.current = None
        closed = self.stack.pop()
        if closed.has_children and closed.runs:
            for run in closed.runs:
                stripped = run.text.strip()
                if not stripped:
                    continue
                lead = run.text[: len(run.text) - len(run.text.lstrip())]
                line = run.line + lead.count("\n")
                column = (
                    len(lead) - lead.rfind("\n") if "\n" in lead else run.column + len(lead) + 1
                )
                self.found.append((line, column, closed.name, stripped))

    def data(self, text: str) -> None:
        if not self.stack:
            return
        if self.current is None:
            top = self.stack[-1]
            self.current = _Run(self.parser.CurrentLineNumber, self.parser.CurrentColumnNumber, "")
            if top.runs is None:
                top.runs = []
            top.runs.append(self.current)
        self.current.text += text


def stray_text(doc: XmlDocument) -> list[Diagnostic]:
    """XML015 for each run of non-whitespace text directly inside an element with child
    elements, at the run's first non-blank character."""
    if doc.root is None or doc.streamed is not None:
        return []  # (a configuration read as it was parsed holds no text that may be stray)
    if not has_stray_text(doc.root):
        return []
    scanner = _Scanner()
    try:
        scanner.parser.Parse(doc.text, True)
    except expat.ExpatError:
        return []  # lxml read it; whatever expat dislikes is reported elsewhere
    found = []
    for line, column, element, text in scanner.found:
        shown = text if len(text) <= 40 else text[:37] + "..."
        found.append(
            Diagnostic.make(
                "XML015",
                f"stray text {shown!r} inside <{element}>, between its child elements; "
                "VR Juggler ignores it",
                doc.path,
                line,
                column,
                hint="Remove it, or move it into the property it was meant for.",
            )
        )
    return found
