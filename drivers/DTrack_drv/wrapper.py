"""The input-manager side of the DTrack driver: a ``dtrack`` element becomes a device with
position, digital and analog units fed from :class:`~.standalone.DTrackStandalone`.

Units, as Gadgeteer's DTrackWrapper numbers them (see :class:`~.standalone.DTrackUnits`):

* position: the Flysticks, then the measurement tools, then the standard bodies; 4x4
  matrices in metres (DTrack sends millimetres);
* digital: 8 buttons per Flystick (unit ``8i + j``), then 4 per tool, then the Flystick
  buttons beyond the eighth, Flystick by Flystick (upstream rejected such Flysticks);
* analog: 2 joystick values per Flystick (unit ``2i + j``, raw in [-1, 1]; analog proxies
  normalise with the element's ``min``/``max``), then any further values the same way.

Every datagram becomes one sample of each kind, stamped from DTrack's ``ts`` field
(upstream kept only the newest datagram of each read). Silence longer than :attr:`DTrackDevice.peer_timeout` raises from ``sample()``, so the input
manager marks the device faulted and restarts it with back-off; a restart after such a loss
succeeds only once datagrams arrive again.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np

from gadgetctl.input import Analog, DeviceConfigError, Digital, Position
from gadgetctl.input.receiving import ReceiverSampling
from gadgetctl.jccl.access import ElementAccess

from .standalone import (
    DEFAULT_LIMITS,
    DTrackDisconnected,
    DTrackFrame,
    DTrackLimits,
    DTrackStandalone,
    DTrackUnits,
)


def _udp_port(access: ElementAccess, prop: str) -> int:
    port = access.integer(prop)
    if not 0 <= port <= 65535:
        raise DeviceConfigError(f"{prop} {port} is not a UDP port (0 to 65535)")
    return port


class DTrackDevice(ReceiverSampling[DTrackStandalone], Position, Digital, Analog):
    """An A.R.T. DTrack tracker (element type ``dtrack``)."""

    ELEMENT_TYPE = "dtrack"
    DISCONNECTED = DTrackDisconnected
    DATA_NAME = "DTrack data"
    PORT_ATTRIBUTE = "receive_port"

    #: When datagrams queue up (a fast tracker), seconds to let the next batch gather: a batch
    #: costs far less per datagram than datagrams one by one. A slow tracker never waits.
    batch_pause = 0.001
    #: Socket receive buffer asked for (bytes): about 0.2 s of a 10 kHz stream of 10 bodies.
    receive_buffer = 4 * 1024 * 1024
    #: Remote control: seconds between "cameras and tracking on" and "start sending" (upstream: 1).
    start_delay = 1.0
    #: Objects per kind, buttons and joystick values a datagram may ask for: a line beyond them
    #: is counted as bad and skipped, so no peer can grow the units past them.
    limits: DTrackLimits = DEFAULT_LIMITS

    def __init__(self) -> None:
        super().__init__()
        self.receive_port = 5000
        self.server_name = ""
        self.command_port = 5001
        self._peer_timeout = 2.0
        self._units = DTrackUnits(extra_units=True, limits=self.limits)
        self._last_stamp = -math.inf

    @property
    def peer_timeout(self) -> float:
        """Seconds without a datagram after which the tracker counts as gone (default 2)."""
        return self._peer_timeout

    @peer_timeout.setter
    def peer_timeout(self, seconds: float) -> None:
        self._peer_timeout = seconds
        if self._receiver is not None:
            self._receiver.peer_timeout = seconds

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, position filters, min and max
        self.receive_port = _udp_port(access, "receive_port")
        self.server_name = access.string("server_name")
        self.command_port = _udp_port(access, "command_port")  # 0 or empty: no remote control

    # -- sampling ---------------------------------------------------------------------------

    def _new_receiver(self) -> DTrackStandalone:
        return DTrackStandalone(
            self.receive_port,
            server_name=self.server_name,
            command_port=self.command_port,
            receive_timeout=self.receive_timeout,
            peer_timeout=self._peer_timeout,
            receive_buffer=self.receive_buffer,
            start_delay=self.start_delay,
            limits=self.limits,
        )

    def _after_sample(self, frames: Sequence[DTrackFrame]) -> None:
        """Frames queue up: let the next batch gather (:attr:`batch_pause`)."""
        if len(frames) > 1:
            time.sleep(self.batch_pause)

    # -- samples ----------------------------------------------------------------------------

    def _add(self, frames: Sequence[DTrackFrame]) -> None:
        """One sample of each kind per frame, all laid out as after the last frame."""
        stamps = self._stamps(frames)
        units = self._units.merge(frames)
        self.add_position_samples(stamps, units.positions)
        self.add_digital_samples(stamps, units.digital)
        self.add_analog_samples(stamps, units.analog)

    def _stamps(self, frames: Sequence[DTrackFrame]) -> np.ndarray:
        """Sample times: the newest frame now, the others earlier by their ``ts`` difference,
        never before the previous batch nor out of order."""
        now = self.now()
        times = [f.timestamp for f in frames]
        if None in times:
            stamps = np.full(len(frames), now)
        else:
            stamps = now - (times[-1] - np.asarray(times, dtype=np.float64))
        stamps = np.maximum.accumulate(np.clip(stamps, self._last_stamp, now))
        self._last_stamp = float(stamps[-1])
        return stamps

    # -- diagnostics ------------------------------------------------------------------------

    @property
    def port(self) -> int | None:
        """The UDP port the device receives on, once it has started."""
        driver = self._receiver
        return driver.port if driver is not None and driver.is_open else None

    @property
    def counters(self) -> dict[str, int]:
        """What the receiver counted since the device was made, reconnections included:
        its ledger's (:meth:`datagram_ledger`) and the DTrack-specific ones."""
        driver = self._receiver
        if driver is None:
            return {}
        return {
            **driver.ledger.counters(),
            "bad_lines": driver.bad_lines,
            "truncated_datagrams": driver.truncated_datagrams,
            "missed_frames": driver.missed_frames,
        }
