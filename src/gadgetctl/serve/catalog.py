"""What `gadgetctl serve` shares: every selected device, proxy and alias as the VRPN
devices that fit its data, under its VRPN name (:mod:`gadgetctl.serve.naming`).

* a device: its position units as the sensors of a Tracker, its digital units as the
  buttons of a Button, its analog units as the channels of an Analog (raw values, between
  the device's ``min`` and ``max``), its string and command units as Text messages;
* a proxy: what applications read from it, as one sensor, button or channel (filtered
  poses, analog values normalised to [0, 1], toggle states as pressed/released) or Text;
* an alias: exactly what its proxy serves, under the alias's own name.

Glove, gesture, hat and keyboard/mouse data have no VRPN device here and are listed as
not served.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum

from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.manager import InputManager
from gadgetctl.input.proxies import (
    AnalogProxy,
    CommandProxy,
    DigitalProxy,
    PositionProxy,
    Proxy,
    StringProxy,
)
from gadgetctl.serve.naming import assign_names


class Role(StrEnum):
    """The VRPN device classes serve speaks."""

    TRACKER = "tracker"
    BUTTON = "button"
    ANALOG = "analog"
    TEXT = "text"


KIND_ROLES: dict[DeviceKind, Role] = {
    DeviceKind.POSITION: Role.TRACKER,
    DeviceKind.DIGITAL: Role.BUTTON,
    DeviceKind.ANALOG: Role.ANALOG,
    DeviceKind.STRING: Role.TEXT,
    DeviceKind.COMMAND: Role.TEXT,
}


def served_positions(items: tuple[tuple[DeviceKind, object], ...]) -> object | None:
    """The position values among a window's ``items`` ((kind, values) pairs) when position is
    the only kind of them that is served (a waveform device's hat values are not), else None:
    such a window is served as tracker reports alone."""
    positions = None
    for kind, values in items:
        if kind is DeviceKind.POSITION:
            positions = values
        elif kind in KIND_ROLES:
            return None
    return positions


PROXY_ROLES: tuple[tuple[type[Proxy], Role], ...] = (
    (PositionProxy, Role.TRACKER),
    (DigitalProxy, Role.BUTTON),
    (AnalogProxy, Role.ANALOG),
    (StringProxy, Role.TEXT),
    (CommandProxy, Role.TEXT),
)


@dataclass(slots=True)
class ServedElement:
    """One element and the VRPN devices it is served as."""

    element: str  # the element's name
    vrpn_name: str
    kind: str  # device, proxy, alias
    element_type: str
    roles: tuple[Role, ...]
    units: dict[Role, int] = field(
        default_factory=dict
    )  # sensors, buttons, channels (as seen so far)
    analog_range: tuple[float, float] | None = None  # the range of the Analog channel values
    source: str | None = None  # a proxy's device (and unit), an alias's proxy
    not_served: tuple[str, ...] = ()  # kinds of data without a VRPN device

    def to_dict(self) -> dict[str, object]:
        entry: dict[str, object] = {
            "element": self.element,
            "vrpn_name": self.vrpn_name,
            "kind": self.kind,
            "type": self.element_type,
            "vrpn": [r.value for r in self.roles],
            "units": {r.value: n for r, n in self.units.items()},
        }
        if self.analog_range is not None:
            entry["analog_min"], entry["analog_max"] = self.analog_range
        if self.source is not None:
            entry["source"] = self.source
        if self.not_served:
            entry["not_served"] = list(self.not_served)
        return entry


def proxy_role(proxy: Proxy) -> Role | None:
    for cls, role in PROXY_ROLES:
        if isinstance(proxy, cls):
            return role
    return None


#: Kinds that come as events, whenever they come: a warm-up cannot wait for them.
SPORADIC_KINDS = (DeviceKind.STRING, DeviceKind.COMMAND)


def _device_entry(manager: InputManager, name: str) -> ServedElement | None:
    """A device's roles are the kinds it has delivered so far (a waveform device provides
    every kind but may be configured with no positions), all its kinds before any sample,
    and Text when its configuration makes strings or commands (events, which the served
    device sends whenever they come, delivered yet or not)."""
    device = manager.device(name)
    if device is None:
        return None
    kinds = device.kinds()
    delivered = [k for k in kinds if device.store.latest(k) is not None]
    configured = device.configured_kinds()
    sporadic = [k for k in SPORADIC_KINDS if k in configured and k not in delivered]
    units: dict[Role, int] = {}
    found: set[Role] = set()
    for kind in [*delivered, *sporadic] if delivered else configured:
        role = KIND_ROLES.get(kind)
        if role is None:
            continue
        found.add(role)
        latest = device.store.latest(kind)
        if latest is not None and role is not Role.TEXT:
            units[role] = max(units.get(role, 0), len(latest.values))
    roles = tuple(r for r in Role if r in found)
    not_served = tuple(
        k.value for k in configured if k not in KIND_ROLES and (not delivered or k in delivered)
    )
    analog = (
        (device.analog_min, device.analog_max)
        if isinstance(device, Analog) and Role.ANALOG in roles
        else None
    )
    return ServedElement(
        name, name, "device", device.element_type, roles, units, analog, None, not_served
    )


def _proxy_entry(
    manager: InputManager, name: str, kind: str, proxy_name: str
) -> ServedElement | None:
    proxy = manager.proxies.get(proxy_name)
    if proxy is None:
        return None
    role = proxy_role(proxy)
    element_type = "alias" if kind == "alias" else proxy.element_type
    source = proxy_name if kind == "alias" else f"{proxy.device_name} unit {proxy.unit}"
    if role is None:
        return ServedElement(
            name, name, kind, element_type, (), {}, None, source, (proxy.KIND.value,)
        )
    units = {} if role is Role.TEXT else {role: 1}
    analog = (0.0, 1.0) if role is Role.ANALOG else None
    return ServedElement(name, name, kind, element_type, (role,), units, analog, source)


def build_catalog(
    manager: InputManager, names: Iterable[str], renames: Mapping[str, str] | None = None
) -> list[ServedElement]:
    """The served elements among ``names`` (devices, proxies, aliases of ``manager``), in
    that order, with their VRPN names. Pending elements are left out."""
    entries: list[ServedElement] = []
    for name in names:
        if manager.device(name) is not None:
            entry = _device_entry(manager, name)
        elif name in manager.proxies:
            entry = _proxy_entry(manager, name, "proxy", name)
        elif name in manager.aliases:
            entry = _proxy_entry(manager, name, "alias", manager.aliases[name])
        else:
            entry = None
        if entry is not None:
            entries.append(entry)
    vrpn_names = assign_names([e.element for e in entries], renames)
    for entry in entries:
        entry.vrpn_name = vrpn_names[entry.element]
    return entries
