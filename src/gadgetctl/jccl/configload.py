"""Loading configurations: files, includes (to any depth) and definition paths.

Includes are resolved against the including file's directory first and then the working
directory (VR Juggler tries the working directory first, which makes a configuration's
meaning depend on where it is started). Missing includes and include cycles are reported
and the rest still loads. Elements keep their file, line and column.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.envvars import expand
from gadgetctl.files import is_file
from gadgetctl.jccl.configuration import (
    _LINE_SPAN,
    ConfigElement,
    ConfigFile,
    Configuration,
    PropertyValue,
    SourceLocation,
    TagLocation,
)
from gadgetctl.jccl.definitions import Location
from gadgetctl.jccl.xmlload import (
    DEFAULT_MAX_SIZE,
    ROOT_KINDS,
    FileKind,
    XmlDocument,
    decode_text,
    has_unsaved,
    load_file,
    parse_bytes,
    xml_parser_options,
)


def _local(node) -> str | None:
    tag = node.tag
    return tag.rpartition("}")[2] if isinstance(tag, str) else None


class UnusualDocument(Exception):
    """Raised while a configuration is read during its parse when it holds what only the
    whole tree answers for (see :func:`parse_configuration`)."""


#: Tags of the document's own structure: inside <elements> they would need the whole tree
#: (the schema validates a nested <configuration>; ranks on a line count them).
_STRUCTURE_TAGS = frozenset({"configuration", "include", "definition_path", "dir", "elements"})


class ElementReader:
    """Builds :class:`ConfigElement` objects from the ``<elements>`` of one document."""

    def __init__(self, doc: XmlDocument, *, streaming: bool = False) -> None:
        self.doc = doc
        # Start tags of each name seen so far on the current line (elements are read in
        # document order, so lines only grow): on a file written on one line, the n-th
        # <device> of the line is the n-th of the document. Elements' own tags count too.
        self._line: int | None = None
        self._on_line: dict[str, int] = {}
        self.embedded = 0  # embedded elements read
        self.streaming = streaming  # raise UnusualDocument at a structure tag

    def location(self, node: etree._Element) -> SourceLocation:
        return SourceLocation(self.doc, node)

    def read(
        self,
        node: etree._Element,
        parent: ConfigElement | None = None,
        parent_property: str | None = None,
    ) -> ConfigElement:
        name = node.get("name")
        tag = node.tag  # (an element: the caller skips comments)
        local = _LOCAL_NAMES.get(tag)
        if local is None:
            local = _local_name(tag)
        if self.streaming and local in _STRUCTURE_TAGS:
            raise UnusualDocument(local)
        doc = self.doc
        line = node.sourceline
        if line is None:  # (never from libxml2; kept exact all the same)
            return self._read_unplaced(node, local, name, parent, parent_property)
        if line != self._line:
            self._line = line
            self._on_line = {}
        on_line = self._on_line
        index = on_line.get(local, 0)
        on_line[local] = index + 1
        at = line * _LINE_SPAN + index
        element = ConfigElement.read(
            local,
            "" if name is None else name,
            node.get("version"),
            doc,
            at,
            parent,
            parent_property,
        )
        properties = element.properties
        streaming = self.streaming
        read_value = PropertyValue.read
        for child in node:
            tag = child.tag
            if not isinstance(tag, str):
                continue
            prop = _LOCAL_NAMES.get(tag)
            if prop is None:
                prop = _local_name(tag)
            if streaming and prop in _STRUCTURE_TAGS:
                raise UnusualDocument(prop)
            embedded = None
            if len(child):  # rare: an embedded element, or text mixed with comments
                embedded = next((c for c in child if isinstance(c.tag, str)), None)
                text = "" if embedded is not None else "".join(child.itertext())
            else:
                text = child.text or ""
            child_line = child.sourceline
            if child_line != self._line:
                self._line = child_line
                on_line = self._on_line = {}
            index = on_line.get(prop, 0)
            on_line[prop] = index + 1
            if child_line is None:
                value = PropertyValue(text, TagLocation(doc, None, prop, index))
            else:
                child_at = child_line * _LINE_SPAN + index
                if child_at == at:
                    child_at = at  # (one int object for the tags of a line)
                value = read_value(text, doc, child_at, prop)
            if embedded is not None:
                self.embedded += 1
                value.element = self.read(embedded, element, prop)
                on_line = self._on_line
            values = properties.get(prop)
            if values is None:
                properties[prop] = [value]
            else:
                values.append(value)
        element.compact()
        return element

    def _read_unplaced(self, node, local, name, parent, parent_property) -> ConfigElement:
        """An element whose node has no line: located by its node, values by no line."""
        element = ConfigElement(
            local,
            "" if name is None else name,
            node.get("version"),
            SourceLocation(self.doc, node),
            {},
            parent,
            parent_property,
        )
        for child in node:
            if not isinstance(child.tag, str):
                continue
            prop = _local_name(child.tag)
            embedded = next((c for c in child if isinstance(c.tag, str)), None)
            text = "" if embedded is not None else "".join(child.itertext())
            value = PropertyValue(text, TagLocation(self.doc, child.sourceline, prop, 0))
            if embedded is not None:
                self.embedded += 1
                value.element = self.read(embedded, element, prop)
            element.properties.setdefault(prop, []).append(value)
        return element


#: The local name of each namespaced tag seen: one string object per name, shared by every
#: element and value (a configuration of 200,000 aliases names "alias" 200,000 times).
_LOCAL_NAMES: dict[str, str] = {}


def _local_name(tag: str) -> str:
    local = tag.rpartition("}")[2]
    if len(_LOCAL_NAMES) < 4096:
        _LOCAL_NAMES[tag] = local
    return local


def read_config_file(doc: XmlDocument, path: Path) -> ConfigFile:
    """The includes, definition directories and elements of one parsed configuration."""
    config = ConfigFile(path=path, display=doc.path)
    root = doc.root
    if root is None:
        return config
    config.name = root.get("name")
    reader = ElementReader(doc)
    streamed = doc.streamed
    for child in root:
        tag = _local(child)
        if tag == "include":
            config.includes.append((child.text or "", reader.location(child).resolved()))
        elif tag == "definition_path":
            for entry in child:
                if _local(entry) == "dir":
                    config.definition_dirs.append(
                        ((entry.text or "").strip(), reader.location(entry).resolved())
                    )
        elif tag == "elements":
            block = None
            if streamed is not None:
                block = next((b for b in streamed if b.node is child), None)
            if block is not None:
                config.elements.extend(block.elements)
                config.embedded += block.embedded
                continue
            config.elements.extend(reader.read(e) for e in child if isinstance(e.tag, str))
    config.embedded += reader.embedded
    return config


# -- reading elements while the document is parsed -------------------------------------------

#: Bytes parsed at a time: the tree holds at most about this much of the file's elements.
STREAM_CHUNK = 1 << 18

# What a file may hold for its elements to be read while it is parsed; anything else (rare)
# is parsed whole, as every other file. A DOCTYPE (entities, reported from the tree); text
# that may be stray (XML015 and SCH001 need the tree's text): text after an end tag, a
# self-closing tag, a comment, a PI or a CDATA section, or right before a start tag, comment,
# CDATA section or PI; and, inside <elements>, an xsi: attribute (the schema reads it).
_DOCTYPE = re.compile(rb"<!DOCTYPE", re.IGNORECASE)
# The text searches run on the file with its XML white space taken out (one fast pass), each
# from a literal, which re scans for quickly (one alternation starting with a character class
# tries every byte). Without white space a tag may join what follows it, so they can only
# find more than the same searches with white space allowed between the parts: a file they
# wrongly flag is parsed whole, with the same result.
_XML_SPACE = b" \t\r\n"
_STRAY_TEXT = tuple(
    re.compile(pattern)
    for pattern in (
        rb"</[^>]*>[^<]",  # text after an end tag
        rb"/>[^<]",  # after a self-closing tag
        rb"-->[^<]",  # after a comment
        rb"\?>[^<]",  # after a PI
        rb"]]>[^<]",  # after a CDATA section
        rb"<(?<=[^>]<)(?:[A-Za-z_:]|!--|!\[|\?)",  # text right before a tag
    )
)
_ELEMENTS_TAG = re.compile(rb"<(?:[\w.-]+:)?elements[ \t\r\n/>]")
_XSI = b"http://www.w3.org/2001/XMLSchema-instance"
_XSI_PREFIX = re.compile(rb"xmlns:([\w.-]+)[ \t\r\n]*=[ \t\r\n]*[\"']" + re.escape(_XSI))


def _needs_whole_tree(data: bytes) -> bool:
    if _DOCTYPE.search(data):
        return True
    packed = data.translate(None, _XML_SPACE)
    if any(pattern.search(packed) for pattern in _STRAY_TEXT):
        return True
    del packed
    elements = _ELEMENTS_TAG.search(data)
    if elements is None:
        return True  # nothing to read while parsing
    if data.find(_XSI, elements.start()) >= 0:
        return True
    for prefix in set(_XSI_PREFIX.findall(data)):
        if data.find(prefix + b":", elements.start()) < 0:
            continue  # (a fast scan for the prefix first: it is rarely used in <elements>)
        attribute = re.compile(rb"[ \t\r\n]" + re.escape(prefix) + rb":[\w.-]+[ \t\r\n]*=")
        if attribute.search(data, elements.start()):
            return True
    return False


class StreamedBlock:
    """The elements of one ``<elements>`` block, read while the file was parsed."""

    __slots__ = ("elements", "embedded", "node")

    def __init__(self, node: etree._Element) -> None:
        self.node = node
        self.elements: list[ConfigElement] = []
        self.embedded = 0


def parse_configuration(data: bytes, path: str, kind: FileKind = FileKind.UNKNOWN) -> XmlDocument:
    """:func:`parse_bytes` for a configuration file, with the same result in far less
    memory: the elements of ``<elements>`` are read as the parse goes on, a chunk at a
    time, and their nodes dropped from the tree (about a kilobyte of libxml2 nodes per
    element otherwise: 200 MB for 200,000 aliases). The document keeps the rest of the tree
    and ``streamed``. A file with anything only the whole tree answers for (see
    ``_needs_whole_tree``; a syntax error, an encoding that needs a fallback) is parsed
    whole."""
    if kind is FileKind.DEFINITION or _needs_whole_tree(data):
        return parse_bytes(data, path, kind)
    doc = XmlDocument(path=path, kind=kind)
    if decode_text(doc, data) is not None:
        return parse_bytes(data, path, kind)
    try:
        # (a file of one chunk at most is parsed whole in one call, then read: the same
        # tree and elements as a pull parse, without its cost)
        taken = _stream(doc, data) if len(data) > STREAM_CHUNK else _take_after_parse(doc, data)
        root, blocks = taken
    except (etree.XMLSyntaxError, UnusualDocument):
        return parse_bytes(data, path, kind)
    doc.root = root
    doc.streamed = blocks
    if doc.kind is FileKind.UNKNOWN:
        doc.kind = ROOT_KINDS.get(etree.QName(root).localname, FileKind.UNKNOWN)
        if doc.kind is FileKind.DEFINITION:  # (no <elements> block was taken from it)
            doc.streamed = None
    return doc


def _stream(doc: XmlDocument, data: bytes) -> tuple[etree._Element, list[StreamedBlock]]:
    parser = etree.XMLPullParser(events=("start",), tag="{*}elements", **xml_parser_options())
    reader = ElementReader(doc, streaming=True)
    blocks: list[StreamedBlock] = []

    def take(block: StreamedBlock, keep_last: bool) -> None:
        """Read the block's complete elements (all but the last one, which the parse may
        still be filling, unless the block is closed) and drop their nodes."""
        node = block.node
        count = len(node) - (1 if keep_last else 0)
        if count <= 0:
            return
        before = reader.embedded
        append = block.elements.append
        for child in node[:count]:
            if isinstance(child.tag, str):
                append(reader.read(child))
        block.embedded += reader.embedded - before
        del node[:count]

    for offset in range(0, len(data), STREAM_CHUNK):
        parser.feed(data[offset : offset + STREAM_CHUNK])
        for _event, node in parser.read_events():
            parent = node.getparent()
            if parent is not None and parent.getparent() is None:  # a child of the root
                if blocks:
                    take(blocks[-1], keep_last=False)
                blocks.append(StreamedBlock(node))
        if blocks:
            take(blocks[-1], keep_last=True)
    root = parser.close()
    if blocks:
        take(blocks[-1], keep_last=False)
    return root, blocks


def _take_after_parse(doc: XmlDocument, data: bytes) -> tuple[etree._Element, list[StreamedBlock]]:
    """What :func:`_stream` gives for a file of one chunk: the file parsed in one call, then
    the elements of each ``<elements>`` child of the root read and dropped, in document
    order."""
    root = etree.fromstring(data, etree.XMLParser(**xml_parser_options()))
    reader = ElementReader(doc, streaming=True)
    blocks: list[StreamedBlock] = []
    for node in root:
        tag = node.tag
        if not isinstance(tag, str) or tag.rpartition("}")[2] != "elements":
            continue
        block = StreamedBlock(node)
        before = reader.embedded
        block.elements = [reader.read(child) for child in node if isinstance(child.tag, str)]
        block.embedded = reader.embedded - before
        del node[:]
        blocks.append(block)
    return root, blocks


class ConfigurationLoader:
    def __init__(
        self,
        *,
        environ: Mapping[str, str] | None = None,
        max_size: int = DEFAULT_MAX_SIZE,
        documents: dict[Path, XmlDocument] | None = None,
        files: dict[Path, ConfigFile] | None = None,
        parsed: Mapping[Path, XmlDocument] | None = None,
    ) -> None:
        self.environ = os.environ if environ is None else environ
        self.max_size = max_size
        # Documents a caller parsed already (a check before running), by resolved path:
        # taken instead of reading the file again, as if loaded here (diagnostics included).
        self.parsed = dict(parsed or {})
        # Already loaded documents and read files, by resolved path; shared (not copied) so
        # that several configurations of one run read each file once.
        self.documents = {} if documents is None else documents
        self.files = {} if files is None else files
        self.configuration = Configuration()
        self._loaded: set[Path] = set()

    def load(self, paths: Iterable[Path]) -> Configuration:
        for path in paths:
            resolved = path if path in self.documents else path.resolve()
            if resolved not in self.configuration.roots:
                self.configuration.roots.append(resolved)
            self._load(path, resolved, stack=[], display=None)
        return self.configuration

    def _document(self, resolved: Path, display: str) -> XmlDocument:
        doc = self.documents.get(resolved)
        if doc is None:
            doc = self.parsed.pop(resolved, None) or load_file(
                resolved, max_size=self.max_size, display=display, parse=parse_configuration
            )
            self.documents[resolved] = doc
            self.configuration.diagnostics.extend(
                # the problems of reading the file (XML001-XML005), not those of checks a
                # caller ran on a document it parsed (XML010 and on)
                d
                for d in doc.diagnostics
                if d.code.startswith("XML00")
            )
        return doc

    def _load(self, path: Path, resolved: Path, stack: list[Path], display: str | None) -> None:
        """Load ``path`` and its includes depth first, each file's elements after those of
        the files it includes. Iterative: an include chain of any length needs no deeper
        Python stack (``stack`` holds the including files, for cycle reports)."""
        frames: list[tuple[ConfigFile, Path, Iterator[tuple[str, Location]]]] = []
        on_stack: set[Path] = set(stack)

        def enter(target: Path, key: Path, shown: str | None) -> None:
            if key in self._loaded:
                return
            self._loaded.add(key)
            config = self.files.get(key)
            if config is None:
                doc = self._document(key, shown or str(target))
                config = self.files[key] = read_config_file(doc, key)
            self.configuration.files.append(config)
            frames.append((config, key, iter(config.includes)))
            on_stack.add(key)

        enter(path, resolved, display)
        while frames:
            config, current, includes = frames[-1]
            step = next(includes, None)
            if step is None:
                frames.pop()
                on_stack.discard(current)
                self.configuration.loaded.extend(config.elements)
                continue
            raw, location = step
            found = self._include_target(raw, location, current)
            if found is None:
                continue
            target, key = found
            if key in on_stack:
                ancestors = [*stack, *(f[1] for f in frames)]
                chain = " -> ".join(p.name for p in [*ancestors[ancestors.index(key) :], key])
                self.configuration.diagnostics.append(
                    Diagnostic.make(
                        "CFG002",
                        f"include cycle: {chain}",
                        location.path,
                        location.line,
                        location.column,
                        hint="VR Juggler would recurse until it crashes; remove one of these includes.",
                    )
                )
                continue
            edges = self.configuration.includes.setdefault(current, [])
            if key not in edges:
                edges.append(key)
            try:
                enter(target, key, _display(target))
            except OSError as err:
                self.configuration.diagnostics.append(
                    Diagnostic.make(
                        "CFG001",
                        f"included file {raw.strip()!r} cannot be read: {err.strerror}",
                        location.path,
                        location.line,
                        location.column,
                    )
                )

    def _include_target(
        self, raw: str, location: Location, parent: Path
    ) -> tuple[Path, Path] | None:
        """The file an ``<include>`` names and its resolved path, or None (reported)."""
        expansion = expand(raw.strip(), self.environ)
        for name in expansion.undefined:
            self.configuration.diagnostics.append(
                Diagnostic.make(
                    "CFG003",
                    f"include {raw.strip()!r} uses ${{{name}}}, which is not set",
                    location.path,
                    location.line,
                    location.column,
                )
            )
        target = self.resolve_include(expansion.text, parent.parent)
        if target is None:
            self.configuration.diagnostics.append(
                Diagnostic.make(
                    "CFG001",
                    f"included file {raw.strip()!r} not found (looked in {parent.parent} and "
                    f"the working directory)",
                    location.path,
                    location.line,
                    location.column,
                )
            )
            return None
        return target, target.resolve()

    @staticmethod
    def resolve_include(name: str, directory: Path) -> Path | None:
        if not name:
            return None
        candidate = Path(name).expanduser()
        if candidate.is_absolute():
            return candidate if _exists(candidate) else None
        for base in (directory, Path.cwd()):
            if _exists(base / candidate):
                return base / candidate
        return None


def _exists(path: Path) -> bool:
    """A file, or an editor's unsaved buffer standing for one (:func:`unsaved_texts`)."""
    return is_file(path) or has_unsaved(path)


