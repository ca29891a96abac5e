"""The configuration model: element instances read from .jconf files."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.definitions import Location

EMBEDDED_SEPARATOR = "/"


class SourceLocation:
    """Where a node of a parsed document starts. Looking up the column costs a search of the
    source line, so line and column are found on first use only (most nodes never need them)."""

    __slots__ = ("_doc", "_found", "_node")

    def __init__(self, doc, node: etree._Element) -> None:
        self._doc = doc
        self._node = node
        self._found: tuple[int | None, int | None] | None = None

    def _locate(self) -> tuple[int | None, int | None]:
        if self._found is None:
            self._found = self._doc.locate(self._node)
        return self._found

    @property
    def path(self) -> str:
        return self._doc.path

    @property
    def line(self) -> int | None:
        return self._locate()[0]

    @property
    def column(self) -> int | None:
        return self._locate()[1]

    def resolved(self) -> Location:
        return Location(self.path, self.line, self.column)

    def __str__(self) -> str:
        return str(self.resolved())

    def __repr__(self) -> str:
        return f"SourceLocation({self})"


class TagLocation(SourceLocation):
    """Where a start tag without attributes (a property value) is, from its line, name and
    how many tags of that name come before it on that line. Keeps no reference to the
    parsed node, so that a large configuration does not pin one lxml proxy per value."""

    __slots__ = ("_index", "_line", "_local")

    def __init__(self, doc, line: int | None, local: str, index: int = 0) -> None:
        self._doc = doc
        self._node = None
        self._found = None
        self._line = line
        self._local = local
        self._index = index

    def _locate(self) -> tuple[int | None, int | None]:
        if self._found is None:
            self._found = self._doc.locate_tag(self._line, self._local, self._index)
        return self._found


@dataclass(slots=True)
class PropertyValue:
    """One value of a property: the text as written, or an embedded element."""

    text: str
    location: Location | SourceLocation
    element: ConfigElement | None = None

    @property
    def stripped(self) -> str:
        return self.text.strip()


def _version_number(text: str | None) -> int | None:
    try:
        return int((text or "").strip())
    except ValueError:
        return None


#: The number of each version attribute text seen (a file holds a handful of them).
_VERSION_NUMBERS: dict[str | None, int | None] = {}


@dataclass(eq=False, slots=True, init=False)
class ConfigElement:
    type: str
    name: str
    version_text: str | None
    location: Location | SourceLocation
    properties: dict[str, list[PropertyValue]]
    parent: ConfigElement | None
    parent_property: str | None
    node: etree._Element | None = field(repr=False)
    #: The version attribute as a number (None when missing or not a number), read once: a
    #: configuration of 50,000 elements asks for it several times per element.
    version: int | None = field(init=False, repr=False)

    def __init__(
        self,
        type: str,
        name: str,
        version_text: str | None,
        location: Location | SourceLocation,
        properties: dict[str, list[PropertyValue]] | None = None,
        parent: ConfigElement | None = None,
        parent_property: str | None = None,
        node: etree._Element | None = None,
    ) -> None:
        # (written out rather than generated: 50,000 elements are made per large check)
        self.type = type
        self.name = name
        self.version_text = version_text
        self.location = location
        self.properties = {} if properties is None else properties
        self.parent = parent
        self.parent_property = parent_property
        self.node = node
        try:
            self.version = _VERSION_NUMBERS[version_text]
        except KeyError:
            self.version = _version_number(version_text)
            if len(_VERSION_NUMBERS) < 1024:
                _VERSION_NUMBERS[version_text] = self.version

    @property
    def file(self) -> str:
        return self.location.path

    @property
    def full_name(self) -> str:
        """``parent/property/child`` for embedded elements, as VR Juggler names them."""
        if self.parent is None:
            return self.name
        return EMBEDDED_SEPARATOR.join(
            (self.parent.full_name, self.parent_property or "", self.name)
        )

    def values(self, prop: str) -> list[PropertyValue]:
        return self.properties.get(prop, [])

    def texts(self, prop: str) -> list[str]:
        return [v.stripped for v in self.values(prop)]

    def embedded(self) -> Iterator[ConfigElement]:
        """Embedded elements, depth-first."""
        for values in self.properties.values():
            for value in values:
                if value.element is not None:
                    yield value.element
                    yield from value.element.embedded()


@dataclass
class ConfigFile:
    path: Path
    display: str
    includes: list[tuple[str, Location]] = field(default_factory=list)
    definition_dirs: list[tuple[str, Location]] = field(default_factory=list)
    elements: list[ConfigElement] = field(default_factory=list)
    name: str | None = None
    embedded: int = 0  # how many embedded elements (at any depth) its elements hold


@dataclass
class Configuration:
    """One or more files loaded together, includes followed."""

    files: list[ConfigFile] = field(default_factory=list)
    loaded: list[ConfigElement] = field(
        default_factory=list
    )  # every top-level element, in load order
    diagnostics: list[Diagnostic] = field(default_factory=list)
    #: The files given, in order (resolved paths), and each file's resolved includes.
    roots: list[Path] = field(default_factory=list)
    includes: dict[Path, list[Path]] = field(default_factory=dict)
    _effective: tuple[int, list[ConfigElement]] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    def reachable(self, start: Path) -> set[Path]:
        """``start`` and every file it includes, directly or not."""
        seen = {start}
        stack = [start]
        while stack:
            for target in self.includes.get(stack.pop(), ()):
                if target not in seen:
                    seen.add(target)
                    stack.append(target)
        return seen

    @property
    def elements(self) -> list[ConfigElement]:
        """The effective elements: a later element replaces an earlier one of the same name in
        place, as VR Juggler's ``Configuration::add`` does (so an including file overrides
        its includes). Worked out again only when ``loaded`` has changed length (elements are
        only ever appended to it); a fresh list each time, so callers may change theirs."""
        cached = self._effective
        if cached is None or cached[0] != len(self.loaded):
            cached = self._effective = (len(self.loaded), self._effective_elements())
        return list(cached[1])

    def _effective_elements(self) -> list[ConfigElement]:
        result: list[ConfigElement] = []
        index: dict[str, int] = {}
        for element in self.loaded:
            if element.name in index:
                result[index[element.name]] = element
            else:
                index[element.name] = len(result)
                result.append(element)
        return result

    def get(self, name: str) -> ConfigElement | None:
        for element in self.elements:
            if element.name == name:
                return element
        return None

    def by_type(self, type_name: str) -> list[ConfigElement]:
        return [e for e in self.elements if e.type == type_name]

    def may_embed(self) -> bool:
        """Whether some top-level element may hold embedded elements: false only when every
        loaded element was read from a file and none of those files had any, which spares
        checks of 50,000 elements a look into each."""
        files = self.files
        return any(f.embedded for f in files) or len(self.loaded) != sum(
            len(f.elements) for f in files
        )

    def all_elements(self) -> Iterator[ConfigElement]:
        """Effective top-level elements and, after each, its embedded elements."""
        for element in self.elements:
            yield element
            yield from element.embedded()
