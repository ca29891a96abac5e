"""`gadgetctl upgrade`: bring files up to date with their definitions and file formats.

Elements older than their definition are passed through the definitions' upgrade
transforms one version at a time, as VRJConfig does: the transform stored in version N
turns a version N-1 element into version N; the first element of its result is the
upgraded element and any further elements are new ones, placed after it. Embedded
elements are upgraded too. File-format markers are fixed by
:mod:`gadgetctl.jccl.formatupgrade`.

Only the changed elements are rewritten; every other byte of the file (comments, layout,
quoting, untouched elements) stays as it was. If one element cannot be upgraded, the file
is left unchanged and the problem reported.
"""

from __future__ import annotations

import copy
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from gadgetctl.boundedread import DEFAULT_MAX_SIZE, FileTooLarge, NotRegularFile, read_limited
from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.jccl.definitions import Location, ValueType
from gadgetctl.jccl.formatupgrade import Edit, configuration_format, definition_format
from gadgetctl.jccl.namespaces import CONFIG_NS
from gadgetctl.jccl.patch import Patcher
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.jccl.runtime import RENAMED_PROPERTIES
from gadgetctl.jccl.searchpath import configuration_entries
from gadgetctl.jccl.spans import Span, element_spans, indentation_before
from gadgetctl.jccl.typeindex import TypeIndex
from gadgetctl.jccl.xmlload import FileKind, declared_encoding, guess_kind, parse_bytes, text_codec
from gadgetctl.jccl.xslt import TransformError, apply_transform, in_namespace

DEFAULT_INDENT = "   "


@dataclass(frozen=True, slots=True)
class ElementUpgrade:
    type: str
    name: str
    line: int | None
    from_version: int
    to_version: int
    created: int = 0  # new elements the transforms made
    dropped: tuple[str, ...] = ()  # properties removed (--drop-removed)
    renamed: tuple[tuple[str, str], ...] = ()  # (old, new) property names, values kept

    @property
    def upgraded(self) -> bool:
        return self.to_version != self.from_version

    def describe(self) -> str:
        extra = (
            f", {self.created} new element{'s' if self.created != 1 else ''}"
            if self.created
            else ""
        )
        if self.renamed:
            extra += ", renamed " + ", ".join(f"{old} to {new}" for old, new in self.renamed)
        if self.dropped:
            extra += f", removed {', '.join(self.dropped)}"
        if not self.upgraded:
            return f"{self.type} {self.name!r}: {extra.removeprefix(', ')}"
        return f"{self.type} {self.name!r}: version {self.from_version} -> {self.to_version}{extra}"


@dataclass
class FileUpgrade:
    path: Path
    display: str
    original: bytes
    upgraded: bytes | None = None
    elements: list[ElementUpgrade] = field(default_factory=list)
    format_notes: list[str] = field(default_factory=list)
    problems: list[Diagnostic] = field(default_factory=list)

    @property
    def changed(self) -> bool:
        return self.upgraded is not None and self.upgraded != self.original

    @property
    def failed(self) -> bool:
        return any(p.severity is Severity.ERROR for p in self.problems)


class UpgradeFailure(Exception):
    pass


def _local(node: etree._Element) -> str:
    return etree.QName(node).localname


def _embedded(node: etree._Element) -> list[etree._Element]:
    """Embedded elements of an element: element children of its property children."""
    return [
        child
        for prop in node
        if isinstance(prop.tag, str)
        for child in prop
        if isinstance(child.tag, str)
    ]


def _version(node: etree._Element) -> int | None:
    try:
        return int((node.get("version") or "").strip())
    except ValueError:
        return None


def indent_tree(node: etree._Element, own: str, unit: str) -> None:
    """Lay out ``node``'s children one per line, ``unit`` deeper than ``own``; text values
    (and mixed content) are left alone."""
    children = [c for c in node if isinstance(c.tag, str)]
    if not children or (node.text or "").strip():
        return
    inner = "\n" + own + unit
    node.text = inner
    for i, child in enumerate(children):
        child.tail = inner if i < len(children) - 1 else "\n" + own
        indent_tree(child, own + unit, unit)


def compact_tree(node: etree._Element) -> None:
    """Drop the layout (blank text between child elements) of ``node``'s tree."""
    children = [c for c in node if isinstance(c.tag, str)]
    if not children:
        return
    if not (node.text or "").strip():
        node.text = None
    for child in children:
        if not (child.tail or "").strip():
            child.tail = None
        compact_tree(child)


