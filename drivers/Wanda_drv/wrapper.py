"""The input-manager side of the Ascension Wanda (element type ``wanda``).

Digital units 0..2 are buttons 0..2 as 0/1 (on the Wanda the rightmost button reports as 0:
VR Juggler's ``example.wanda.jconf`` aliases VJButton0 to unit 2); analog units 0 and 1 the
joystick's X and Y, raw -34..34. As Gadgeteer's Wanda driver does, the analog range is -34 to
34 whatever ``min``/``max`` say (the definition's defaults, 0 and 255, would leave the
joystick near one end).

A Wanda is silent while its ball is at rest and no button changes, so silence is not a fault
(the C++ ignores read timeouts); and as VRPN's ``vrpn_Wanda.C`` found, the Wanda may not send
the centred packet when the ball is let go, so after ``rest_time`` (VRPN's 0.2 s) without a
packet a joystick that was off centre reads centred again (one analog sample (0, 0); the
buttons keep their state).

Differences from the C++, on purpose: a lost line (a hang-up) raises from ``sample`` and the
input manager restarts the device; bytes outside packets are counted (``bad_records``,
``skipped_bytes``) and skipped; a sample is added per packet, not per read.
"""

from __future__ import annotations

import time

from gadgetctl.input import Analog, DeviceConfigError, Digital
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import LIMIT, Wanda, WandaError, WandaPacket


class WandaDevice(Digital, Analog, CarriedCounters):
    """Buttons and joystick of an Ascension Wanda on a serial port."""

    ELEMENT_TYPE = "wanda"
    sample_interval = 0.0  # sample() waits for packets (at most read_timeout)

    # Protocol timing in seconds (the C++ driver's); tests shorten them.
    reset_time = 0.1  # each half of the RTS pulse (only where the line has RTS)
    hello_timeout = 2.0  # for the Wanda's M3
    rest_time = 0.2  # no packet for this long with the joystick off centre: it is centred

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.read_timeout = 0.02
        self.wanda: Wanda | None = None
        self._axes: tuple[int, int] = (0, 0)
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.analog_min, self.analog_max = -float(LIMIT), float(LIMIT)
        self.port = access.string("port")
        timeout_ms = access.integer("read_timeout")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the Wanda is on")
        if not 1 <= timeout_ms <= 10_000:
            raise DeviceConfigError(f"read_timeout {timeout_ms} ms is outside 1..10000")
        self.read_timeout = timeout_ms / 1000.0

    def start_sampling(self) -> None:
        wanda = Wanda(
            self.port,
            read_timeout=self.read_timeout,
            hello_timeout=self.hello_timeout,
            reset_time=self.reset_time,
        )
        wanda.open()
        self.wanda = wanda
        self.counts.attach(wanda)

    def sample(self) -> None:
        wanda = self.wanda
        if wanda is None:
            raise WandaError("the Wanda is not open")
        packets = wanda.read()  # raises WandaDisconnected when the line is lost
        for packet in packets:
            self._add(packet)
        resting = time.monotonic() - wanda.heard_at > self.rest_time
        if not packets and self._axes != (0, 0) and resting:
            self._axes = (0, 0)  # let go without a centred packet (VRPN's observation)
            self.add_analog_sample([0.0, 0.0], self.now())

    def stop_sampling(self) -> None:
        wanda, self.wanda = self.wanda, None
        self.counts.detach()
        if wanda is not None:
            wanda.close()

    def _add(self, packet: WandaPacket) -> None:
        stamp = self.now()
        self.add_digital_sample(list(packet.buttons), stamp)
        self.add_analog_sample([float(v) for v in packet.axes], stamp)
        self._axes = packet.axes
