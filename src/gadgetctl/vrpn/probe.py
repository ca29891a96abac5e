"""Ask a VRPN server what it serves: whether it answers, its version, the device (sender)
names it announces and, for named devices, the layout their first reports show (tracker
sensors, buttons, analog channels). Used by ``doctor --probe`` and ``monitor vrpn:NAME``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from .client import VrpnClient
from .codecs import (
    MAX_DIALS,
    MAX_SENSORS,
    AnalogChannels,
    ButtonChange,
    ButtonStates,
    DialUpdate,
    TextReport,
    TrackerAcceleration,
    TrackerPose,
    TrackerVelocity,
)
from .names import Location

#: Names every C++ server announces that are not devices.
SYSTEM_SENDERS = frozenset({"VRPN Control", "vrpn_Forwarder_Brain"})


@dataclass
class Layout:
    """What the reports of one device showed: 0 means "none seen". Sensor and dial ids are
    bounded (:data:`~.codecs.MAX_SENSORS`, :data:`~.codecs.MAX_DIALS`): a report beyond is
    counted in ``stray`` (the first such id in ``first_stray``) and shapes no layout."""

    sensors: int = 0
    buttons: int = 0
    channels: int = 0
    dials: int = 0
    texts: int = 0
    reports: int = 0
    stray: int = 0
    first_stray: str | None = None

    def note(self, report: object) -> None:
        self.reports += 1
        if isinstance(report, (TrackerPose, TrackerVelocity, TrackerAcceleration)):
            if report.sensor >= MAX_SENSORS:
                self._stray(f"sensor {report.sensor} (sensors are 0 to {MAX_SENSORS - 1})")
            else:
                self.sensors = max(self.sensors, report.sensor + 1)
        elif isinstance(report, DialUpdate):
            if not 0 <= report.dial < MAX_DIALS:
                self._stray(f"dial {report.dial} (dials are 0 to {MAX_DIALS - 1})")
            else:
                self.dials = max(self.dials, report.dial + 1)
        elif isinstance(report, TextReport):
            self.texts += 1
        elif isinstance(report, ButtonChange):
            self.buttons = max(self.buttons, report.button + 1)
        elif isinstance(report, ButtonStates):
            self.buttons = max(self.buttons, len(report.states))
        elif isinstance(report, AnalogChannels):
            self.channels = max(self.channels, len(report.channels))
        else:
            self.reports -= 1

    def _stray(self, what: str) -> None:
        self.reports -= 1
        self.stray += 1
        if self.first_stray is None:
            self.first_stray = what


@dataclass
class ProbeResult:
    location: Location
    answered: bool = False
    version: str | None = None
    error: str | None = None
    announced: list[str] = field(default_factory=list)
    layouts: dict[str, Layout] = field(default_factory=dict)
    heard: set[str] = field(default_factory=set)  # named devices that sent something (a pong...)

    @property
    def devices(self) -> list[str]:
        """Announced names without the server's own (``VRPN Control``...)."""
        return [n for n in self.announced if n not in SYSTEM_SENDERS]

    def has(self, device: str) -> bool:
        """Whether the server serves ``device``: it announces it and the device answered the
        client's ping or sent a report. (A C++ ``vrpn_server`` also announces, for good, any
        name a client ever described to it, with no device behind it.)"""
        return device in self.announced and device in self.heard

    def listed_only(self, device: str) -> bool:
        """Announced, but silent: most likely a name some client once asked a vrpn_server for."""
        return device in self.announced and device not in self.heard


def probe(
    location: Location | str, devices: list[str] = (), *, timeout: float = 2.0, observe: float = 0.5
) -> ProbeResult:
    """Connect (as ``location`` says: lob or direct TCP) within ``timeout``; then watch the
    named devices' reports for ``observe`` seconds (longer, up to ``timeout``, while a named
    and announced device has not answered its ping or sent no report)."""
    client = VrpnClient(location, list(devices), retry_interval=0.25)
    result = ProbeResult(client.location)
    result.layouts = {d: Layout() for d in devices}
    deadline = time.monotonic() + timeout
    try:
        if not client.wait_connected(timeout):
            result.error = client.last_error or f"no VRPN server answered within {timeout:g} s"
            return result
        result.answered = True
        result.version = client.server_version
        settle = time.monotonic() + min(observe, max(0.0, deadline - time.monotonic()))
        while True:
            now = time.monotonic()
            waiting = [
                d
                for d in devices
                if d in client.announced
                and (d not in result.heard or not result.layouts[d].reports)
            ]
            if not client.announced:  # the descriptions follow the cookie: wait for them
                waiting = ["(descriptions)"]
            if now >= deadline or (now >= settle and not waiting):
                break
            result.announced = client.announced or result.announced
            for m in client.poll(min(0.05, max(0.0, deadline - now))):
                if m.sender in result.layouts:
                    result.heard.add(m.sender)
                    if m.report is not None:
                        result.layouts[m.sender].note(m.report)
            if client.state != "connected":
                result.error = client.last_error
                break
        result.announced = client.announced or result.announced
    finally:
        client.close()
    return result
