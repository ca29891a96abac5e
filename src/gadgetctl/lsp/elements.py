"""Where a scanned position is in JCCL terms: which element (type and version) and which of
its properties, with their definitions from the type index the checks use."""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.jccl.definitions import PropertyDefinition
from gadgetctl.jccl.runtime import REQUIRED_POINTERS
from gadgetctl.jccl.typeindex import TypeIndex, TypeView
from gadgetctl.lsp.syntax import Tag

ELEMENTS = "elements"


@dataclass
class Place:
    """The element and property chain of a position inside ``<elements>``: ``elements`` is
    every open element tag (outermost first), ``prop`` the open property of the innermost
    one, if any."""

    elements: list[Tag]
    prop: Tag | None

    @property
    def element(self) -> Tag | None:
        return self.elements[-1] if self.elements else None


def place_of(stack: list[Tag]) -> Place | None:
    """None when the position is not inside ``<elements>``."""
    names = [t.name for t in stack]
    if ELEMENTS not in names:
        return None
    chain = stack[names.index(ELEMENTS) + 1 :]
    elements = chain[0::2]
    props = chain[1::2]
    prop = props[-1] if len(props) == len(elements) and props else None
    return Place(elements, prop)


def version_of(tag: Tag) -> int | None:
    text = (tag.get("version") or "").strip()
    return int(text) if text.isdigit() and len(text) < 10 else None


def view_of(index: TypeIndex, tag: Tag) -> TypeView | None:
    """The definition version an element tag is judged by (its own when known, else the newest)."""
    versions = index.versions(tag.name)
    if not versions:
        return None
    version = version_of(tag)
    return index.view(tag.name, version if version in versions else None)


def property_of(index: TypeIndex, element: Tag, prop: str) -> PropertyDefinition | None:
    view = view_of(index, element)
    return view.get(prop) if view is not None else None


def required_properties(index: TypeIndex, view: TypeView) -> list[str]:
    """The pointers an element of ``view`` must set (validate's CFG033 rule)."""
    return [
        prop
        for base, prop, _ in REQUIRED_POINTERS
        if prop in view.properties and index.is_a(view.name, base)
    ]


def concrete_types(index: TypeIndex, allowed: tuple[str, ...] = ()) -> list[str]:
    """Non-abstract types (of one of ``allowed`` when given), by name."""
    repo = index.repo
    found = []
    for definition in repo.all_newest():
        if definition.abstract:
            continue
        if allowed and not index.is_any(definition.name, allowed):
            continue
        found.append(definition.name)
    return sorted(found)
