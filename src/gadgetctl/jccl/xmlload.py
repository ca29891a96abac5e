"""Safe, bounded loading of JCCL XML files.

Never touches the network and never expands entities: no DTD is loaded, entity
references stay unexpanded (and are reported), nesting depth is bounded by libxml2's
default limit, and files above a size limit are not read at all. Every problem becomes
a :class:`~gadgetctl.diagnostics.Diagnostic` with a line and column.
"""

from __future__ import annotations

import codecs
import os
import re
from array import array
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from enum import StrEnum
from itertools import accumulate, count, repeat
from operator import add
from pathlib import Path

from lxml import etree

from gadgetctl.boundedread import (
    DEFAULT_MAX_SIZE,
    FileTooLarge,
    NotRegularFile,
    read_limited,
    too_large_message,
)
from gadgetctl.diagnostics import Diagnostic

_DECLARED_ENCODING = re.compile(rb"^<\?xml[^>]*?encoding\s*=\s*[\"']([A-Za-z][A-Za-z0-9._-]*)[\"']")
_DOCTYPE = re.compile(rb"<!DOCTYPE", re.IGNORECASE)
_BOMS = (
    (codecs.BOM_UTF8, "utf-8"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
)


class FileKind(StrEnum):
    CONFIGURATION = "configuration"
    DEFINITION = "definition"
    UNKNOWN = "unknown"


EXTENSION_KINDS = {".jconf": FileKind.CONFIGURATION, ".jdef": FileKind.DEFINITION}
ROOT_KINDS = {"configuration": FileKind.CONFIGURATION, "definition": FileKind.DEFINITION}


def _parser(encoding: str | None = None, recover: bool = False) -> etree.XMLParser:
    return etree.XMLParser(encoding=encoding, recover=recover, **xml_parser_options())


#: What str.splitlines() splits at.
_LINE_BREAK = re.compile(r"\r\n|[\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029]")
#: Line breaks other than \n (a text without them is indexed by splitting); the ASCII ones
#: first, all that an ASCII text can hold.
_OTHER_BREAKS = ("\r", "\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029")
#: Characters split at a time when indexing \n line breaks (bounds the pieces held at once).
_SPLIT_CHUNK = 1 << 20


def _line_breaks(text: str) -> array:
    """Start and end of every line break of ``text``, one after the other."""
    others = _OTHER_BREAKS[:6] if text.isascii() else _OTHER_BREAKS
    if any(other in text for other in others):  # (each a fast scan for one character)
        return array("q", (i for m in _LINE_BREAK.finditer(text) for i in m.span()))
    breaks = array("q")
    for start in range(0, len(text), _SPLIT_CHUNK):
        pieces = text[start : start + _SPLIT_CHUNK].split("\n")
        # the k-th \n of the chunk follows k + 1 pieces and k earlier line breaks
        ends = array("q", map(add, accumulate(map(len, pieces[:-1])), count(start)))
        pair = array("q", bytes(16 * len(ends)))
        pair[0::2] = ends
        pair[1::2] = array("q", map(add, ends, repeat(1)))
        breaks.extend(pair)
    return breaks


class SourceLines:
    """The lines of a text as ``text.splitlines()`` gives them, each cut out when asked
    for: an index of line breaks (8 bytes a line) instead of a string per line."""

    __slots__ = ("_breaks", "_count", "_text")

    def __init__(self, text: str) -> None:
        self._text = text
        self._breaks = breaks = _line_breaks(text)  # start and end of every line break, in turn
        count = len(breaks) // 2
        ends_with_break = count and breaks[-1] == len(text)
        self._count = count if ends_with_break or not text else count + 1

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, index: int) -> str:
        if index < 0:
            index += self._count
        if not 0 <= index < self._count:
            raise IndexError("line index out of range")
        breaks = self._breaks
        start = breaks[2 * index - 1] if index else 0
        end = breaks[2 * index] if 2 * index < len(breaks) else len(self._text)
        return self._text[start:end]


