"""VRPN device names: ``Device@location``.

Locations: ``host``, ``host:port``, ``tcp://host:port`` or ``tcp:host:port`` (direct TCP
instead of the UDP connection request), ``x-vrpn://host:port`` / ``x-vrpn:host:port`` (same
as plain). The host ends at the first ``:`` or ``/``; the port is the number after the last
``:``; without one it is 3883. ``x-vrsh:`` (starting a server over ssh) and ``file:`` are not
supported.
"""

from __future__ import annotations

from dataclasses import dataclass

from .wire import DEFAULT_PORT, MAX_NAME


class VrpnNameError(ValueError):
    """A device name or location that cannot be used (the message says why)."""


@dataclass(frozen=True)
class Location:
    """Where a VRPN server is: host, port and whether to connect by direct TCP."""

    host: str
    port: int = DEFAULT_PORT
    tcp: bool = False

    def __str__(self) -> str:
        return f"tcp://{self.host}:{self.port}" if self.tcp else f"{self.host}:{self.port}"


@dataclass(frozen=True)
class DeviceName:
    """``device`` (the VRPN sender name) at ``location``."""

    device: str
    location: Location

    def __str__(self) -> str:
        return f"{self.device}@{self.location}"


_PREFIXES = (("tcp://", True), ("tcp:", True), ("x-vrpn://", False), ("x-vrpn:", False))


def parse_location(text: str) -> Location:
    """A :class:`Location` from ``host``, ``host:port`` or ``tcp://host:port``."""
    rest = text.strip()
    tcp = False
    lowered = rest.lower()
    if lowered.startswith(("x-vrsh:", "file:")):
        raise VrpnNameError(f"{text!r}: {rest.split(':', 1)[0]}: locations are not supported")
    for prefix, is_tcp in _PREFIXES:
        if lowered.startswith(prefix):
            rest, tcp = rest[len(prefix) :], is_tcp
            break
    host = rest
    for i, c in enumerate(rest):
        if c in ":/":
            host = rest[:i]
            break
    if not host:
        raise VrpnNameError(f"{text!r} names no host")
    port = DEFAULT_PORT
    if ":" in rest:
        tail = rest.rsplit(":", 1)[1].split("/", 1)[0]
        if not tail.isdigit() or not 1 <= int(tail) <= 65535:
            raise VrpnNameError(f"{text!r}: port {tail!r} is not a number from 1 to 65535")
        port = int(tail)
    return Location(host, port, tcp)


def parse_device_name(text: str) -> DeviceName:
    """A :class:`DeviceName` from ``Device@location`` (the device part ends at the first ``@``)."""
    device, sep, location = text.strip().partition("@")
    if not sep:
        raise VrpnNameError(f"{text!r} is not written as Device@host")
    if not device:
        raise VrpnNameError(f"{text!r} names no device before '@'")
    if len(device.encode("latin-1", "replace")) > MAX_NAME:
        raise VrpnNameError(f"device name {device!r} is longer than {MAX_NAME} characters")
    return DeviceName(device, parse_location(location))
