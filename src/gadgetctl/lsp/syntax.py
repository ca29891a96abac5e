"""A forgiving reading of a JCCL document's tags around a position, for text being typed.

lxml cannot parse a half-typed file, and completion is asked for exactly then. This scan
finds start and end tags with one regular expression (comments blanked out first), keeps
the stack of elements open at the position, and says what the position is in: a tag name
being typed, an attribute value, or the text of an element. Work is bounded by the text
before the position (and ``MAX_DEPTH`` open elements), and every expression here runs in
time linear in its input: names and runs are possessive and attributes start at a word's
start, so a hostile line (a long name with no ``>``, thousands of ``="``) cannot make a
search backtrack quadratically.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from enum import StrEnum

TAG = re.compile(
    r"<(/?)([A-Za-z_][\w.:-]*+)((?:[^<>\"'/]++|/(?!>)|\"[^\"<]*+\"|'[^'<]*+')*+)(/?)>",
)
ATTRIBUTE = re.compile(r"(?<![\w.:-])([\w.:-]++)\s*+=\s*+(?:\"([^\"]*+)\"|'([^']*+)')")
COMMENT = re.compile(r"<!--.*?(?:-->|\Z)|<!\[CDATA\[.*?(?:\]\]>|\Z)|<\?.*?(?:\?>|\Z)", re.S)
#: An attribute whose value is being typed: what is left of a start tag after its
#: complete attributes (matched at that point only).
_OPEN_VALUE = re.compile(r"\s*+([\w.:-]++)\s*+=\s*+([\"'])([^\"']*+)\Z")
_NEXT_ATTRIBUTE = re.compile(r"\s*+[\w.:-]++\s*+=\s*+(?:\"[^\"]*+\"|'[^']*+')")
_NAME_SO_FAR = re.compile(r"[\w.:-]*+\Z")
MAX_DEPTH = 256
#: How much of a start tag before the position is read (a longer one is not being typed).
MAX_TAG = 4096


class Where(StrEnum):
    TAG = "tag"  # typing a start tag's name: <prefix|
    CLOSING = "closing"  # </prefix|
    ATTRIBUTE = "attribute"  # inside a start tag, between attributes
    VALUE = "value"  # inside an attribute value: name="prefix|
    TEXT = "text"  # in an element's text


@dataclass
class Tag:
    name: str  # local name (any prefix dropped)
    start: int  # offset of "<"
    end: int  # offset just after ">"
    attributes: dict[str, str] = field(default_factory=dict)

    def get(self, attribute: str) -> str | None:
        return self.attributes.get(attribute)


@dataclass
class Context:
    where: Where
    stack: list[Tag]  # elements open at the position, outermost first
    prefix: str  # what is typed of the word being completed
    start: int  # where that word starts (the completion replaces start..position)
    attribute: str | None = None  # VALUE: which attribute
    tag: Tag | None = None  # ATTRIBUTE, VALUE: the tag being written

    @property
    def parent(self) -> Tag | None:
        return self.stack[-1] if self.stack else None

    def names(self) -> list[str]:
        return [t.name for t in self.stack]


def local(name: str) -> str:
    return name.rpartition(":")[2]


def attributes(text: str) -> dict[str, str]:
    return {
        m.group(1): m.group(2) if m.group(2) is not None else m.group(3)
        for m in ATTRIBUTE.finditer(text)
    }


def blank_comments(text: str) -> str:
    """``text`` with comments, CDATA and processing instructions replaced by spaces (offsets kept)."""
    if "<!" not in text and "<?" not in text:
        return text
    return COMMENT.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def open_stack(text: str, end: int) -> list[Tag]:
    """The elements open at ``end`` (an end tag closes up to the nearest open tag of its name)."""
    stack: list[Tag] = []
    for match in TAG.finditer(text, 0, end):
        closing, name, attrs, empty = match.groups()
        name = local(name)
        if closing:
            for i in range(len(stack) - 1, -1, -1):
                if stack[i].name == name:
                    del stack[i:]
                    break
        elif not empty and len(stack) < MAX_DEPTH:
            stack.append(Tag(name, match.start(), match.end(), attributes(attrs)))
    return stack


def context_at(text: str, offset: int) -> Context:
    offset = max(0, min(offset, len(text)))
    clean = blank_comments(text[:offset])
    lt = clean.rfind("<")
    gt = clean.rfind(">")
    if lt > gt and offset - lt <= MAX_TAG:
        segment = clean[lt + 1 :]
        stack = open_stack(clean, lt)
        if segment.startswith("/"):
            return Context(Where.CLOSING, stack, segment[1:], lt + 2)
        if _NAME_SO_FAR.fullmatch(segment):
            return Context(Where.TAG, stack, segment, lt + 1)
        name = re.match(r"[\w.:-]*+", segment).group(0)
        tag = Tag(local(name), lt, offset, attributes(segment))
        rest = len(name)
        while (complete := _NEXT_ATTRIBUTE.match(segment, rest)) is not None:
            rest = complete.end()
        value = _OPEN_VALUE.match(segment, rest)
        if value is not None:
            typed = value.group(3)
            return Context(Where.VALUE, stack, typed, offset - len(typed), value.group(1), tag)
        word = len(segment)
        while word > 0 and (segment[word - 1].isalnum() or segment[word - 1] in "_.:-"):
            word -= 1
        typed = segment[word:]
        return Context(Where.ATTRIBUTE, stack, typed, offset - len(typed), tag=tag)
    if lt > gt:  # a start tag longer than anyone types: nothing to complete in it
        return Context(Where.ATTRIBUTE, open_stack(clean, lt), "", offset)
    stack = open_stack(clean, offset)
    typed = clean[gt + 1 :] if gt >= 0 else clean
    stripped = typed.lstrip()
    return Context(Where.TEXT, stack, stripped, offset - len(stripped))


def text_range(text: str, tag_end: int) -> tuple[int, int]:
    """The trimmed text after a start tag ending at ``tag_end``, up to the next ``<``."""
    stop = text.find("<", tag_end)
    stop = len(text) if stop < 0 else stop
    start = tag_end
    while start < stop and text[start].isspace():
        start += 1
    while stop > start and text[stop - 1].isspace():
        stop -= 1
    return start, stop


def tag_at(text: str, offset: int) -> tuple[str, int, int] | None:
    """The name of the start or end tag whose name holds ``offset``, with its range."""
    lt = text.rfind("<", max(0, offset - 512), offset + 1)
    if lt < 0:
        return None
    match = re.compile(r"</?([A-Za-z_][\w.:-]*)").match(text, lt)
    if match is None or not (match.start(1) <= offset <= match.end(1)):
        return None
    return local(match.group(1)), match.start(1), match.end(1)


def end_tag(text: str, start: int, name: str) -> tuple[int, int] | None:
    """The name range of the end tag closing the start tag at ``start`` (None if empty)."""
    open_end = text.find(">", start)
    if open_end < 0 or text[open_end - 1] == "/":
        return None
    depth = 0
    for match in TAG.finditer(text, open_end + 1):
        closing, tag, _, empty = match.groups()
        if local(tag) != name or empty:
            continue
        if not closing:
            depth += 1
        elif depth == 0:
            return match.end(2) - len(name), match.end(2)
        else:
            depth -= 1
    return None
