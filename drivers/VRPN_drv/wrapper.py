"""The input-manager side of the VRPN driver: a ``vrpn`` element becomes a device with
``tracker_count`` position units, ``button_count`` digital units and ``analog_count``
analog units, read by :class:`~.standalone.VrpnInput`.

A server that is down, goes away, or does not announce the named device makes ``sample()``
raise, so the input manager shows the device faulted (with the reason) and restarts it with
back-off (at most 1 s apart): samples resume within about a second of the server's return.

Sample times are each message's own VRPN time mapped onto the local clock (see
:class:`~.standalone.ServerClock`). The server's own timestamps are also kept in
:attr:`VrpnDevice.remote_clock`: the difference (local receive wall time minus server
time) is the clock offset plus the transport latency.

Nothing is published before the server's first report: proxies read "no data yet" until
then. The kernel's count of the datagrams it dropped on the UDP channel (a full receive
buffer) is the device's transport loss, shown with its other drops. With many sensors the
sample buffer holds at most :data:`STORE_POSE_BYTES` of poses between two frames.
"""

from __future__ import annotations

import time

import numpy as np

from gadgetctl.input import Analog, DeviceConfigError, Digital, Position
from gadgetctl.input.samples import DEFAULT_CAP
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.safetext import printable
from gadgetctl.transport.udp import DatagramLedger
from gadgetctl.vrpn import VrpnNameError
from gadgetctl.vrpn.codecs import MAX_SENSORS

from .standalone import POSE_BYTES, Batch, VrpnInput

#: Counts above these are configuration mistakes (VRPN's own limits: 256 buttons, 128
#: channels; sensors: gadgetctl's bound, :data:`gadgetctl.vrpn.codecs.MAX_SENSORS`).
MAX_BUTTONS = 256
MAX_CHANNELS = 128
#: Bytes of position samples the device's buffer holds between two frames at most: with many
#: sensors it keeps fewer samples than :data:`~gadgetctl.input.samples.DEFAULT_CAP` (the
#: older ones are dropped and counted, as for any device whose frames fall behind).
STORE_POSE_BYTES = 64 << 20
#: The fewest samples the buffer keeps whatever the sensor count.
MIN_CAP = 64
#: Characters of the newest text message shown in the device's health.
MAX_TEXT_SHOWN = 200


