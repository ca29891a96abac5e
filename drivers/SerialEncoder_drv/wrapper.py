"""The input-manager side of the US Digital serial encoders (element type ``serial_encoder``).

Position unit 0 is the table: T(0, height / 39.37, 0) . R_x(tilt), from the encoders at SEI
addresses 1 (tilt, degrees) and 2 (height, inches). A sample is added when both answered
with a valid position. The bus is polled at :attr:`SerialEncoderDevice.poll_rate` (96 reads
of both encoders a second fill 9600 baud; the C++ polled back to back).

Differences from the C++, on purpose:

* ``config`` succeeds when the configuration is good. The C++ returned the bus
  initialisation's status code from ``config``, 0 on success, which reads as false: a working
  encoder left the element pending, and only a failing one was accepted. Here ``config``
  only checks the element, and opening the line happens in ``start_sampling`` (a failure
  there is a fault the input manager retries);
* the line speed is the element's ``baud`` where one is written, 9600 otherwise (the C++
  ignored the property and the definition's default 38400 is not the bus's speed);
* a corrupt or missing answer is counted, not turned into a zero height.
"""

from __future__ import annotations

import time

from gadgetctl.input import DeviceConfigError, Position
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import CarriedCounters, CarriedCounts

from .standalone import BAUD, SerialEncoderBus, SerialEncoderError, table_matrix


class SerialEncoderDevice(Position, CarriedCounters):
    """A table's tilt and height from two SEI encoders on a serial port."""

    ELEMENT_TYPE = "serial_encoder"
    sample_interval = 0.0  # sample() polls the bus and paces itself

    poll_rate = 96.0  # polls of both encoders per second
    reply_timeout = 1.0  # the C++ waited 1 s for an answer
    poll_interval = 0.005

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = BAUD
        self.bus: SerialEncoderBus | None = None
        self._next_poll = 0.0
        # counted over every connection
        self.counts = CarriedCounts(("records", "bad_records", "skipped_bytes", "timeouts"))

    def config(self, access: ElementAccess) -> None:
        # Upstream quirk fixed: the C++ config() returned the bus set-up's status (0 on
        # success) as its result, so it failed exactly when the bus worked. Here config()
        # only checks the element; the bus is opened in start_sampling().
        super().config(access)
        self.port = access.string("port")
        self.baud = access.integer("baud") if access.count("baud") else BAUD
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device of the SEI bus")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")

    def start_sampling(self) -> None:
        bus = SerialEncoderBus(
            self.port, self.baud, reply_timeout=self.reply_timeout, poll_interval=self.poll_interval
        )
        bus.open()
        self.bus = bus
        self.counts.attach(bus.counters)
        self._next_poll = time.monotonic()

    def sample(self) -> None:
        bus = self.bus
        if bus is None:
            raise SerialEncoderError("the bus is not open")
        wait = self._next_poll - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        self._next_poll = max(self._next_poll + 1.0 / self.poll_rate, time.monotonic() - 0.1)
        tilt, height = bus.table()  # raises SerialEncoderDisconnected when the line is lost
        if tilt is not None and height is not None:
            self.add_position_sample([table_matrix(tilt, height)])

    def stop_sampling(self) -> None:
        bus, self.bus = self.bus, None
        self.counts.detach()  # what it counted is kept
        if bus is not None:
            bus.close()

    @property
    def timeouts(self) -> int:
        """Reads no encoder answered in time."""
        return self.counts.get("timeouts")
