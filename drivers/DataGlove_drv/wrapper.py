"""The input-manager side of the 5DT DataGlove (element type ``data_glove``).

Units, as the C++ driver fills them: analog 0..4 the thumb..pinky flexures (0 open .. 1
bent), 5 pitch and 6 roll in degrees (0..180), 7 the gesture number (0..15, 16 for none),
8 the capability byte: a packet's 10th byte as the glove sends it (0 right or 6 left as VR
Juggler documents it, 0x01 or 0x40 from wireless gloves, 0x55 from some wired ones), or for
9-byte packets the hand the glove's ``G`` answer gave, 0 right or 6 left. Analog proxies normalise with the
analog range (0..1, as the definition has no min/max), so pitch and roll read clamped; read
them raw from the device, or through the glove.

Glove unit 0 (the definition's glove_device parent, which the C++ never filled): each
finger's three flexion joints bend by flexure x pi/2, abduction and the wrist row stay 0.

Differences from the C++, on purpose: a packet counts when its checksum *matches* (the C++
test was inverted, so it kept only corrupt packets); 9-byte packets and any 10th byte are
accepted (an earlier gadgetctl insisted on 0 or 6 and read nothing from most real gloves);
``A``, ``G``, ``D`` start a wired glove that streams only when asked (VRPN's start; the C++
sends nothing); every packet read is added; a lost line raises so the input manager restarts
the device. ``reply_timeout`` bounds each wait for the glove at the start.
"""

from __future__ import annotations

import math

import numpy as np

from gadgetctl.input import Analog, DeviceConfigError, Glove
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import FINGERS, DataGlove, DataGloveError, GloveSample

GLOVE_ROWS, GLOVE_JOINTS, FLEXION_JOINTS = 6, 4, 3


def glove_angles(sample: GloveSample) -> np.ndarray:
    """The (1, 6, 4) joint angles of the hand: flexion joints at flexure x pi/2."""
    angles = np.zeros((1, GLOVE_ROWS, GLOVE_JOINTS))
    for finger, flex in enumerate(sample.flexure):
        angles[0, finger, :FLEXION_JOINTS] = flex * math.pi / 2
    return angles


class DataGloveDevice(Glove, Analog, CarriedCounters):
    """Nine analog values and one glove from a 5DT DataGlove on a serial port."""

    ELEMENT_TYPE = "data_glove"
    sample_interval = 0.0  # sample() waits for packets (at most sample_timeout)

    sample_timeout = 0.1
    poll_interval = 0.01
    reply_timeout = 2.0  # for each answer at the start (VRPN's)

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 38400
        self.glove: DataGlove | None = None
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.port = access.string("port")
        self.baud = access.integer("baud")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the glove is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")

    def start_sampling(self) -> None:
        glove = DataGlove(
            self.port,
            self.baud,
            sample_timeout=self.sample_timeout,
            poll_interval=self.poll_interval,
            reply_timeout=self.reply_timeout,
        )
        glove.open()
        self.glove = glove
        self.counts.attach(glove)

    def sample(self) -> None:
        glove = self.glove
        if glove is None:
            raise DataGloveError("the glove is not open")
        packets = glove.poll()  # raises DataGloveDisconnected when the line is lost
        if not packets:
            return
        stamp = self.now()
        for packet in packets:
            self.add_analog_sample(packet.analog, stamp)
            self.add_glove_sample(glove_angles(packet), stamp)

    def stop_sampling(self) -> None:
        glove, self.glove = self.glove, None
        self.counts.detach()  # what it counted is kept
        if glove is not None:
            glove.close()


__all__ = ["FINGERS", "DataGloveDevice", "glove_angles"]
