"""The protocol half of the VRPN driver: one ``vrpn`` element's tracker, button and analog
devices read from VRPN servers, as sample batches. Knows nothing of the input manager; the
protocol itself is :mod:`gadgetctl.vrpn` (standalone too, as Gadgeteer drivers use VPR).

Devices at the same location share one connection. Units:

* tracker sensors ``0 .. tracker_count-1`` are position units (4x4 matrices, metres, from
  VRPN's position and (x, y, z, w) quaternion); one position sample per tracker tick (the
  reports of one server timestamp), carrying every sensor's newest pose;
* buttons ``0 .. button_count-1`` are digital units; every change is a sample, so a press and
  release between two frames is never lost; a "States" message is one sample;
* channels ``0 .. analog_count-1`` are analog units (raw; proxies normalise).

Sensors, buttons and channels beyond the counts are counted (``beyond_count``) and ignored.
Each sample carries the local receive time; the server's own time of the same message is
kept beside it (``remote_times``), so that clock offset plus transport latency can be shown.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from gadgetctl.vrpn import VrpnClient, parse_device_name
from gadgetctl.vrpn.codecs import (
    ANALOG_CHANNEL,
    BUTTON_CHANGE,
    BUTTON_STATES,
    TRACKER_ACCELERATION,
    TRACKER_POS_QUAT,
    TRACKER_VELOCITY,
    AnalogChannels,
    ButtonChange,
    ButtonStates,
    TrackerPose,
)
from gadgetctl.vrpn.names import DeviceName, Location
from gadgetctl.vrpn.probe import SYSTEM_SENDERS

TRACKER_MOTION = frozenset({TRACKER_VELOCITY, TRACKER_ACCELERATION})


class VrpnUnavailable(ConnectionError):
    """No connection to a server (down, unreachable, refused, or lost)."""


class VrpnDeviceMissing(ConnectionError):
    """The server answers but does not announce the named device."""


def pose_rows(
    position: tuple[float, float, float], quat: tuple[float, float, float, float]
) -> list[list[float]]:
    """The rows of the 4x4 matrix of a position and an (x, y, z, w) quaternion (normalised
    first; a zero quaternion is no rotation)."""
    x, y, z, w = quat
    n = x * x + y * y + z * z + w * w
    px, py, pz = position
    if n <= 0.0:
        return [[1.0, 0.0, 0.0, px], [0.0, 1.0, 0.0, py], [0.0, 0.0, 1.0, pz], [0.0, 0.0, 0.0, 1.0]]
    s = 2.0 / n
    return [
        [1.0 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w), px],
        [s * (x * y + z * w), 1.0 - s * (x * x + z * z), s * (y * z - x * w), py],
        [s * (x * z - y * w), s * (y * z + x * w), 1.0 - s * (x * x + y * y), pz],
        [0.0, 0.0, 0.0, 1.0],
    ]


def pose_matrix(
    position: tuple[float, float, float], quat: tuple[float, float, float, float]
) -> np.ndarray:
    """A 4x4 matrix from a position and an (x, y, z, w) quaternion (normalised first)."""
    return np.array(pose_rows(position, quat))


@dataclass
class Batch:
    """Samples read by one :meth:`VrpnInput.read`: (receive time, values) per kind, receive
    times as Unix seconds, and the server's time of each sample in ``remote_times``."""

    positions: list[tuple[float, np.ndarray]] = field(default_factory=list)
    digital: list[tuple[float, tuple[int, ...]]] = field(default_factory=list)
    analog: list[tuple[float, tuple[float, ...]]] = field(default_factory=list)
    remote_times: list[tuple[float, float]] = field(default_factory=list)  # (received, server)

    def __bool__(self) -> bool:
        return bool(self.positions or self.digital or self.analog)


def _why(location: Location, client: VrpnClient) -> str:
    """Why no connection is up, naming the server once."""
    error = client.last_error
    if error and str(location) in error:
        return error
    return f"no VRPN server at {location}: {error or 'no answer'}"


