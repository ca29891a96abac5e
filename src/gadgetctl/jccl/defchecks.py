"""Definition-level checks of .jdef files, against the definition repository."""

from __future__ import annotations

from collections.abc import Iterable

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.jccl.definitions import (
    Definition,
    DefinitionVersion,
    Location,
    ValueType,
    parse_value,
)
from gadgetctl.jccl.repository import DefinitionRepository
from gadgetctl.wording import counted

_TYPED = (ValueType.INTEGER, ValueType.FLOAT, ValueType.BOOLEAN)


def _at(code: str, message: str, location: Location | None, **kwargs) -> Diagnostic:
    if location is None:
        return Diagnostic.make(code, message, **kwargs)
    return Diagnostic.make(code, message, location.path, location.line, location.column, **kwargs)


def check_definition(
    definition: Definition, order: list[int], repo: DefinitionRepository
) -> list[Diagnostic]:
    """Checks of one definition file. ``order`` is the version numbers as written."""
    found: list[Diagnostic] = []
    found += _check_version_order(definition, order)
    newest = max(definition.versions) if definition.versions else None
    for number in sorted(definition.versions):
        version = definition.versions[number]
        found += _check_properties(version, repo, newest=number == newest)
        found += _check_parents(version, repo)
        if number != min(definition.versions) and version.upgrade_transform is None:
            found.append(
                _at(
                    "DEF011",
                    f"{definition.name} version {number} has no upgrade transform from "
                    f"version {_previous(definition, number)}",
                    version.location,
                )
            )
    return found


def _previous(definition: Definition, number: int) -> int:
    return max(v for v in definition.versions if v < number)


def _check_version_order(definition: Definition, order: list[int]) -> list[Diagnostic]:
    found = []
    seen: set[int] = set()
    for position, number in enumerate(order):
        location = (
            definition.versions[number].location
            if number in definition.versions
            else definition.location
        )
        if number in seen:
            found.append(
                _at(
                    "DEF010",
                    f"version {number} of {definition.name} is defined more than once",
                    definition.location,
                )
            )
        elif position and number < max(order[:position]):
            found.append(
                _at(
                    "DEF009",
                    f"version {number} of {definition.name} comes after version "
                    f"{max(order[:position])}",
                    location,
                )
            )
        seen.add(number)
    return found


def _check_properties(
    version: DefinitionVersion, repo: DefinitionRepository, *, newest: bool
) -> list[Diagnostic]:
    found: list[Diagnostic] = []
    names: set[str] = set()
    label = f"{version.name} v{version.version}"
    for prop in version.properties:
        where = prop.location
        if prop.name in names:
            found.append(_at("DEF007", f"{label}: property {prop.name!r} is defined twice", where))
        names.add(prop.name)
        if prop.valuetype in _TYPED:
            for slot in prop.values:
                if (
                    slot.default is not None
                    and slot.default.strip()
                    and not parse_value(prop.valuetype, slot.default)[0]
                ):
                    found.append(
                        _at(
                            "DEF001",
                            f"{label}: default {slot.default!r} of {prop.name!r} "
                            f"is not a valid {prop.valuetype.value}",
                            where,
                        )
                    )
            if prop.enumeration:
                for choice in prop.enumeration.choices:
                    if not parse_value(prop.valuetype, choice.value)[0]:
                        found.append(
                            _at(
                                "DEF002",
                                f"{label}: enumeration entry {choice.label!r} of "
                                f"{prop.name!r} has value {choice.value!r}, not a valid "
                                f"{prop.valuetype.value}",
                                where,
                            )
                        )
        if prop.variable and len(prop.values) != 1:
            found.append(
                _at(
                    "DEF003",
                    f"{label}: variable property {prop.name!r} has {len(prop.values)} "
                    "template values; expected exactly one",
                    where,
                )
            )
        for allowed in prop.allowed_types:
            if allowed not in repo:
                found.append(
                    _at(
                        "DEF004",
                        f"{label}: allowed type {allowed!r} of {prop.name!r} is not defined "
                        "on the search path",
                        where,
                        severity=None if newest else Severity.INFO,
                        hint=_suggest(allowed, repo),
                    )
                )
        inherited = _inherited_property(version, prop.name, repo)
        if inherited is not None and inherited.valuetype is not prop.valuetype:
            found.append(
                _at(
                    "DEF008",
                    f"{label}: property {prop.name!r} is {prop.valuetype.value} here but "
                    f"{inherited.valuetype.value} in the inherited definition",
                    where,
                )
            )
    return found


def _inherited_property(version: DefinitionVersion, name: str, repo: DefinitionRepository):
    owners = repo.property_owners(name) - {version.name}
    if not owners:  # nobody else declares it: no ancestor walk (linear in long chains)
        return None
    for ancestor in repo.ancestors(version.name, version.version):
        parent = repo.get(ancestor) if ancestor in owners else None
        if parent is not None:
            prop = parent.own_property(name)
            if prop is not None:
                return prop
    return None


def _check_parents(version: DefinitionVersion, repo: DefinitionRepository) -> list[Diagnostic]:
    found = []
    for parent in version.parents:
        if parent not in repo:
            found.append(
                _at(
                    "DEF005",
                    f"{version.name} v{version.version}: parent {parent!r} is not defined "
                    "on the search path",
                    version.location,
                    hint=_suggest(parent, repo),
                )
            )
    return found


_CYCLE_PATH_SHOWN = 8


def check_cycles(definitions: Iterable[Definition], repo: DefinitionRepository) -> list[Diagnostic]:
    """One DEF006 per definition given that takes part in an inheritance cycle.

    Each message shows at most ``_CYCLE_PATH_SHOWN`` steps of the cycle, so a cycle of N
    definitions costs O(N) to report, not O(N^2)."""
    mine = {d.name: d for d in definitions}
    found = []
    for cycle in repo.cycles():
        members = set(cycle)
        for name in cycle:
            if name in mine:
                steps, cut = _cycle_path(name, members, repo)
                path = " -> ".join([name, *steps])
                if cut:
                    path += f" -> ... (a cycle of {counted(len(cycle), 'definition')})"
                found.append(
                    _at(
                        "DEF006", f"{name} inherits from itself: {path}", mine[name].newest.location
                    )
                )
    return found


def _cycle_path(
    start: str, members: set[str], repo: DefinitionRepository
) -> tuple[list[str], bool]:
    """The first steps of the cycle from ``start``, and whether the walk was cut short."""
    path, current, seen = [], start, {start}
    while len(path) < _CYCLE_PATH_SHOWN:
        nxt = next((p for p in repo.parents_of(current) if p in members), None)
        if nxt is None:
            return path, False
        path.append(nxt)
        if nxt in seen:
            return path, False
        seen.add(nxt)
        current = nxt
    return path, True


def _suggest(name: str, repo: DefinitionRepository) -> str | None:
    close = repo.close_names(name, cutoff=0.6)
    return f"Did you mean {', '.join(close)}?" if close else None
