"""Byte spans of the elements of an XML file, for edits that leave everything else as it was.

lxml records only line numbers, so the file is scanned once more with expat, which reports
the byte offset of every start and end tag. Element *i* in document order here is element
*i* of ``root.iter()`` in lxml (both count elements only, in the same order).
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.parsers import expat


@dataclass(frozen=True, slots=True)
class Span:
    start: int  # the "<" of the start tag
    start_end: int  # just after the start tag's ">"
    end: int  # just after the end tag's ">" (== start_end for <empty/> tags)

    @property
    def empty(self) -> bool:
        return self.start_end == self.end


def tag_end(data: bytes, start: int) -> int:
    """Offset just after the ``>`` closing the tag that starts at ``start``."""
    quote = 0
    for i in range(start + 1, len(data)):
        byte = data[i]
        if quote:
            if byte == quote:
                quote = 0
        elif byte in (0x22, 0x27):  # " '
            quote = byte
        elif byte == 0x3E:  # >
            return i + 1
    raise ValueError("unterminated tag")


def element_spans(data: bytes) -> list[Span]:
    """Spans of every element in document order; raises ``ValueError`` if expat refuses the file.

    A file whose bytes do not match its declared encoding (reported elsewhere) is scanned as
    Latin-1, which accepts any byte and leaves the offsets unchanged."""
    try:
        return _spans(data, None)
    except ValueError:
        return _spans(data, "ISO-8859-1")


def _spans(data: bytes, encoding: str | None) -> list[Span]:
    parser = expat.ParserCreate(encoding)
    starts: list[tuple[int, int]] = []  # (start, start_end) in document order
    ends: dict[int, int] = {}
    stack: list[int] = []

    def on_start(name, attrs) -> None:
        start = parser.CurrentByteIndex
        stack.append(len(starts))
        starts.append((start, tag_end(data, start)))

    def on_end(name) -> None:
        index = stack.pop()
        start_end = starts[index][1]
        if data[start_end - 2 : start_end] == b"/>":
            ends[index] = start_end
        else:
            ends[index] = tag_end(data, parser.CurrentByteIndex)

    parser.StartElementHandler = on_start
    parser.EndElementHandler = on_end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as err:
        raise ValueError(str(err)) from None
    return [Span(s, e, ends[i]) for i, (s, e) in enumerate(starts)]


def indentation_before(data: bytes, start: int) -> bytes:
    """The spaces and tabs between the last newline before ``start`` and ``start``."""
    line_start = data.rfind(b"\n", 0, start) + 1
    prefix = data[line_start:start]
    return prefix if not prefix.strip() else b""
