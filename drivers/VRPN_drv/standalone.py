"""The protocol half of the VRPN driver: one ``vrpn`` element's tracker, button and analog
devices read from VRPN servers, as sample batches. Knows nothing of the input manager; the
protocol itself is :mod:`gadgetctl.vrpn` (standalone too, as Gadgeteer drivers use VPR).

Devices at the same location share one connection. Units:

* tracker sensors ``0 .. tracker_count-1`` are position units (4x4 matrices, metres, from
  VRPN's position and (x, y, z, w) quaternion); one position sample per tracker tick (the
  reports of one server timestamp), carrying every sensor's newest pose. A tick is complete
  when every sensor reported in it, when a report of another timestamp arrives, or after
  :data:`TICK_HOLD` seconds: a tick split over two reads (two datagrams, two TCP segments)
  is still one sample, so a sample never mixes sensors of two ticks;
* buttons ``0 .. button_count-1`` are digital units; every change is a sample, so a press and
  release between two frames is never lost; a "States" message is one sample;
* channels ``0 .. analog_count-1`` are analog units (raw; proxies normalise). A VRPN *dial*
  named as the analog server is read as analog units too: unit ``d`` is dial ``d``'s
  accumulated rotation in revolutions (the sum of its updates' deltas).

Nothing is published before the server's first report of a kind (proxies read "no data
yet" until then); sensors that have not reported yet in the first ticks are identity poses.
Sensors, buttons, channels and dials beyond the counts are counted (``beyond_count``) and
ignored. Text messages of the element's devices (and of its ``text_server``, a device read
for its text only) are counted (``text_messages``) and the newest few kept
(:attr:`VrpnInput.texts`).

Each sample carries its own VRPN message time, mapped onto the local wall clock
(:class:`ServerClock`): the server's time plus the smallest ``received - sent`` seen, so the
intervals between samples are the server's, not those of the reads; a kind's sample times
never go back. A message whose time is 0 (a C++ ``vrpn_Button_Server`` sends it) takes its
receive time. The server's time of each message is also kept beside its receive time
(``remote_times``), so that clock offset plus transport latency can be shown.

The tracker's poses are not decoded one by one: the client leaves them framed
(``VrpnClient(bulk=...)``, :class:`gadgetctl.vrpn.wire.Block`) and :meth:`VrpnInput.
_take_block` reads a whole read's worth with one numpy record view and builds every matrix
at once. Each server location's UDP channel is accounted for by a
:class:`~gadgetctl.transport.udp.DatagramLedger` (:attr:`VrpnInput.ledgers`): datagrams
decoded or bad, and the kernel's drops.

A read makes at most :data:`POSE_READ_BYTES` of position samples: with a large
``tracker_count``, ticks beyond that within one read are merged into the read's last sample
(counted as ``merged_ticks``), so neither memory nor the cost of a read grows with the
number of small reports times the number of sensors.
"""

from __future__ import annotations

import time
from collections import Counter, deque
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from gadgetctl.serve.framing import POSE_MESSAGE
from gadgetctl.transport.udp import DatagramLedger
from gadgetctl.vrpn import VrpnClient, parse_device_name
from gadgetctl.vrpn.codecs import (
    ANALOG_CHANNEL,
    BUTTON_CHANGE,
    BUTTON_STATES,
    DIAL_UPDATE,
    TEXT_MESSAGE,
    TRACKER_ACCELERATION,
    TRACKER_POS_QUAT,
    TRACKER_VELOCITY,
    AnalogChannels,
    ButtonChange,
    ButtonStates,
    DialUpdate,
    TextReport,
    TrackerPose,
)
from gadgetctl.vrpn.names import DeviceName, Location
from gadgetctl.vrpn.probe import SYSTEM_SENDERS
from gadgetctl.vrpn.wire import Block

#: Tracker reports that come with the poses and are not read.
TRACKER_MOTION = (TRACKER_VELOCITY, TRACKER_ACCELERATION)
#: Seconds an incomplete tracker tick waits for the rest of its sensors before it is
#: published with what came (a server that reports a subset of its sensors per tick).
TICK_HOLD = 0.02
#: Bytes of position samples one read makes at most (see the module's notes).
POSE_READ_BYTES = 4 << 20
#: Bytes of one sensor's pose in a sample (a 4x4 float64 matrix).
POSE_BYTES = 16 * 8
#: Text messages kept (the newest).
TEXTS_KEPT = 16
#: A server time this far from the mapping (seconds) re-anchors it: the server's clock
#: stepped, or the link stalled.
CLOCK_RESYNC = 1.0


