"""Edits that turn an element of a file into a changed copy of it, keeping the file's own
spelling: the bytes of every unchanged property, the attribute order and quoting of start
tags, self-closing tags and indentation. Only what differs is rewritten, so that a diff of
an upgrade shows the real changes and nothing else.

The old element comes from the parsed file (its byte spans known); the new one is any tree
of the same type (an upgrade transform's result, a copy with properties dropped). Children
are aligned by content, ignoring layout; a run of changed children with the same tags is
patched child by child, other runs are removed or inserted whole.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from difflib import SequenceMatcher

from lxml import etree

from gadgetctl.jccl.formatupgrade import Edit
from gadgetctl.jccl.spans import Span, indentation_before

_ATTRIBUTE = re.compile(rb"""(\s+)([^\s=/>]+)(\s*=\s*)(["'])(.*?)\4""", re.S)

Key = tuple


def _local(node: etree._Element) -> str:
    return etree.QName(node).localname


def _children(node: etree._Element) -> list[etree._Element]:
    return [c for c in node if isinstance(c.tag, str)]


def content_key(node: etree._Element) -> Key:
    """What an element means, layout aside: its name, attributes, text or children."""
    children = _children(node)
    text = "" if children else (node.text or "")
    return (
        _local(node),
        tuple(sorted(node.attrib.items())),
        text,
        tuple(content_key(c) for c in children),
    )


def _mixed(node: etree._Element) -> bool:
    return bool(_children(node)) and bool(
        (node.text or "").strip() or any((c.tail or "").strip() for c in node)
    )


class Patcher:
    """Edits within the bytes ``data`` of a file whose element spans are ``spans``."""

    def __init__(
        self,
        data: bytes,
        spans: dict[etree._Element, Span],
        encoding: str,
        # (own indentation and unit, or None and None for a compact copy without layout)
        serialise: Callable[[etree._Element, str | None, str | None], bytes],
        newline: str = "\n",
    ) -> None:
        self.data = data
        self.spans = spans
        self.encoding = encoding
        self.serialise = serialise
        self.newline = newline

    def encode(self, text: str) -> bytes:
        return text.encode(self.encoding, "xmlcharrefreplace")

    def whole(self, old: etree._Element, new: etree._Element, own: str, unit: str) -> list[Edit]:
        span = self.spans[old]
        return [Edit(span.start, span.end, self.serialise(new, own, unit))]

    def patch(self, old: etree._Element, new: etree._Element, own: str, unit: str) -> list[Edit]:
        """Edits turning ``old`` (in the file, indented by ``own``) into ``new``."""
        if content_key(old) == content_key(new):
            return []
        span = self.spans[old]
        old_children, new_children = _children(old), _children(new)
        new_text = "" if new_children else (new.text or "")
        if (
            _local(old) != _local(new)
            or _mixed(old)
            or _mixed(new)
            or (span.empty and (new_children or new_text))
            or (not old_children and new_children)
            or (old_children and not new_children)
        ):
            return self.whole(old, new, own, unit)
        edits = self.attributes(old, new, span)
        if not old_children:
            if (old.text or "") != new_text:
                close = self.data.rfind(b"</", span.start_end, span.end)
                edits.append(Edit(span.start_end, close, self.encode(_escape_text(new_text))))
            return edits
        first = self.spans[old_children[0]].start
        # A compact element (its first property on its start tag's line, e.g. all on one
        # line) gets new children the way it writes its own: on that line, separated as its
        # first two are.
        compact = b"\n" not in self.data[span.start : first]
        inner = indentation_before(self.data, first).decode(self.encoding, "replace")
        if not inner:
            inner = own + unit
        separator = self.newline + inner
        if compact:
            between = b""
            if len(old_children) > 1:
                between = self.data[
                    self.spans[old_children[0]].end : self.spans[old_children[1]].start
                ]
            separator = between.decode(self.encoding, "replace") if not between.strip() else ""
        old_keys = [content_key(c) for c in old_children]
        new_keys = [content_key(c) for c in new_children]
        matcher = SequenceMatcher(None, old_keys, new_keys, autojunk=False)
        for tag, i1, i2, j1, j2 in matcher.get_opcodes():
            if tag == "equal":
                continue
            pairs = list(zip(old_children[i1:i2], new_children[j1:j2], strict=False))
            if (
                tag == "replace"
                and i2 - i1 == j2 - j1
                and all(_local(a) == _local(b) for a, b in pairs)
            ):
                for a, b in pairs:
                    edits += self.patch(a, b, inner, unit)
                continue
            removals = [self.removal(old, child) for child in old_children[i1:i2]]
            edits += removals
            if j2 > j1:  # where the removed ones were, or after the previous child
                if removals:
                    at = removals[0].start
                else:
                    at = self.spans[old_children[i1 - 1]].end if i1 > 0 else span.start_end
                text = b"".join(
                    self.encode(separator)
                    + (self.serialise(c, None, None) if compact else self.serialise(c, inner, unit))
                    for c in new_children[j1:j2]
                )
                edits.append(Edit(at, at, text))
        return edits

    def removal(self, parent: etree._Element, child: etree._Element) -> Edit:
        """Remove ``child`` with the line break and indentation before it (when nothing
        else stands on its line before it)."""
        span = self.spans[child]
        start = span.start
        newline = self.data.rfind(b"\n", self.spans[parent].start_end, start)
        if newline >= 0 and not self.data[newline + 1 : start].strip():
            start = newline - 1 if self.data[newline - 1 : newline] == b"\r" else newline
        return Edit(start, span.end, b"")

    def attributes(self, old: etree._Element, new: etree._Element, span: Span) -> list[Edit]:
        """Edits of the start tag's attribute values, in place and in their own quotes."""
        if dict(old.attrib) == dict(new.attrib):
            return []
        tag = self.data[span.start : span.start_end]
        found = {m.group(2).decode(self.encoding, "replace"): m for m in _ATTRIBUTE.finditer(tag)}
        edits: list[Edit] = []
        wanted = dict(new.attrib)
        for name, match in found.items():
            if name.startswith("xmlns"):
                continue
            if name not in wanted:
                edits.append(Edit(span.start + match.start(), span.start + match.end(), b""))
            elif old.get(name) != wanted[name]:
                quote = match.group(4)
                value = self.encode(_escape_attribute(wanted[name], quote.decode()))
                edits.append(Edit(span.start + match.start(5), span.start + match.end(5), value))
        missing = [name for name in wanted if name not in found]
        if missing:
            name_end = re.match(rb"<[^\s/>]*", tag).end()
            at = span.start + max((m.end() for m in found.values()), default=name_end)
            text = "".join(
                f' {name}="{_escape_attribute(wanted[name], chr(34))}"' for name in missing
            )
            edits.append(Edit(at, at, self.encode(text)))
        return edits


def _escape_text(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _escape_attribute(value: str, quote: str) -> str:
    value = value.replace("&", "&amp;").replace("<", "&lt;")
    return value.replace(quote, "&quot;" if quote == '"' else "&apos;")
