"""The definition model: element types described by .jdef files (format 3.1)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum


class ValueType(StrEnum):
    BOOLEAN = "boolean"
    INTEGER = "integer"
    FLOAT = "float"
    STRING = "string"
    CONFIGELEMENT = "configelement"
    POINTER = "configelementpointer"


BOOLEAN_SPELLINGS = {"true": True, "1": True, "false": False, "0": False}


def parse_value(valuetype: ValueType, text: str) -> tuple[bool, object]:
    """Parse ``text`` strictly as ``valuetype``: ``(ok, value)``.

    Surrounding whitespace is ignored, as VR Juggler trims values before reading them.
    Booleans accept exactly ``true``, ``false``, ``1`` and ``0``.
    """
    value = text.strip()
    if valuetype is ValueType.INTEGER:
        try:
            return True, int(value, 10)
        except ValueError:
            return False, None
    if valuetype is ValueType.FLOAT:
        try:
            number = float(value)
        except ValueError:
            return False, None
        return (
            not math.isnan(number) and value.lower() not in ("inf", "-inf", "+inf", "infinity")
        ), number
    if valuetype is ValueType.BOOLEAN:
        if value in BOOLEAN_SPELLINGS:
            return True, BOOLEAN_SPELLINGS[value]
        return False, None
    return True, value


@dataclass(frozen=True, slots=True)
class Location:
    """A place in a file: its path, and its line and column where known."""

    path: str
    line: int | None = None
    column: int | None = None

    def __str__(self) -> str:
        parts = [self.path]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)


@dataclass(frozen=True, slots=True)
class ValueSlot:
    """One value of a property: its label and default."""

    label: str
    default: str | None


@dataclass(frozen=True, slots=True)
class EnumChoice:
    """One choice of an enumeration: the label written and the value it stands for."""

    label: str
    value: str


@dataclass(frozen=True, slots=True)
class Enumeration:
    """The choices of a property's value, and whether others may be written."""

    editable: bool
    choices: tuple[EnumChoice, ...]

    def substitute(self, text: str) -> str:
        """Replace labels by values exactly as VR Juggler does.

        Entries are walked in order; whenever the current text equals an entry's label it is
        replaced by that entry's value and the walk goes on (so a value equal to a later
        label is substituted again). Labels are case-sensitive.
        """
        for choice in self.choices:
            if text == choice.label:
                text = choice.value
        return text

    def label_for(self, value: str) -> str | None:
        for choice in self.choices:
            if choice.value == value:
                return choice.label
        return None

    def case_insensitive_label(self, text: str) -> EnumChoice | None:
        lowered = text.lower()
        for choice in self.choices:
            if choice.label.lower() == lowered:
                return choice
        return None


@dataclass(frozen=True, slots=True)
class PropertyDefinition:
    """A property of a definition version: its type, values, and what it allows."""

    name: str
    valuetype: ValueType
    variable: bool
    help: str
    values: tuple[ValueSlot, ...]
    allowed_types: tuple[str, ...] = ()
    enumeration: Enumeration | None = None
    #: (or, read by validate from a file it is given, a configuration.SourceLocation: the
    #: same path, line and column, looked up when a finding needs them)
    location: Location | None = None

    @property
    def count(self) -> int | None:
        """Number of values of a fixed-count property; ``None`` when variable."""
        return None if self.variable else len(self.values)

    def default(self, index: int) -> str | None:
        """The default of value slot ``index`` (the template's for a variable property)."""
        if self.variable:
            return self.values[0].default if self.values else None
        return self.values[index].default if index < len(self.values) else None

    @property
    def is_element_valued(self) -> bool:
        return self.valuetype in (ValueType.CONFIGELEMENT, ValueType.POINTER)


@dataclass(slots=True)
class DefinitionVersion:
    """One version of an element type: its parents, categories and properties."""

    name: str
    version: int
    label: str
    abstract: bool
    help: str
    parents: tuple[str, ...]
    categories: tuple[str, ...]
    properties: tuple[PropertyDefinition, ...]
    upgrade_transform: bytes | None = None
    location: Location | None = None  # (see PropertyDefinition.location)

    def own_property(self, name: str) -> PropertyDefinition | None:
        for prop in self.properties:
            if prop.name == name:
                return prop
        return None


@dataclass(slots=True)
class Definition:
    """All versions of one element type, as read from one file."""

    name: str
    versions: dict[int, DefinitionVersion] = field(default_factory=dict)
    location: Location | None = None  # (see PropertyDefinition.location)
    icon_path: str | None = None
    order: list[int] = field(default_factory=list)  # version numbers as written

    @property
    def newest(self) -> DefinitionVersion:
        return self.versions[max(self.versions)]
