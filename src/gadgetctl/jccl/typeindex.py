"""Cached views of element types for checking many elements against one repository.

Effective property maps are computed once per (type, version), inheritance answers once
per pair of types; checking a configuration then costs a few dictionary look-ups per value.
"""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.jccl.definitions import DefinitionVersion, PropertyDefinition
from gadgetctl.jccl.repository import DefinitionRepository, EffectiveProperty


@dataclass(frozen=True, slots=True)
class TypeView:
    """One version of a type with its own and inherited properties, by name."""

    definition: DefinitionVersion
    properties: dict[str, EffectiveProperty]

    @property
    def name(self) -> str:
        return self.definition.name

    @property
    def version(self) -> int:
        return self.definition.version

    def get(self, prop: str) -> PropertyDefinition | None:
        found = self.properties.get(prop)
        return found.definition if found else None


@dataclass(frozen=True, slots=True)
class PropertyOrigin:
    """A type and version whose own properties include a given property."""

    type: str
    version: int


class TypeIndex:
    def __init__(self, repo: DefinitionRepository) -> None:
        self.repo = repo
        self._views: dict[tuple[str, int | None], TypeView | None] = {}
        self._is_a: dict[tuple[str, str], bool] = {}
        self._versions: dict[str, list[int]] = {}
        self._history: dict[tuple[str, str], list[PropertyOrigin]] = {}

    def versions(self, type_name: str) -> list[int]:
        found = self._versions.get(type_name)
        if found is None:
            found = self._versions[type_name] = self.repo.versions(type_name)
        return found

    def newest(self, type_name: str) -> int | None:
        versions = self.versions(type_name)
        return versions[-1] if versions else None

    def view(self, type_name: str, version: int | None = None) -> TypeView | None:
        key = (type_name, version)
        if key not in self._views:
            definition = self.repo.get(type_name, version)
            if definition is None:
                self._views[key] = None
            else:
                props = {
                    p.name: p for p in self.repo.effective_properties(type_name, definition.version)
                }
                self._views[key] = TypeView(definition, props)
        return self._views[key]

    def is_a(self, type_name: str, base: str) -> bool:
        key = (type_name, base)
        found = self._is_a.get(key)
        if found is None:
            found = self._is_a[key] = self.repo.is_a(type_name, base)
        return found

    def is_any(self, type_name: str, bases: tuple[str, ...]) -> bool:
        return any(self.is_a(type_name, base) for base in bases)

    def known(self, type_name: str) -> bool:
        return bool(self.versions(type_name))

    def history(self, type_name: str, prop: str) -> list[PropertyOrigin]:
        """Every version of the type and of its ancestors that defines ``prop`` itself."""
        key = (type_name, prop)
        if key not in self._history:
            found: list[PropertyOrigin] = []
            for owner in (type_name, *self.repo.ancestors(type_name)):
                for number in self.versions(owner):
                    definition = self.repo.get(owner, number)
                    if definition is not None and definition.own_property(prop) is not None:
                        found.append(PropertyOrigin(owner, number))
            self._history[key] = found
        return self._history[key]