@dataclass
class XmlDocument:
    """A parsed file, or what could be learnt of one that did not parse."""

    path: str
    kind: FileKind
    root: etree._Element | None = None
    text: str = ""
    diagnostics: list[Diagnostic] = field(default_factory=list)
    _lines: SourceLines | None = field(default=None, repr=False)
    _tag_starts: dict[tuple[int, str], list[int]] | None = field(default=None, repr=False)
    _ranks: dict[etree._Element, int] | None = field(default=None, repr=False)
    _ranked_roots: list[etree._Element] = field(default_factory=list, repr=False)
    #: Elements read while the document was parsed (see configload.parse_configuration):
    #: one (``<elements>`` node, its elements) pair per block, whose nodes the tree no
    #: longer holds. None when the tree is whole.
    streamed: list | None = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        return self.root is not None

    @property
    def lines(self) -> SourceLines:
        if self._lines is None:
            self._lines = SourceLines(self.text)
        return self._lines

    def column_of(self, element: etree._Element) -> int | None:
        """The 1-based column of ``element``'s start tag (lxml records only the line)."""
        return self.locate(element)[1]

    def locate(self, element: etree._Element) -> tuple[int | None, int | None]:
        """Line and column of the start tag's ``<``.

        libxml2 records the line on which a start tag *ends*, so a tag whose attributes span
        several lines is searched for backwards from there. Each line is searched once per
        tag name, and where several tags of a name share a line, the element's rank among
        them comes from one index of the whole tree: a file written on one line costs one
        scan, not one per element.
        """
        line_no = element.sourceline
        tag = element.tag
        if not line_no or not isinstance(tag, str) or line_no > len(self.lines):
            return line_no, None
        local = tag.rpartition("}")[2]  # (what etree.QName(element).localname gives)
        starts = self.tag_starts(line_no, local)
        if len(starts) == 1:
            return line_no, starts[0]
        if starts:
            return line_no, starts[min(self._rank_on_line(element), len(starts) - 1)]
        return self._search_back(line_no, local)

    def locate_tag(
        self, line_no: int | None, local: str, index: int
    ) -> tuple[int | None, int | None]:
        """Line and column of the ``index``-th ``<local`` start tag on ``line_no`` (the line
        libxml2 gives, where the tag ends), searching backwards for a tag that spans lines."""
        if not line_no or line_no > len(self.lines):
            return line_no, None
        starts = self.tag_starts(line_no, local)
        if starts:
            return line_no, starts[min(index, len(starts) - 1)]
        return self._search_back(line_no, local)

    def tag_starts(self, line_no: int, local: str) -> list[int]:
        """1-based columns of every ``<local`` start tag on line ``line_no`` (searched once)."""
        cache = self._tag_starts
        if cache is None:
            cache = self._tag_starts = {}
        key = (line_no, local)
        found = cache.get(key)
        if found is None:
            line = self.lines[line_no - 1]
            found = cache[key] = [start + 1 for start in tag_offsets(line, local)]
        return found

    def _search_back(self, line_no: int, local: str) -> tuple[int | None, int | None]:
        for back in range(line_no - 1, max(0, line_no - 200), -1):
            found = tag_offsets(self.lines[back - 1], local)
            if found:
                return back, found[-1] + 1
        return line_no, None

    def _rank_on_line(self, element: etree._Element) -> int:
        """How many elements of ``element``'s local name start before it on its line, in
        document order (nested ones included, as the line's tags are)."""
        if self._ranks is None:
            self._ranks = {}
        rank = self._ranks.get(element)
        if rank is None:
            self._rank_tree(element)
            rank = self._ranks.get(element, 0)
        return rank

    def _rank_tree(self, element: etree._Element) -> None:
        """Rank every element of ``element``'s tree that shares its line with another element
        of its name (only those are kept, so a usual file pins no extra lxml proxies)."""
        root = element.getroottree().getroot()
        if any(r is root for r in self._ranked_roots):
            return
        self._ranked_roots.append(root)
        counts: dict[tuple[int, str], int] = {}
        for node in root.iter(etree.Element):
            key = (node.sourceline, etree.QName(node).localname)
            counts[key] = counts.get(key, 0) + 1
        seen: dict[tuple[int, str], int] = {}
        ranks = self._ranks if self._ranks is not None else {}
        for node in root.iter(etree.Element):
            key = (node.sourceline, etree.QName(node).localname)
            if counts[key] > 1:
                ranks[node] = seen.get(key, 0)
                seen[key] = ranks[node] + 1
        self._ranks = ranks


#: What may follow a tag's name: white space, ``/``, ``>`` (or the end of the line).
_AFTER_NAME = frozenset("/>")


