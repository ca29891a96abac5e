"""Checks of single property values: numbers, booleans and enumeration labels.

Values are judged the way VR Juggler's run time reads them (:mod:`gadgetctl.jccl.access`):
trimmed, enumeration labels replaced by their values, then parsed as the property's type.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from gadgetctl.jccl.access import read_float, read_int
from gadgetctl.jccl.definitions import Enumeration, PropertyDefinition, ValueType
from gadgetctl.suggest import close_names

_INTEGER = re.compile(r"[+-]?\d+\Z")
# One way only to split the digits (``\d+\.?\d*`` has n of them, and a long number that
# fails at its end then backtracks quadratically: minutes for a few 5,000-digit values).
_FLOAT = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?\Z")
_BOOLEANS = ("true", "false", "1", "0")
MAX_CHOICES_SHOWN = 10


@dataclass(frozen=True, slots=True)
class ValueProblem:
    """What is wrong with a value: a diagnostic code, its message and hint."""

    code: str
    message: str
    hint: str | None = None
    #: A suggestion only (info), dropped where a plug-in or element has the value's exact
    #: name: the value differs in case from a label of an editable enumeration.
    note: bool = False


def is_number(valuetype: ValueType, text: str) -> bool:
    pattern = _INTEGER if valuetype is ValueType.INTEGER else _FLOAT
    return pattern.match(text) is not None


def describe_choices(enumeration: Enumeration) -> str:
    shown = [
        f"{c.label} ({c.value})" if c.label != c.value else c.label
        for c in enumeration.choices[:MAX_CHOICES_SHOWN]
    ]
    more = len(enumeration.choices) - MAX_CHOICES_SHOWN
    return ", ".join(shown) + (f", ... ({len(enumeration.choices)} in all)" if more > 0 else "")


def _same_value(valuetype: ValueType, a: str, b: str) -> bool:
    if a == b:
        return True
    if (
        valuetype in (ValueType.INTEGER, ValueType.FLOAT)
        and is_number(ValueType.FLOAT, a)
        and is_number(ValueType.FLOAT, b)
    ):
        return float(a) == float(b)
    return False


def _label_problem(prop: PropertyDefinition, raw: str) -> ValueProblem | None:
    enumeration = prop.enumeration
    assert enumeration is not None
    if any(raw == c.label for c in enumeration.choices):
        return None
    if any(_same_value(prop.valuetype, raw, c.value) for c in enumeration.choices):
        return None
    near = enumeration.case_insensitive_label(raw)
    if near is not None and enumeration.editable:
        # VR Juggler uses the text of an editable enumeration as written: 'OptiTrack_drv'
        # is the Unix plug-in VR Juggler's list spells 'Optitrack_drv'.
        return ValueProblem(
            "CFG027",
            f"{prop.name} {raw!r} differs only in case from the label {near.label!r}; the "
            "enumeration is editable, so VR Juggler uses the text as written, and no plug-in "
            "or element has that exact name",
            f"If {near.label!r} is meant, write it so.",
            note=True,
        )
    if near is not None:
        reads = _reading(prop.valuetype, raw)
        return ValueProblem(
            "CFG027",
            f"{prop.name} {raw!r} is not a label of its enumeration: labels are "
            f"case-sensitive, so it is not replaced by {near.label}'s value {near.value!r}"
            + (f" and is read as {reads}" if reads else ""),
            f"Write {near.label!r}. Choices: {describe_choices(enumeration)}.",
        )
    if enumeration.editable:
        return None

    close = close_names(raw, [c.label for c in enumeration.choices], cutoff=0.6)
    hint = f"Did you mean {', '.join(repr(c) for c in close)}? " if close else ""
    return ValueProblem(
        "CFG028",
        f"{prop.name} {raw!r} is none of its enumeration's labels or values",
        f"{hint}Choices: {describe_choices(enumeration)}.",
    )


def _reading(valuetype: ValueType, text: str) -> str | None:
    if valuetype is ValueType.INTEGER:
        return str(read_int(text))
    if valuetype is ValueType.FLOAT:
        return repr(read_float(text))
    if valuetype is ValueType.BOOLEAN:
        return "true" if text not in ("false", "0") else "false"
    return None


def check_text(prop: PropertyDefinition, text: str) -> ValueProblem | None:
    """The first problem of one written value of a text-valued property, if any."""
    raw = text.strip()
    value = raw
    if prop.enumeration is not None and prop.enumeration.choices and raw:
        problem = _label_problem(prop, raw)
        if problem is not None and problem.code == "CFG027":
            return problem
        value = prop.enumeration.substitute(raw)
        if problem is not None:
            return problem
    valuetype = prop.valuetype
    if valuetype in (ValueType.INTEGER, ValueType.FLOAT):
        if is_number(valuetype, value):
            return None
        default = prop.values[0].default if prop.values else None
        shown = "an empty value" if not value else repr(value)
        what = "an integer" if valuetype is ValueType.INTEGER else "a number"
        hint = None
        if not value:
            hint = (
                f"Remove the tag to get the default {default!r}."
                if default
                else "Write a value or remove the tag."
            )
        return ValueProblem(
            "CFG025",
            f"{prop.name}: {shown} is not {what}; VR Juggler reads it as "
            f"{_reading(valuetype, value)} without a warning",
            hint,
        )
    if valuetype is ValueType.BOOLEAN and value not in _BOOLEANS:
        shown = "an empty value" if not value else repr(value)
        lowered = value.lower()
        hint = f"Write {lowered!r}." if lowered in ("true", "false") else "Write true or false."
        return ValueProblem(
            "CFG026",
            f"{prop.name}: {shown} is not true, false, 1 or 0; VR Juggler's "
            "run time reads it as true",
            hint,
        )
    return None
