"""File-format upgrades: the markers of a file, not its elements.

* configurations: the settings processing instruction says ``configuration.version="3.0"``
  and the root is in the 3.0 configuration namespace (files claiming a 3.1 configuration
  format, using another namespace or none are moved there);
* definitions in format 3.0: the namespace becomes the 3.1 one, the processing instruction
  says ``definition.version="3.1"``, and ``<abstract>false</abstract>`` is inserted as the
  first child of each ``definition_version`` (what ``jdef_3.0-3.1.xsl`` does).

Changes are byte edits of the original file; see :mod:`gadgetctl.jccl.spans`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from lxml import etree

from gadgetctl.jccl import namespaces as ns
from gadgetctl.jccl.spans import Span, indentation_before

_PI = re.compile(rb"<\?" + re.escape(ns.SETTINGS_PI.encode()) + rb"\b(.*?)\?>", re.S)
_XML_DECL = re.compile(rb"^(\xef\xbb\xbf)?<\?xml[^>]*\?>[ \t]*\r?\n?")
_XMLNS = re.compile(rb"""\sxmlns\s*=\s*(["'])(.*?)\1""", re.S)
_OLD_URI = re.compile(rb"http://www\.vrjuggler\.org/jccl/xsd/[0-9.]+/configuration")


@dataclass(frozen=True, slots=True)
class Edit:
    start: int
    end: int
    text: bytes


@dataclass
class FormatChanges:
    edits: list[Edit]
    notes: list[str]


def _pi_edit(
    data: bytes, root_start: int, keys: tuple[str, ...], expected: str, newline: bytes
) -> tuple[Edit | None, str | None]:
    wanted = f'<?{ns.SETTINGS_PI} {keys[0]}="{expected}"?>'.encode()
    match = _PI.search(data, 0, root_start)
    if match is None:
        decl = _XML_DECL.match(data)
        at = decl.end() if decl else 0
        if decl and not decl.group(0).endswith(b"\n"):
            return Edit(
                at, at, newline + wanted + newline
            ), f'added the {keys[0]}="{expected}" processing instruction'
        return Edit(
            at, at, wanted + newline
        ), f'added the {keys[0]}="{expected}" processing instruction'
    body = match.group(1).decode("utf-8", "replace")
    for key in keys:
        found = re.search(re.escape(key) + r"""\s*=\s*["']([^"']*)["']""", body)
        if found:
            if key == keys[0] and found.group(1) == expected:
                return None, None
            return Edit(
                match.start(), match.end(), wanted
            ), f'file-format version {key}="{found.group(1)}" -> {keys[0]}="{expected}"'
    return Edit(
        match.start(), match.end(), wanted
    ), f'processing instruction now says {keys[0]}="{expected}"'


def _newline(data: bytes) -> bytes:
    return b"\r\n" if b"\r\n" in data[:4096] else b"\n"


def configuration_format(
    data: bytes, elements: list[etree._Element], spans: list[Span]
) -> FormatChanges:
    """``elements`` and ``spans``: every element of the file in document order, root first."""
    changes = FormatChanges([], [])
    root, root_span = elements[0], spans[0]
    edit, note = _pi_edit(
        data, root_span.start, ns.CONFIG_VERSION_KEYS, ns.CONFIG_FORMAT, _newline(data)
    )
    if edit is not None:
        changes.edits.append(edit)
        changes.notes.append(note or "")
    namespace = etree.QName(root).namespace
    if namespace == ns.CONFIG_NS:
        return changes
    tag = data[root_span.start : root_span.start_end]
    new_tag = _OLD_URI.sub(ns.CONFIG_NS.encode(), tag)
    match = _XMLNS.search(new_tag)
    if match is None:
        name_end = re.match(rb"<[\w:.-]+", new_tag).end()
        new_tag = new_tag[:name_end] + f' xmlns="{ns.CONFIG_NS}"'.encode() + new_tag[name_end:]
    elif match.group(2) != ns.CONFIG_NS.encode():
        new_tag = new_tag[: match.start(2)] + ns.CONFIG_NS.encode() + new_tag[match.end(2) :]
    changes.edits.append(Edit(root_span.start, root_span.start_end, new_tag))
    # Elements that redeclare the old default namespace (or none, xmlns="") follow the root.
    old = (namespace or "").encode()
    for span in spans[1:]:
        tag = data[span.start : span.start_end]
        found = _XMLNS.search(tag) if b"xmlns" in tag else None
        if found is not None and found.group(2) == old:
            changes.edits.append(
                Edit(span.start, span.start_end, tag[: found.start()] + tag[found.end() :])
            )
    changes.notes.append(f"namespace {namespace or '(none)'} -> {ns.CONFIG_NS}")
    return changes


def definition_format(
    data: bytes, root: etree._Element, spans: list[Span], elements: list[etree._Element]
) -> FormatChanges:
    """Format 3.0 definitions to 3.1; nothing for files already in 3.1 (or unknown ones)."""
    changes = FormatChanges([], [])
    namespace = etree.QName(root).namespace
    pi = _PI.search(data, 0, spans[0].start)
    old_pi = bool(
        pi and re.search(rb"""(definition|desc\.db)\.version\s*=\s*["']3\.0["']""", pi.group(1))
    )
    if namespace != ns.OLD_DEFINITION_NS and not old_pi:
        return changes
    edit, _ = _pi_edit(
        data, spans[0].start, ns.DEFINITION_VERSION_KEYS, ns.DEFINITION_FORMAT, _newline(data)
    )
    if edit is not None:
        changes.edits.append(edit)
    tag = data[spans[0].start : spans[0].start_end]
    new_tag = tag.replace(ns.OLD_DEFINITION_NS.encode(), ns.DEFINITION_NS.encode())
    if new_tag != tag:
        changes.edits.append(Edit(spans[0].start, spans[0].start_end, new_tag))
    added = 0
    position = {node: i for i, node in enumerate(elements)}
    for node, span in zip(elements, spans, strict=True):
        if etree.QName(node).localname != "definition_version" or span.empty:
            continue
        if any(isinstance(c.tag, str) and etree.QName(c).localname == "abstract" for c in node):
            continue
        first = next((position[c] for c in node if isinstance(c.tag, str)), None)
        indent = indentation_before(data, spans[first].start) if first is not None else b""
        if not indent:
            indent = indentation_before(data, span.start) + b"   "
        changes.edits.append(
            Edit(
                span.start_end,
                span.start_end,
                _newline(data) + indent + b"<abstract>false</abstract>",
            )
        )
        added += 1
    changes.notes.append(
        f"definition format 3.0 -> 3.1 ({added} <abstract>false</abstract> inserted)"
    )
    return changes