_SPACED_EMPTY = re.compile(rb"<[^<>!?]*\s/>")
_TIGHT_EMPTY = re.compile(rb"<[^<>!?]*[^\s/]/>")
_EMPTY_TAG_END = re.compile(r"(?<=[^\s/])/>")


class ElementUpgrader:
    """Upgrades element trees against one repository; with ``drop_removed``, also removes
    the properties their newest definition no longer has (those `validate` reports as
    CFG021)."""

    def __init__(self, repo: DefinitionRepository, *, drop_removed: bool = False) -> None:
        self.repo = repo
        self.index = TypeIndex(repo)
        self.drop_removed = drop_removed
        self.warnings: list[str] = []

    def embedded(self, node: etree._Element) -> list[etree._Element]:
        """The embedded elements `validate` checks: only under properties the element's
        judged definition version defines as configelement (none when its type is
        unknown), so that upgrade and validate agree on what is outdated."""
        type_name = _local(node)
        versions = self.index.versions(type_name)
        if not versions:
            return []
        declared = _version(node)
        view = self.index.view(type_name, declared if declared in versions else None)
        if view is None:
            return []
        found = []
        for prop in node:
            if not isinstance(prop.tag, str):
                continue
            definition = view.get(_local(prop))
            if definition is not None and definition.valuetype is ValueType.CONFIGELEMENT:
                found += [child for child in prop if isinstance(child.tag, str)]
        return found

    def removed_properties(self, node: etree._Element) -> list[etree._Element]:
        """Property children that the newest definition of the element's type no longer
        has but an older version (of it or of a type it derives from) had."""
        if not self.drop_removed:
            return []
        type_name = _local(node)
        view = self.index.view(type_name)
        if view is None or (_version(node) or 0) < view.version:
            return []
        return [
            prop
            for prop in node
            if isinstance(prop.tag, str)
            and view.get(_local(prop)) is None
            and self.index.history(type_name, _local(prop))
        ]

    def renamed_properties(self, node: etree._Element) -> list[tuple[etree._Element, str]]:
        """Property children under a name that the element's (current) version renamed,
        with the new name: the element declares the newer version but kept the old name,
        whose values VR Juggler would ignore. Not when the new name is written too."""
        type_name = _local(node)
        view = self.index.view(type_name)
        if view is None or (_version(node) or 0) < view.version:
            return []
        children = [c for c in node if isinstance(c.tag, str)]
        names = {_local(c) for c in children}
        found = []
        for prop in children:
            new = RENAMED_PROPERTIES.get((type_name, _local(prop)))
            if new is not None and new not in names and view.get(new) is not None:
                found.append((prop, new))
        return found

    def drop(self, node: etree._Element) -> list[str]:
        """Remove, in place, the removed properties of ``node``; their names."""
        names = []
        for prop in self.removed_properties(node):
            names.append(_local(prop))
            previous = prop.getprevious()
            if prop.tail and previous is not None:
                previous.tail = prop.tail
            elif prop.tail:
                prop.getparent().text = prop.tail
            prop.getparent().remove(prop)
        return list(dict.fromkeys(names))

    def needs(self, node: etree._Element) -> tuple[int, int] | None:
        versions = self.repo.versions(_local(node))
        declared = _version(node)
        if not versions or declared is None or declared >= versions[-1]:
            return None
        return declared, versions[-1]

    def upgrade(self, node: etree._Element) -> tuple[etree._Element, list[etree._Element]]:
        """The upgraded copy of ``node`` and any new elements; ``node`` is not changed."""
        type_name = _local(node)
        declared, newest = self.needs(node) or (0, 0)
        current = in_namespace(node)
        created: list[etree._Element] = []
        for number in range(declared + 1, newest + 1):
            definition = self.repo.get(type_name, number)
            if definition is None:
                raise UpgradeFailure(
                    f"version {number} of {type_name} is not on the search path, so "
                    f"there is no way from version {number - 1} to {number}"
                )
            if not definition.upgrade_transform:
                raise UpgradeFailure(f"version {number} of {type_name} has no upgrade transform")
            try:
                source = definition.location.path if definition.location is not None else None
                result = apply_transform(definition.upgrade_transform, current, source)
            except TransformError as err:
                raise UpgradeFailure(
                    f"{type_name} version {number - 1} -> {number}: {err}"
                ) from None
            first = result[0]
            if _local(first) != type_name:
                raise UpgradeFailure(
                    f"the {type_name} version {number} transform produced a "
                    f"<{_local(first)}>, not a <{type_name}>"
                )
            current = in_namespace(first)
            current.set("version", str(number))
            created += [in_namespace(extra) for extra in result[1:]]
        self.check_counts(node, current)
        return current, created

    def check_counts(self, before: etree._Element, after: etree._Element) -> None:
        """Warn about fixed-count properties the transforms gave more values than they have,
        typically because the element already carried a property a newer version adds."""

        def counts(node: etree._Element) -> dict[str, int]:
            found: dict[str, int] = {}
            for prop in node:
                if isinstance(prop.tag, str):
                    found[_local(prop)] = found.get(_local(prop), 0) + 1
            return found

        old, new = counts(before), counts(after)
        type_name = _local(after)
        for name, count in new.items():
            found = self.repo.find_property(type_name, name)
            if found is None or found.definition.variable:
                continue
            slots = len(found.definition.values)
            if count > slots >= old.get(name, 0):
                self.warnings.append(
                    f"{type_name} {after.get('name')!r}: after the upgrade {name} has {count} values "
                    f"but {slots} slot{'s' if slots != 1 else ''}; the element already had it before "
                    "the transform added it. Remove the extra value."
                )

    def upgrade_embedded(
        self,
        node: etree._Element,
        log: list[ElementUpgrade],
        lines: dict[tuple, int | None],
        chain: tuple = (),
    ) -> None:
        """Upgrade, in place, the embedded elements of an element tree that is not in a file
        (and drop their removed properties). ``lines`` maps chains of (type, name) from the
        top element to source lines."""
        for child in self.embedded(node):
            key = (*chain, (_local(child), child.get("name")))
            step = self.needs(child)
            if step is None:
                dropped = self.drop(child)
                if dropped:
                    version = _version(child) or 0
                    log.append(
                        ElementUpgrade(
                            _local(child),
                            child.get("name") or "",
                            lines.get(key),
                            version,
                            version,
                            dropped=tuple(dropped),
                        )
                    )
                self.upgrade_embedded(child, log, lines, key)
                continue
            upgraded, created = self.upgrade(child)
            dropped = self.drop(upgraded)
            self.upgrade_embedded(upgraded, log, lines, key)
            upgraded.tail = child.tail
            child.getparent().replace(child, upgraded)
            log.append(
                ElementUpgrade(
                    _local(child),
                    child.get("name") or "",
                    lines.get(key),
                    *step,
                    len(created),
                    tuple(dropped),
                )
            )


