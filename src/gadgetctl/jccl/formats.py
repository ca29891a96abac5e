"""File-format markers of JCCL files: the settings processing instruction and namespaces."""

from __future__ import annotations

import re
from copy import deepcopy

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl import namespaces as ns
from gadgetctl.jccl.xmlload import FileKind, XmlDocument

_PSEUDO_ATTR = re.compile(r"([\w.:-]+)\s*=\s*[\"']([^\"']*)[\"']")


def settings_pi(root: etree._Element) -> etree._ProcessingInstruction | None:
    for node in root.itersiblings(preceding=True):
        if isinstance(node, etree._ProcessingInstruction) and node.target == ns.SETTINGS_PI:
            return node
    return None


def pi_attributes(pi: etree._ProcessingInstruction) -> dict[str, str]:
    return dict(_PSEUDO_ATTR.findall(pi.text or ""))


def format_version(root: etree._Element, kind: FileKind) -> str | None:
    pi = settings_pi(root)
    if pi is None:
        return None
    attrs = pi_attributes(pi)
    keys = ns.CONFIG_VERSION_KEYS if kind is FileKind.CONFIGURATION else ns.DEFINITION_VERSION_KEYS
    for key in keys:
        if key in attrs:
            return attrs[key]
    return None


def check_format(doc: XmlDocument) -> None:
    """Append diagnostics about the PI and the root namespace of a parsed document."""
    assert doc.root is not None
    root = doc.root
    local = etree.QName(root).localname
    if (
        (doc.kind is FileKind.CONFIGURATION and local != "configuration")
        or (doc.kind is FileKind.DEFINITION and local != "definition")
        or doc.kind is FileKind.UNKNOWN
    ):
        expected = {"configuration": "<configuration>", "definition": "<definition>"}.get(
            doc.kind.value
        )
        what = f"expected {expected}" if expected else "expected <configuration> or <definition>"
        line, column = doc.locate(root)
        doc.diagnostics.append(
            Diagnostic.make(
                "XML014",
                f"root element <{local}> is not a JCCL document ({what})",
                doc.path,
                line,
                column,
            )
        )
        return
    if doc.kind is FileKind.CONFIGURATION:
        _check_configuration(doc, root)
    else:
        _check_definition(doc, root)


def _pi_location(
    doc: XmlDocument, pi: etree._ProcessingInstruction
) -> tuple[int | None, int | None]:
    line = pi.sourceline
    if line and line <= len(doc.lines):
        col = doc.lines[line - 1].find("<?" + ns.SETTINGS_PI)
        return line, col + 1 if col >= 0 else None
    return line, None


def _check_pi(
    doc: XmlDocument, root: etree._Element, keys: tuple[str, ...], expected: str
) -> str | None:
    pi = settings_pi(root)
    if pi is None:
        doc.diagnostics.append(
            Diagnostic.make(
                "XML010",
                f'no <?{ns.SETTINGS_PI} {keys[0]}="{expected}"?> processing instruction',
                doc.path,
                1,
                1,
                hint=f'Add <?{ns.SETTINGS_PI} {keys[0]}="{expected}"?> before the root element.',
            )
        )
        return None
    attrs = pi_attributes(pi)
    for key in keys:
        if key in attrs:
            return (
                attrs[key]
                if attrs[key] == expected
                else _wrong_version(doc, key, attrs[key], expected, pi)
            )
    line, column = _pi_location(doc, pi)  # (looked up only for a finding)
    doc.diagnostics.append(
        Diagnostic.make(
            "XML011",
            f"processing instruction has no {keys[0]} pseudo-attribute",
            doc.path,
            line,
            column,
            hint=f'Write <?{ns.SETTINGS_PI} {keys[0]}="{expected}"?>.',
        )
    )
    return None


def _wrong_version(
    doc: XmlDocument, key: str, value: str, expected: str, pi: etree._ProcessingInstruction
) -> str:
    if key in ns.DEFINITION_VERSION_KEYS and value == "3.0":
        return value  # reported once, with the namespace, as an older definition format
    line, column = _pi_location(doc, pi)
    doc.diagnostics.append(
        Diagnostic.make(
            "XML011",
            f'file-format version {key}="{value}" is not known; expected "{expected}"',
            doc.path,
            line,
            column,
            hint=f'Use {key}="{expected}".',
        )
    )
    return value


def _check_configuration(doc: XmlDocument, root: etree._Element) -> None:
    _check_pi(doc, root, ns.CONFIG_VERSION_KEYS, ns.CONFIG_FORMAT)
    namespace = etree.QName(root).namespace
    if namespace == ns.CONFIG_NS:
        return
    line, column = doc.locate(root)
    if namespace is None:
        message = f"<configuration> has no namespace; expected {ns.CONFIG_NS}"
    elif "/jccl/xsd/" in namespace and namespace.endswith("/configuration"):
        message = f"there is no configuration namespace {namespace}; expected {ns.CONFIG_NS}"
    else:
        message = f"<configuration> is in namespace {namespace}; expected {ns.CONFIG_NS}"
    doc.diagnostics.append(
        Diagnostic.make(
            "XML012",
            message,
            doc.path,
            line,
            column,
            hint=f'Set xmlns="{ns.CONFIG_NS}" (`gadgetctl upgrade` does it).',
        )
    )


def _check_definition(doc: XmlDocument, root: etree._Element) -> None:
    version = _check_pi(doc, root, ns.DEFINITION_VERSION_KEYS, ns.DEFINITION_FORMAT)
    namespace = etree.QName(root).namespace
    if namespace == ns.DEFINITION_NS and version != "3.0":
        return
    line, column = doc.locate(root)
    if namespace == ns.OLD_DEFINITION_NS or version == "3.0":
        doc.diagnostics.append(
            Diagnostic.make(
                "XML013",
                "definition file is in the older format 3.0; VR Juggler 3 reads only format 3.1",
                doc.path,
                line,
                column,
                hint="Run `gadgetctl upgrade FILE`: it moves the file to the 3.1 namespace and adds "
                "<abstract>false</abstract> to each definition_version.",
            )
        )
        return
    shown = namespace or "no namespace"
    doc.diagnostics.append(
        Diagnostic.make(
            "XML012",
            f"<definition> is in {shown}; expected {ns.DEFINITION_NS}",
            doc.path,
            line,
            column,
            hint=f'Set xmlns="{ns.DEFINITION_NS}" (`gadgetctl upgrade` does it).',
        )
    )


def normalised_copy(doc: XmlDocument) -> etree._Element:
    """The root moved into its format's expected namespace, for schema checks of the rest."""
    assert doc.root is not None
    target = ns.CONFIG_NS if doc.kind is FileKind.CONFIGURATION else ns.DEFINITION_NS
    if etree.QName(doc.root).namespace == target:
        return doc.root
    # A copy of the tree, not a serialise-and-parse round trip: lxml writes a non-ASCII
    # attribute name as a character reference, which does not parse back.
    root = deepcopy(doc.root)
    for copy, original in zip(root.iter(), doc.root.iter(), strict=True):
        copy.sourceline = original.sourceline
        if not isinstance(copy.tag, str):
            continue
        qname = etree.QName(copy)
        if qname.namespace in (None, ns.OLD_DEFINITION_NS) or (
            qname.namespace and qname.namespace.startswith("http://www.vrjuggler.org/jccl/xsd/")
        ):
            copy.tag = f"{{{target}}}{qname.localname}"
    etree.cleanup_namespaces(root)
    return root
