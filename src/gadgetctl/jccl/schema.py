"""XML Schema validation of JCCL files against gadgetctl's bundled XSDs."""

from __future__ import annotations

import re
from copy import deepcopy
from functools import cache

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.formats import normalised_copy
from gadgetctl.jccl.xmlload import FileKind, XmlDocument
from gadgetctl.resources import schemas_dir

SCHEMA_FILES = {
    FileKind.CONFIGURATION: "configuration-3.0.xsd",
    FileKind.DEFINITION: "definition-3.1.xsd",
}
_CLARK = re.compile(r"\{[^}]*\}")


@cache
def schema_for(kind: FileKind) -> etree.XMLSchema:
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    return etree.XMLSchema(etree.parse(str(schemas_dir() / SCHEMA_FILES[kind]), parser))


def readable_path(element: etree._Element) -> str:
    """``/definition/definition_version[2]/property[3]`` style path with local names."""
    parts: list[str] = []
    node = element
    while node is not None:
        local = etree.QName(node).localname
        parent = node.getparent()
        if parent is not None:
            same = [
                c for c in parent if isinstance(c.tag, str) and etree.QName(c).localname == local
            ]
            if len(same) > 1:
                local = f"{local}[{same.index(node) + 1}]"
        parts.append(local)
        node = parent
    return "/" + "/".join(reversed(parts))


_STEP = re.compile(r"^(?:[\w.-]+:)?([\w.*-]+)(?:\[(\d+)\])?$")


def element_at(root: etree._Element, path: str) -> etree._Element | None:
    """Follow a libxml2 error path such as ``/*/*/*[3]`` or ``/ns0:a/ns0:b[2]``."""
    steps = [s for s in path.split("/") if s]
    if not steps:
        return None
    node: etree._Element | None = None
    for depth, step in enumerate(steps):
        match = _STEP.match(step)
        if match is None:
            return None
        name, index = match.group(1), int(match.group(2) or 1)
        pool = [root] if depth == 0 else [c for c in node if isinstance(c.tag, str)]
        if name != "*":
            pool = [c for c in pool if etree.QName(c).localname == name]
        if len(pool) < index:
            return None
        node = pool[index - 1]
    return node


def _clean(message: str) -> str:
    message = _CLARK.sub("", message).strip()
    return re.sub(
        r"^Element '[^']*'(, attribute '([^']*)')?: ",
        lambda m: f"attribute {m.group(2)!r}: " if m.group(2) else "",
        message,
    )


def _stray_text_error(message: str, element: etree._Element) -> bool:
    """Whether the error is text between child elements, which stray_text reports."""
    return message.startswith("Character content other than whitespace") and any(
        isinstance(child.tag, str) for child in element
    )


def _copy_with_lines(root: etree._Element) -> etree._Element:
    copy = deepcopy(root)
    for node, original in zip(copy.iter(), root.iter(), strict=True):
        node.sourceline = original.sourceline
    return copy


def _without_entities(root: etree._Element) -> etree._Element:
    """``root`` with its entity reference nodes taken out, the text after each kept."""
    for entity in list(root.iter(etree.Entity)):
        parent, previous, tail = entity.getparent(), entity.getprevious(), entity.tail or ""
        if previous is not None:
            previous.tail = (previous.tail or "") + tail
        elif parent is not None:
            parent.text = (parent.text or "") + tail
        if parent is not None:
            parent.remove(entity)
    return root


def check_schema(doc: XmlDocument) -> None:
    """Append one SCH001 diagnostic per schema violation, with element path and column."""
    if doc.root is None or doc.kind not in SCHEMA_FILES:
        return
    schema = schema_for(doc.kind)
    root = normalised_copy(doc)
    if next(root.iter(etree.Entity), None) is not None:
        # entity references (XML003) make libxml2's validator fail outright: check the
        # text around them
        root = _without_entities(root if root is not doc.root else _copy_with_lines(root))
    tree = root.getroottree()
    if schema.validate(tree):
        return
    for entry in schema.error_log:
        element = None
        if entry.path:
            element = element_at(root, entry.path)
        line, column, where = entry.line or None, None, ""
        if element is not None:
            where = readable_path(element)
            line, column = doc.locate(element)  # the copy keeps the original source lines
        message = _clean(entry.message)
        if element is not None and _stray_text_error(message, element):
            continue  # reported as stray text (XML015) with its own place: one fact, one finding
        doc.diagnostics.append(
            Diagnostic.make(
                "SCH001", f"{where}: {message}" if where else message, doc.path, line, column
            )
        )
