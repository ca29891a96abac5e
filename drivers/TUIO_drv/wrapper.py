"""The input-manager side of the TUIO driver: a ``TUIO_drv`` element becomes a device with
``points`` touch slots. Digital unit ``i`` is ON while a finger holds slot ``i`` (a new
finger takes the lowest free slot); analog units ``2i`` and ``2i + 1`` are its x and y
(TUIO's 0 to 1; 0 once the finger leaves). Analog proxies normalise them with the element's
``min`` and ``max`` (0 and 1 by default; upstream forced 0 and 1).

Every TUIO frame applied (a bundle with cursor data that is not late) becomes one sample of
each kind. Silence longer than
:attr:`TuioDevice.peer_timeout` raises from ``sample()``, so the input manager marks the
device faulted and restarts it; a restart succeeds only once datagrams arrive again.
"""

from __future__ import annotations

from gadgetctl.input import Analog, DeviceConfigError, Digital
from gadgetctl.input.receiving import ReceiverSampling
from gadgetctl.jccl.access import ElementAccess

from .standalone import TuioDisconnected, TuioReceiver

#: Most touch slots an element may ask for.
MAX_POINTS = 256


class TuioDevice(ReceiverSampling[TuioReceiver], Digital, Analog):
    """A TUIO multi-touch source (element type ``TUIO_drv``)."""

    ELEMENT_TYPE = "TUIO_drv"
    DISCONNECTED = TuioDisconnected
    DATA_NAME = "TUIO data"

    def __init__(self) -> None:
        super().__init__()
        self.port = 3333
        self.points = 10
        self.peer_timeout = 2.0

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, min and max
        self.port = access.integer("port")
        if not 0 <= self.port <= 65535:
            raise DeviceConfigError(f"port {self.port} is not a UDP port (0 to 65535)")
        self.points = access.integer("points")
        if not 1 <= self.points <= MAX_POINTS:
            raise DeviceConfigError(f"points {self.points} is not between 1 and {MAX_POINTS}")

    def _new_receiver(self) -> TuioReceiver:
        return TuioReceiver(self.port, self.points, receive_timeout=self.receive_timeout)

    def _first_start(self, driver: TuioReceiver) -> None:
        """Every slot up until the first datagram."""
        self.add_digital_sample(driver.slots.digital())
        self.add_analog_sample(driver.slots.analog())

    def _add(self, states: list[tuple[list[int], list[float]]]) -> None:
        now = self.now()
        stamps = [now] * len(states)
        self.add_digital_samples(stamps, [d for d, _ in states])
        self.add_analog_samples(stamps, [a for _, a in states])

    @property
    def counters(self) -> dict[str, int]:
        r = self._receiver
        if r is None:
            return {}
        s = r.slots
        return {
            **r.ledger.counters(),
            "bad_records": s.bad_records,
            "unknown_sessions": s.unknown_sessions,
            "overflow_sessions": s.overflow_sessions,
            "other_messages": s.other_messages,
            "late_frames": s.late_frames,
            "overflow_sources": s.overflow_sources,
            "forgotten_sources": s.forgotten_sources,
        }