def source_lines(node: etree._Element, chain: tuple = ()) -> dict[tuple, int | None]:
    """Source lines of the embedded elements of ``node``, by chain of (type, name)."""
    found: dict[tuple, int | None] = {}
    for child in _embedded(node):
        key = (*chain, (_local(child), child.get("name")))
        found.setdefault(key, child.sourceline)
        found.update(source_lines(child, key))
    return found


class FileUpgrader:
    def __init__(
        self,
        path: Path,
        data: bytes,
        display: str,
        repo: DefinitionRepository,
        environ: Mapping[str, str] | None = None,
        *,
        drop_removed: bool = False,
    ) -> None:
        self.result = FileUpgrade(path, display, data)
        self.data = data
        self.repo = repo
        self.environ = environ
        self.drop_removed = drop_removed
        self.encoding = declared_encoding(data)
        self.newline = "\r\n" if b"\r\n" in data[:4096] else "\n"
        # how the file ends its empty elements: <x /> or <x/>
        self.spaced_empty = len(_SPACED_EMPTY.findall(data)) > len(_TIGHT_EMPTY.findall(data))
        self.edits: list[Edit] = []
        self.format_edits: list[Edit] = []

    def problem(self, message: str, line: int | None = None, code: str = "CFG050") -> None:
        self.result.problems.append(Diagnostic.make(code, message, self.result.display, line))

    def run(self) -> FileUpgrade:
        doc = parse_bytes(self.data, self.result.display, guess_kind(self.result.path))
        if doc.root is None or not text_codec(self.encoding):
            self.result.problems.extend(d for d in doc.diagnostics if d.severity is Severity.ERROR)
            return self.result
        elements = list(doc.root.iter(etree.Element))
        try:
            spans = element_spans(self.data)
        except ValueError as err:
            self.problem(f"cannot edit the file in place: {err}", code="XML001")
            return self.result
        if len(spans) != len(elements):
            self.problem(
                "cannot match the file's elements to their positions; not changed", code="XML001"
            )
            return self.result
        self.spans = dict(zip(elements, spans, strict=True))
        if doc.kind is FileKind.DEFINITION:
            changes = definition_format(self.data, doc.root, spans, elements)
        elif doc.kind is FileKind.CONFIGURATION:
            changes = configuration_format(self.data, elements, spans)
            self.format_edits = changes.edits
            self.repo = self.with_definition_path(doc.root)
            self.upgrade_elements(doc.root)
        else:
            return self.result
        self.edits += changes.edits
        self.result.format_notes += changes.notes
        if self.result.failed:
            return self.result
        self.result.upgraded = self.apply()
        self.verify()
        return self.result

    def with_definition_path(self, root: etree._Element) -> DefinitionRepository:
        """The repository plus the file's <definition_path> directories."""
        dirs = [
            ((d.text or "").strip(), Location(self.result.display, d.sourceline))
            for node in root
            if isinstance(node.tag, str) and _local(node) == "definition_path"
            for d in node
            if isinstance(d.tag, str) and _local(d) == "dir"
        ]
        entries = configuration_entries(dirs, self.result.path.resolve().parent, self.environ)
        return self.repo.extended(entries) if entries else self.repo

    # -- elements --------------------------------------------------------------------

    def upgrade_elements(self, root: etree._Element) -> None:
        upgrader = ElementUpgrader(self.repo, drop_removed=self.drop_removed)
        self.patcher = Patcher(self.data, self.spans, self.encoding, self.serialise, self.newline)
        for container in root:
            if isinstance(container.tag, str) and _local(container) == "elements":
                for node in container:
                    if isinstance(node.tag, str):
                        self.visit(upgrader, node, self.spans[node])

    def visit(self, upgrader: ElementUpgrader, node: etree._Element, top: Span) -> None:
        type_name = _local(node)
        if not upgrader.repo.versions(type_name):
            # nothing says whether it is up to date: never "all up to date" (validate: CFG010)
            self.problem(
                f"{type_name} {node.get('name')!r}: no definition of {type_name} on the search "
                "path, so whether it is up to date cannot be checked",
                node.sourceline,
                code="CFG010",
            )
            return
        step = upgrader.needs(node)
        if step is None:
            renames = upgrader.renamed_properties(node)
            carried = {id(prop) for prop, _ in renames}
            removed = [p for p in upgrader.removed_properties(node) if id(p) not in carried]
            if renames:
                self.edits += self.rename(node, renames)
            if removed or renames:
                names = tuple(dict.fromkeys(_local(p) for p in removed))
                for prop in removed:
                    self.edits.append(self.patcher.removal(node, prop))
                version = _version(node) or 0
                self.result.elements.append(
                    ElementUpgrade(
                        _local(node),
                        node.get("name") or "",
                        node.sourceline,
                        version,
                        version,
                        dropped=names,
                        renamed=tuple((_local(p), new) for p, new in renames),
                    )
                )
            for child in upgrader.embedded(node):
                if not any(child in prop for prop in removed):
                    self.visit(upgrader, child, top)
            return
        line = node.sourceline
        log: list[ElementUpgrade] = []
        try:
            upgraded, created = upgrader.upgrade(node)
            dropped = upgrader.drop(upgraded)
            upgrader.upgrade_embedded(upgraded, log, source_lines(node))
        except UpgradeFailure as err:
            self.problem(
                f"{_local(node)} {node.get('name')!r} (version {step[0]}) cannot be upgraded: "
                f"{err}",
                line,
            )
            return
        finally:
            for warning in upgrader.warnings:
                self.result.problems.append(
                    Diagnostic.make(
                        "CFG023", warning, self.result.display, line, severity=Severity.WARNING
                    )
                )
            upgrader.warnings.clear()
        span = self.spans[node]
        own = indentation_before(self.data, span.start).decode(self.encoding, "replace")
        unit = self.indent_unit(node, own)
        if any(e.start < span.end and e.end > span.start for e in self.format_edits):
            # a file-format fix edits this element's tags too: write it out whole
            self.edits += self.patcher.whole(node, upgraded, own, unit)
        else:
            self.edits += self.patcher.patch(node, upgraded, own, unit)
        top_own = indentation_before(self.data, top.start).decode(self.encoding, "replace")
        for extra in created:  # new top-level elements, after the top-level element
            text = (self.newline + top_own).encode(self.encoding) + self.serialise(
                extra, top_own, unit
            )
            self.edits.append(Edit(top.end, top.end, text))
        self.result.elements.append(
            ElementUpgrade(
                _local(node), node.get("name") or "", line, *step, len(created), tuple(dropped)
            )
        )
        self.result.elements.extend(log)

    def rename(self, node: etree._Element, renames: list[tuple[etree._Element, str]]) -> list[Edit]:
        """Edits giving the renamed properties of ``node`` their new names, values kept."""
        renamed_copy = copy.deepcopy(node)
        new_names = {
            index: new for index, child in enumerate(node) for prop, new in renames if child is prop
        }
        for index, child in enumerate(renamed_copy):
            if index in new_names:
                child.tag = etree.QName(etree.QName(child).namespace, new_names[index]).text
        span = self.spans[node]
        own = indentation_before(self.data, span.start).decode(self.encoding, "replace")
        return self.patcher.patch(node, renamed_copy, own, self.indent_unit(node, own))

    def indent_unit(self, node: etree._Element, own: str) -> str:
        children = [c for c in node if isinstance(c.tag, str)]
        if children:
            inner = indentation_before(self.data, self.spans[children[0]].start).decode(
                self.encoding, "replace"
            )
            if inner.startswith(own) and len(inner) > len(own):
                return inner[len(own) :]
        return DEFAULT_INDENT

    def serialise(self, node: etree._Element, own: str | None, unit: str | None) -> bytes:
        """``node`` laid out one child per line from ``own`` by ``unit``, or written
        compactly (no layout at all) when they are None; empty elements as the file writes them."""
        if own is None or unit is None:
            compact_tree(node)
        else:
            indent_tree(node, own, unit)
        node.tail = None
        text = etree.tostring(node, encoding="unicode")
        text = re.sub(r'\sxmlns="' + re.escape(CONFIG_NS) + '"', "", text, count=1)
        if self.spaced_empty:
            text = _EMPTY_TAG_END.sub(" />", text)
        if self.newline != "\n":
            text = text.replace("\n", self.newline)
        return text.encode(self.encoding, "xmlcharrefreplace")

    # -- output ----------------------------------------------------------------------

    def apply(self) -> bytes:
        out = bytearray()
        position = 0
        # Insertions before replacements at the same place; a replacement before the edits
        # it contains, which are then dropped.
        for edit in sorted(self.edits, key=lambda e: (e.start, e.end != e.start, -e.end)):
            if edit.start < position:
                if edit.end <= position:
                    continue  # inside an element that is rewritten as a whole
                raise AssertionError("overlapping upgrade edits")
            out += self.data[position : edit.start]
            out += edit.text
            position = edit.end
        out += self.data[position:]
        return bytes(out)

    def verify(self) -> None:
        upgraded = self.result.upgraded
        if upgraded is None or upgraded == self.data:
            return
        check = parse_bytes(upgraded, self.result.display)
        if check.root is None:
            self.result.upgraded = None
            self.problem(
                "the upgraded file would not be well-formed; not changed "
                f"({check.diagnostics[0].message if check.diagnostics else 'unknown error'})"
            )