class ServerClock:
    """Maps one server's message times onto the local wall clock: ``sent + offset``, where the
    offset is the smallest ``received - sent`` seen (clock difference plus the least
    latency). A read's messages are all observed before any is mapped, so the newest message
    of a burst maps to no later than its arrival and the earlier ones keep the server's
    intervals before it."""

    __slots__ = ("offset",)

    def __init__(self) -> None:
        self.offset: float | None = None

    def observe(self, sent: float, received: float) -> None:
        """One message's times (a ``sent`` of 0 or less says nothing)."""
        if sent <= 0.0:
            return
        difference = received - sent
        offset = self.offset
        if offset is None or difference < offset or difference - offset > CLOCK_RESYNC:
            self.offset = difference

    def local(self, sent: float, received: float) -> float:
        """The local time of a message sent at ``sent`` (its ``received`` when it has no
        time: a C++ ``vrpn_Button_Server`` sends 0)."""
        if sent <= 0.0 or self.offset is None:
            return received
        return sent + self.offset


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


def pose_records(block: Block) -> np.ndarray:
    """The pose messages of ``block`` as :data:`POSE_MESSAGE` records, read in one go."""
    offsets = block.offsets
    size = POSE_MESSAGE.itemsize
    first, count = offsets[0], len(offsets)
    if offsets[-1] - first == (count - 1) * size:  # back to back: no gathering
        return np.frombuffer(block.data, POSE_MESSAGE, count=count, offset=first)
    raw = np.frombuffer(block.data, np.uint8)
    rows = raw[np.asarray(offsets)[:, None] + np.arange(size)]
    return rows.view(POSE_MESSAGE)[:, 0]


# Rotation matrix entries as sums of quaternion products: entry (row, column) of the
# rotation is [row==column] + s * sum(sign * q[i] * q[j]) over the pairs listed (x, y, z, w
# = 0, 1, 2, 3), s = 2 / |q|^2, as :func:`pose_rows` writes them out.
_PRODUCTS = np.zeros((16, 9))
for _entry, _terms in enumerate(
    (
        ((1, 1, -1), (2, 2, -1)),
        ((0, 1, 1), (2, 3, -1)),
        ((0, 2, 1), (1, 3, 1)),
        ((0, 1, 1), (2, 3, 1)),
        ((0, 0, -1), (2, 2, -1)),
        ((1, 2, 1), (0, 3, -1)),
        ((0, 2, 1), (1, 3, -1)),
        ((1, 2, 1), (0, 3, 1)),
        ((0, 0, -1), (1, 1, -1)),
    )
):
    for _i, _j, _sign in _terms:
        _PRODUCTS[4 * _i + _j, _entry] = _sign
_IDENTITY3 = np.eye(3).reshape(9)


