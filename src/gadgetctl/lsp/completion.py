"""Completion: what may be written at a position, from the definitions the document is
judged by and the elements of its configuration (with its includes)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from gadgetctl.jccl.definitions import ValueType
from gadgetctl.lsp.analysis import Model
from gadgetctl.lsp.elements import (
    concrete_types,
    place_of,
    property_of,
    required_properties,
    view_of,
)
from gadgetctl.lsp.syntax import TAG, Context, Tag, Where, context_at, end_tag, local

#: Completion kinds of the protocol used here.
CLASS, PROPERTY, ENUM_MEMBER, VALUE, REFERENCE, FILE, KEYWORD = 7, 10, 20, 12, 18, 17, 14
MAX_ITEMS = 2000  # candidates offered at most (element names of a huge configuration)
MAX_FILES = 500  # include paths looked at, at most


@dataclass(frozen=True)
class Item:
    label: str
    kind: int
    detail: str | None = None
    documentation: str | None = None
    sort: str | None = None


@dataclass(frozen=True)
class Completion:
    start: int  # the completed word's start: items replace start..position
    items: list[Item]
    complete: bool = True  # False: more candidates than MAX_ITEMS, the rest left out


CONFIGURATION_CHILDREN = ("include", "definition_path", "elements")


def complete(model: Model, text: str, offset: int) -> Completion:
    ctx = context_at(text, offset)
    if model.path.suffix == ".jdef":
        items = _definition_file(model, ctx)
    else:
        items = _configuration(model, ctx, text)
    return Completion(ctx.start, items[:MAX_ITEMS], len(items) <= MAX_ITEMS)


def _configuration(model: Model, ctx: Context, text: str) -> list[Item]:
    index = model.index
    names = ctx.names()
    place = place_of(ctx.stack)
    if ctx.where is Where.CLOSING:
        return [Item(names[-1], KEYWORD)] if names else []
    if ctx.where is Where.TAG:
        if not names:
            return [Item("configuration", KEYWORD)]
        if names[-1] == "configuration":
            return [Item(n, KEYWORD) for n in CONFIGURATION_CHILDREN]
        if names[-1] == "definition_path":
            return [Item("dir", KEYWORD)]
        if place is None:
            return []
        if place.element is None or place.prop is not None:
            allowed = ()
            if place.prop is not None and place.element is not None:
                prop = property_of(index, place.element, place.prop.name)
                if prop is None or prop.valuetype is not ValueType.CONFIGELEMENT:
                    return []
                allowed = prop.allowed_types
            return _types(model, allowed)
        return _properties(model, place.element, _written(text, place.element, ctx.start - 1))
    if ctx.where is Where.VALUE:
        if ctx.attribute == "version" and ctx.tag is not None and place is not None:
            versions = index.versions(ctx.tag.name)
            return [
                Item(str(v), VALUE, "newest" if v == versions[-1] else None, sort=f"{9999 - v:04}")
                for v in versions
            ]
        return []
    if ctx.where is Where.ATTRIBUTE:
        if place is not None and ctx.tag is not None:
            return [Item(a, PROPERTY) for a in ("name", "version") if a not in ctx.tag.attributes]
        return []
    # text
    if names and names[-1] == "include":
        return _include_paths(model, ctx.prefix)
    if place is None or place.prop is None or place.element is None:
        return []
    prop = property_of(index, place.element, place.prop.name)
    if prop is None:
        return []
    items: list[Item] = []
    if prop.enumeration is not None:
        for choice in prop.enumeration.choices:
            detail = f"value {choice.value}" if choice.value != choice.label else None
            items.append(Item(choice.label, ENUM_MEMBER, detail))
        if not prop.enumeration.editable:
            return items
    if prop.valuetype is ValueType.BOOLEAN:
        items += [Item("true", VALUE), Item("false", VALUE)]
    elif prop.valuetype is ValueType.POINTER:
        items += _targets(model, prop.allowed_types, place.elements[0].get("name"))
    return items


def _types(model: Model, allowed: tuple[str, ...]) -> list[Item]:
    items = []
    for name in concrete_types(model.index, allowed):
        definition = model.repo.get(name)
        items.append(
            Item(
                name,
                CLASS,
                definition.label if definition is not None else None,
                definition.help if definition is not None else None,
            )
        )
    return items


def _written(text: str, element: Tag, typing: int) -> set[str]:
    """The property tags the element already has (other than the one being typed)."""
    end = end_tag(text, element.start, element.name)
    stop = end[0] - 2 if end is not None else len(text)
    found, depth = set(), 0
    for match in TAG.finditer(text, element.end, max(element.end, stop)):
        closing, name, _, empty = match.groups()
        if closing:
            depth -= 1
        else:
            if depth == 0 and match.start() != typing:
                found.add(local(name))
            if not empty:
                depth += 1
    return found


def _properties(model: Model, element: Tag, written: set[str]) -> list[Item]:
    """The element's properties, the pointers it must set first; one-value properties it
    already has are left out."""
    view = view_of(model.index, element)
    if view is None:
        return []
    required = set(required_properties(model.index, view))
    items = []
    for name, effective in view.properties.items():
        prop = effective.definition
        if name in written and not prop.variable and len(prop.values) <= 1:
            continue
        default = prop.default(0)
        detail = prop.valuetype.value
        if prop.allowed_types:
            detail += f" ({' or '.join(prop.allowed_types)})"
        if default:
            detail += f" = {default}"
        if required:
            detail = ("required; " if name in required else "") + detail
        items.append(
            Item(
                name,
                PROPERTY,
                detail,
                prop.help or None,
                sort=("0" if name in required else "1") + name,
            )
        )
    return items


def _targets(model: Model, allowed: tuple[str, ...], own: str | None) -> list[Item]:
    configuration = model.configuration
    if configuration is None:
        return []
    index = model.index
    items = []
    seen: set[str] = set()
    for element in configuration.elements:
        if not element.name or element.name in seen or element.name == own:
            continue
        if allowed and not (index.known(element.type) and index.is_any(element.type, allowed)):
            continue
        seen.add(element.name)
        items.append(Item(element.name, REFERENCE, element.type, f"{element.file}"))
        if len(items) > MAX_ITEMS:
            break  # (one more than shown: the list says it is incomplete)
    return items


def _include_paths(model: Model, typed: str) -> list[Item]:
    """.jconf files under the document's folder (relative names), the typed folder first."""
    base = model.path.parent
    folder = (base / typed).parent if "/" in typed else base
    items = []
    try:
        for root, dirs, files in os.walk(folder):
            dirs[:] = sorted(d for d in dirs if not d.startswith("."))
            for name in sorted(files):
                if name.endswith(".jconf"):
                    path = Path(root, name)
                    if path == model.path:
                        continue
                    items.append(Item(os.path.relpath(path, base), FILE))
                    if len(items) >= MAX_FILES:
                        return items
            if Path(root) != folder and len(Path(root).relative_to(folder).parts) >= 2:
                dirs[:] = []
    except (OSError, ValueError):
        pass
    return items


def _definition_file(model: Model, ctx: Context) -> list[Item]:
    names = ctx.names()
    if ctx.where is Where.TEXT and names and names[-1] == "parent":
        return [
            Item(d.name, CLASS, d.label, d.help)
            for d in sorted(model.repo.all_newest(), key=lambda d: d.name)
        ]
    if ctx.where is Where.CLOSING and names:
        return [Item(names[-1], KEYWORD)]
    return []
