"""Hover: what the definitions say about the element or property under the cursor, the
value VR Juggler reads (the resolver behind `config show`), and whether the element stays
pending and why (validate's findings about it)."""

from __future__ import annotations

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.definitions import PropertyDefinition, ValueType
from gadgetctl.jccl.resolve import DEFAULT, Resolver
from gadgetctl.lsp.analysis import Model, element_at_line
from gadgetctl.lsp.elements import place_of, view_of
from gadgetctl.lsp.syntax import Tag, Where, context_at, end_tag, tag_at
from gadgetctl.lsp.text import LineIndex
from gadgetctl.wording import counted

#: validate's codes that say an element stays pending, and why (CFG041: waits for a
#: pending element, refused version, no handler; CFG031: waits for a name nothing has).
PENDING_CODES = ("CFG041", "CFG031")
MAX_CHOICES = 40


def hover(model: Model, text: str, offset: int, findings: list[Diagnostic]) -> str | None:
    """Markdown for the position, or None."""
    if model.path.suffix == ".jdef":
        return None
    on_tag = tag_at(text, offset)
    at = on_tag[1] - 1 if on_tag else offset
    if on_tag is not None and text[at] == "/":  # an end tag: what its start tag is
        at -= 1
        stack = context_at(text, at).stack
        if not stack or stack[-1].name != on_tag[0]:
            return None
        at = stack[-1].start
    ctx = context_at(text, at)
    place = place_of(ctx.stack)
    if place is None:
        return None
    index = LineIndex(text, utf16=False)
    if on_tag is not None:
        name = on_tag[0]
        if place.element is None or place.prop is not None:
            line = index.position(at)[0] + 1
            closing = end_tag(text, at, name)
            last = index.position(closing[1])[0] + 1 if closing else line
            return _element(model, Tag(name, at, at, {}), line, last, findings)
        return _property(model, place.element, name, index)
    if ctx.where is Where.TEXT and place.element is not None and place.prop is not None:
        return _property(model, place.element, place.prop.name, index)
    return None


def _element(model: Model, tag: Tag, line: int, last: int, findings: list[Diagnostic]) -> str:
    element = element_at_line(model, line, tag.name)
    versions = model.index.versions(tag.name)
    if not versions:
        return f"**{tag.name}**: no definition of this element type on the search path"
    version = element.version if element is not None and element.version in versions else None
    definition = model.repo.get(tag.name, version)
    assert definition is not None
    lines = [f"**{tag.name}** ({definition.label}), definition version {definition.version}"]
    if definition.help:
        lines += ["", definition.help]
    parents = model.repo.ancestors(tag.name, definition.version)
    if parents:
        lines += ["", f"is a: {', '.join(parents)}"]
    if definition.location is not None:
        lines += [f"defined in {definition.location}"]
    if element is not None:
        reasons = [
            d.message
            for d in findings
            if d.code in PENDING_CODES and d.line is not None and line <= d.line <= last
        ]
        lines += [""]
        if reasons:
            lines += ["**stays pending**:", *(f"- {r}" for r in reasons)]
        else:
            lines += ["becomes active: validate finds nothing that keeps it pending"]
    return "\n".join(lines)


def _property(model: Model, element_tag: Tag, name: str, index: LineIndex) -> str | None:
    view = view_of(model.index, element_tag)
    if view is None:
        return None
    prop = view.get(name)
    if prop is None:
        return f"**{name}**: no property of {view.name} version {view.version}"
    lines = [f"**{name}** ({_kind(prop)}) of {view.name} version {view.version}"]
    if prop.help:
        lines += ["", prop.help]
    slots = [
        f"- {slot.label or f'value {i + 1}'}"
        + (f" (default {slot.default})" if slot.default else "")
        for i, slot in enumerate(prop.values)
    ]
    if slots:
        lines += ["", "values:" if not prop.variable else "each value:", *slots]
    if prop.enumeration is not None:
        choices = ", ".join(
            c.label if c.label == c.value else f"{c.label} = {c.value}"
            for c in prop.enumeration.choices[:MAX_CHOICES]
        )
        more = " (other values allowed)" if prop.enumeration.editable else ""
        lines += ["", f"allowed: {choices}{more}"]
    if prop.allowed_types:
        lines += ["", f"allowed types: {', '.join(prop.allowed_types)}"]
    line = index.position(element_tag.start)[0] + 1
    element = element_at_line(model, line, element_tag.name)
    if element is not None:
        read = Resolver(model.index).values(prop, element.values(name))
        shown = []
        for value in read:
            if value.element is not None:
                shown.append(f"embedded {value.element.type} {value.element.name!r}")
                continue
            text = repr(value.value)
            if value.label and value.label != value.value:
                text += f" ({value.label})"
            if value.source == DEFAULT:
                text += " (default)"
            if value.note:
                text += f": {value.note}"
            shown.append(text)
        if shown:
            lines += ["", "VR Juggler reads: " + ", ".join(shown)]
    return "\n".join(lines)


def _kind(prop: PropertyDefinition) -> str:
    kind = prop.valuetype.value
    if prop.valuetype is ValueType.POINTER:
        kind = "pointer"
    count = "variable number of values" if prop.variable else counted(len(prop.values), "value")
    return f"{kind}, {count}"
