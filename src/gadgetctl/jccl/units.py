"""How many units of each kind a device has, and proxies that read a unit beyond them.

Gadgeteer publishes exactly as many units as a device has (a vrpn device's button_count
buttons, one unit per key binding of a simulated device, ten contacts of a pinch glove), so
a proxy whose unit is beyond them reads default data for ever (and the C++ bounds check is
off by one). The count is known before run time when the configuration states it or the
definition fixes it; :func:`proxy_unit_problem` is the one rule `gadgetctl validate` and the
input manager (`gadgetctl config pending`) both apply.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.jccl.access import ElementAccess, UnknownProperty, read_int
from gadgetctl.jccl.configuration import ConfigElement
from gadgetctl.jccl.repository import DefinitionRepository

#: Proxy element types with a unit, and the kind of data the unit indexes.
PROXY_KINDS = {
    "analog_proxy": "analog",
    "digital_proxy": "digital",
    "position_proxy": "position",
    "glove_proxy": "glove",
}


@dataclass(frozen=True, slots=True)
class UnitRange:
    """How many units of a kind a device element has, and what sets that count."""

    kind: str
    count: int
    source: str  # what sets the count, for messages: "button_count 14", "3 key_pair bindings"
    hint: str | None = None


@dataclass(frozen=True, slots=True)
class _Rule:
    """How a device element's units of a kind are counted: ``count`` gives the number alone
    (None: not known before run time), ``describe`` the :class:`UnitRange` of that number,
    made only for a finding (checking 10,000 proxies against their devices needs the
    numbers only)."""

    count: Callable[[ElementAccess], int | None]
    describe: Callable[[ElementAccess, str, int], UnitRange]


def _stated(prop: str, hint: str) -> _Rule:
    """A count the configuration states in an integer property (or its default)."""

    def count(access: ElementAccess) -> int | None:
        return access.integer(prop) if access.has(prop) else None

    def describe(access: ElementAccess, kind: str, value: int) -> UnitRange:
        shown = f"{prop} {value}" if access.count(prop) else f"{prop} {value} (the default)"
        return UnitRange(kind, value, shown, hint.format(prop=prop))

    return _Rule(count, describe)


def _listed(prop: str, what: str) -> _Rule:
    """One unit per value of a variable property."""

    def count(access: ElementAccess) -> int | None:
        return access.count(prop) if access.has(prop) else None

    def describe(access: ElementAccess, kind: str, written: int) -> UnitRange:
        return UnitRange(
            kind,
            written,
            f"{written} {prop} {what}",
            f"Add a {prop} for each unit the proxies read.",
        )

    return _Rule(count, describe)


def _scaled(prop: str, per: int, hint: str) -> _Rule:
    """``per`` units for each of the count an integer property states."""

    def count(access: ElementAccess) -> int | None:
        return per * access.integer(prop) if access.has(prop) else None

    def describe(access: ElementAccess, kind: str, units: int) -> UnitRange:
        return UnitRange(kind, units, f"{per} per {prop} ({access.integer(prop)})", hint)

    return _Rule(count, describe)


def _children(props: tuple[str, ...], what: str) -> _Rule:
    """One unit per value of each of several variable properties, together."""

    def count(access: ElementAccess) -> int | None:
        if not all(access.has(p) for p in props):
            return None
        return sum(access.count(p) for p in props)

    def describe(access: ElementAccess, kind: str, written: int) -> UnitRange:
        return UnitRange(
            kind, written, f"{written} {what}", f"Add a {' or '.join(props)} for each unit."
        )

    return _Rule(count, describe)


def _fixed(number: int, hint: str | None = None) -> _Rule:
    def count(access: ElementAccess) -> int | None:
        return number

    def describe(access: ElementAccess, kind: str, units: int) -> UnitRange:
        return UnitRange(kind, units, f"a {access.element.type} has {units}", hint)

    return _Rule(count, describe)


def _station_spans(kind: str) -> _Rule:
    """An intersense element's units: one position unit per station child; digital (analog)
    units up to the largest ``<kind>_first + <kind>_count`` of its stations."""

    def count(access: ElementAccess) -> int | None:
        stations = [ElementAccess(c, access.repo) for c in access.children("stations")]
        if kind == "position":
            return len(stations)
        ends = [s.integer(f"{kind}_first") + s.integer(f"{kind}_count") for s in stations]
        return max(ends, default=0)

    def describe(access: ElementAccess, _kind: str, units: int) -> UnitRange:
        if kind == "position":
            return UnitRange(
                kind,
                units,
                f"{units} station{'s' * (units != 1)}",
                "Add an intersense_station for each position unit the proxies read.",
            )
        return UnitRange(
            kind,
            units,
            f"stations' {kind}_first + {kind}_count",
            f"Raise a station's {kind}_count to cover the unit.",
        )

    return _Rule(count, describe)


_PINCH = (
    "A pinch_glove numbers the left hand's contacts 0-4 (thumb to pinky) and the right "
    "hand's 5-9; VR Juggler's pinch.mixin.jconf numbers the right hand 6-10, which shifts "
    "every right-hand proxy by one finger."
)
_SERVER = "Use a unit below the count, or raise {prop} if the server provides more."

#: Element type -> kind -> how its unit count is found.
UNIT_RULES: dict[str, dict[str, _Rule]] = {
    "vrpn": {
        "position": _stated("tracker_count", _SERVER),
        "digital": _stated("button_count", _SERVER),
        "analog": _stated("analog_count", _SERVER),
    },
    "pinch_glove": {
        "digital": _fixed(10, _PINCH),
        "glove": _fixed(2, "Glove 0 is the left hand, glove 1 the right."),
    },
    "ibox": {
        "digital": _fixed(4, "Digital units 0-3 are the IBox's buttons 0-3."),
        "analog": _fixed(4, "Analog units 0-3 are the IBox's analog inputs 0-3."),
    },
    "wanda": {
        "digital": _fixed(3, "Digital units 0-2 are the Wanda's buttons (the rightmost is 0)."),
        "analog": _fixed(2, "Analog units 0 and 1 are the Wanda's joystick X and Y."),
    },
    "intersense": {k: _station_spans(k) for k in ("position", "digital", "analog")},
    "serial_encoder": {"position": _fixed(1, "Position unit 0 is the table (tilt and height).")},
    "data_glove_ultra_wireless": {
        "analog": _fixed(28, "Analog units 0-13 are glove A's sensors, 14-27 glove B's."),
        "command": _fixed(2, "Command unit 0 is glove A's gesture, 1 glove B's."),
    },
    "data_glove": {
        "analog": _fixed(9, "Analog units 0-8: five flexures, pitch, roll, gesture, hand."),
        "glove": _fixed(1, "A data_glove is one hand: glove unit 0."),
    },
    "puck_device": {
        "digital": _fixed(12, "Digital units 0-11 are the puck's buttons 1-12."),
        "analog": _fixed(6, "Analog units 0-5 are the axes tx, ty, tz, rx, ry, rz."),
    },
    "fastrak": {
        "position": _fixed(4, "Units 0-3 are stations 1-4."),
        "digital": _fixed(1, "Digital unit 0 is the stylus switch on station 1."),
    },
    "three_d_mouse": {
        "position": _fixed(1, "Position unit 0 is the mouse."),
        "digital": _fixed(3, "Digital units 0-2 are the left, middle and right buttons."),
    },
    "simulated_digital_device": {"digital": _listed("key_pair", "bindings")},
    "simulated_analog_device": {"analog": _listed("increment_keypress", "bindings")},
    "simulated_digital_glove": {"digital": _fixed(10), "glove": _fixed(2)},
    "simulated_positional_device": {"position": _fixed(1)},
    "simulated_relative_position": {"position": _fixed(1)},
    "simulated_setable_position": {"position": _fixed(1)},
    "elexol_ether24": {
        "digital": _fixed(24, "Units 0-7 are port A's pins, 8-15 port B's, 16-23 port C's.")
    },
    "TUIO_drv": {
        "digital": _stated("points", "Unit i is touch slot i; raise {prop} for more fingers."),
        "analog": _scaled("points", 2, "Units 2i and 2i+1 are the x and y of touch slot i."),
    },
    "optitrack": {"position": _children(("rigid_body", "marker"), "embedded bodies and markers")},
    "waveform_device": {
        "analog": _listed("analog_waveform", "channels"),
        "digital": _listed("button_period", "buttons"),
        "position": _listed("position_path", "paths"),
    },
}


def unit_range(device: ConfigElement, kind: str, repo: DefinitionRepository) -> UnitRange | None:
    """The number of ``kind`` units ``device`` has, when known before run time, and what
    sets it."""
    rule = UNIT_RULES.get(device.type, {}).get(kind)
    if rule is None or device.type not in repo:
        return None
    access = ElementAccess(device, repo)
    try:
        count = rule.count(access)
        return None if count is None else rule.describe(access, kind, count)
    except UnknownProperty:
        return None


def unit_count(device: ConfigElement, kind: str, repo: DefinitionRepository) -> int | None:
    """:attr:`UnitRange.count` of :func:`unit_range` alone (None when not known)."""
    rule = UNIT_RULES.get(device.type, {}).get(kind)
    if rule is None or device.type not in repo:
        return None
    try:
        return rule.count(ElementAccess(device, repo))
    except UnknownProperty:
        return None


def proxy_unit_problem(
    proxy: ConfigElement, device: ConfigElement | None, repo: DefinitionRepository
) -> Diagnostic | None:
    """CFG034 when ``proxy`` reads a unit ``device`` does not have; None otherwise (also when
    the count is not known before run time)."""
    kind = PROXY_KINDS.get(proxy.type)
    if kind is None or device is None:
        return None
    count = unit_count(device, kind, repo)
    if count is None:
        return None
    values = proxy.values("unit")
    unit = read_int(values[0].stripped) if values else 0
    if 0 <= unit < count:
        return None
    units = unit_range(device, kind, repo)  # (that count, and what sets it)
    if units is None:
        return None
    valid = (
        f"units 0-{units.count - 1}"
        if units.count > 1
        else ("unit 0" if units.count == 1 else "no units")
    )
    location = values[0].location if values else proxy.location
    return Diagnostic.make(
        "CFG034",
        f"{proxy.type} {proxy.full_name!r} reads {kind} unit {unit}, but {device.type} "
        f"{device.full_name!r} has {valid} ({units.source}); the proxy only ever reads default data",
        location.path,
        location.line,
        location.column,
        hint=units.hint,
    )


def proxy_unit_problems(
    elements: Iterable[ConfigElement], repo: DefinitionRepository
) -> list[Diagnostic]:
    """:func:`proxy_unit_problem` for every proxy among ``elements`` (the effective top-level
    elements of a configuration), against the element its device property names."""
    elements = list(elements)
    by_name = {e.name: e for e in elements}
    found = []
    for element in elements:
        if element.type in PROXY_KINDS:
            values = element.values("device")
            device = by_name.get(values[0].stripped) if values else None
            problem = proxy_unit_problem(element, device, repo)
            if problem is not None:
                found.append(problem)
    return found
