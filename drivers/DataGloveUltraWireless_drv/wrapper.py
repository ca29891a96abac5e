"""The input-manager side of the 5DT Data Glove Ultra Wireless (``data_glove_ultra_wireless``).

Units: analog 0..13 are glove A's sensors (thumb near, thumb far, thumb-index, index near,
index far, index-middle, middle near, middle far, middle-ring, ring near, ring far,
ring-little, little near, little far), 14..27 glove B's, each auto-ranged to 0..1 (a sensor
whose range is still empty, a glove not heard from yet included, reads 0). Command unit 0 is
glove A's gesture, 1 glove B's, as VR Juggler computes it: bit k set while finger k (index,
middle, ring, little) is open, a flat hand 15, a fist 0, -1 while a finger is undefined (both
its sensors between ``gesture_lower_threshold`` and ``gesture_upper_threshold``; one closed
sensor makes the finger closed). ``auto_range_reset`` (definition version 2, default true)
makes a record with an all-open gesture its glove's minima and one with a fist its maxima;
the ranges are kept across reconnections, as the C++ object keeps them. The rules and what
was fixed from the C++ are in ``standalone.py``.

Differences from the C++, on purpose: a record from a port that is not enabled is dropped
(the C++ read it as glove B's when port A was disabled); every record read is added (the C++
waited until each enabled glove had spoken, then added one sample); a lost line raises so the
input manager restarts the device.
"""

from __future__ import annotations

from gadgetctl.input import Analog, Command, DeviceConfigError
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import (
    NO_GESTURE,
    PORT_A,
    PORT_B,
    SENSORS,
    AutoRange,
    UltraGlove,
    UltraGloveError,
    gesture,
)


class UltraGloveDevice(Analog, Command, CarriedCounters):
    """Two gloves' sensors and gestures from a 5DT wireless receiver on a serial port."""

    ELEMENT_TYPE = "data_glove_ultra_wireless"
    sample_interval = 0.0  # sample() waits for records (at most sample_timeout)

    sample_timeout = 0.1
    poll_interval = 0.01

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 115200
        self.enabled = (True, True)
        self.lower, self.upper = 0.35, 0.65
        self.range = AutoRange(auto_reset=True)
        self.receiver: UltraGlove | None = None
        self.ignored = 0
        self._analog = [0.0] * (2 * SENSORS)
        self._gestures = [NO_GESTURE, NO_GESTURE]
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.port = access.string("port")
        self.baud = access.integer("baud")
        self.enabled = (access.boolean("port_a_enabled"), access.boolean("port_b_enabled"))
        if access.has("gesture_lower_threshold"):
            self.lower = access.float("gesture_lower_threshold")
            self.upper = access.float("gesture_upper_threshold")
            self.range.auto_reset = access.boolean("auto_range_reset")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the receiver is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")
        if not any(self.enabled):
            raise DeviceConfigError(
                "port_a_enabled and port_b_enabled are both false: no glove to read"
            )
        if not 0.0 <= self.lower <= self.upper <= 1.0:
            raise DeviceConfigError(
                f"gesture thresholds {self.lower:g} (lower) and {self.upper:g} (upper) must rise within 0..1"
            )

    def start_sampling(self) -> None:
        receiver = UltraGlove(
            self.port,
            self.baud,
            sample_timeout=self.sample_timeout,
            poll_interval=self.poll_interval,
        )
        receiver.open()
        self.receiver = receiver
        self.counts.attach(receiver)

    def sample(self) -> None:
        receiver = self.receiver
        if receiver is None:
            raise UltraGloveError("the receiver is not open")
        records = receiver.poll()  # raises UltraGloveDisconnected when the line is lost
        if not records:
            return
        stamp = self.now()
        for record in records:
            if not self.enabled[record.port]:
                self.ignored += 1
                continue
            scaled = self.range.scale(record)
            first = SENSORS * (record.port - PORT_A)
            self._analog[first : first + SENSORS] = [0.0 if v is None else v for v in scaled]
            number = gesture(scaled, self.lower, self.upper)
            self._gestures[record.port] = number
            self.range.after_gesture(record, number)
            self.add_analog_sample(self._analog, stamp)
            self.add_command_sample(self._gestures, stamp)

    def stop_sampling(self) -> None:
        receiver, self.receiver = self.receiver, None
        self.counts.detach()  # what it counted is kept
        if receiver is not None:
            receiver.close()


__all__ = ["PORT_B", "UltraGloveDevice"]
