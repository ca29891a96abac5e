"""The input-manager side of the SpaceMouse / SpaceBall (element type ``puck_device``).

Units: analog 0..5 are the axes tx, ty, tz, rx, ry, rz in raw counts; digital 0..11 are
buttons 1..12.

Normalisation, as the C++ ``PuckDevice`` does it: the analog range is the model's, -500..500
for the SpaceMouse dialects and -2000..2000 for the SpaceBall 4000 FLX and 2003B, **whatever
the element's min/max say**. The definition's min/max defaults are 0 and 255, and VRJConfig
writes them into every file it saves, so honouring min/max would read a centred axis as 0.0
(and clamp every negative count); with the model's range a centred axis reads 0.5, a full
push 0 or 1. (The Wanda driver treats its -34..34 the same way.) To change sensitivity, use
the puck's own settings, not min/max.

Differences from the C++ ``PuckDevice``, on purpose:

* buttons are stored as 0/1 (the C++ stored the masked bit, 2048 for button 12);
* analog values are stored raw and normalised by the proxies once (the C++ normalised
  before adding, so proxies normalised twice);
* every record read is added (the C++ added one per sample() call), and a lost line raises
  so the input manager restarts the device.
"""

from __future__ import annotations

from gadgetctl.input import Analog, DeviceConfigError, Digital
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import AXES, AXIS_RANGE, BAUD, BUTTONS, MODELS, SpaceBall, SpaceBallError


class PuckDevice(Analog, Digital, CarriedCounters):
    """Six axes and twelve buttons from a SpaceMouse or SpaceBall on a serial port."""

    ELEMENT_TYPE = "puck_device"
    sample_interval = 0.0  # sample() waits for records (at most sample_timeout)

    reset_wait = 2.0  # for the SpaceBall's reset banner / the SpaceMouse's version reply
    sample_timeout = 0.1
    poll_interval = 0.01

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.model = MODELS[0]
        self.puck: SpaceBall | None = None
        self.version = ""
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection
        self._axes = (0,) * AXES
        self._buttons = (0,) * BUTTONS

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.port = access.string("port")
        self.model = access.string("device")
        baud = access.integer("baud")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the puck is on")
        if self.model not in MODELS:
            raise DeviceConfigError(
                f"device {self.model!r} is not a serial puck; one of {', '.join(MODELS)}"
            )
        if baud != BAUD:
            raise DeviceConfigError(f"baud {baud}: the pucks talk {BAUD} bit/s only")
        span = AXIS_RANGE[self.model]
        self.analog_min, self.analog_max = -span, span  # min/max ignored, as in the C++

    def start_sampling(self) -> None:
        puck = SpaceBall(
            self.port,
            self.model,
            reset_wait=self.reset_wait,
            sample_timeout=self.sample_timeout,
            poll_interval=self.poll_interval,
        )
        puck.open()
        self.version = puck.version or self.version
        self.puck = puck
        self.counts.attach(puck.decoder)
        stamp = self.now()  # centred axes and released buttons until the puck reports
        self._axes, self._buttons = (0,) * AXES, (0,) * BUTTONS
        self.add_analog_sample(self._axes, stamp)
        self.add_digital_sample(self._buttons, stamp)

    def sample(self) -> None:
        puck = self.puck
        if puck is None:
            raise SpaceBallError("the puck is not open")
        stamp = self.now()
        for record in puck.poll():  # raises SpaceBallDisconnected when the line is lost
            if record.axes is not None:
                self.add_analog_sample(record.axes, stamp)
            if record.buttons is not None:
                self.add_digital_sample(record.buttons, stamp)

    def stop_sampling(self) -> None:
        puck, self.puck = self.puck, None
        self.counts.detach()  # what it counted is kept
        if puck is not None:
            puck.close()