def upgrade_bytes(
    path: Path,
    data: bytes,
    repo: DefinitionRepository,
    display: str | None = None,
    environ: Mapping[str, str] | None = None,
    *,
    drop_removed: bool = False,
) -> FileUpgrade:
    """Upgrade the content ``data`` of ``path`` (which is not read or written)."""
    return FileUpgrader(
        path, data, display or str(path), repo, environ, drop_removed=drop_removed
    ).run()


def upgrade_file(
    path: Path,
    repo: DefinitionRepository,
    display: str | None = None,
    environ: Mapping[str, str] | None = None,
    max_size: int = DEFAULT_MAX_SIZE,
    *,
    drop_removed: bool = False,
) -> FileUpgrade:
    """Upgrade the file ``path`` (read with the size limit; not written). A file above the
    limit or not a regular file is a failed upgrade with its diagnostic; other I/O errors
    raise :class:`OSError`."""
    try:
        data = read_limited(path, max_size)
    except (FileTooLarge, NotRegularFile) as err:
        shown = display or str(path)
        result = FileUpgrade(path, shown, b"")
        code = "XML004" if isinstance(err, FileTooLarge) else "XML005"
        result.problems.append(Diagnostic.make(code, err.strerror, shown))
        return result
    return upgrade_bytes(path, data, repo, display, environ, drop_removed=drop_removed)


def with_given_definitions(repo: DefinitionRepository, paths: list[Path]) -> DefinitionRepository:
    """``repo`` with the definitions among ``paths`` put first, as `gadgetctl validate` does."""
    from gadgetctl.jccl.defparser import read_definition
    from gadgetctl.jccl.xmlload import load_file

    definitions = []
    for path in paths:
        if path.suffix == ".jdef":
            doc = load_file(path)
            definition = read_definition(doc, columns=False) if doc.root is not None else None
            if definition is not None and definition.name:
                definitions.append(definition)
    return repo.overlay(definitions) if definitions else repo
