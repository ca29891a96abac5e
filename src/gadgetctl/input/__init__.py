"""The embedded input manager: device types, sample buffers, proxies, aliases, position
filters, driver plug-in discovery and loading, simulated devices.

The public names below are imported lazily (``from gadgetctl.input import Digital``), so
importing this package costs nothing until a name is used. See docs/architecture.md,
"Device API", for how a driver's device class is written.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    # devices
    "Input": "device",
    "SamplingMode": "device",
    "DeviceState": "device",
    "DeviceStats": "device",
    "DeviceContext": "device",
    "Analog": "devicetypes",
    "Digital": "devicetypes",
    "Position": "devicetypes",
    "Glove": "devicetypes",
    "Gesture": "devicetypes",
    "Command": "devicetypes",
    "String": "devicetypes",
    "Hat": "devicetypes",
    "Rumble": "devicetypes",
    "KeyboardMouse": "devicetypes",
    "DigitalState": "devicetypes",
    "HatState": "devicetypes",
    "DeviceKind": "kinds",
    # samples
    "Sample": "samples",
    "SampleBatch": "samples",
    "FrameSamples": "samples",
    "SampleStore": "samples",
    # proxies
    "Proxy": "proxies",
    "AnalogProxy": "proxies",
    "DigitalProxy": "proxies",
    "PositionProxy": "proxies",
    "GloveProxy": "proxies",
    "GestureProxy": "proxies",
    "CommandProxy": "proxies",
    "StringProxy": "proxies",
    "HatProxy": "proxies",
    "KeyboardMouseProxy": "proxies",
    "RumbleProxy": "proxies",
    "LengthUnit": "proxies",
    # manager
    "InputManager": "manager",
    "ManagerOptions": "manager",
    "RestartPolicy": "sampling",
    "PendingEntry": "pending",
    "PendingKind": "pending",
    "ElementStatus": "status",
    # registry and plug-ins
    "DeviceRegistry": "registry",
    "PLUGIN_API_VERSION": "plugins",
    # events
    "EventSource": "events",
    "Key": "keys",
    "Modifier": "keys",
    # errors
    "DeviceConfigError": "errors",
    "DeviceStartError": "errors",
    "ElementVersionError": "errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