def sample_cap(sensors: int) -> int:
    """Samples per kind the device's buffer keeps for ``sensors`` tracker sensors."""
    if sensors <= 0:
        return DEFAULT_CAP
    return max(MIN_CAP, min(DEFAULT_CAP, STORE_POSE_BYTES // (POSE_BYTES * sensors)))


class RemoteClock:
    """Running statistics of ``received - server time`` (seconds) for one device."""

    def __init__(self) -> None:
        self.count = 0
        self.minimum: float | None = None
        self.latest: float | None = None
        self._sum = 0.0

    def add(self, deltas: list[float]) -> None:
        if not deltas:
            return
        self.count += len(deltas)
        self._sum += sum(deltas)
        low = min(deltas)
        self.minimum = low if self.minimum is None else min(self.minimum, low)
        self.latest = deltas[-1]

    @property
    def mean(self) -> float | None:
        return self._sum / self.count if self.count else None

    def to_dict(self) -> dict[str, float | int | None]:
        """``offset``: the smallest difference (clock offset plus the least latency);
        ``latency``: how much the mean exceeds it (transport and queueing delay)."""
        mean = self.mean
        return {
            "samples": self.count,
            "offset": self.minimum,
            "latency": None if mean is None or self.minimum is None else mean - self.minimum,
            "latest": self.latest,
        }


class VrpnDevice(Position, Digital, Analog):
    """A VRPN client (element type ``vrpn``)."""

    ELEMENT_TYPE = "vrpn"
    sample_interval = 0.0  # sample() waits for messages itself

    #: Seconds one sample() call waits for messages.
    receive_timeout = 0.05
    #: Seconds start_sampling() waits for every server to accept the connection.
    connect_timeout = 1.0
    #: A connection with nothing from the server for this long is lost (idle servers still
    #: answer the client's pings).
    silence_timeout = 3.0
    #: Bytes asked of the kernel for the UDP channel's receive buffer.
    receive_buffer = 4 << 20
    #: Seconds between two reads at least: what arrives meanwhile waits in the sockets and
    #: is taken in one read (a read costs about as much as fifty reports, so at 32 sensors
    #: and 1 kHz a read per tick or two would cost more than the reports). Sample times are
    #: the messages' own, so only the delivery is later, by at most this (half a frame at
    #: 60 Hz).
    read_interval = 0.008

    def __init__(self) -> None:
        super().__init__()
        self.tracker_server = self.button_server = self.analog_server = self.text_server = ""
        self.tracker_count = self.button_count = self.analog_count = 0
        self._input: VrpnInput | None = None
        self.remote_clock = RemoteClock()
        self._started = False

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, position filters, min and max
        for kind, limit in (
            ("tracker", MAX_SENSORS),
            ("button", MAX_BUTTONS),
            ("analog", MAX_CHANNELS),
        ):
            server = access.string(f"{kind}_server").strip() if access.has(f"{kind}_server") else ""
            count = access.integer(f"{kind}_count") if access.has(f"{kind}_count") else 0
            if not 0 <= count <= limit:
                raise DeviceConfigError(f"{kind}_count {count} is out of range (0 to {limit})")
            setattr(self, f"{kind}_server", server)
            setattr(self, f"{kind}_count", count)
        self.text_server = access.string("text_server").strip() if access.has("text_server") else ""
        self.store.cap = sample_cap(self.tracker_count)
        try:
            self._input = self._make_input()
        except VrpnNameError as exc:
            raise DeviceConfigError(str(exc)) from None
        if not self._input.devices:
            self.warn("DRV101", "no VRPN device to read: every *_server is empty or its count is 0")

    def _make_input(self) -> VrpnInput:
        return VrpnInput(
            self.tracker_server,
            self.tracker_count,
            self.button_server,
            self.button_count,
            self.analog_server,
            self.analog_count,
            silence_timeout=self.silence_timeout,
            udp_receive_buffer=self.receive_buffer,
            text=self.text_server,
        )

    # -- sampling ---------------------------------------------------------------------------

    def start_sampling(self) -> None:
        if self._input is None:
            self._input = self._make_input()
        # The first start does not wait: a server that is down then shows as a fault (and
        # the restarts) rather than as an element that failed to start.
        self._input.open(self.connect_timeout, wait=self._started)
        self._started = True
        # Nothing is published until the server reports: no made-up first state.

    def sample(self) -> None:
        if self._input is None:
            raise ConnectionError("not configured")
        if not self._input.devices:
            time.sleep(self.receive_timeout)
            return
        began = time.monotonic()
        batch = self._input.read(self.receive_timeout)
        if batch:
            self._add(batch)
        rest = self.read_interval - (time.monotonic() - began)
        if rest > 0:
            time.sleep(rest)

    def stop_sampling(self) -> None:
        if self._input is not None:
            self._input.close()

    def _add(self, batch: Batch) -> None:
        offset = self.now() - time.time()  # wall-clock receive times onto the sample clock
        if batch.positions:
            stamps = np.array([t for t, _ in batch.positions]) + offset
            self.add_position_samples(stamps, np.stack([m for _, m in batch.positions]))
        if batch.digital:
            stamps = np.array([t for t, _ in batch.digital]) + offset
            self.add_digital_samples(stamps, np.array([v for _, v in batch.digital]))
        if batch.analog:
            stamps = np.array([t for t, _ in batch.analog]) + offset
            self.add_analog_samples(stamps, np.array([v for _, v in batch.analog]))
        self.remote_clock.add([received - server for received, server in batch.remote_times])

    # -- diagnostics ------------------------------------------------------------------------

    def health(self) -> dict[str, int | float | str]:
        """The base health, and the newest text message of the element's devices
        (``last_text``: "warning 3 from Text0: ...", made printable)."""
        found = super().health()
        if self._input is not None and self._input.texts:
            _moment, device, severity, level, text = self._input.texts[-1]
            kind = {0: "normal", 1: "warning", 2: "error"}.get(severity, f"severity {severity}")
            found["last_text"] = printable(f"{kind} {level} from {device}: {text}")[:MAX_TEXT_SHOWN]
        return found

    def datagram_ledger(self) -> DatagramLedger | None:
        """The account of the UDP channel's datagrams (lob mode) of the element's first
        server: read, decoded or bad, dropped by the kernel (:meth:`transport_dropped`
        sums the kernel's drops of every server)."""
        if self._input is None or not self._input.devices:
            return None
        location = self._input.devices[0].location
        return self._input.ledgers.get(location)

    def transport_dropped(self) -> int:
        """Datagrams the kernel dropped on the UDP channels (a full receive buffer)."""
        return self._input.kernel_dropped if self._input is not None else 0

    @property
    def counters(self) -> dict[str, int]:
        """What the connections counted since the device was made, reconnections included."""
        return dict(self._input.counts()) if self._input is not None else {}
