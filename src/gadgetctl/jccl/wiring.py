"""Checks across the elements of one configuration: pointers, duplicate names, and which
elements VR Juggler would leave pending.

The pending simulation follows the ConfigManager (reference section 4): an element becomes
active once every non-empty pointer of it and of its embedded elements names an active
top-level element; stupefiable proxies and cluster nodes skip that test; some handlers
refuse old versions, and gesture proxies are never handled.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from difflib import get_close_matches

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.jccl.configuration import ConfigElement, Configuration
from gadgetctl.jccl.elementcheck import ElementReport, PointerValue, at, describe
from gadgetctl.jccl.runtime import (
    MINIMUM_VERSIONS,
    NEVER_HANDLED,
    NO_DEPENDENCY_CHECK,
    missing_target_effect,
)
from gadgetctl.jccl.typeindex import TypeIndex


@dataclass(frozen=True, slots=True)
class Scope:
    """How complete the configuration is, for wording and severity of missing targets."""

    complete: bool
    root: str  # the file (or files) the configuration was loaded from, for messages

    def nowhere(self) -> str:
        if self.complete:
            return "no element of the configuration has that name"
        return (f"no element in {self.root} or its includes has that name; it may come from another "
                "file loaded with it (check them together with --together)")


class Wiring:
    def __init__(self, config: Configuration, reports: dict[int, ElementReport], index: TypeIndex,
                 scope: Scope) -> None:
        self.config = config
        self.reports = reports
        self.index = index
        self.scope = scope
        self.effective = config.elements
        self.by_name = {e.name: e for e in self.effective}
        self.embedded = {c.full_name: c for e in self.effective for c in e.embedded()}

    def check(self) -> list[Diagnostic]:
        found = self.duplicates()
        for element in self.config.loaded:
            for pointer in self.reports[id(element)].pointers:
                found.extend(self.pointer(pointer, element))
        found.extend(self.pending())
        return found

    # -- names -----------------------------------------------------------------------

    def duplicates(self) -> list[Diagnostic]:
        found = []
        first: dict[str, ConfigElement] = {}
        for element in self.config.loaded:
            if not element.name.strip():
                continue
            earlier = first.setdefault(element.name, element)
            if earlier is element:
                continue
            same_file = earlier.file == element.file
            found.append(at(
                "CFG040", f"element name {element.name!r} ({element.type}) is used before, by the "
                f"{earlier.type} at {earlier.location}; VR Juggler keeps only the later one, at the "
                "earlier one's place", element.location,
                severity=Severity.ERROR if same_file else None,
                hint="Rename or remove one of them." if same_file else
                "If this element is meant to override the other, remove the other; otherwise rename one."))
        return found

    # -- pointers --------------------------------------------------------------------

    def pointer(self, pointer: PointerValue, root: ConfigElement) -> list[Diagnostic]:
        target = self.by_name.get(pointer.target)
        prop = pointer.prop
        who = f"{describe(pointer.element)}: {prop.name} {pointer.target!r}"
        if target is None:
            if pointer.target in self.embedded:
                return []  # found, but never satisfies a dependency: see pending()
            close = get_close_matches(pointer.target, list(self.by_name), n=3, cutoff=0.7)
            return [at("CFG031", f"{who}: {self.scope.nowhere()}; {missing_target_effect(root.type)}",
                       pointer.value.location,
                       severity=Severity.ERROR if self.scope.complete else None,
                       hint=f"Did you mean {', '.join(repr(c) for c in close)}?" if close else None)]
        allowed = prop.allowed_types
        index = self.index
        if allowed and all(index.known(t) for t in allowed) and index.known(target.type) \
                and not index.is_any(target.type, allowed):
            return [at("CFG032", f"{who} is a {target.type} (at {target.location}); {prop.name} "
                       f"takes {' or '.join(allowed)}", pointer.value.location)]
        return []

    # -- pending ---------------------------------------------------------------------

    def _blocked(self, element: ConfigElement) -> str | None:
        """Why the element can never become active whatever the others do, or None."""
        view = self.reports[id(element)].views.get(id(element))
        if view is None or view.definition.abstract:
            return "unhandled"  # reported as CFG010 / CFG011
        minimum = MINIMUM_VERSIONS.get(element.type)
        if minimum is not None and (element.version or 0) < minimum:
            return (f"VR Juggler refuses {element.type} elements older than version {minimum} "
                    f"(this one is version {element.version or 0})")
        return NEVER_HANDLED.get(element.type)

    def pending(self) -> list[Diagnostic]:
        waiting: dict[str, list[ConfigElement]] = defaultdict(list)
        unmet: dict[int, int] = {}
        ready: list[ConfigElement] = []
        blocked: dict[int, str] = {}
        for element in self.effective:
            reason = self._blocked(element)
            if reason is not None:
                blocked[id(element)] = reason
                continue
            deps = set() if element.type in NO_DEPENDENCY_CHECK else \
                {p.target for p in self.reports[id(element)].pointers}
            unmet[id(element)] = len(deps)
            for dep in deps:
                waiting[dep].append(element)
            if not deps:
                ready.append(element)
        active: set[str] = set()
        while ready:
            element = ready.pop()
            if element.name in active:
                continue
            active.add(element.name)
            for dependent in waiting.get(element.name, ()):
                unmet[id(dependent)] -= 1
                if unmet[id(dependent)] == 0:
                    ready.append(dependent)
        found = []
        for element in self.effective:
            if element.name in active:
                continue
            reason = blocked.get(id(element))
            if reason == "unhandled":
                continue
            if reason is not None:
                found.append(at("CFG041", f"{describe(element)} would stay pending: {reason}",
                                element.location))
                continue
            found.extend(self._waiting(element, active))
        return found

    def _waiting(self, element: ConfigElement, active: set[str]) -> list[Diagnostic]:
        reasons: list[tuple[PointerValue, str]] = []
        for pointer in self.reports[id(element)].pointers:
            name = pointer.target
            if name in active:
                continue
            target = self.by_name.get(name)
            if target is None and name in self.embedded:
                reasons.append((pointer, f"{pointer.prop.name} names the embedded element {name!r}, "
                                "and VR Juggler only looks for top-level elements"))
            elif target is not None:
                why = "which stays pending itself"
                if self._blocked(target) == "unhandled":
                    why = ("whose type VR Juggler does not handle" if self.index.known(target.type)
                           else "which VR Juggler drops because its type has no definition")
                reasons.append((pointer, f"it waits for {target.type} {name!r}, {why}"))
        if not reasons:
            return []  # only missing targets: reported as CFG031
        pointer, text = reasons[0]
        more = f" (and {len(reasons) - 1} more)" if len(reasons) > 1 else ""
        severity = None if self.scope.complete or not self._rooted_in_missing(element, active) \
            else Severity.WARNING
        return [at("CFG041", f"{describe(element)} would stay pending: {text}{more}",
                   pointer.value.location, severity=severity)]

    def _rooted_in_missing(self, element: ConfigElement, active: set[str]) -> bool:
        """True when a chain of unmet pointers from ``element`` ends at a name no element has."""
        seen: set[int] = set()
        stack = [element]
        while stack:
            current = stack.pop()
            if id(current) in seen:
                continue
            seen.add(id(current))
            for pointer in self.reports[id(current)].pointers:
                if pointer.target in active:
                    continue
                target = self.by_name.get(pointer.target)
                if target is None:
                    if pointer.target not in self.embedded:
                        return True
                else:
                    stack.append(target)
        return False


def check_wiring(config: Configuration, reports: dict[int, ElementReport], index: TypeIndex,
                 scope: Scope) -> list[Diagnostic]:
    return Wiring(config, reports, index, scope).check()