def tag_offsets(line: str, local: str) -> list[int]:
    """0-based offsets of the ``<`` of each start tag ``<local`` or ``<prefix:local`` on
    ``line``: what ``<(?:[\\w.-]+:)?local(?=[\\s/>]|$)`` finds, without compiling a pattern
    per tag name (most of the cost where a process locates a few tags of many names)."""
    found: list[int] = []
    size = len(line)
    width = len(local)
    if not width:
        return found
    at = line.find(local)
    while at >= 0:
        end = at + width
        if end == size or line[end] in _AFTER_NAME or line[end].isspace():
            before = at - 1
            if before >= 0:
                mark = line[before]
                if mark == "<":
                    found.append(before)
                elif mark == ":":  # a prefix (word characters, dots, dashes) back to the <
                    start = before - 1
                    while start >= 0 and (line[start].isalnum() or line[start] in "_.-"):
                        start -= 1
                    if 0 <= start < before - 1 and line[start] == "<":
                        found.append(start)
        at = line.find(local, at + 1)
    return found


def guess_kind(path: Path) -> FileKind:
    return EXTENSION_KINDS.get(path.suffix.lower(), FileKind.UNKNOWN)


def declared_encoding(data: bytes) -> str:
    for bom, name in _BOMS:
        if data.startswith(bom):
            return name
    match = _DECLARED_ENCODING.match(data)
    return match.group(1).decode("ascii") if match else "utf-8"


def text_codec(name: str) -> bool:
    """Whether ``name`` is an encoding Python decodes text with (not ``rot13``, ``base64``,
    ``zlib`` or an unknown name)."""
    try:
        info = codecs.lookup(name)
    except LookupError:
        return False
    return getattr(info, "_is_text_encoding", True) and info.name not in _NOT_FOR_XML


# Text codecs that cannot be an XML file's encoding: they do not decode ASCII as ASCII.
_NOT_FOR_XML = frozenset(
    {"punycode", "idna", "raw-unicode-escape", "unicode-escape", "undefined", "uu", "quopri"}
)


def _position_of_offset(data: bytes, offset: int, encoding: str) -> tuple[int, int]:
    """1-based line and column (in characters) of a byte offset."""
    line_start = data.rfind(b"\n", 0, offset) + 1
    line = data.count(b"\n", 0, offset) + 1
    column = len(data[line_start:offset].decode(encoding, errors="replace")) + 1
    return line, column


def decode_text(doc: XmlDocument, data: bytes) -> str | None:
    """Set ``doc.text``; None, or the encoding to parse with after a bad byte (reported)."""
    return _decode(doc, data)


def xml_parser_options() -> dict[str, bool]:
    """The options every JCCL parse uses (no network, no DTD, no entity expansion)."""
    return {
        "resolve_entities": False,
        "no_network": True,
        "load_dtd": False,
        "dtd_validation": False,
        "huge_tree": False,
        "collect_ids": False,
    }


def _decode(doc: XmlDocument, data: bytes) -> str | None:
    """Decode ``data``; on a bad byte report it and return the encoding to parse with."""
    encoding = declared_encoding(data)
    if not text_codec(encoding):
        doc.text = data.decode("latin-1")
        line, column = _encoding_position(data)
        doc.diagnostics.append(
            Diagnostic.make(
                "XML002",
                f"unknown encoding {encoding!r} declared; read as Latin-1",
                doc.path,
                line,
                column,
                hint='Declare encoding="UTF-8" and save the file as UTF-8.',
            )
        )
        return "ISO-8859-1"
    try:
        doc.text = data.decode(encoding)
        return None
    except UnicodeDecodeError as err:
        line, column = _position_of_offset(data, err.start, encoding)
        bad = data[err.start : err.start + 1].hex().upper()
        doc.diagnostics.append(
            Diagnostic.make(
                "XML002",
                f"byte 0x{bad} is not valid {encoding.upper()}; the rest of the file is read as Latin-1",
                doc.path,
                line,
                column,
                hint=f"Re-save the file as {encoding.upper()} (this byte is "
                f"{data[err.start : err.start + 1].decode('latin-1')!r} in Latin-1).",
            )
        )
        doc.text = data.decode("latin-1")
        return "ISO-8859-1"


