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
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.udp import DatagramLedger

from .standalone import TuioDisconnected, TuioReceiver

#: Most touch slots an element may ask for.
MAX_POINTS = 256


class TuioDevice(Digital, Analog):
    """A TUIO multi-touch source (element type ``TUIO_drv``)."""

    ELEMENT_TYPE = "TUIO_drv"
    sample_interval = 0.0  # sample() waits for datagrams itself

    receive_timeout = 0.1
    probe_timeout = 0.25
    batch_limit = 100

    def __init__(self) -> None:
        super().__init__()
        self.port = 3333
        self.points = 10
        self.peer_timeout = 2.0
        self._receiver: TuioReceiver | None = None
        self._open = False
        self._started = False

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, min and max
        self.port = access.integer("port")
        if not 0 <= self.port <= 65535:
            raise DeviceConfigError(f"port {self.port} is not a UDP port (0 to 65535)")
        self.points = access.integer("points")
        if not 1 <= self.points <= MAX_POINTS:
            raise DeviceConfigError(f"points {self.points} is not between 1 and {MAX_POINTS}")

    def _driver(self) -> TuioReceiver:
        """One receiver for the device's life, so its counters add up over reconnections."""
        if self._receiver is None:
            self._receiver = TuioReceiver(
                self.port, self.points, receive_timeout=self.receive_timeout
            )
        self._receiver.peer_timeout = self.peer_timeout
        return self._receiver

    def start_sampling(self) -> None:
        driver = self._driver()
        driver.open()
        self._open = True
        if driver.requested_port == 0:
            driver.requested_port = driver.port
        if self._started:
            self._probe(driver)
        else:  # every slot up until the first datagram
            self.add_digital_sample(driver.slots.digital())
            self.add_analog_sample(driver.slots.analog())
        self._started = True

    def _probe(self, driver: TuioReceiver) -> None:
        driver.receive_timeout = self.probe_timeout
        try:
            states = driver.sample_all(self.batch_limit)
            if not states:
                why = driver.ledger.undecodable()
                raise TuioDisconnected(
                    f"still no TUIO data on UDP port {driver.port}"
                    + (f" (undecodable: {why})" if why else "")
                )
        except BaseException:
            self.stop_sampling()
            raise
        finally:
            driver.receive_timeout = self.receive_timeout
        self._add(states)

    def sample(self) -> None:
        driver = self._receiver
        if driver is None or not self._open:
            raise TuioDisconnected("the receiver is closed")
        states = driver.sample_all(self.batch_limit)
        if states:
            self._add(states)

    def stop_sampling(self) -> None:
        if self._receiver is not None and self._open:
            self._open = False
            self._receiver.close()

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

    def datagram_ledger(self) -> DatagramLedger | None:
        """The receiver's account of its datagrams: decoded, bad, dropped by the kernel."""
        return self._receiver.ledger if self._receiver is not None else None