def _display(path: Path) -> str:
    try:
        return os.path.relpath(path)
    except ValueError:
        return str(path)


def load_configuration(
    paths: Iterable[Path],
    *,
    environ: Mapping[str, str] | None = None,
    documents: dict[Path, XmlDocument] | None = None,
    files: dict[Path, ConfigFile] | None = None,
    parsed: Mapping[Path, XmlDocument] | None = None,
) -> Configuration:
    return ConfigurationLoader(
        environ=environ, documents=documents, files=files, parsed=parsed
    ).load(paths)


def require_loadable(configuration: Configuration) -> None:
    """Raise :class:`GadgetctlError` (one line, exit status 2) when a file of the
    configuration could not be loaded: not well-formed, too large, a missing or cyclic
    include. Every command that runs a configuration (config show, graph, pending,
    monitor, replay) applies this one rule; `gadgetctl validate` reports the same problems
    as findings instead."""
    from gadgetctl.diagnostics import Severity
    from gadgetctl.errors import GadgetctlError

    errors = [d for d in configuration.diagnostics if d.severity is Severity.ERROR]
    if errors:
        first = errors[0]
        more = (
            f" (and {len(errors) - 1} more {'error' if len(errors) == 2 else 'errors'}: gadgetctl validate shows them)"
            if len(errors) > 1
            else ""
        )
        raise GadgetctlError(
            f"{first.location}: cannot load the configuration: {first.message}{more}"
        )