def _encoding_position(data: bytes) -> tuple[int, int]:
    """Line and column of the encoding name in the XML declaration."""
    match = _DECLARED_ENCODING.match(data)
    return _position_of_offset(data, match.start(1), "latin-1") if match else (1, 1)


def _report_doctype(doc: XmlDocument, data: bytes) -> None:
    match = _DOCTYPE.search(data)
    if match is None:
        return
    line, column = _position_of_offset(data, match.start(), "utf-8")
    doc.diagnostics.append(
        Diagnostic.make(
            "XML003",
            "document type declaration ignored: no DTD is loaded and no entity is expanded",
            doc.path,
            line,
            column,
            hint="JCCL files need no DOCTYPE; remove it.",
        )
    )


def _doctype_end(data: bytes, start: int) -> int | None:
    """The offset just past the document type declaration starting at ``start`` (quoted
    strings, comments and the internal subset skipped), or None when it does not end."""
    i, size, quote, in_subset = start + len(b"<!DOCTYPE"), len(data), 0, False
    while i < size:
        byte = data[i]
        if quote:
            quote = 0 if byte == quote else quote
        elif byte in b"\"'":
            quote = byte
        elif data.startswith(b"<!--", i):
            end = data.find(b"-->", i + 4)
            if end < 0:
                return None
            i = end + 3
            continue
        elif byte == ord("["):
            in_subset = True
        elif byte == ord("]"):
            in_subset = False
        elif byte == ord(">") and not in_subset:
            return i + 1
        i += 1
    return None


def _without_declarations(data: bytes) -> bytes | None:
    """``data`` with a document type declaration that declares entities blanked out (spaces,
    line breaks kept, so lines and columns stay), or None when it declares none. libxml2
    expands an internal entity in an attribute value whatever the parser options; undeclared,
    every reference stays a reference (in element content) or is left out (in an attribute)."""
    match = _DOCTYPE.search(data)
    if match is None:
        return None
    end = _doctype_end(data, match.start())
    if end is None or b"<!ENTITY" not in data[match.start() : end]:
        return None
    blank = bytes(b if b in b"\r\n" else 0x20 for b in data[match.start() : end])
    return data[: match.start()] + blank + data[end:]


_UNDECLARED = re.compile(r"Entity '([^']*)' not defined")


def _parse_undeclared(doc: XmlDocument, data: bytes, encoding: str | None) -> etree._Element | None:
    """Parse ``data`` whose entity declarations were blanked out: each reference is XML003 at
    its own place; any other error is XML001 (and no tree)."""
    parser = _parser(encoding, recover=True)
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as err:
        line, column = err.position if err.position else (err.lineno, None)
        doc.diagnostics.append(
            Diagnostic.make("XML001", err.msg or "XML syntax error", doc.path, line, column)
        )
        return None
    errors = [e for e in parser.error_log if e.level >= etree.ErrorLevels.ERROR]
    other = [e for e in errors if _UNDECLARED.match(e.message) is None]
    if other or root is None:
        first = other[0] if other else None
        doc.diagnostics.append(
            Diagnostic.make(
                "XML001",
                first.message if first else "XML syntax error",
                doc.path,
                first.line if first else None,
                first.column if first else None,
            )
        )
        return None
    for error in errors:
        match = _UNDECLARED.match(error.message)
        assert match is not None
        reference = f"&{match.group(1)};"
        column = error.column - len(reference) if error.column > len(reference) else None
        doc.diagnostics.append(
            Diagnostic.make(
                "XML003",
                f"entity reference {reference} was not expanded",
                doc.path,
                error.line or None,
                column,  # libxml2 points just past the reference
                hint="Write the text itself instead of an entity reference.",
            )
        )
    return root


def _report_entities(doc: XmlDocument, root: etree._Element) -> None:
    for entity in root.iter(etree.Entity):
        parent = entity.getparent()
        line, column = doc.locate(parent) if parent is not None else (None, None)
        doc.diagnostics.append(
            Diagnostic.make(
                "XML003",
                f"entity reference {entity.text} was not expanded",
                doc.path,
                line,
                column,
                hint="Write the text itself instead of an entity reference.",
            )
        )


