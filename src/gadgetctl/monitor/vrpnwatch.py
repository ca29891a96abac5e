"""Watching VRPN devices without a configuration: ``gadgetctl monitor vrpn:Tracker0@host``.

Each ``vrpn:Device@location`` argument becomes one ``vrpn`` element of a configuration made
on the fly (element name ``Device@location``), read by the bundled ``VRPN_drv``. The server is
asked first (:func:`gadgetctl.vrpn.probe.probe`) so that the element gets the layout the
device's first reports show: as many position units as tracker sensors, digital units as
buttons, analog units as channels or dials (a dial's unit is its accumulated rotation in
revolutions; analog proxies are not involved, so values are raw); a device that sent only
text (a ``vrpn_Text_Sender``) is watched with no units, its text messages counted and the
newest shown in its health (``text_messages``, ``last_text``), as for every watched device. Reports beyond the
client's bounds (a sensor id past :data:`gadgetctl.vrpn.codecs.MAX_SENSORS`...) shape no
layout: they are reported, once per device, and the watch runs with the rest.
A server that does not answer, or does not announce the device, is a usage error that
names what the server does announce.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from gadgetctl.errors import GadgetctlError

PREFIX = "vrpn:"


def is_vrpn_argument(argument: str) -> bool:
    return argument.lower().startswith(PREFIX)


@dataclass(frozen=True)
class WatchedDevice:
    argument: str  # as given, without the prefix
    device: str
    server: str  # Device@location as a vrpn element writes it
    sensors: int
    buttons: int
    channels: int
    #: What the first reports held beyond the client's bounds, as one line (or None).
    stray: str | None = None


def resolve(arguments: list[str], *, timeout: float = 2.0) -> list[WatchedDevice]:
    """Probe the servers of ``vrpn:`` arguments; the devices with their layouts."""
    from gadgetctl.vrpn import VrpnNameError, parse_device_name
    from gadgetctl.vrpn.probe import probe

    names = []
    for argument in arguments:
        text = argument[len(PREFIX) :]
        try:
            names.append((text, parse_device_name(text)))
        except VrpnNameError as exc:
            raise GadgetctlError(
                f"{argument}: {exc} (write vrpn:Device@host[:port] or vrpn:Device@tcp://host:port)"
            ) from None
    by_location = defaultdict(list)
    for _text, name in names:
        by_location[name.location].append(name.device)
    results = {loc: probe(loc, devices, timeout=timeout) for loc, devices in by_location.items()}
    watched = []
    for text, name in names:
        result = results[name.location]
        if not result.answered:
            raise GadgetctlError(f"vrpn:{text}: {result.error}")
        if result.listed_only(name.device):
            raise GadgetctlError(
                f"vrpn:{text}: the VRPN server at {name.location} lists {name.device!r} but "
                f"nothing answered for it within {timeout:g} s (a vrpn_server lists any "
                f"name a client once asked for); it announces: {', '.join(result.devices)}"
            )
        if not result.has(name.device):
            offered = ", ".join(result.devices) or "no devices"
            raise GadgetctlError(
                f"vrpn:{text}: the VRPN server at {name.location} has no device "
                f"{name.device!r}; it announces: {offered}"
            )
        layout = result.layouts[name.device]
        stray = None
        if layout.stray:
            count = f"{layout.stray} report" + ("" if layout.stray == 1 else "s")
            stray = f"vrpn:{text}: ignored {count} beyond the client's bounds, the first for {layout.first_stray}"
        if not layout.reports and not layout.texts:
            raise GadgetctlError(
                f"vrpn:{text}: the device sent no tracker, button, analog or dial report "
                f"and no text within {timeout:g} s, so its layout is unknown"
                + (f" ({stray.split(': ', 1)[1]})" if stray else "")
            )
        channels = max(layout.channels, layout.dials)
        watched.append(
            WatchedDevice(text, name.device, text, layout.sensors, layout.buttons, channels, stray)
        )
    return watched


def configuration_text(devices: list[WatchedDevice]) -> str:
    """A configuration with one ``vrpn`` element per device."""
    # imported here: xml.sax.saxutils imports urllib.request (http.client, email, ssl), a
    # third of a tenth of a second every `monitor` paid, with or without a vrpn: argument
    from xml.sax.saxutils import escape, quoteattr

    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<?org-vrjuggler-jccl-settings configuration.version="3.0"?>',
        '<configuration xmlns="http://www.vrjuggler.org/jccl/xsd/3.0/configuration" name="vrpn watch">',
        "<elements>",
        '<input_manager name="VRPN watch" version="2"><driver>VRPN_drv</driver></input_manager>',
    ]
    for d in devices:
        server = escape(d.server)
        lines.append(
            f'<vrpn name={quoteattr(d.argument)} version="3">'
            f"<tracker_server>{server}</tracker_server><button_server>{server}</button_server>"
            f"<analog_server>{server}</analog_server><tracker_count>{d.sensors}</tracker_count>"
            f"<button_count>{d.buttons}</button_count><analog_count>{d.channels}</analog_count>"
            f"<min>-1.0</min><max>1.0</max><text_server>{server}</text_server></vrpn>"
        )
    lines += ["</elements>", "</configuration>", ""]
    return "\n".join(lines)


def write_configuration(
    arguments: list[str],
    directory: Path,
    *,
    timeout: float = 2.0,
    note: Callable[[str], None] | None = None,
) -> Path:
    """Probe, then write the configuration for ``arguments`` into ``directory``; ``note``
    hears a line per device whose first reports went beyond the client's bounds."""
    path = directory / "vrpn-watch.jconf"
    devices = resolve(arguments, timeout=timeout)
    if note is not None:
        for device in devices:
            if device.stray:
                note(device.stray)
    path.write_text(configuration_text(devices), encoding="utf-8")
    return path
