"""The kinds of input data a device can provide, and how they map onto definitions.

A device class provides one or more kinds (its device types); each kind has a proxy type
and, for all but gestures, an abstract base definition that a configurable element type
of a device providing that kind must inherit from.
"""

from __future__ import annotations

from enum import StrEnum


class DeviceKind(StrEnum):
    ANALOG = "analog"
    DIGITAL = "digital"
    POSITION = "position"
    GLOVE = "glove"
    GESTURE = "gesture"
    COMMAND = "command"
    STRING = "string"
    HAT = "hat"
    KEYBOARD_MOUSE = "keyboard_mouse"
    RUMBLE = "rumble"  # force-feedback output: no samples, no base definition


#: The definition an element type must derive from when its device class provides the kind.
#: Gestures have no base definition of their own (simulated_glove_gesture is a glove_device);
#: nor has rumble (Gadgeteer's rumble_proxy points at any input_device).
BASE_DEFINITIONS: dict[DeviceKind, str] = {
    DeviceKind.ANALOG: "analog_device",
    DeviceKind.DIGITAL: "digital_device",
    DeviceKind.POSITION: "positional_device",
    DeviceKind.GLOVE: "glove_device",
    DeviceKind.COMMAND: "command_device",
    DeviceKind.STRING: "string_device",
    DeviceKind.HAT: "hat_device",
    DeviceKind.KEYBOARD_MOUSE: "keyboard_mouse_device",
}

#: Proxy element types and the kind of data they read.
PROXY_TYPES: dict[str, DeviceKind] = {
    "analog_proxy": DeviceKind.ANALOG,
    "digital_proxy": DeviceKind.DIGITAL,
    "position_proxy": DeviceKind.POSITION,
    "glove_proxy": DeviceKind.GLOVE,
    "gesture_proxy": DeviceKind.GESTURE,
    "command_proxy": DeviceKind.COMMAND,
    "string_proxy": DeviceKind.STRING,
    "hat_proxy": DeviceKind.HAT,
    "keyboard_mouse_proxy": DeviceKind.KEYBOARD_MOUSE,
    "rumble_proxy": DeviceKind.RUMBLE,
}

INPUT_DEVICE = "input_device"
PROXY_BASE = "proxy"
ALIAS = "alias"
INPUT_MANAGER = "input_manager"

#: Element types Gadgeteer's input manager handles that gadgetctl does not implement,
#: with the reason shown for them.
UNSUPPORTED_TYPES: dict[str, str] = {
    "gadget_logger": "the Gadgeteer input logger is not supported; use `gadgetctl monitor --record`",
    "event_emitter": "input event emission to applications is not supported by gadgetctl",
}


def parse_kinds(names: object) -> tuple[DeviceKind, ...]:
    """Device kinds from metadata such as ``("digital", "analog")``; raises ``ValueError``."""
    if isinstance(names, str) or not isinstance(names, (tuple, list)):
        raise ValueError(f"device types must be a tuple of names, not {names!r}")
    known = {k.value for k in DeviceKind}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(
            f"unknown device {'type' if len(unknown) == 1 else 'types'} {', '.join(map(repr, unknown))} "
            f"(known: {', '.join(sorted(known))})"
        )
    return tuple(DeviceKind(n) for n in names)
