"""Reading .jdef documents into :mod:`gadgetctl.jccl.definitions` objects.

The reader is tolerant: the schema check reports structural problems, and whatever can be
understood is still read so that later checks have something to work on. Tags are matched
by local name, so the older 3.0 format and files without a namespace are read too.
"""

from __future__ import annotations

from lxml import etree

from gadgetctl.jccl.configuration import SourceLocation
from gadgetctl.jccl.definitions import (
    Definition,
    DefinitionVersion,
    EnumChoice,
    Enumeration,
    Location,
    PropertyDefinition,
    ValueSlot,
    ValueType,
)
from gadgetctl.jccl.xmlload import XmlDocument

_VALUETYPES = {v.value: v for v in ValueType}


def _local(node: etree._Element) -> str | None:
    tag = node.tag
    if not isinstance(tag, str):
        return None
    return tag.rpartition("}")[2]


def _children(node: etree._Element, name: str) -> list[etree._Element]:
    return [c for c in node if _local(c) == name]


def _grouped(node: etree._Element) -> dict[str, list[etree._Element]]:
    """The child elements of ``node`` by local name, in document order (one pass over the
    children instead of one per name asked for)."""
    groups: dict[str, list[etree._Element]] = {}
    for child in node:
        tag = child.tag
        if isinstance(tag, str):
            local = tag.rpartition("}")[2]
            found = groups.get(local)
            if found is None:
                groups[local] = [child]
            else:
                found.append(child)
    return groups


def _only(groups: dict[str, list[etree._Element]], name: str) -> etree._Element | None:
    found = groups.get(name)
    return found[0] if found else None


def _text(node: etree._Element | None) -> str:
    if node is None:
        return ""
    if not len(node):  # (the usual leaf: its text is all itertext() gives)
        text = node.text
        return text.strip() if text else ""
    return "".join(node.itertext()).strip()


def _bool(text: str | None, default: bool = False) -> bool:
    if text is None:
        return default
    return text.strip() in ("true", "1")


class DefinitionReader:
    """Turns one parsed .jdef document into a :class:`Definition`."""

    def __init__(self, doc: XmlDocument, *, columns: bool = True) -> None:
        self.doc = doc
        self.columns = columns

    def location(self, node: etree._Element) -> Location | SourceLocation:
        """Where ``node`` is: its line only, or (``columns``) its line and column, looked up
        when first asked for (few definitions and properties are ever reported)."""
        if not self.columns:
            return Location(self.doc.path, node.sourceline)
        return SourceLocation(self.doc, node)

    def read(self) -> Definition | None:
        root = self.doc.root
        if root is None or _local(root) != "definition":
            return None
        name = (root.get("name") or "").strip()
        definition = Definition(
            name=name, location=self.location(root), icon_path=root.get("icon_path")
        )
        for node in _children(root, "definition_version"):
            version = self.read_version(name, node)
            if version is None:
                continue
            definition.order.append(version.version)
            if version.version not in definition.versions:
                definition.versions[version.version] = version
        return definition

    def read_version(self, name: str, node: etree._Element) -> DefinitionVersion | None:
        try:
            number = int((node.get("version") or "").strip())
        except ValueError:
            return None
        transform = None
        children = _grouped(node)
        upgrade = _only(children, "upgrade_transform")
        if upgrade is not None:
            sheets = [c for c in upgrade if isinstance(c.tag, str)]
            if sheets:
                transform = etree.tostring(sheets[0])
        return DefinitionVersion(
            name=name,
            version=number,
            label=(node.get("label") or "").strip(),
            abstract=_bool(_text(_only(children, "abstract")) or None),
            help=_text(_only(children, "help")),
            parents=tuple(t for t in (_text(p) for p in children.get("parent", ())) if t),
            categories=tuple(t for t in (_text(c) for c in children.get("category", ())) if t),
            properties=tuple(
                self.read_property(p)
                for p in children.get("property", ())
                if (p.get("valuetype") or "") in _VALUETYPES and p.get("name")
            ),
            upgrade_transform=transform,
            location=self.location(node),
        )

    def read_property(self, node: etree._Element) -> PropertyDefinition:
        help_node = enum_node = None
        values: list[etree._Element] = []
        allowed: list[etree._Element] = []
        for child in node:  # (one pass: a definition file has dozens of properties)
            tag = child.tag
            if not isinstance(tag, str):
                continue
            local = tag.rpartition("}")[2]
            if local == "value":
                values.append(child)
            elif local == "allowed_type":
                allowed.append(child)
            elif local == "help":
                help_node = child if help_node is None else help_node
            elif local == "enumeration":
                enum_node = child if enum_node is None else enum_node
        enumeration = None
        if enum_node is not None:
            enumeration = Enumeration(
                editable=_bool(enum_node.get("editable")),
                choices=tuple(
                    EnumChoice(e.get("label") or "", e.get("value") or "")
                    for e in _children(enum_node, "enum")
                ),
            )
        return PropertyDefinition(
            name=node.get("name") or "",
            valuetype=_VALUETYPES[node.get("valuetype") or ""],
            variable=_bool(node.get("variable")),
            help=_text(help_node),
            values=tuple(ValueSlot(v.get("label") or "", v.get("defaultvalue")) for v in values),
            allowed_types=tuple(t for t in (_text(a) for a in allowed) if t),
            enumeration=enumeration,
            location=self.location(node),
        )


def read_definition(doc: XmlDocument, *, columns: bool = True) -> Definition | None:
    """Read a definition; ``columns=False`` gives locations without a column (bulk loads:
    they keep no reference to the document)."""
    return DefinitionReader(doc, columns=columns).read()
