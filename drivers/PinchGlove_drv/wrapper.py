"""The input-manager side of the Fakespace PinchGlove (element type ``pinch_glove``).

Units, as Gadgeteer's PinchGlove driver and ``Glove::getGloveDataFromDigitalData`` give them:

* digital unit ``5 * hand + bit``: 0..4 the left pinky, ring, middle, index, thumb, 5..9 the
  right ones in the same order (bit k of the hand's contact byte, as VR Juggler numbers
  them), 1 while that fingertip touches another;
* glove unit 0 the left hand, 1 the right; each finger row (thumb first) holds π/2 in all
  four joints while that finger touches, 0 otherwise; the wrist row stays 0. Fix: the C++
  filled row k from unit k, which put the pinky's contact in the thumb's row.

Differences from the C++ wrapper, on purpose:

* ``config`` runs the device types' own ``config`` (the C++ called only ``Input::config``,
  so ``glove_position`` was never read and glove proxies had no hand position);
* ``stop_sampling`` closes the serial port, so the device can be started again (the C++
  only ended its thread and kept the port open);
* a lost serial line raises from ``sample`` and the input manager restarts the device
  (the C++ sample loop kept failing quietly);
* proxies that read units the glove does not have are reported (VR Juggler's
  ``pinch.mixin.jconf`` numbers the right hand 6..10 instead of 5..9) by the input manager,
  with the rule ``gadgetctl validate`` applies (``gadgetctl.jccl.units``, CFG034).
"""

from __future__ import annotations

import numpy as np

from gadgetctl.input import DeviceConfigError, Digital, Glove
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import CarriedCounts

from .standalone import FINGERS, HANDS, PinchGlove, PinchGloveError, PinchSample

GLOVE_ROWS, GLOVE_JOINTS = 6, 4  # five fingers and the wrist, four joints each


def glove_angles(sample: PinchSample) -> np.ndarray:
    """The (2, 6, 4) joint angles of both hands; the wrist row stays 0."""
    angles = np.zeros((len(HANDS), GLOVE_ROWS, GLOVE_JOINTS))
    for unit, hand in enumerate(sample.hands):
        angles[unit, : len(FINGERS), :] = hand.angles
    return angles


class PinchGloveDevice(Glove, Digital):
    """Glove and digital data from a PinchGlove box on a serial port."""

    ELEMENT_TYPE = "pinch_glove"
    sample_interval = 0.0  # sample() waits for a touch frame (at most sample_timeout)

    # Protocol timing in seconds. The defaults are the C++ driver's; tests shorten them.
    command_delay = 0.1  # between the two bytes of a command
    echo_wait = 0.1  # for a confused glove's '?' after the first byte
    read_timeout = 5.0  # per byte of a reply or of a started frame
    sample_timeout = 0.25  # one sample() call waiting for a frame to start
    poll_interval = 0.05  # serial read granularity

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 9600
        self.info: dict[str, str] = {}
        self.glove: PinchGlove | None = None
        # counted over every connection
        self.counts = CarriedCounts(("frames", "bad_frames", "skipped_bytes"))

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, and the glove_position proxy (Glove)
        self.port = access.string("port")
        self.baud = access.integer("baud")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the glove box is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")

    def start_sampling(self) -> None:
        # The hardware description is only printed by the C++ driver; after a restart
        # it is not asked again, which saves four command round trips.
        glove = PinchGlove(
            self.port,
            self.baud,
            timestamps=True,
            query_info=not self.info,
            command_delay=self.command_delay,
            echo_wait=self.echo_wait,
            read_timeout=self.read_timeout,
            sample_timeout=self.sample_timeout,
            poll_interval=self.poll_interval,
        )
        opened = glove.open()
        self.info = glove.info or self.info
        self.glove = glove
        self.counts.attach(glove)
        # The box is silent until a contact changes: start from open hands, as the C++ does.
        self._add(opened)

    def sample(self) -> None:
        glove = self.glove
        if glove is None:
            raise PinchGloveError("the glove is not open")
        frame = glove.sample()  # raises PinchGloveDisconnected when the line is lost
        if frame is not None:
            self._add(frame)

    def stop_sampling(self) -> None:
        glove, self.glove = self.glove, None
        self.counts.detach()  # what it counted is kept
        if glove is not None:
            glove.close()

    @property
    def frames(self) -> int:
        """Touch frames decoded."""
        return self.counts.get("frames")

    @property
    def bad_frames(self) -> int:
        """Malformed or truncated frames dropped."""
        return self.counts.get("bad_frames")

    @property
    def skipped_bytes(self) -> int:
        """Bytes outside any frame."""
        return self.counts.get("skipped_bytes")

    @property
    def counters(self) -> dict[str, int]:
        """The driver's health counters, reconnections included."""
        return self.counts.snapshot()

    # -- internals ------------------------------------------------------------------------

    def _add(self, sample: PinchSample) -> None:
        stamp = self.now()
        self.add_digital_sample(sample.digital, stamp)
        self.add_glove_sample(glove_angles(sample), stamp)
