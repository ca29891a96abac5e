"""The input-manager side of the Polhemus Fastrak (element type ``fastrak``).

Units, as Gadgeteer's Fastrak driver gives them:

* position units 0..3: stations 1..4 (always four; a station the tracker does not report
  keeps the identity), 4x4 matrices in metres with the rotation of the tracker's quaternion;
* digital unit 0: the stylus switch on station 1, 0/1.

Differences from the C++, on purpose:

* the C++ stored station ``s`` at index ``s`` of its four-element arrays, so station 4 was
  written past the end and station 1 landed in unit 1; here station ``s`` is unit ``s - 1``;
* the C++ sent its set-up before the port was open (see :meth:`~.standalone.Fastrak.open`);
* the stylus switch is read from the records (the C++ definition listed a digital device
  but its version-2 driver never filled it);
* a lost or silent line raises from ``sample`` and the input manager restarts the device.
"""

from __future__ import annotations

import numpy as np

from gadgetctl.input import DeviceConfigError, Digital, Position
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import HEMISPHERES, STATIONS, Fastrak, FastrakError, FastrakRecord


class FastrakDevice(Position, Digital, CarriedCounters):
    """Four stations and a stylus switch of a Polhemus Fastrak on a serial port."""

    ELEMENT_TYPE = "fastrak"
    sample_interval = 0.0  # sample() waits for records (at most poll_interval)

    read_timeout = 2.0  # for a reply during the start
    silence_timeout = 2.0  # no record for this long: the line counts as lost
    poll_interval = 0.02  # serial read granularity

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 115200
        self.hemisphere = 3
        self.tracker: Fastrak | None = None
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection
        self._matrices = np.tile(np.eye(4), (STATIONS, 1, 1))
        self._stylus = 0

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, position filters
        self.port = access.string("port")
        self.baud = access.integer("baud")
        self.hemisphere = access.integer("hemisphere")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the tracker is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")
        if self.hemisphere not in HEMISPHERES:
            raise DeviceConfigError(f"hemisphere {self.hemisphere} is not one of 0..6")

    def start_sampling(self) -> None:
        tracker = Fastrak(
            self.port,
            self.baud,
            self.hemisphere,
            read_timeout=self.read_timeout,
            silence_timeout=self.silence_timeout,
            poll_interval=self.poll_interval,
        )
        tracker.open()
        self.tracker = tracker
        self.counts.attach(tracker)

    def sample(self) -> None:
        tracker = self.tracker
        if tracker is None:
            raise FastrakError("the tracker is not open")
        records = tracker.read()  # raises FastrakDisconnected when the line is lost or silent
        if records:
            self._add(records)

    def stop_sampling(self) -> None:
        tracker, self.tracker = self.tracker, None
        self.counts.detach()  # what it counted is kept
        if tracker is not None:
            tracker.close()

    def _add(self, records: list[FastrakRecord]) -> None:
        for record in records:
            self._matrices[record.station - 1] = record.matrix()  # station 4 is unit 3
            if record.station == 1:
                self._stylus = record.stylus
        stamp = self.now()
        self.add_position_sample(self._matrices, stamp)
        self.add_digital_sample((self._stylus,), stamp)
