"""The input-manager side of the Immersion Interface Box (element type ``ibox``).

Digital units 0..3 are buttons 0..3 as 0/1; analog units 0..3 the analog inputs 0..3, raw
0..255, as Gadgeteer's IBox driver gives them.

Differences from the C++, on purpose: a lost or silent line raises from ``sample`` and the
input manager restarts the device; junk and broken packets are counted (``bad_records``,
``skipped_bytes``) and skipped; a query is sent as soon as the previous one was answered.
"""

from __future__ import annotations

from gadgetctl.input import Analog, DeviceConfigError, Digital
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import IBox, IBoxError, IBoxPacket

DIGITAL_UNITS = 4
ANALOG_UNITS = 4


class IBoxDevice(Digital, Analog, CarriedCounters):
    """Buttons and analog inputs of an Immersion Interface Box on a serial port."""

    ELEMENT_TYPE = "ibox"
    sample_interval = 0.0  # sample() waits for a packet (at most poll_interval)

    # Protocol timing in seconds (the C++ driver's where it has one); tests shorten them.
    settle = 0.1  # after END
    read_timeout = 1.0  # for an answer during the start
    poll_timeout = 0.1  # an unanswered query is repeated after this
    silence_timeout = 2.0  # no packet for this long: the line counts as lost
    poll_interval = 0.01  # serial read granularity

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 38400
        self.box: IBox | None = None
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, min and max
        self.port = access.string("port")
        self.baud = access.integer("baud")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the IBox is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")

    def start_sampling(self) -> None:
        box = IBox(
            self.port,
            self.baud,
            settle=self.settle,
            read_timeout=self.read_timeout,
            poll_timeout=self.poll_timeout,
            silence_timeout=self.silence_timeout,
            poll_interval=self.poll_interval,
        )
        box.open()
        self.box = box
        self.counts.attach(box)

    def sample(self) -> None:
        box = self.box
        if box is None:
            raise IBoxError("the IBox is not open")
        for packet in box.read():  # raises IBoxDisconnected when the line is lost or silent
            self._add(packet)

    def stop_sampling(self) -> None:
        box, self.box = self.box, None
        self.counts.detach()
        if box is not None:
            box.close()

    def _add(self, packet: IBoxPacket) -> None:
        stamp = self.now()
        self.add_digital_sample(list(packet.buttons[:DIGITAL_UNITS]), stamp)
        self.add_analog_sample([float(v) for v in packet.analog[:ANALOG_UNITS]], stamp)