def parse_bytes(data: bytes, path: str, kind: FileKind = FileKind.UNKNOWN) -> XmlDocument:
    doc = XmlDocument(path=path, kind=kind)
    override = _decode(doc, data)
    _report_doctype(doc, data)
    undeclared = _without_declarations(data)
    if undeclared is not None:
        doc.root = _parse_undeclared(doc, undeclared, override)
        if doc.root is not None and doc.kind is FileKind.UNKNOWN:
            doc.kind = ROOT_KINDS.get(etree.QName(doc.root).localname, FileKind.UNKNOWN)
        return doc
    parser = _parser(override)
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as err:
        line, column = err.position if err.position else (err.lineno, None)
        message = re.sub(r", line \d+, column \d+$", "", err.msg or "XML syntax error")
        doc.diagnostics.append(
            Diagnostic.make("XML001", message, path, line or None, column or None)
        )
        return doc
    doc.root = root
    _report_entities(doc, root)
    if doc.kind is FileKind.UNKNOWN:
        doc.kind = ROOT_KINDS.get(etree.QName(root).localname, FileKind.UNKNOWN)
    return doc


#: Texts that stand for files during one check (an editor's unsaved buffers), by real path.
_UNSAVED: ContextVar[dict[str, str] | None] = ContextVar("gadgetctl_unsaved", default=None)


@contextmanager
def unsaved_texts(texts: Mapping[Path, str]) -> Iterator[None]:
    """Within the block (in this thread or task), :func:`load_file` reads each of these paths'
    text instead of the file, and :func:`has_unsaved` says it exists: the language server
    checks what the editor shows, through the same loading and checks as ``validate``."""
    token = _UNSAVED.set({os.path.realpath(path): text for path, text in texts.items()})
    try:
        yield
    finally:
        _UNSAVED.reset(token)


def unsaved_text(path: str | os.PathLike[str]) -> str | None:
    """The text standing for ``path`` in the current :func:`unsaved_texts` block, if any."""
    texts = _UNSAVED.get()
    if not texts:
        return None
    return texts.get(os.path.realpath(path))


def unsaved_within(directory: str | os.PathLike[str]) -> bool:
    """Whether a text of the current :func:`unsaved_texts` block stands for a file directly
    in ``directory``."""
    texts = _UNSAVED.get()
    if not texts:
        return False
    real = os.path.realpath(directory)
    return any(os.path.dirname(path) == real for path in texts)


def has_unsaved(path: str | os.PathLike[str]) -> bool:
    return unsaved_text(path) is not None


def unsaved_bytes(text: str) -> bytes:
    """The bytes a saved buffer would have: in the encoding its declaration names, where
    Python has that text codec (characters it cannot hold become character references)."""
    head = text[:200].encode("utf-8", errors="replace")
    encoding = declared_encoding(head)
    if encoding.lower().replace("_", "-") in ("utf-16", "utf-32") or not text_codec(encoding):
        encoding = "utf-8"
    return text.encode(encoding, errors="xmlcharrefreplace")


def load_file(
    path: Path,
    *,
    max_size: int = DEFAULT_MAX_SIZE,
    display: str | None = None,
    parse: Callable[[bytes, str, FileKind], XmlDocument] | None = None,
) -> XmlDocument:
    """Read (at most ``max_size`` bytes) and parse one file (with ``parse``, by default
    :func:`parse_bytes`). A file above the limit or not a regular file is a diagnostic;
    other I/O errors propagate as :class:`OSError`. Inside :func:`unsaved_texts` a path
    given there is read from its text instead."""
    shown = display or str(path)
    unsaved = unsaved_text(path)
    if unsaved is not None:
        data = unsaved_bytes(unsaved)
        if len(data) > max_size:
            doc = XmlDocument(path=shown, kind=guess_kind(path))
            doc.diagnostics.append(
                Diagnostic.make("XML004", too_large_message(max_size, len(data)), shown)
            )
            return doc
        return (parse or parse_bytes)(data, shown, guess_kind(path))
    try:
        data = read_limited(path, max_size)
    except (FileTooLarge, NotRegularFile) as err:
        doc = XmlDocument(path=shown, kind=guess_kind(path))
        code = "XML004" if isinstance(err, FileTooLarge) else "XML005"
        doc.diagnostics.append(Diagnostic.make(code, err.strerror, shown))
        return doc
    return (parse or parse_bytes)(data, shown, guess_kind(path))
