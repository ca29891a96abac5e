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
    NEVER_HANDLED,
    NO_DEPENDENCY_CHECK,
    minimum_version,
    missing_target_effect,
)
from gadgetctl.jccl.typeindex import TypeIndex

UNHANDLED = "unhandled"


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
            candidates = self.embedded if "/" in pointer.target else self.by_name
            close = get_close_matches(pointer.target, list(candidates), n=3, cutoff=0.7)
            effect = missing_target_effect(root.type, root.name, pointer.element is not root)
            return [at("CFG031", f"{who}: {self.scope.nowhere()}; {effect}",
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

    def _blocked(self, element: ConfigElement) -> tuple[str, Severity] | None:
        """Why the element can never become active whatever the others do, and how bad that
        is; None when it can."""
        view = self.reports[id(element)].views.get(id(element))
        if view is None or view.definition.abstract:
            return UNHANDLED, Severity.ERROR  # reported as CFG010 / CFG011
        minimum = minimum_version(element.type, self.index.versions(element.type))
        if minimum is not None and (element.version or 0) < minimum:
            return (f"VR Juggler refuses {element.type} elements older than version {minimum} "
                    f"(this one is version {element.version or 0})"), Severity.ERROR
        reason = NEVER_HANDLED.get(element.type)
        return (reason, Severity.WARNING) if reason else None

    def pending(self) -> list[Diagnostic]:
        waiting: dict[str, list[ConfigElement]] = defaultdict(list)
        unmet: dict[int, int] = {}
        ready: list[ConfigElement] = []
        self.blocked: dict[int, tuple[str, Severity]] = {}
        for element in self.effective:
            blocker = self._blocked(element)
            if blocker is not None:
                self.blocked[id(element)] = blocker
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
            blocker = self.blocked.get(id(element))
            if blocker is None:
                found.extend(self._waiting(element, active))
            elif blocker[0] != UNHANDLED:
                found.append(at("CFG041", f"{describe(element)} would stay pending: {blocker[0]}",
                                element.location, severity=blocker[1]))
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
                if self.blocked.get(id(target), ("",))[0] == UNHANDLED:
                    why = ("whose type VR Juggler does not handle" if self.index.known(target.type)
                           else "which VR Juggler drops because its type has no definition")
                reasons.append((pointer, f"it waits for {target.type} {name!r}, {why}"))
        if not reasons:
            return []  # only missing targets: reported as CFG031
        pointer, text = reasons[0]
        more = f" (and {len(reasons) - 1} more)" if len(reasons) > 1 else ""
        return [at("CFG041", f"{describe(element)} would stay pending: {text}{more}",
                   pointer.value.location, severity=self._root_severity(element, active))]

    def _root_severity(self, element: ConfigElement, active: set[str]) -> Severity:
        """The worst of the causes at the ends of the chains of unmet pointers from ``element``:
        a missing target (an error only when the configuration is complete), an element that
        can never be active, an embedded target; a pure waiting cycle is an error."""
        missing = Severity.ERROR if self.scope.complete else Severity.WARNING
        causes: set[Severity] = set()
        seen: set[int] = set()
        stack = [element]
        while stack:
            current = stack.pop()
            if id(current) in seen:
                continue
            seen.add(id(current))
            blocker = self.blocked.get(id(current))
            if blocker is not None:
                causes.add(blocker[1])
                continue
            for pointer in self.reports[id(current)].pointers:
                if pointer.target in active:
                    continue
                target = self.by_name.get(pointer.target)
                if target is not None:
                    stack.append(target)
                else:
                    causes.add(Severity.ERROR if pointer.target in self.embedded else missing)
        if not causes or Severity.ERROR in causes:
            return Severity.ERROR
        return Severity.WARNING


def check_wiring(config: Configuration, reports: dict[int, ElementReport], index: TypeIndex,
                 scope: Scope) -> list[Diagnostic]:
    return Wiring(config, reports, index, scope).check()
