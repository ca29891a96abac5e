"""The input-manager side of the Logitech 3D mouse (element type ``three_d_mouse``).

Units:

* position unit 0: the mouse, translation in metres (the mouse reports thousandths of an
  inch) and the rotation Rx Ry Rz of its three angles;
* digital units 0, 1, 2: the left, middle and right buttons, 0/1.

Differences from the C++, on purpose:

* the C++ wrote the three angles into the translation, over X, Y and Z, so the position was
  lost and no rotation was set; here the translation stays and the angles rotate;
* the buttons, in every report, are published (the C++ dropped them although the definition
  makes the mouse a digital device);
* the line speed comes from the element (the C++ always used 19200); the definition's
  enumeration gives its "19200" label the value 12900, read here as 19200;
* a lost or silent line raises from ``sample`` and the input manager restarts the device.
"""

from __future__ import annotations

from gadgetctl.input import DeviceConfigError, Digital, Position
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import BAUD, MouseReport, ThreeDMouse, ThreeDMouseError

#: The definition's enumeration value for its "19200" label (an upstream typo).
MISTYPED_19200 = 12900


class ThreeDMouseDevice(Position, Digital, CarriedCounters):
    """Position and buttons of a Logitech 3D mouse on a serial port."""

    ELEMENT_TYPE = "three_d_mouse"
    sample_interval = 0.0  # sample() waits for reports (at most poll_interval)

    # Protocol timing in seconds (the C++ driver's); tests shorten them.
    demand_wait = 0.1
    reset_wait = 1.0
    diagnostic_wait = 1.0
    read_timeout = 2.0
    poll_timeout = 0.1
    silence_timeout = 2.0
    poll_interval = 0.02

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = BAUD
        self.mouse: ThreeDMouse | None = None
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, position filters
        self.port = access.string("port")
        baud = access.integer("baud")
        self.baud = BAUD if baud == MISTYPED_19200 else baud
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the mouse is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")

    def start_sampling(self) -> None:
        mouse = ThreeDMouse(
            self.port,
            self.baud,
            demand_wait=self.demand_wait,
            reset_wait=self.reset_wait,
            diagnostic_wait=self.diagnostic_wait,
            read_timeout=self.read_timeout,
            poll_timeout=self.poll_timeout,
            silence_timeout=self.silence_timeout,
            poll_interval=self.poll_interval,
        )
        mouse.open()
        self.mouse = mouse
        self.counts.attach(mouse)

    def sample(self) -> None:
        mouse = self.mouse
        if mouse is None:
            raise ThreeDMouseError("the mouse is not open")
        for report in mouse.read():  # raises ThreeDMouseDisconnected on a lost or silent line
            self._add(report)

    def stop_sampling(self) -> None:
        mouse, self.mouse = self.mouse, None
        self.counts.detach()  # what it counted is kept
        if mouse is not None:
            mouse.close()

    def _add(self, report: MouseReport) -> None:
        stamp = self.now()
        self.add_position_sample([report.matrix()], stamp)
        self.add_digital_sample(report.buttons, stamp)
