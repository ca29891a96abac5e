"""The resolved configuration behind `gadgetctl config show`: every effective property of
every element, with its value and whether it was written or comes from a default.

Values are given as VR Juggler's run time reads them (trimmed, enumeration labels replaced
by their values); the label is kept alongside. Each element is resolved against the
definition version it is judged by (see :mod:`gadgetctl.jccl.elementcheck`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from gadgetctl.jccl.access import read_float, read_int
from gadgetctl.jccl.configuration import ConfigElement, Configuration, PropertyValue
from gadgetctl.jccl.definitions import PropertyDefinition, ValueType
from gadgetctl.jccl.typeindex import TypeIndex, TypeView
from gadgetctl.jccl.valuecheck import is_number

WRITTEN, DEFAULT = "written", "default"


@dataclass
class ResolvedValue:
    value: str | None  # None for an embedded element
    source: str  # WRITTEN or DEFAULT
    written: str | None = None  # the text as written, when it differs from value
    label: str | None = None  # the enumeration label of the value, if any
    element: ResolvedElement | None = None
    note: str | None = None  # why the value differs from the text, when it is not a label

    def to_dict(self) -> dict[str, object]:
        data: dict[str, object] = {"source": self.source}
        if self.element is not None:
            data["element"] = self.element.to_dict()
        else:
            data["value"] = self.value
        if self.written is not None:
            data["written"] = self.written
        if self.label is not None:
            data["label"] = self.label
        if self.note is not None:
            data["note"] = self.note
        return data


@dataclass
class ResolvedProperty:
    name: str
    valuetype: str
    variable: bool
    values: list[ResolvedValue]
    defined_by: str | None = None  # the ancestor type that defines an inherited property
    known: bool = True  # False: written, but not a property of the definition

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "valuetype": self.valuetype,
            "variable": self.variable,
            "inherited_from": self.defined_by,
            "known": self.known,
            "values": [v.to_dict() for v in self.values],
        }


@dataclass
class ResolvedElement:
    type: str
    name: str
    full_name: str
    version: str | None
    definition_version: int | None
    file: str
    line: int | None
    properties: list[ResolvedProperty] = field(default_factory=list)

    def to_dict(self) -> dict[str, object]:
        return {
            "type": self.type,
            "name": self.name,
            "full_name": self.full_name,
            "version": self.version,
            "definition_version": self.definition_version,
            "file": self.file,
            "line": self.line,
            "properties": [p.to_dict() for p in self.properties],
        }


def judged_view(element: ConfigElement, index: TypeIndex) -> TypeView | None:
    versions = index.versions(element.type)
    if not versions:
        return None
    version = element.version
    return index.view(element.type, version if version in versions else None)


def _text_value(prop: PropertyDefinition, text: str, source: str) -> ResolvedValue:
    raw = text.strip()
    value, label = raw, None
    if prop.enumeration is not None:
        value = prop.enumeration.substitute(raw)
        label = raw if value != raw else prop.enumeration.label_for(value)
    note = None
    if (
        source == WRITTEN
        and prop.valuetype in (ValueType.INTEGER, ValueType.FLOAT)
        and not is_number(prop.valuetype, value)
    ):
        # read as VR Juggler's run time reads it: the leading number, else 0
        read = (
            str(read_int(value)) if prop.valuetype is ValueType.INTEGER else repr(read_float(value))
        )
        kind = "an integer" if prop.valuetype is ValueType.INTEGER else "a number"
        shown = repr(value) if value else "the empty text"
        note = f"{shown} does not parse as {kind}; VR Juggler reads {read}"
        value = read
    written = text if source == WRITTEN and text != value else None
    return ResolvedValue(value, source, written, label, note=note)


class Resolver:
    def __init__(self, index: TypeIndex) -> None:
        self.index = index

    def element(self, element: ConfigElement) -> ResolvedElement:
        view = judged_view(element, self.index)
        resolved = ResolvedElement(
            element.type,
            element.name,
            element.full_name,
            element.version_text,
            view.version if view else None,
            element.location.path,
            element.location.line,
        )
        if view is not None:
            for name, effective in view.properties.items():
                prop = effective.definition
                resolved.properties.append(
                    ResolvedProperty(
                        name,
                        prop.valuetype.value,
                        prop.variable,
                        self.values(prop, element.values(name)),
                        effective.defined_by if effective.defined_by != element.type else None,
                    )
                )
        for name, values in element.properties.items():
            if view is None or name not in view.properties:
                resolved.properties.append(
                    ResolvedProperty(
                        name, "unknown", True, [self.unknown(v) for v in values], known=False
                    )
                )
        return resolved

    def values(self, prop: PropertyDefinition, written: list[PropertyValue]) -> list[ResolvedValue]:
        count = len(written) if prop.variable else max(len(prop.values), len(written))
        result = []
        for i in range(count):
            if i < len(written):
                value = written[i]
                if value.element is not None:
                    result.append(ResolvedValue(None, WRITTEN, element=self.element(value.element)))
                elif prop.valuetype is ValueType.CONFIGELEMENT:
                    result.append(ResolvedValue(value.stripped, WRITTEN))
                else:
                    result.append(_text_value(prop, value.text, WRITTEN))
            else:
                result.append(_text_value(prop, prop.default(i) or "", DEFAULT))
        return result

    def unknown(self, value: PropertyValue) -> ResolvedValue:
        if value.element is not None:
            return ResolvedValue(None, WRITTEN, element=self.element(value.element))
        return ResolvedValue(value.stripped, WRITTEN)


def resolve_configuration(
    config: Configuration, index: TypeIndex, names: list[str] | None = None
) -> list[ResolvedElement]:
    """The effective elements (or those whose name or full name is in ``names``)."""
    resolver = Resolver(index)
    if not names:
        return [resolver.element(e) for e in config.elements]
    wanted = set(names)
    return [
        resolver.element(e)
        for e in config.all_elements()
        if e.name in wanted or e.full_name in wanted
    ]