class VrpnInput:
    """The VRPN devices of one element. ``open()``, then ``read()`` repeatedly, ``close()``."""

    def __init__(
        self,
        tracker: str = "",
        tracker_count: int = 0,
        button: str = "",
        button_count: int = 0,
        analog: str = "",
        analog_count: int = 0,
        *,
        retry_interval: float = 0.25,
        silence_timeout: float | None = 3.0,
        missing_after: float = 1.0,
    ) -> None:
        self.tracker = parse_device_name(tracker) if tracker and tracker_count > 0 else None
        self.button = parse_device_name(button) if button and button_count > 0 else None
        self.analog = parse_device_name(analog) if analog and analog_count > 0 else None
        self.tracker_count, self.button_count, self.analog_count = (
            tracker_count,
            button_count,
            analog_count,
        )
        self.retry_interval = retry_interval
        self.silence_timeout = silence_timeout
        self.missing_after = missing_after
        self.poses = np.tile(np.eye(4), (max(tracker_count, 0), 1, 1))
        self.buttons = [0] * max(button_count, 0)
        self.channels = [0.0] * max(analog_count, 0)
        self.counters: Counter[str] = Counter()
        self._clients: dict[Location, VrpnClient] = {}
        self._connected_at: dict[Location, float] = {}
        self._checked: set[Location] = set()
        self._heard: set[tuple[Location, str]] = set()  # senders heard on the current connections
        self._deadline = 0.0

    @property
    def devices(self) -> list[DeviceName]:
        return [d for d in (self.tracker, self.button, self.analog) if d is not None]

    @property
    def clients(self) -> dict[Location, VrpnClient]:
        return dict(self._clients)

    def open(self, timeout: float = 1.0, *, wait: bool = True) -> None:
        """Connect to every server within ``timeout``: wait for it (:class:`VrpnUnavailable`
        when one does not answer in time), or with ``wait=False`` return at once and let
        :meth:`read` raise if the connections are not made by then."""
        self.close()
        for dev in self.devices:
            client = self._clients.get(dev.location)
            if client is None:
                client = self._clients[dev.location] = VrpnClient(
                    dev.location,
                    retry_interval=self.retry_interval,
                    silence_timeout=self.silence_timeout,
                )
            client.add_device(dev.device)
        self._deadline = time.monotonic() + timeout
        if not wait:
            return
        for location, client in self._clients.items():
            if not client.wait_connected(max(0.0, self._deadline - time.monotonic())):
                reason = _why(location, client)
                self.close()
                raise VrpnUnavailable(reason)
            self._connected_at[location] = time.monotonic()

    def close(self) -> None:
        for client in self._clients.values():
            self.counters.update(client.counts())
            client.close()
        self._clients.clear()
        self._connected_at.clear()
        self._checked.clear()
        self._heard.clear()

    def read(self, timeout: float = 0.1) -> Batch:
        """What arrived within ``timeout``; raises when a connection is lost or a device is
        not served."""
        batch = Batch()
        clients = list(self._clients.items())
        if not clients:
            raise VrpnUnavailable("not connected")
        share = timeout / len(clients)
        for location, client in clients:
            messages = client.poll(share)
            if client.state != "connected":
                if client.connects:
                    raise VrpnUnavailable(
                        f"lost the VRPN server at {location}: {client.last_error}"
                    )
                if time.monotonic() >= self._deadline:
                    raise VrpnUnavailable(_why(location, client))
                continue
            if client.connects == 1 and location not in self._checked:
                self._connected_at.setdefault(location, time.monotonic())
            for m in messages:
                if m.sender is not None:
                    self._heard.add((location, m.sender))
            self._check_announced(location, client)
            self._take(messages, batch)
        return batch

    def _check_announced(self, location: Location, client: VrpnClient) -> None:
        """Once per connection, ``missing_after`` seconds in: every device of this location
        must have answered its ping or sent a report. (Being announced is not enough: a C++
        vrpn_server announces, for good, every name any client ever asked it for.)"""
        since = self._connected_at.get(location)
        if since is None or time.monotonic() - since < self.missing_after:
            return
        announced = set(client.announced)
        for dev in self.devices:
            if dev.location == location and (location, dev.device) not in self._heard:
                names = ", ".join(sorted(announced - SYSTEM_SENDERS - {dev.device})) or "none"
                listed = (
                    " (it lists the name but nothing answers for it)"
                    if dev.device in announced
                    else ""
                )
                raise VrpnDeviceMissing(
                    f"the VRPN server at {location} has no device {dev.device!r}{listed}; "
                    f"it announces: {names}"
                )
        self._connected_at.pop(location)
        self._checked.add(location)  # checked once per connection

    def _take(self, messages: list, batch: Batch) -> None:
        tick: tuple[int, int] | None = None
        tick_received = 0.0
        tracker = self.tracker.device if self.tracker is not None else None
        button = self.button.device if self.button is not None else None
        analog = self.analog.device if self.analog is not None else None

        def end_tick() -> None:
            batch.positions.append((tick_received, self.poses.copy()))

        for m in messages:
            report = m.report
            if (
                m.type == TRACKER_POS_QUAT
                and m.sender == tracker
                and isinstance(report, TrackerPose)
            ):
                if report.sensor >= self.tracker_count:
                    self.counters["beyond_count"] += 1
                    continue
                if tick is not None and (m.sec, m.usec) != tick:
                    end_tick()
                tick, tick_received = (m.sec, m.usec), m.received
                self.poses[report.sensor] = pose_rows(report.position, report.quat)
                if not batch.remote_times or batch.remote_times[-1][1] != m.timestamp:
                    batch.remote_times.append((m.received, m.timestamp))
                continue
            if m.sender == tracker and m.type in TRACKER_MOTION:
                continue  # velocity and acceleration of the same tick do not end it
            if tick is not None:
                end_tick()
                tick = None
            if m.sender == button and isinstance(report, ButtonChange) and m.type == BUTTON_CHANGE:
                if report.button >= self.button_count:
                    self.counters["beyond_count"] += 1
                    continue
                self.buttons[report.button] = report.state
                batch.digital.append((m.received, tuple(self.buttons)))
            elif (
                m.sender == button and isinstance(report, ButtonStates) and m.type == BUTTON_STATES
            ):
                n = min(len(report.states), self.button_count)
                self.buttons[:n] = report.states[:n]
                batch.digital.append((m.received, tuple(self.buttons)))
            elif (
                m.sender == analog
                and isinstance(report, AnalogChannels)
                and m.type == ANALOG_CHANNEL
            ):
                n = min(len(report.channels), self.analog_count)
                if len(report.channels) > self.analog_count:
                    self.counters["beyond_count"] += 1
                self.channels[:n] = report.channels[:n]
                batch.analog.append((m.received, tuple(self.channels)))
            else:
                continue
            batch.remote_times.append((m.received, m.timestamp))
        if tick is not None:
            end_tick()

    def counts(self) -> Counter[str]:
        """Counters of this element's connections, reconnections included."""
        total = Counter(self.counters)
        for client in self._clients.values():
            total.update(client.counts())
        return total
