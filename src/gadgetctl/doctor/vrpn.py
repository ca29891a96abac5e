"""Checking a VRPN device name (``Device@host[:port]``): the name reads, the host resolves,
and with ``--probe`` a VRPN server answers there and announces the device. When it does not,
the check names the devices the server does announce: the most common VRPN mistake, which
VRPN itself only shows as "No response from server"."""

from __future__ import annotations

import socket

from gadgetctl.doctor.model import PortCheck, Status
from gadgetctl.wording import counted


def check_vrpn_name(text: str, *, probe: bool, timeout: float) -> PortCheck:
    from gadgetctl.vrpn import VrpnNameError, parse_device_name
    from gadgetctl.vrpn.probe import probe as probe_server

    target = text.strip()
    try:
        name = parse_device_name(target)
    except VrpnNameError as exc:
        return PortCheck(
            "vrpn",
            target,
            Status.PROBLEM,
            str(exc),
            "DRV110",
            "write the device as Device@host, Device@host:port or Device@tcp://host:port",
        )
    host = name.location.host
    try:
        address = socket.gethostbyname(host)
    except (OSError, UnicodeError) as exc:
        return PortCheck(
            "vrpn",
            target,
            Status.PROBLEM,
            f"host {host!r} does not resolve: {getattr(exc, 'strerror', None) or exc}",
            "DRV110",
            "fix the host name, or write the server's IPv4 address",
        )
    resolved = "" if address == host else f" ({host} is {address})"
    if not probe:
        return PortCheck(
            "vrpn",
            target,
            Status.UNCHECKED,
            f"not contacted{resolved} (run with --probe to ask the VRPN server at {name.location})",
        )
    result = probe_server(name.location, [name.device], timeout=timeout, observe=0.3)
    if not result.answered:
        return PortCheck(
            "vrpn",
            target,
            Status.PROBLEM,
            _no_answer(name.location, result.error),
            "DRV111",
            "start the VRPN server (vrpn_server, gadgetctl serve...) or fix the host and port",
        )
    version = f"VRPN {result.version} server at {name.location}"
    if result.listed_only(name.device):
        offered = ", ".join(d for d in result.devices if d != name.device) or "no devices"
        return PortCheck(
            "vrpn",
            target,
            Status.PROBLEM,
            f"the {version} lists {name.device!r} but nothing answers for it within "
            f"{timeout:g} s (no pong, no report); a vrpn_server lists any name a client "
            f"once asked for; it announces: {offered}",
            "DRV112",
            "use a device the server really serves (its configuration file names them)",
        )
    if not result.has(name.device):
        offered = ", ".join(result.devices) or "no devices"
        return PortCheck(
            "vrpn",
            target,
            Status.PROBLEM,
            f"the {version} has no device {name.device!r}; it announces: {offered}",
            "DRV112",
            "use one of the announced names (the part before '@' is the server's device name)",
        )
    layout = result.layouts[name.device]
    seen = [
        counted(n, what)
        for n, what in (
            (layout.sensors, "sensor"),
            (layout.buttons, "button"),
            (layout.channels, "channel"),
        )
        if n
    ]
    shown = f" (reports show {', '.join(seen)})" if seen else ""
    return PortCheck("vrpn", target, Status.OK, f"the {version} announces {name.device}{shown}")


def _no_answer(location: str, error: str | None) -> str:
    """Why no VRPN server answered at ``location``, saying so once (the client's own error
    often starts with the same words)."""
    said = f"no VRPN server answers at {location}"
    if not error:
        return said
    _, found, rest = error.partition(f"{location}: ")
    if found and rest:  # "no VRPN server at HOST: ...", "cannot connect to HOST: ...": the cause
        return f"{said}: {rest}"
    return error if error.startswith("no VRPN server") else f"{said}: {error}"
