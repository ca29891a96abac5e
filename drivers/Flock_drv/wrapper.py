"""The input-manager side of the Ascension Flock of Birds (element type ``flock``).

Position unit ``i`` is the ``i``-th bird with a sensor, lowest FBB address first (one unit
in standalone mode, ``master_address`` 0); 4x4 matrices with the translation in feet and the
rotation from the PosQuaternion records, as Gadgeteer's Flock driver gives them.

Differences from the C++, on purpose:

* ``addressing_mode`` "Super Extended" (value 2 in the definition) means the protocol's 3
  (see :data:`standalone.ADDRESSING_FROM_CONFIG`);
* the waits around the FBB auto-configuration are conditions (the master answers an
  examine), not fixed sleeps; the RTS reset is skipped where the line has no RTS (a pty);
* a lost or silent line raises from ``sample`` and the input manager restarts the device;
* bad records are counted (``bad_records``, ``skipped_bytes``) and skipped, the report rate
  is never lowered.
"""

from __future__ import annotations

import numpy as np

from gadgetctl.input import DeviceConfigError, Position
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import ADDRESSING_FROM_CONFIG, HEMISPHERES, BirdRecord, Flock, FlockError


class FlockDevice(Position, CarriedCounters):
    """Positions of the birds of an Ascension Flock of Birds on a serial port."""

    ELEMENT_TYPE = "flock"
    sample_interval = 0.0  # sample() waits for records (at most poll_interval)

    # Protocol timing in seconds (the C++ driver's); tests shorten them.
    reset_time = 1.0  # each half of the RTS reset pulse (only where the line has RTS)
    examine_delay = 0.05  # before each examine command
    read_timeout = 2.0  # for a reply during the start
    ready_timeout = 5.0  # for the bus after auto-configuration
    silence_timeout = 2.0  # no data at all for this long: the line counts as lost
    poll_interval = 0.02  # serial read granularity

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 38400
        self.hemisphere = 3
        self.master_address = 1
        self.addressing_mode = 0
        self.flock: Flock | None = None
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection
        self._matrices = np.zeros((0, 4, 4))
        self._unit_of: dict[int, int] = {}

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name and position filters
        self.port = access.string("port")
        self.baud = access.integer("baud")
        self.hemisphere = access.integer("hemisphere")
        self.master_address = access.integer("master_address")
        mode = access.integer("addressing_mode")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the master bird is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")
        if self.hemisphere not in HEMISPHERES:
            raise DeviceConfigError(f"hemisphere {self.hemisphere} is not one of 0..5")
        if mode not in ADDRESSING_FROM_CONFIG:
            raise DeviceConfigError(f"addressing_mode {mode} is not 0, 1 or 2")
        if not 0 <= self.master_address <= 126:
            raise DeviceConfigError(f"master_address {self.master_address} is outside 0..126")
        self.addressing_mode = ADDRESSING_FROM_CONFIG[mode]

    def start_sampling(self) -> None:
        flock = Flock(
            self.port,
            self.baud,
            hemisphere=self.hemisphere,
            master_address=self.master_address,
            addressing_mode=self.addressing_mode,
            reset_time=self.reset_time,
            examine_delay=self.examine_delay,
            read_timeout=self.read_timeout,
            ready_timeout=self.ready_timeout,
            silence_timeout=self.silence_timeout,
            poll_interval=self.poll_interval,
        )
        flock.open()
        self.flock = flock
        self.counts.attach(flock)
        self._unit_of = {address: unit for unit, address in enumerate(flock.sensors)}
        if len(self._matrices) != len(flock.sensors):
            self._matrices = np.tile(np.eye(4), (len(flock.sensors), 1, 1))

    def sample(self) -> None:
        flock = self.flock
        if flock is None:
            raise FlockError("the Flock is not open")
        records = flock.read()  # raises FlockDisconnected when the line is lost or silent
        if records:
            self._add(records)

    def stop_sampling(self) -> None:
        flock, self.flock = self.flock, None
        self.counts.detach()
        if flock is not None:
            flock.close()

    def _add(self, records: list[BirdRecord]) -> None:
        for record in records:
            self._matrices[self._unit_of[record.address]] = record.matrix()
        self.add_position_sample(self._matrices, self.now())
