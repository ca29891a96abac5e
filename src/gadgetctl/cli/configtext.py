"""Text rendering of `gadgetctl config show` (ANSI colour only when asked for)."""

from __future__ import annotations

from gadgetctl.jccl.resolve import DEFAULT, ResolvedElement, ResolvedProperty, ResolvedValue
from gadgetctl.safetext import printable

_DIM, _BOLD, _YELLOW, _RESET = "\x1b[2m", "\x1b[1m", "\x1b[33m", "\x1b[0m"


class _Style:
    def __init__(self, color: bool) -> None:
        self.color = color

    def __call__(self, code: str, text: str) -> str:
        return f"{code}{text}{_RESET}" if self.color else text


def _value(value: ResolvedValue) -> str:
    shown = "''" if value.value == "" else printable(value.value or "")
    if value.label is not None and value.label != value.value:
        label = printable(value.label)
        shown = f"{label} = {shown}" if value.written is not None else f"{shown} ({label})"
    return shown


def _property_lines(prop: ResolvedProperty, indent: str, width: int, style: _Style) -> list[str]:
    name = printable(prop.name).ljust(width)
    notes = []
    if prop.defined_by:
        notes.append(f"from {printable(prop.defined_by)}")
    if not prop.known:
        notes.append("not in the definition: ignored")
    tail = style(_DIM, f"  [{', '.join(notes)}]") if notes else ""
    if not prop.values:
        return [f"{indent}{name}  {style(_DIM, '(none)')}{tail}"]
    texts = [v for v in prop.values if v.element is None]
    lines = []
    if texts:
        all_default = all(v.source == DEFAULT for v in texts)
        parts = [
            _value(v)
            + ("" if all_default or v.source != DEFAULT else style(_DIM, " (default)"))
            + (style(_YELLOW, f" ({printable(v.note)})") if v.note else "")
            for v in texts
        ]
        joined = ", ".join(parts)
        if all_default:
            joined = style(_DIM, joined + "  (default)")
        lines.append(f"{indent}{name}  {joined}{tail}")
    embedded = [v.element for v in prop.values if v.element is not None]
    if embedded:
        if not texts:
            lines.append(f"{indent}{printable(prop.name)}{tail}")
        for child in embedded:
            lines += _element_lines(child, indent + "    ", style)
    return lines


def _element_lines(element: ResolvedElement, indent: str, style: _Style) -> list[str]:
    version = f"version {element.version}" if element.version is not None else "no version"
    if element.definition_version is None:
        judged = style(_YELLOW, " (no definition)")
    elif element.version != str(element.definition_version):
        judged = f", read as version {element.definition_version}"
    else:
        judged = ""
    where = printable(f"{element.file}:{element.line}" if element.line else element.file)
    version = printable(version)
    lines = [
        f"{indent}{style(_BOLD, printable(element.type))} {printable(repr(element.name))} "
        f"({version}{judged})  {style(_DIM, where)}"
    ]
    width = max((len(p.name) for p in element.properties), default=0)
    for prop in element.properties:
        lines += _property_lines(prop, indent + "  ", width, style)
    return lines


def render_elements(elements: list[ResolvedElement], *, color: bool = False) -> str:
    style = _Style(color)
    blocks = ["\n".join(_element_lines(e, "", style)) for e in elements]
    return "\n\n".join(blocks)