def pose_matrices(position: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """The 4x4 matrices of positions (n, 3) and (x, y, z, w) quaternions (n, 4), as
    :func:`pose_rows` makes them one by one (a zero quaternion is no rotation)."""
    q = np.asarray(quat, dtype=np.float64)
    n = len(q)
    norm = np.einsum("ij,ij->i", q, q)
    s = np.divide(2.0, norm, out=np.zeros(n), where=norm > 0.0)
    products = (q[:, :, None] * q[:, None, :]).reshape(n, 16)
    out = np.zeros((n, 4, 4))
    out[:, :3, :3] = (_IDENTITY3 + s[:, None] * (products @ _PRODUCTS)).reshape(n, 3, 3)
    out[:, :3, 3] = position
    out[:, 3, 3] = 1.0
    return out


def pose_matrix(
    position: tuple[float, float, float], quat: tuple[float, float, float, float]
) -> np.ndarray:
    """A 4x4 matrix from a position and an (x, y, z, w) quaternion (normalised first)."""
    return np.array(pose_rows(position, quat))


@dataclass
class Batch:
    """Samples read by one :meth:`VrpnInput.read`: (time, values) per kind, times as Unix
    seconds (each message's own time, see :class:`ServerClock`), and the receive and server
    times of each message in ``remote_times``."""

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
        udp_receive_buffer: int = 4 << 20,
        text: str = "",
    ) -> None:
        self.tracker = parse_device_name(tracker) if tracker and tracker_count > 0 else None
        #: A device read for its text messages only (``text_server``).
        self.text = parse_device_name(text) if text else None
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
        self.udp_receive_buffer = udp_receive_buffer
        self.poses = np.tile(np.eye(4), (max(tracker_count, 0), 1, 1))
        self.buttons = [0] * max(button_count, 0)
        self.channels = [0.0] * max(analog_count, 0)
        self.counters: Counter[str] = Counter()
        #: The newest text messages of the element's devices: (time, device, severity,
        #: level, text).
        self.texts: deque[tuple[float, str, int, int, str]] = deque(maxlen=TEXTS_KEPT)
        #: Position samples one read makes at most (see :data:`POSE_READ_BYTES`).
        self.pose_limit = max(1, POSE_READ_BYTES // max(1, POSE_BYTES * max(tracker_count, 0)))
        self._clocks: dict[Location, ServerClock] = {}
        self._last_times: dict[str, float] = {}  # the newest sample time per kind
        #: Per server location, the account of its UDP channel's datagrams (every
        #: connection so far): read, decoded or bad, and dropped by the kernel.
        self.ledgers: dict[Location, DatagramLedger] = {}
        # the tracker tick being gathered: its (sec, usec), local time, arrival, sensors seen
        self._tick: int | None = None  # seconds * 1e6 + microseconds
        self._tick_time = 0.0
        self._tick_arrival = 0.0
        self._tick_seen = np.zeros(max(tracker_count, 0), dtype=bool)
        self._tick_count = 0  # sensors seen in the tick
        self._clients: dict[Location, VrpnClient] = {}
        self._connected_at: dict[Location, float] = {}
        self._checked: set[Location] = set()
        self._heard: set[tuple[Location, str]] = set()  # senders heard on the current connections
        self._deadline = 0.0

    @property
    def devices(self) -> list[DeviceName]:
        named = [d for d in (self.tracker, self.button, self.analog) if d is not None]
        if self.text is not None and self.text not in named:
            named.append(self.text)
        return named

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
                receiver = self.ledgers.setdefault(dev.location, DatagramLedger())
                client = self._clients[dev.location] = VrpnClient(
                    dev.location,
                    retry_interval=self.retry_interval,
                    silence_timeout=self.silence_timeout,
                    udp_receiver=receiver,
                    udp_receive_buffer=self.udp_receive_buffer,
                    bulk=self._bulk(dev.location),
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
        self._clocks.clear()
        self._connected_at.clear()
        self._checked.clear()
        self._heard.clear()
        self._tick = None  # a tick cut by the connection's end is not published
        self._tick_seen[:] = False
        self._tick_count = 0

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
            blocks = client.take_blocks()
            for m in messages:
                if m.sender is not None:
                    self._heard.add((location, m.sender))
            for block in blocks:
                self._heard.add((location, block.sender))
            self._check_announced(location, client)
            clock = self._clocks.setdefault(location, ServerClock())
            self._take(messages, batch, clock)
            for block in blocks:
                if block.type == TRACKER_POS_QUAT:
                    self._take_block(block, batch, clock)
                else:
                    self.counters["motion_reports"] += len(block.offsets)  # not read
        if self._tick is not None and time.time() - self._tick_arrival >= TICK_HOLD:
            self._end_tick(batch)  # the rest of its sensors did not come
        return batch

    def _bulk(self, location: Location) -> list[tuple[str, str]]:
        """The (sender, type) pairs the client at ``location`` leaves framed for
        :meth:`_take_block`: the tracker's poses."""
        tracker = self.tracker
        if tracker is None or tracker.location != location:
            return []
        # velocity and acceleration too: not read, but then they cost no decoding either (a
        # C++ tracker sends both with every pose)
        return [(tracker.device, kind) for kind in (TRACKER_POS_QUAT, *TRACKER_MOTION)]

    @property
    def kernel_dropped(self) -> int:
        """Datagrams the kernel dropped on the UDP channels (every connection so far)."""
        return sum(ledger.kernel_dropped for ledger in self.ledgers.values())

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

    def _after(self, kind: str, moment: float) -> float:
        """``moment``, or the kind's previous sample time if that is later: the mapping onto
        the local clock may move back a little (less latency seen), a kind's samples never
        do."""
        last = self._last_times.get(kind)
        if last is not None and moment < last:
            moment = last
        self._last_times[kind] = moment
        return moment

    def _end_tick(self, batch: Batch) -> None:
        """Publish the tick gathered so far as one position sample."""
        self._tick = None
        self._tick_seen[:] = False
        self._tick_count = 0
        self._tick_time = self._after("position", self._tick_time)
        positions = batch.positions
        if len(positions) >= self.pose_limit:
            # the read's budget is spent: this tick replaces the read's last sample (its
            # array reused, nothing allocated)
            _, values = positions[-1]
            np.copyto(values, self.poses)
            positions[-1] = (self._tick_time, values)
            self.counters["merged_ticks"] += 1
        else:
            positions.append((self._tick_time, self.poses.copy()))

    def _take_block(self, block: Block, batch: Batch, clock: ServerClock) -> None:
        """A read's tracker poses (framed by the client, see :class:`~gadgetctl.vrpn.wire.
        Block`), unpacked at once: the same samples as :meth:`_take` makes of them one by
        one."""
        records = pose_records(block)
        received = block.received
        sec = records["sec"].astype(np.int64)
        usec = records["usec"].astype(np.int64)
        times = sec + usec * 1e-6
        timed = times[sec > 0]
        if len(timed):
            clock.observe(float(timed.max()), received)
        sensors = records["sensor"].astype(np.int64)
        inside = sensors < self.tracker_count
        if not inside.all():
            self.counters["beyond_count"] += int(np.count_nonzero(~inside))
            records, sensors, sec, usec, times = (
                records[inside],
                sensors[inside],
                sec[inside],
                usec[inside],
                times[inside],
            )
        if not len(records):
            return
        matrices = pose_matrices(records["position"], records["quat"])
        keys = sec * 1_000_000 + usec
        starts = [0, *(np.flatnonzero(keys[1:] != keys[:-1]) + 1).tolist(), len(keys)]
        poses, seen, count = self.poses, self._tick_seen, self.tracker_count
        for first, last in pairwise(starts):
            key = int(keys[first])
            if self._tick is not None and key != self._tick:
                self._end_tick(batch)
            if self._tick is None:
                self._tick = key
                self._tick_arrival = received
                sent = float(times[first])
                self._tick_time = clock.local(sent, received)
                batch.remote_times.append((received, sent))
            these = sensors[first:last]
            poses[these] = matrices[first:last]
            seen[these] = True
            self._tick_count = int(np.count_nonzero(seen))
            if self._tick_count == count:
                self._end_tick(batch)  # every sensor reported: the tick is whole

    def _take(self, messages: list, batch: Batch, clock: ServerClock | None = None) -> None:
        """Turn one read's messages into samples (``clock``: the server's, see
        :class:`ServerClock`; a new one when not given)."""
        if clock is None:
            clock = ServerClock()
        tracker = self.tracker.device if self.tracker is not None else None
        button = self.button.device if self.button is not None else None
        analog = self.analog.device if self.analog is not None else None
        texts_from = {d.device for d in self.devices}
        counters = self.counters
        observe, local = clock.observe, clock.local
        for m in messages:
            observe(m.timestamp, m.received)
        for m in messages:
            report = m.report
            sender = m.sender
            if report is None or sender is None:
                continue
            kind = m.type
            if sender == tracker and kind == TRACKER_POS_QUAT and isinstance(report, TrackerPose):
                sensor = report.sensor
                if sensor >= self.tracker_count:
                    counters["beyond_count"] += 1
                    continue
                stamp = m.sec * 1_000_000 + m.usec
                if self._tick is not None and stamp != self._tick:
                    self._end_tick(batch)
                if self._tick is None:
                    self._tick = stamp
                    self._tick_arrival = m.received
                    self._tick_time = local(m.timestamp, m.received)
                    batch.remote_times.append((m.received, m.timestamp))
                self.poses[sensor] = pose_rows(report.position, report.quat)
                if not self._tick_seen[sensor]:
                    self._tick_seen[sensor] = True
                    self._tick_count += 1
                    if self._tick_count == self.tracker_count:
                        self._end_tick(batch)  # every sensor reported: the tick is whole
                continue
            if kind == TEXT_MESSAGE and isinstance(report, TextReport):
                if sender in texts_from:
                    counters["text_messages"] += 1
                    self.texts.append(
                        (local(m.timestamp, m.received), sender, *report)  # type: ignore[arg-type]
                    )
                continue
            if sender == button and kind == BUTTON_CHANGE and isinstance(report, ButtonChange):
                if report.button >= self.button_count:
                    counters["beyond_count"] += 1
                    continue
                self.buttons[report.button] = report.state
                batch.digital.append(
                    (self._after("digital", local(m.timestamp, m.received)), tuple(self.buttons))
                )
            elif sender == button and kind == BUTTON_STATES and isinstance(report, ButtonStates):
                n = min(len(report.states), self.button_count)
                self.buttons[:n] = report.states[:n]
                batch.digital.append(
                    (self._after("digital", local(m.timestamp, m.received)), tuple(self.buttons))
                )
            elif sender == analog and kind == ANALOG_CHANNEL and isinstance(report, AnalogChannels):
                n = min(len(report.channels), self.analog_count)
                if len(report.channels) > self.analog_count:
                    counters["beyond_count"] += 1
                self.channels[:n] = report.channels[:n]
                batch.analog.append(
                    (self._after("analog", local(m.timestamp, m.received)), tuple(self.channels))
                )
            elif sender == analog and kind == DIAL_UPDATE and isinstance(report, DialUpdate):
                if not 0 <= report.dial < self.analog_count:
                    counters["beyond_count"] += 1
                    continue
                self.channels[report.dial] += report.delta  # revolutions, accumulated
                batch.analog.append(
                    (self._after("analog", local(m.timestamp, m.received)), tuple(self.channels))
                )
            else:
                continue
            batch.remote_times.append((m.received, m.timestamp))

    def counts(self) -> Counter[str]:
        """Counters of this element's connections, reconnections included."""
        total = Counter(self.counters)
        for client in self._clients.values():
            total.update(client.counts())
        return total
