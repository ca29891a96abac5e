"""The input-manager side of the trackd driver: ``trackd_sensor`` elements become position
devices and ``trackd_controller`` elements digital and analog devices, read from trackd's
shared memory by :class:`~.standalone.TrackdSegment`.

Units, as Gadgeteer numbers them: position unit i = sensor i; digital unit i = button i;
analog unit j = valuator j (raw; analog proxies normalise with the element's ``min``/``max``).

The segment is polled :attr:`TrackdDevice.poll_rate` times a second (on a fixed grid, so a
late poll does not slow the rate down), and a sample is added
when its contents changed (and once after attaching). A header that does not fit its segment
is counted in ``bad_records`` and skipped; a segment that goes away raises, so the input
manager marks the device faulted and attaches again with back-off once trackd is back.
"""

from __future__ import annotations

import time

from gadgetctl.input import Analog, DeviceConfigError, Digital, Position
from gadgetctl.input.device import Input
from gadgetctl.jccl.access import ElementAccess

from .standalone import (
    BadSegment,
    TrackdDisconnected,
    TrackdSegment,
    decode_controller,
    pose_matrices,
    tracker_poses,
)


class TrackdDevice(Input):
    """What both element types share: the key, the polling, the counters."""

    sample_interval = 0.0  # sample() paces itself on a fixed grid of poll_rate
    poll_rate = 1000.0  # polls of the segment per second
    DEFAULT_KEY = 0

    def __init__(self) -> None:
        super().__init__()
        self.shared_memory_key = self.DEFAULT_KEY
        self._segment: TrackdSegment | None = None
        self._last: bytes | None = None
        self._next_poll = 0.0
        self.polls = 0
        self.records = 0
        self.bad_records = 0

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.shared_memory_key = access.integer("shared_memory_key")
        if not 0 < self.shared_memory_key <= 0x7FFFFFFF:
            raise DeviceConfigError(
                f"shared_memory_key {self.shared_memory_key} is not a System V key (1 to 2147483647)"
            )

    def start_sampling(self) -> None:
        segment = TrackdSegment(self.shared_memory_key)
        segment.open()
        self._segment = segment
        self._last = None
        self._next_poll = time.monotonic()

    def stop_sampling(self) -> None:
        segment, self._segment = self._segment, None
        if segment is not None:
            segment.close()

    def sample(self) -> None:
        segment = self._segment
        if segment is None:
            raise TrackdDisconnected(f"shared-memory key {self.shared_memory_key}: not attached")
        wait = self._next_poll - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        self._next_poll = max(self._next_poll + 1.0 / self.poll_rate, time.monotonic() - 0.05)
        data = self._read(segment)
        self.polls += 1
        if data == self._last:
            return
        self._last = data
        try:
            self._decode(data)
        except BadSegment:
            self.bad_records += 1
            return
        self.records += 1

    def _read(self, segment: TrackdSegment) -> bytes:
        """The header and the blocks it names, never the whole segment."""
        raise NotImplementedError

    def _decode(self, data: bytes) -> None:
        raise NotImplementedError

    @property
    def counters(self) -> dict[str, int]:
        """Segments read that changed (``records``), of which had a header that does not fit
        (``bad_records``, not in ``records``)."""
        return {"records": self.records, "bad_records": self.bad_records}


class TrackdSensorDevice(TrackdDevice, Position):
    """trackd's tracker sensors (element type ``trackd_sensor``)."""

    ELEMENT_TYPE = "trackd_sensor"
    DEFAULT_KEY = 4126

    def _read(self, segment: TrackdSegment) -> bytes:
        return segment.read_tracker()

    def _decode(self, data: bytes) -> None:
        poses = tracker_poses(data)
        if len(poses):
            self.add_position_sample(pose_matrices(poses))


class TrackdControllerDevice(TrackdDevice, Digital, Analog):
    """trackd's buttons and valuators (element type ``trackd_controller``)."""

    ELEMENT_TYPE = "trackd_controller"
    DEFAULT_KEY = 4127

    def _read(self, segment: TrackdSegment) -> bytes:
        return segment.read_controller()

    def _decode(self, data: bytes) -> None:
        state = decode_controller(data)
        now = self.now()
        if state.buttons:
            self.add_digital_sample([1 if b else 0 for b in state.buttons], now)
        if state.valuators:
            self.add_analog_sample(state.valuators, now)
