"""Checking the connections of one device element, from its transports' properties."""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.doctor.model import PortCheck, Status
from gadgetctl.doctor.permissions import Identity
from gadgetctl.doctor.ports import (
    JOYSTICK_GLOB,
    check_multicast,
    check_path,
    check_tcp,
    check_udp,
    list_joysticks,
)
from gadgetctl.doctor.transports import Transport
from gadgetctl.jccl.access import ElementAccess, UnknownProperty


@dataclass(frozen=True)
class CheckSettings:
    probe: bool = False  # connect to TCP servers
    timeout: float = 2.0  # seconds per TCP probe
    identity: Identity | None = None  # None: the current user
    joystick_glob: str = JOYSTICK_GLOB
    serial_ports: tuple[str, ...] | None = None  # for hints; None: unknown
    emulator: str | None = None  # plug-in whose emulator can stand in for the device


class _Unknown(Exception):
    def __init__(self, prop: str) -> None:
        self.prop = prop


def _read(
    access: ElementAccess, transport: Transport, key: str, number: bool = False
) -> str | int | None:
    prop = transport.prop(key)
    if prop is None:
        return None
    try:
        return access.integer(prop) if number else access.string(prop)
    except UnknownProperty:
        raise _Unknown(prop) from None


def check_transport(
    access: ElementAccess, transport: Transport, settings: CheckSettings
) -> list[PortCheck]:
    """Every check of one transport of the element ``access`` reads."""
    try:
        return _check(access, transport, settings)
    except _Unknown as unknown:
        return [
            PortCheck(
                transport.kind,
                "",
                Status.WARNING,
                f"{access.element.type} has no property {unknown.prop!r} to read the port from",
                "DRV107",
                prop=unknown.prop,
            )
        ]


def _port(access: ElementAccess, transport: Transport) -> int:
    """The port the driver uses: the element's, or ``port_unset`` (the driver's own default,
    where it differs from the definition's) when the element does not set it."""
    unset = transport.prop("port_unset")
    prop = transport.props["port"]
    if unset and access.has(prop) and not access.count(prop):
        return int(unset)
    return int(_read(access, transport, "port", number=True) or 0)


def _check(access: ElementAccess, transport: Transport, settings: CheckSettings) -> list[PortCheck]:
    kind = transport.kind
    if kind in ("file", "serial"):
        key = "path" if kind == "file" else "port"
        path = str(_read(access, transport, key))
        result = check_path(path, kind, identity=settings.identity)
        if result.code == "DRV100":
            result = _with_hint(result, _missing_hint(kind, path, settings))
        if kind == "serial" and result.status is Status.OK and transport.prop("baud"):
            baud = _read(access, transport, "baud", number=True)
            result = PortCheck(
                result.kind, result.target, result.status, f"{result.detail}, {baud} baud"
            )
        return [result.with_prop(transport.props[key])]
    if kind == "udp":
        port = _port(access, transport)
        checks = [check_udp(port).with_prop(transport.props["port"])]
        if transport.prop("group"):  # a literal multicast address the driver joins
            checks.append(check_multicast(transport.props["group"]))
        host = _read(access, transport, "host")
        if host:
            peer = _read(access, transport, "peer_port", number=True)
            target = f"{host}:{peer}" if peer else str(host)
            checks.append(
                PortCheck(
                    "udp",
                    target,
                    Status.UNCHECKED,
                    f"commands are sent to {target} (UDP; not contacted)",
                    prop=transport.props["host"],
                )
            )
        return checks
    if kind == "udp-peer":
        # a board found by its MAC address (optional keys "mac" and "method": the element's
        # discovery method property says "find_mac") is reached through discovery, not host
        mac = str(_read(access, transport, "mac") or "")
        if mac and _read(access, transport, "method") == "find_mac":
            return [
                PortCheck(
                    "udp",
                    f"MAC {mac}",
                    Status.UNCHECKED,
                    f"the board with MAC {mac} is looked for by the driver's discovery "
                    "when the device starts (not contacted)",
                    prop=transport.props["mac"],
                )
            ]
        host = str(_read(access, transport, "host") or "")
        return [
            PortCheck(
                "udp",
                host or "(no address)",
                Status.UNCHECKED,
                f"commands are sent to {host or 'no address'} (UDP; not contacted)",
                prop=transport.props["host"],
            )
        ]
    if kind == "tcp":
        host = str(_read(access, transport, "host"))
        port = _port(access, transport)
        result = check_tcp(host, port, probe=settings.probe, timeout=settings.timeout)
        if result.code == "DRV104" and settings.emulator:
            result = _with_hint(
                result,
                f"{result.hint + '; ' if result.hint else ''}"
                f"to try without the hardware: gadgetctl emulate {settings.emulator}",
            )
        return [result.with_prop(f"{transport.props['host']}, {transport.props['port']}")]
    if kind == "vrpn":
        name = str(_read(access, transport, "name") or "").strip()
        count = _read(access, transport, "count", number=True) if transport.prop("count") else None
        if not name or count == 0:
            return []  # this device of the element is not used
        from gadgetctl.doctor.vrpn import check_vrpn_name

        return [
            check_vrpn_name(name, probe=settings.probe, timeout=settings.timeout).with_prop(
                transport.props["name"]
            )
        ]
    if kind == "shm":
        from gadgetctl.doctor.shm import check_shm

        key = int(_read(access, transport, "key", number=True) or 0)
        return [
            check_shm(key, identity=settings.identity, emulator=settings.emulator).with_prop(
                transport.props["key"]
            )
        ]
    if kind == "sdl":
        from gadgetctl.doctor.sdl import check_sdl

        index = int(_read(access, transport, "index", number=True) or 0)
        return [check_sdl(index, emulator=settings.emulator).with_prop(transport.props["index"])]
    return []


def _with_hint(check: PortCheck, hint: str | None) -> PortCheck:
    return PortCheck(
        check.kind, check.target, check.status, check.detail, check.code, hint, check.prop
    )


def _missing_hint(kind: str, path: str, settings: CheckSettings) -> str:
    parts = []
    if kind == "serial":
        ports = settings.serial_ports
        if ports is None:
            parts.append("pyserial cannot list the serial ports here")
        else:
            parts.append(
                f"serial ports found: {', '.join(ports)}" if ports else "no serial ports found"
            )
    elif path.startswith("/dev/input/") or path.startswith("/dev/js"):
        found = [c.target for c in list_joysticks(settings.joystick_glob)]
        parts.append(
            f"joystick devices found: {', '.join(found)}"
            if found
            else "no joystick devices found (is the joydev kernel module loaded?)"
        )
    if settings.emulator:
        parts.append(f"to try without the hardware: gadgetctl emulate {settings.emulator} --help")
    return "; ".join(parts)
