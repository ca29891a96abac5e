"""The configuration model: element instances read from .jconf files."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.definitions import Location

EMBEDDED_SEPARATOR = "/"


@dataclass(slots=True)
class PropertyValue:
    """One value of a property: the text as written, or an embedded element."""

    text: str
    location: Location
    element: ConfigElement | None = None

    @property
    def stripped(self) -> str:
        return self.text.strip()


@dataclass(eq=False)
class ConfigElement:
    type: str
    name: str
    version_text: str | None
    location: Location
    properties: dict[str, list[PropertyValue]] = field(default_factory=dict)
    parent: ConfigElement | None = None
    parent_property: str | None = None
    node: etree._Element | None = field(default=None, repr=False)

    @property
    def version(self) -> int | None:
        try:
            return int((self.version_text or "").strip())
        except ValueError:
            return None

    @property
    def file(self) -> str:
        return self.location.path

    @property
    def full_name(self) -> str:
        """``parent/property/child`` for embedded elements, as VR Juggler names them."""
        if self.parent is None:
            return self.name
        return EMBEDDED_SEPARATOR.join((self.parent.full_name, self.parent_property or "", self.name))

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


@dataclass
class Configuration:
    """One or more files loaded together, includes followed."""

    files: list[ConfigFile] = field(default_factory=list)
    loaded: list[ConfigElement] = field(default_factory=list)  # every top-level element, in load order
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def elements(self) -> list[ConfigElement]:
        """The effective elements: a later element replaces an earlier one of the same name in
        place, as VR Juggler's ``Configuration::add`` does (so an including file overrides
        its includes)."""
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

    def all_elements(self) -> Iterator[ConfigElement]:
        """Effective top-level elements and, after each, its embedded elements."""
        for element in self.elements:
            yield element
            yield from element.embedded()
