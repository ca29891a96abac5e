"""Loading configurations: files, includes (to any depth) and definition paths.

Includes are resolved against the including file's directory first and then the working
directory (VR Juggler tries the working directory first, which makes a configuration's
meaning depend on where it is started). Missing includes and include cycles are reported
and the rest still loads. Elements keep their file, line and column.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.envvars import expand
from gadgetctl.files import is_file
from gadgetctl.jccl.configuration import (
    ConfigElement,
    ConfigFile,
    Configuration,
    PropertyValue,
    SourceLocation,
    TagLocation,
)
from gadgetctl.jccl.definitions import Location
from gadgetctl.jccl.xmlload import DEFAULT_MAX_SIZE, XmlDocument, has_unsaved, load_file


def _local(node) -> str | None:
    tag = node.tag
    return tag.rpartition("}")[2] if isinstance(tag, str) else None


class ElementReader:
    """Builds :class:`ConfigElement` objects from the ``<elements>`` of one document."""

    def __init__(self, doc: XmlDocument) -> None:
        self.doc = doc
        # Property tags of each name seen so far on the current line (elements are read in
        # document order, so lines only grow): on a file written on one line, the n-th
        # <device> of the line is the n-th of the document.
        self._line: int | None = None
        self._on_line: dict[str, int] = {}
        self.embedded = 0  # embedded elements read

    def location(self, node: etree._Element) -> SourceLocation:
        return SourceLocation(self.doc, node)

    def read(
        self,
        node: etree._Element,
        parent: ConfigElement | None = None,
        parent_property: str | None = None,
    ) -> ConfigElement:
        name = node.get("name")
        element = ConfigElement(
            node.tag.rpartition("}")[2],  # (an element: the caller skips comments)
            "" if name is None else name,
            node.get("version"),
            SourceLocation(self.doc, node),
            {},
            parent,
            parent_property,
            node,
        )
        doc = self.doc
        properties = element.properties
        on_line = self._on_line
        for child in node:
            tag = child.tag
            if not isinstance(tag, str):
                continue
            prop = tag.rpartition("}")[2]
            embedded = None
            if len(child):  # rare: an embedded element, or text mixed with comments
                embedded = next((c for c in child if isinstance(c.tag, str)), None)
                text = "" if embedded is not None else "".join(child.itertext())
            else:
                text = child.text or ""
            line = child.sourceline
            if line != self._line:
                self._line = line
                on_line = self._on_line = {}
            index = on_line.get(prop, 0)
            on_line[prop] = index + 1
            value = PropertyValue(text=text, location=TagLocation(doc, line, prop, index))
            if embedded is not None:
                self.embedded += 1
                value.element = self.read(embedded, element, prop)
            values = properties.get(prop)
            if values is None:
                properties[prop] = [value]
            else:
                values.append(value)
        return element


def read_config_file(doc: XmlDocument, path: Path) -> ConfigFile:
    """The includes, definition directories and elements of one parsed configuration."""
    config = ConfigFile(path=path, display=doc.path)
    root = doc.root
    if root is None:
        return config
    config.name = root.get("name")
    reader = ElementReader(doc)
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
            config.elements.extend(reader.read(e) for e in child if isinstance(e.tag, str))
    config.embedded = reader.embedded
    return config


class ConfigurationLoader:
    def __init__(
        self,
        *,
        environ: Mapping[str, str] | None = None,
        max_size: int = DEFAULT_MAX_SIZE,
        documents: dict[Path, XmlDocument] | None = None,
        files: dict[Path, ConfigFile] | None = None,
    ) -> None:
        self.environ = os.environ if environ is None else environ
        self.max_size = max_size
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
            doc = load_file(resolved, max_size=self.max_size, display=display)
            self.documents[resolved] = doc
            self.configuration.diagnostics.extend(
                d for d in doc.diagnostics if d.code.startswith("XML0")
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
) -> Configuration:
    return ConfigurationLoader(environ=environ, documents=documents, files=files).load(paths)


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
