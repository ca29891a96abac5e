"""Reading an element's property values the way VR Juggler's run time does.

* a value written in the file is used even when empty (``<port/>`` reads as ""); a slot not
  written falls back to the definition's default for that slot;
* text is trimmed, then enumeration labels are replaced by their values;
* numbers are read like a C++ stream extraction (a leading number, junk after it ignored,
  nothing parsable gives 0); booleans are false only for exactly ``false`` or ``0``.

``gadgetctl validate`` reports every value where these rules give a surprising result.
"""

from __future__ import annotations

import re
from collections.abc import Container, Mapping

from gadgetctl.jccl.configuration import ConfigElement
from gadgetctl.jccl.definitions import PropertyDefinition
from gadgetctl.jccl.repository import DefinitionRepository

_LEADING_INT = re.compile(r"^[+-]?\d+")
_LEADING_FLOAT = re.compile(r"^[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


class UnknownProperty(KeyError):
    """A property the element's definition does not have was asked for."""


#: strtol's range on the platforms VR Juggler runs on (64-bit long): it saturates beyond.
_LONG_MAX = 2**63 - 1


#: Texts read before and what they read as: configurations write the same few numbers again
#: and again (20,000 elements read "0", "1.0" and "-1.0" tens of thousands of times).
_READ_INTS: dict[str, int] = {}
_READ_FLOATS: dict[str, float] = {}
#: At most this many texts are remembered per kind of number (short ones only).
_READ_MOST = 4096
_READ_LONGEST = 32


def read_int(text: str) -> int:
    """The leading integer of ``text`` as C's ``strtol`` reads it (0 without one), saturated
    to the range of a 64-bit long, so thousands of digits never reach ``int()``'s limit."""
    known = _READ_INTS.get(text)
    if known is not None:
        return known
    if text.isascii() and text.isdigit() and len(text) <= 18:
        return int(text)  # (plain digits, such as 10,000 seeds: the same as _read_int)
    value = _read_int(text)
    if len(text) <= _READ_LONGEST and len(_READ_INTS) < _READ_MOST:
        _READ_INTS[text] = value
    return value


def _read_int(text: str) -> int:
    match = _LEADING_INT.match(text.strip())
    if not match:
        return 0
    digits = match.group(0)
    negative = digits.startswith("-")
    if len(digits.lstrip("+-").lstrip("0")) > 19:  # beyond any 64-bit value
        return -_LONG_MAX - 1 if negative else _LONG_MAX
    return max(-_LONG_MAX - 1, min(_LONG_MAX, int(digits)))


def read_float(text: str) -> float:
    """The leading number of ``text`` as a C++ stream reads it (0.0 without one)."""
    known = _READ_FLOATS.get(text)
    if known is not None:
        return known
    match = _LEADING_FLOAT.match(text.strip())
    value = float(match.group(0)) if match else 0.0
    if len(text) <= _READ_LONGEST and len(_READ_FLOATS) < _READ_MOST:
        _READ_FLOATS[text] = value
    return value


#: default_text answers by (id of the definition, slot): (the definition, the text). Definitions
#: are never changed once read; the entry keeps its definition, so the id stays its own.
_DEFAULT_TEXTS: dict[tuple[int, int], tuple[PropertyDefinition, str]] = {}
_DEFAULT_TEXTS_MOST = 4096


def default_text(definition: PropertyDefinition, index: int) -> str:
    """What a slot not written reads as: the definition's default for slot ``index``, trimmed,
    an enumeration label replaced by its value ("" without a default). Worked out once per
    definition and slot: 10,000 elements of a type read the same defaults."""
    key = (id(definition), index)
    found = _DEFAULT_TEXTS.get(key)
    if found is not None and found[0] is definition:
        return found[1]
    text = (definition.default(index) or "").strip()
    if definition.enumeration is not None:
        text = definition.enumeration.substitute(text)
    if len(_DEFAULT_TEXTS) < _DEFAULT_TEXTS_MOST:
        _DEFAULT_TEXTS[key] = (definition, text)
    return text


def read_bool(text: str) -> bool:
    return text.strip() not in ("false", "0")


class ElementAccess:
    """Typed, definition-aware reads of one element's properties."""

    def __init__(self, element: ConfigElement, repo: DefinitionRepository) -> None:
        self.element = element
        self.repo = repo
        self._props = repo.property_map(element.type)

    @property
    def name(self) -> str:
        return self.element.full_name

    @property
    def definitions(self) -> Mapping[str, PropertyDefinition]:
        """The element type's properties by name (the repository's shared, read-only map: the
        same object for every element of a type)."""
        return self._props

    def written(self, props: Container[str]) -> tuple[tuple[str, tuple[str, ...]], ...] | None:
        """The texts written for those of ``props`` the element has, in the order written (what
        reads of only these properties depend on, besides :attr:`definitions`); None when one
        of them holds an embedded element."""
        return self.element.written_texts(props)

    def definition(self, prop: str) -> PropertyDefinition:
        try:
            return self._props[prop]
        except KeyError:
            raise UnknownProperty(f"{self.element.type} has no property {prop!r}") from None

    def has(self, prop: str) -> bool:
        return prop in self._props

    def count(self, prop: str) -> int:
        """Number of values written (defaults are not counted)."""
        return len(self.element.values(prop))

    def string(self, prop: str, index: int = 0) -> str:
        try:
            definition = self._props[prop]
        except KeyError:
            raise UnknownProperty(f"{self.element.type} has no property {prop!r}") from None
        values = self.element.values(prop)
        if index >= len(values):
            return default_text(definition, index)
        text = values[index].text.strip()
        enumeration = definition.enumeration
        return text if enumeration is None else enumeration.substitute(text)

    def integer(self, prop: str, index: int = 0) -> int:
        return read_int(self.string(prop, index))

    def float(self, prop: str, index: int = 0) -> float:
        return read_float(self.string(prop, index))

    def boolean(self, prop: str, index: int = 0) -> bool:
        return read_bool(self.string(prop, index))

    def slots(self, prop: str) -> int:
        """Values to read: the written count for a variable property, the slot count otherwise."""
        definition = self.definition(prop)
        return (
            self.count(prop)
            if definition.variable
            else max(len(definition.values), self.count(prop))
        )

    def strings(self, prop: str) -> list[str]:
        return [self.string(prop, i) for i in range(self.slots(prop))]

    def floats(self, prop: str) -> list[float]:
        return [read_float(s) for s in self.strings(prop)]

    def integers(self, prop: str) -> list[int]:
        return [read_int(s) for s in self.strings(prop)]

    def child(self, prop: str, index: int = 0) -> ConfigElement | None:
        self.definition(prop)
        values = self.element.values(prop)
        return values[index].element if index < len(values) else None

    def children(self, prop: str) -> list[ConfigElement]:
        self.definition(prop)
        return [v.element for v in self.element.values(prop) if v.element is not None]
