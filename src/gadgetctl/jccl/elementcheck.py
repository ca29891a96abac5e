"""Checks of one element (and its embedded elements) against its definition.

These checks need no other element of the configuration, so their results are kept per
element and shared by every configuration that contains it. Pointer values are collected
on the way for :mod:`gadgetctl.jccl.wiring`.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

from gadgetctl.diagnostics import Diagnostic, Severity
from gadgetctl.jccl.configuration import ConfigElement, PropertyValue, SourceLocation
from gadgetctl.jccl.definitions import Location, PropertyDefinition, ValueType
from gadgetctl.jccl.runtime import RENAMED_PROPERTIES, REQUIRED_POINTERS, renamed_from
from gadgetctl.jccl.typeindex import TypeIndex, TypeView
from gadgetctl.jccl.valuecheck import ValueProblem, check_text
from gadgetctl.suggest import close_names
from gadgetctl.wording import with_article


class PointerValue(NamedTuple):
    """A non-empty pointer value: who points, through which property, at what name. (A named
    tuple: a configuration of 50,000 elements makes 50,000 of them per check.)"""

    element: ConfigElement
    prop: PropertyDefinition
    value: PropertyValue
    target: str  # the value without surrounding white space: the name pointed at


#: PointerValue(...) without the named tuple's Python-level ``__new__``.
_pointer = partial(tuple.__new__, PointerValue)


class ElementReport(list):
    """What checking one element found: its diagnostics and the view of its definition it
    was judged by; the report itself is the list of its pointer values (:attr:`pointers`),
    so that an element with a pointer and no finding (the usual one: 200,000 aliases make
    200,000 reports) costs one list."""

    __slots__ = ("checker", "diagnostics", "notes", "place", "view")

    def __init__(self, checker: ElementChecker | None = None) -> None:
        super().__init__()
        # (an empty tuple until there is something: most elements have no finding)
        self.diagnostics: list[Diagnostic] | tuple[()] = ()
        #: The definition version the element was judged by (None: none).
        self.view: TypeView | None = None
        #: Suggestions that hold unless a plug-in or element has the value's exact name:
        #: (the finding, the value without surrounding white space). None when there are none.
        self.notes: list[tuple[Diagnostic, str]] | None = None
        self.checker = checker  # whose report it is (see ElementChecker.check)
        self.place = -1  # scratch of wiring's pending simulation (its place in a list)

    @property
    def pointers(self) -> list[PointerValue]:
        """The non-empty pointer values of the element and its embedded elements."""
        return self

    def add(self, diagnostic: Diagnostic) -> None:
        if self.diagnostics:
            self.diagnostics.append(diagnostic)
        else:
            self.diagnostics = [diagnostic]

    __hash__ = object.__hash__  # (one report per element: identity)

    def __eq__(self, other: object) -> bool:
        return self is other


def at(code: str, message: str, location: Location | SourceLocation, **kwargs) -> Diagnostic:
    return Diagnostic.make(code, message, location.path, location.line, location.column, **kwargs)


def describe(element: ConfigElement) -> str:
    return f"{element.type} {element.full_name!r}"


class ElementChecker:
    """Checks elements against one repository; results are cached per element."""

    def __init__(self, index: TypeIndex, search_path: str = "") -> None:
        self.index = index
        self.search_path = search_path
        self._values: dict[tuple[int, str], ValueProblem | None] = {}
        self._clean_views: dict[tuple[str, int | None], TypeView] = {}
        self._plans: dict[int, tuple] = {}  # id of a view -> see _plan (which holds the view)

    def check(self, element: ConfigElement) -> ElementReport:
        """The element's report, kept on the element (one per element, not a cache entry:
        a configuration of 200,000 elements would hold 200,000 of those)."""
        report = element.report
        if report is not None and report.checker is self:
            return report
        report = ElementReport(self)
        report.view = self._check(element, report)
        element.report = report
        return report

    # -- one element -----------------------------------------------------------------

    def _check(self, element: ConfigElement, report: ElementReport) -> TypeView | None:
        """Check ``element`` (and its embedded elements) into ``report``; the view it was
        judged by."""
        view = self._judged_view(element, report)
        if view is None:
            return None
        plan = self._plans.get(id(view))
        if plan is None or plan[0] is not view:
            plan = self._plans[id(view)] = self._plan(view)
        _, definitions, required = plan
        for prop_name, values in element.property_items():
            found = definitions.get(prop_name)
            if found is None:
                report.add(self._unknown_property(element, view, prop_name, values[0]))
                continue
            prop, slots = found
            if slots is not None and len(values) != slots:
                self._check_count(element, prop, values, report)
            if prop.valuetype is ValueType.POINTER:  # the usual case of a large configuration
                for value in values:
                    if value.element is None:
                        target = value.text.strip()
                        if target:
                            report.append(_pointer((element, prop, value, target)))
                    else:
                        self._check_value(element, prop, value, report)
                continue
            for value in values:
                self._check_value(element, prop, value, report)
        if required:
            self._check_required(element, required, report)
        return view

    def _plan(
        self, view: TypeView
    ) -> tuple[
        TypeView,
        dict[str, tuple[PropertyDefinition, int | None]],
        list[tuple[PropertyDefinition, str]],
    ]:
        """What checking an element of a view needs, worked out once per view:
        each property's definition with its fixed number of values (None when variable or
        undefined, see :meth:`_check_count`), and the pointers it must set."""
        definitions = {}
        for name, effective in view.properties.items():
            prop = effective.definition
            fixed = None if prop.variable or not prop.values else len(prop.values)
            definitions[name] = (prop, fixed)
        return view, definitions, self._required(view)

    def _judged_view(self, element: ConfigElement, report: ElementReport) -> TypeView | None:
        """The definition version the element is judged by; version and type findings."""
        index, found = self.index, report
        if not element.name.strip():
            found.add(at("CFG015", f"{element.type} element has no name", element.location))
        clean = self._clean_views.get((element.type, element.version))
        if clean is not None:
            return clean
        versions = index.versions(element.type)
        if not versions:
            close = self.index.repo.close_names(element.type, cutoff=0.6)
            hint = f"Did you mean {', '.join(close)}? " if close else ""
            searched = f"Searched: {self.search_path}. " if self.search_path else ""
            found.add(
                at(
                    "CFG010",
                    f"no definition of element type {element.type!r} on the search "
                    f"path; VR Juggler drops {element.full_name!r} when loading",
                    element.location,
                    hint=f"{hint}{searched}Add its .jdef with --definitions DIR or "
                    "JCCL_DEFINITION_PATH, or fix the tag.",
                )
            )
            return None
        newest = versions[-1]
        declared = element.version
        judged: int | None = None
        if declared is None:
            shown = (
                "no version"
                if element.version_text is None
                else f"version {element.version_text!r}"
            )
            found.add(
                at(
                    "CFG014",
                    f"{describe(element)} has {shown}; VR Juggler reads it as 0",
                    element.location,
                    hint=f'Add version="{newest}" if it was written for '
                    f"the newest {element.type} definition.",
                )
            )
        elif declared > newest:
            found.add(
                at(
                    "CFG013",
                    f"{describe(element)} declares version {declared}, newer than "
                    f"any known {element.type} definition (newest: {newest}); checked "
                    f"against version {newest}",
                    element.location,
                )
            )
        elif declared < newest:
            judged = declared if declared in versions else None
            found.add(self._older(element, declared, newest, versions))
        else:
            judged = declared
        view = index.view(element.type, judged)
        assert view is not None
        if judged == newest and not view.definition.abstract:
            # Nothing to say about the type or version of any element of this type and
            # version: the next one is judged by this view at once.
            self._clean_views[(element.type, declared)] = view
        if view.definition.abstract:
            found.add(
                at(
                    "CFG011",
                    f"{describe(element)}: {element.type} is abstract (a base for "
                    "other types); no part of VR Juggler handles it",
                    element.location,
                    hint=self._concrete_hint(element.type),
                )
            )
        return view

    def _older(
        self, element: ConfigElement, declared: int, newest: int, versions: list[int]
    ) -> Diagnostic:
        message = (
            f"{describe(element)} is version {declared}; its definition is at version {newest}"
        )
        if declared not in versions:
            return at(
                "CFG012",
                message + f", and version {declared} is not on the search path, so it "
                f"is checked against version {newest}",
                element.location,
                hint="No upgrade path is known; compare the element with the newest definition by hand.",
            )
        steps = [v for v in versions if declared < v <= newest]
        hint = "Run `gadgetctl upgrade FILE` to bring it up to date."
        if steps != list(range(declared + 1, newest + 1)):
            hint = "Some intermediate versions are missing on the search path, so it cannot be upgraded automatically."
        return at("CFG012", message, element.location, hint=hint)

    def _concrete_hint(self, type_name: str) -> str | None:
        repo = self.index.repo
        derived = [
            n
            for n in repo.names()
            if n != type_name
            and self.index.is_a(n, type_name)
            and not (repo.get(n) and repo.get(n).abstract)
        ]
        return f"Use a concrete type such as {', '.join(derived[:4])}." if derived else None

    # -- properties ------------------------------------------------------------------

    def _unknown_property(
        self, element: ConfigElement, view: TypeView, name: str, first: PropertyValue
    ) -> Diagnostic:
        history = self.index.history(element.type, name)
        judged = f"{element.type} version {view.version}"
        newer = [o for o in history if o.type == element.type and o.version > view.version]
        if newer:
            first_newer = min(o.version for o in newer)
            return at(
                "CFG022",
                f"{describe(element)}: {judged} has no property {name!r}; version "
                f"{first_newer} added it, so the version attribute is probably wrong (upgrading "
                f"from version {view.version} would add {name!r} a second time)",
                first.location,
                hint=f'Set version="{first_newer}" or later if the element was written for it.',
            )
        older = [o for o in history if not (o.type == element.type and o.version >= view.version)]
        if older:
            last = max(older, key=lambda o: (o.type == element.type, o.version))
            owner = "" if last.type == element.type else f" {last.type}"
            renamed = RENAMED_PROPERTIES.get((element.type, name))
            if renamed is not None and renamed in view.properties:
                return at(
                    "CFG021",
                    f"{describe(element)}: {name!r} is no property of {judged}; version "
                    f"{last.version + 1} renamed it {renamed!r}, and VR Juggler ignores the old name",
                    first.location,
                    hint=f"Rename it {renamed!r}, keeping its values (`gadgetctl upgrade FILE` does).",
                )
            return at(
                "CFG021",
                f"{describe(element)}: {name!r} is no property of {judged}; it was "
                f"dropped after{owner} version {last.version}, and VR Juggler ignores it",
                first.location,
                hint="Remove it (`gadgetctl upgrade --drop-removed FILE` does).",
            )
        close = close_names(name, list(view.properties), cutoff=0.6)
        hint = (
            f"Did you mean {', '.join(close)}?"
            if close
            else (f"{element.type} has: {', '.join(view.properties) or 'no properties'}.")
        )
        return at(
            "CFG020",
            f"{describe(element)}: {judged} has no property {name!r}; VR Juggler ignores it",
            first.location,
            hint=hint,
        )

    def _check_count(
        self,
        element: ConfigElement,
        prop: PropertyDefinition,
        values: list[PropertyValue],
        report: ElementReport,
    ) -> None:
        slots = len(prop.values)
        if prop.variable or not slots:  # no slots at all: a broken definition, reported there
            return
        if len(values) > slots:
            report.add(
                at(
                    "CFG023",
                    f"{describe(element)}: {prop.name} has {len(values)} values; its definition "
                    f"has {slots} (VR Juggler ignores the rest)",
                    values[slots].location,
                    hint=f"Remove the value{'s' if len(values) - slots > 1 else ''} after the {_nth(slots)}.",
                )
            )
        elif len(values) < slots:
            missing = [
                f"{s.label or f'slot {i + 1}'} = {s.default!r}"
                if s.default is not None
                else (s.label or f"slot {i + 1}")
                for i, s in enumerate(prop.values)
                if i >= len(values)
            ]
            report.add(
                at(
                    "CFG024",
                    f"{describe(element)}: {prop.name} has {len(values)} of {slots} values; "
                    f"defaults fill in {', '.join(missing)}",
                    values[-1].location,
                )
            )

    def _check_value(
        self,
        element: ConfigElement,
        prop: PropertyDefinition,
        value: PropertyValue,
        report: ElementReport,
    ) -> None:
        """One value's findings (a pointer's plain values are taken by :meth:`_check`)."""
        if prop.valuetype is ValueType.CONFIGELEMENT:
            if value.element is None:
                if value.stripped:
                    report.add(
                        at(
                            "CFG029",
                            f"{describe(element)}: {prop.name} holds text {value.stripped!r}; "
                            "it takes an embedded element",
                            value.location,
                        )
                    )
                return
            self._check_embedded(element, prop, value, report)
            return
        if value.element is not None:
            report.add(
                at(
                    "CFG029",
                    f"{describe(element)}: {prop.name} holds an embedded "
                    f"{value.element.type}; it takes {with_article(prop.valuetype.value)} value",
                    value.location,
                )
            )
            return
        key = (id(prop), value.text)
        try:
            problem = self._values[key]
        except KeyError:
            problem = self._values[key] = check_text(prop, value.text)
        if problem is None:
            return
        if problem.note:
            if report.notes is None:
                report.notes = []
            report.notes.append(
                (
                    at(
                        problem.code,
                        f"{describe(element)}: {problem.message}",
                        value.location,
                        hint=problem.hint,
                        severity=Severity.INFO,
                    ),
                    value.text.strip(),
                )
            )
            return
        report.add(
            at(
                problem.code,
                f"{describe(element)}: {problem.message}",
                value.location,
                hint=problem.hint,
            )
        )

    def _check_embedded(
        self,
        element: ConfigElement,
        prop: PropertyDefinition,
        value: PropertyValue,
        report: ElementReport,
    ) -> None:
        child = value.element
        assert child is not None
        allowed = prop.allowed_types
        if (
            allowed
            and all(self.index.known(t) for t in allowed)
            and self.index.known(child.type)
            and not self.index.is_any(child.type, allowed)
        ):
            report.add(
                at(
                    "CFG030",
                    f"{describe(element)}: {prop.name} allows {_types(allowed)}, not "
                    f"{child.type} ({child.name!r})",
                    child.location,
                )
            )
        self._check(child, report)

    def _required(self, view: TypeView) -> list[tuple[PropertyDefinition, str]]:
        """The pointers an element of ``view`` must set, with what happens when one is not."""
        found = []
        for base, prop_name, effect in REQUIRED_POINTERS:
            prop = view.get(prop_name)
            if prop is None:  # an old version: the same pointer under its old name
                old_name = renamed_from(view.name, prop_name)
                prop = view.get(old_name) if old_name is not None else None
            if (
                prop is not None
                and prop.valuetype is ValueType.POINTER
                and self.index.is_a(view.name, base)
            ):
                found.append((prop, effect))
        return found

    def _check_required(
        self,
        element: ConfigElement,
        required: list[tuple[PropertyDefinition, str]],
        report: ElementReport,
    ) -> None:
        for prop, effect in required:
            prop_name = prop.name
            values = element.values(prop_name)
            if values and _any_set(values):
                continue
            where = values[0].location if values else element.location
            state = "is empty" if values else "is not set"
            report.add(
                at(
                    "CFG033",
                    f"{describe(element)}: {prop_name} {state}; {effect}",
                    where,
                    hint=f"Name the {_types(prop.allowed_types) if prop.allowed_types else 'element'} it should use.",
                )
            )


def _any_set(values: list[PropertyValue]) -> bool:
    """Whether any value is non-blank or an embedded element (the first one, nearly always)."""
    first = values[0]
    return bool(
        first.element is not None
        or first.text.strip()
        or any(v.element is not None or v.text.strip() for v in values[1:])
    )


def _types(names: tuple[str, ...]) -> str:
    return " or ".join(names) if len(names) <= 2 else ", ".join(names[:-1]) + " or " + names[-1]


def _nth(n: int) -> str:
    return {1: "first", 2: "second", 3: "third"}.get(n, f"{n}th")
