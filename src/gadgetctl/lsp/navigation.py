"""Navigation: where a pointer, an include or an element type leads, what points at an
element, renaming an element with every pointer to it, the outline and folding ranges."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from gadgetctl.envvars import expand
from gadgetctl.jccl.configload import ConfigurationLoader
from gadgetctl.jccl.configuration import ConfigElement
from gadgetctl.jccl.definitions import ValueType
from gadgetctl.jccl.resolve import judged_view
from gadgetctl.lsp.analysis import Model, elements_of, real
from gadgetctl.lsp.elements import place_of, property_of
from gadgetctl.lsp.syntax import (
    COMMENT,
    TAG,
    Where,
    blank_comments,
    context_at,
    local,
    tag_at,
    text_range,
)
from gadgetctl.lsp.text import LineIndex

MAX_SYMBOLS = 20000


@dataclass(frozen=True)
class Spot:
    """A range in a file: offsets into its text (as the model read it)."""

    path: Path
    start: int
    end: int


@dataclass(frozen=True)
class Target:
    """A place in a file given by 1-based line and column (a definition, an element)."""

    path: Path
    line: int | None
    column: int | None


def _text(model: Model, path: Path) -> str | None:
    return model.text if path == model.path else model.text_of(path)


def _tag_spot(model: Model, element: ConfigElement) -> Spot | None:
    path = real(element.file)
    text = _text(model, path)
    if text is None:
        return None
    index = LineIndex(text, utf16=False)
    start = index.at_line_column(element.location.line, element.location.column)
    name = _name_attribute(text, start)
    if name is not None:
        return Spot(path, *name)
    return Spot(path, start, start + 1 + len(element.type))


_NAME_ATTRIBUTE = re.compile(r"""\bname\s*=\s*(["'])([^"'<>]*)\1""")


def _name_attribute(text: str, tag_start: int) -> tuple[int, int] | None:
    """The range of the name attribute's value in the start tag at ``tag_start``."""
    end = text.find(">", tag_start)
    if end < 0:
        return None
    match = _NAME_ATTRIBUTE.search(text, tag_start, end)
    return (match.start(2), match.end(2)) if match else None


def _value_spot(model: Model, path: Path, value) -> Spot | None:
    text = _text(model, path)
    if text is None:
        return None
    index = LineIndex(text, utf16=False)
    start = index.at_line_column(value.location.line, value.location.column)
    tag_end = text.find(">", start)
    if tag_end < 0 or text[tag_end - 1] == "/":
        return None
    return Spot(path, *text_range(text, tag_end + 1))


# -- what is under the cursor ----------------------------------------------------------


@dataclass(frozen=True)
class Under:
    kind: str  # "pointer", "include", "type", "element", "parent"
    text: str
    start: int
    end: int


def under(model: Model, text: str, offset: int) -> Under | None:
    on_tag = tag_at(text, offset)
    if on_tag is not None:
        return Under("type", *on_tag)
    ctx = context_at(text, offset)
    if ctx.where is Where.VALUE and ctx.attribute == "name" and ctx.tag is not None:
        end = offset + len(re.match(r"[^\"'<>]*", text[offset : offset + 4096]).group(0))
        return Under("element", text[ctx.start : end], ctx.start, end)
    if ctx.where is not Where.TEXT or not ctx.stack:
        return None
    tag = ctx.stack[-1]
    start, end = text_range(text, tag.end)
    if not start <= offset <= end:
        return None
    value = text[start:end]
    if tag.name == "include":
        return Under("include", value, start, end)
    if tag.name == "parent" and model.path.suffix == ".jdef":
        return Under("parent", value, start, end)
    place = place_of(ctx.stack)
    if place is not None and place.element is not None and place.prop is not None:
        prop = property_of(model.index, place.element, place.prop.name)
        if prop is not None and prop.valuetype is ValueType.POINTER:
            return Under("pointer", value, start, end)
    return None


# -- go to definition ------------------------------------------------------------------


def definition(model: Model, text: str, offset: int) -> Spot | Target | None:
    found = under(model, text, offset)
    if found is None:
        return None
    if found.kind == "include":
        expanded = expand(found.text, model.environ).text
        target = ConfigurationLoader.resolve_include(expanded, model.path.parent)
        return Target(real(target), 1, 1) if target is not None else None
    if found.kind == "pointer":
        element = _named(model, found.text)
        return _tag_spot(model, element) if element is not None else None
    if found.kind in ("type", "parent"):
        definition = model.repo.get(found.text)
        if definition is None or definition.location is None:
            return None
        location = definition.location
        return Target(real(location.path), location.line, location.column)
    return None


def _named(model: Model, name: str) -> ConfigElement | None:
    configuration = model.configuration
    if configuration is None:
        return None
    for element in configuration.all_elements():
        if element.name == name or element.full_name == name:
            return element
    return None


# -- references and rename -------------------------------------------------------------


def _pointers_to(model: Model, name: str) -> list[Spot]:
    configuration = model.configuration
    if configuration is None:
        return []
    spots = []
    for config_file in configuration.files:
        for element in elements_of(model, config_file.path):
            view = judged_view(element, model.index)
            if view is None:
                continue
            for prop_name, values in element.properties.items():
                prop = view.get(prop_name)
                if prop is None or prop.valuetype is not ValueType.POINTER:
                    continue
                for value in values:
                    if value.element is None and value.stripped == name:
                        spot = _value_spot(model, config_file.path, value)
                        if spot is not None:
                            spots.append(spot)
    return spots


def _declarations(model: Model, name: str) -> list[Spot]:
    configuration = model.configuration
    if configuration is None:
        return []
    spots = []
    for config_file in configuration.files:
        for element in config_file.elements:
            if element.name == name:
                spot = _tag_spot(model, element)
                if spot is not None:
                    spots.append(spot)
    return spots


def _element_name(model: Model, text: str, offset: int) -> str | None:
    found = under(model, text, offset)
    if found is None:
        return None
    if found.kind in ("pointer", "element"):
        return found.text
    if found.kind == "type":
        ctx = context_at(text, found.start - 1)
        place = place_of(ctx.stack)
        if place is not None and (place.element is None or place.prop is not None):
            close = text.find(">", found.end)
            attributes_text = text[found.end : close if close >= 0 else found.end]
            match = _NAME_ATTRIBUTE.search(attributes_text)
            return match.group(2) if match else None
    return None


def references(model: Model, text: str, offset: int, declaration: bool) -> list[Spot]:
    name = _element_name(model, text, offset)
    if not name:
        return []
    spots = _pointers_to(model, name)
    if declaration:
        spots = _declarations(model, name) + spots
    return spots


def rename(model: Model, text: str, offset: int, new_name: str) -> dict[Path, list[Spot]] | None:
    """Every range to replace by ``new_name``, by file; None when nothing renamable is here."""
    name = _element_name(model, text, offset)
    if not name or not _declarations(model, name):
        return None
    edits: dict[Path, list[Spot]] = {}
    for spot in _declarations(model, name) + _pointers_to(model, name):
        edits.setdefault(spot.path, []).append(spot)
    return edits


def rename_range(model: Model, text: str, offset: int) -> tuple[int, int, str] | None:
    found = under(model, text, offset)
    name = _element_name(model, text, offset)
    if found is None or not name:
        return None
    if found.kind == "type":
        spot = _name_attribute(text, found.start - 1)
        return (*spot, name) if spot else None
    return found.start, found.end, name


# -- outline and folding ---------------------------------------------------------------


@dataclass
class Symbol:
    name: str
    detail: str
    start: int
    end: int
    select_start: int
    select_end: int
    children: list[Symbol]


#: Tags read for the outline and folding at most (a file past it: the outline says so).
MAX_SPANS = 8 * MAX_SYMBOLS


def element_spans(text: str) -> list[tuple[str, str, int, int, int]]:
    """(tag, attribute text, start, end, depth) of every element of the text, by a forgiving
    scan (an element left open ends where its parent does, or at the end)."""
    clean = blank_comments(text)
    stack: list[list] = []
    spans = []
    for match in TAG.finditer(clean):
        closing, name, attrs, empty = match.groups()
        name = local(name)
        if closing:
            for i in range(len(stack) - 1, -1, -1):
                if stack[i][0] == name:
                    while len(stack) > i:
                        entry = stack.pop()
                        spans.append((entry[0], entry[1], entry[2], match.end(), len(stack)))
                    break
        elif empty:
            spans.append((name, attrs, match.start(), match.end(), len(stack)))
        elif len(stack) < 256:
            stack.append([name, attrs, match.start()])
        if len(spans) >= MAX_SPANS:
            break
    while stack:
        entry = stack.pop()
        spans.append((entry[0], entry[1], entry[2], len(text), len(stack)))
    spans.sort(key=lambda s: s[2])
    return spans


def symbols(text: str) -> list[Symbol]:
    """The outline: the configuration's elements grouped by type, or a .jdef's definitions."""
    by_type: dict[str, list[Symbol]] = {}
    elements_depth = None
    shown = 0
    truncated = False
    spans = element_spans(text)
    for name, attrs, start, end, depth in spans:
        if name in ("elements",) and elements_depth is None:
            elements_depth = depth
            continue
        if elements_depth is None or depth != elements_depth + 1:
            if name == "definition" and depth <= 1:
                match = _NAME_ATTRIBUTE.search(attrs)
                label = match.group(2) if match else name
                by_type.setdefault("definition", []).append(
                    Symbol(label, "definition", start, end, start, start + 1 + len(name), [])
                )
            continue
        if shown >= MAX_SYMBOLS:
            truncated = True
            break
        match = _NAME_ATTRIBUTE.search(attrs)
        label = match.group(2) if match and match.group(2) else f"({name})"
        symbol = Symbol(label, name, start, end, start + 1, start + 1 + len(name), [])
        by_type.setdefault(name, []).append(symbol)
        shown += 1
    groups = []
    for type_name, members in by_type.items():
        groups.append(
            Symbol(
                type_name,
                f"{len(members)} element{'s' if len(members) != 1 else ''}",
                members[0].start,
                members[-1].end,
                members[0].select_start,
                members[0].select_end,
                members,
            )
        )
    if truncated or len(spans) >= MAX_SPANS:
        note = f"(the outline stops at {MAX_SYMBOLS} elements)"
        groups.append(Symbol(note, "", 0, 0, 0, 0, []))
    return groups


def folding(text: str) -> list[tuple[int, int]]:
    """(first line, last line) of every element and comment spanning lines (0-based)."""
    index = LineIndex(text, utf16=False)
    ranges = []
    for _, _, start, end, _ in element_spans(text):
        first, last = index.position(start)[0], index.position(max(start, end - 1))[0]
        if last > first:
            ranges.append((first, last))
    for match in COMMENT.finditer(text):
        if not match.group(0).startswith("<!--"):
            continue
        first, last = index.position(match.start())[0], index.position(match.end() - 1)[0]
        if last > first:
            ranges.append((first, last))
        if len(ranges) > MAX_SYMBOLS:
            break
    return ranges[:MAX_SYMBOLS]
