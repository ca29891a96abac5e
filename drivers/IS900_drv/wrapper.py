"""The input-manager side of the InterSense IS-900 (element type ``intersense``).

Units, as Gadgeteer's Intersense driver numbers them:

* position unit ``i``: the ``i``-th ``stations`` child (its ``station_index`` names the
  tracker station, counted from 0); 4x4 matrices in metres, rotation from the azimuth,
  elevation and roll the tracker sends (ZYX Euler angles);
* digital units ``digital_first .. digital_first + digital_count - 1`` of a station with
  ``use_digital``: its buttons 0, 1, ... as 0/1 (at most 8 per station);
* analog units ``analog_first ..`` of a station with ``use_analog``: its joystick bytes, raw
  0..255 (analog proxies normalise with the element's ``min``/``max``; at most 2 per station).

There are as many digital (analog) units as the largest ``first + count`` of any station,
whether or not it reads them, so proxies of a station with ``use_digital`` false read 0.

Differences from the C++, on purpose:

* ``enabled`` false does not switch a station off: the driver only switches on the stations
  that ask for it and reads every configured station the tracker reports (VR Juggler's own
  ``example.intersense.jconf`` lists both its stations as disabled and expects data);
* the samples are one per poll the tracker answered, not one per 50 ms sleep;
* a lost or silent line raises from ``sample`` and the input manager restarts the device.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gadgetctl.input import Analog, DeviceConfigError, Digital, Position
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import SCANNER_COUNTERS, CarriedCounters, CarriedCounts

from .standalone import (
    ANALOG_PER_STATION,
    BUTTONS_PER_STATION,
    IS900,
    MAX_STATIONS,
    IS900Error,
    StationRecord,
    StationSetup,
)

#: Digital and analog units an intersense element may ask for at most (Gadgeteer's limits).
MAX_DIGITAL_UNITS = 128
MAX_ANALOG_UNITS = 128


@dataclass(frozen=True)
class StationConfig:
    """One ``intersense_station`` child."""

    enabled: bool
    index: int
    use_digital: bool
    use_analog: bool
    digital_first: int
    digital_count: int
    analog_first: int
    analog_count: int


def _station(access: ElementAccess, child: ElementAccess) -> StationConfig:
    config = StationConfig(
        child.boolean("enabled"),
        child.integer("station_index"),
        child.boolean("use_digital"),
        child.boolean("use_analog"),
        child.integer("digital_first"),
        child.integer("digital_count"),
        child.integer("analog_first"),
        child.integer("analog_count"),
    )
    where = f"station {child.name!r}"
    if not 0 <= config.index < MAX_STATIONS:
        raise DeviceConfigError(
            f"{where}: station_index {config.index} is outside 0..{MAX_STATIONS - 1}"
        )
    for kind, first, count, limit in (
        ("digital", config.digital_first, config.digital_count, MAX_DIGITAL_UNITS),
        ("analog", config.analog_first, config.analog_count, MAX_ANALOG_UNITS),
    ):
        if first < 0 or count < 0 or first + count > limit:
            raise DeviceConfigError(
                f"{where}: {kind}_first {first} and {kind}_count {count} leave units 0..{limit - 1}"
            )
    return config


class IntersenseDevice(Position, Digital, Analog, CarriedCounters):
    """Position, buttons and joysticks of an InterSense IS-900 on a serial port."""

    ELEMENT_TYPE = "intersense"
    sample_interval = 0.0  # sample() waits for the tracker's records (at most poll_interval)

    # Protocol timing in seconds (the C++ driver's where it has one); tests shorten them.
    settle = 0.1  # after 'c' (continuous output off)
    read_timeout = 2.0  # for a reply line during the start
    poll_timeout = 0.1  # a poll not fully answered is repeated after this
    silence_timeout = 2.0  # no record at all for this long: the line counts as lost
    poll_interval = 0.02  # serial read granularity

    def __init__(self) -> None:
        super().__init__()
        self.port = ""
        self.baud = 115200
        self.stations: list[StationConfig] = []
        self.tracker: IS900 | None = None
        self.counts = CarriedCounts(SCANNER_COUNTERS)  # over every connection
        self._matrices = np.zeros((0, 4, 4))
        self._digital = np.zeros(0, dtype=np.int8)
        self._analog = np.zeros(0)
        self._units_of: dict[int, list[int]] = {}

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, position filters, min and max
        self.port = access.string("port")
        self.baud = access.integer("baud")
        if not self.port:
            raise DeviceConfigError("port is empty: name the serial device the tracker is on")
        if self.baud <= 0:
            raise DeviceConfigError(f"baud {self.baud} is not a line speed")
        children = access.children("stations")
        if not children:
            raise DeviceConfigError(
                "no stations: add an intersense_station for each tracked station"
            )
        self.stations = [_station(access, ElementAccess(c, access.repo)) for c in children]
        self._matrices = np.tile(np.eye(4), (len(self.stations), 1, 1))
        self._digital = np.zeros(
            max(s.digital_first + s.digital_count for s in self.stations), dtype=np.int8
        )
        self._analog = np.zeros(max(s.analog_first + s.analog_count for s in self.stations))
        self._units_of = {}
        for unit, station in enumerate(self.stations):
            self._units_of.setdefault(station.index, []).append(unit)

    def start_sampling(self) -> None:
        setups = {s.index: StationSetup(s.index, s.enabled) for s in self.stations if not s.enabled}
        setups.update({s.index: StationSetup(s.index, True) for s in self.stations if s.enabled})
        tracker = IS900(
            self.port,
            self.baud,
            tuple(setups[i] for i in sorted(setups)),
            settle=self.settle,
            read_timeout=self.read_timeout,
            poll_timeout=self.poll_timeout,
            silence_timeout=self.silence_timeout,
            poll_interval=self.poll_interval,
        )
        tracker.open()
        self.tracker = tracker
        self.counts.attach(tracker)

    def sample(self) -> None:
        tracker = self.tracker
        if tracker is None:
            raise IS900Error("the tracker is not open")
        records = tracker.read()  # raises IS900Disconnected when the line is lost or silent
        if records:
            self._add(records)

    def stop_sampling(self) -> None:
        tracker, self.tracker = self.tracker, None
        self.counts.detach()  # what it counted is kept
        if tracker is not None:
            tracker.close()

    # -- internals ------------------------------------------------------------------------

    def _add(self, records: list[StationRecord]) -> None:
        for record in records:
            for unit in self._units_of.get(record.station, ()):
                station = self.stations[unit]
                self._matrices[unit] = record.matrix()
                if station.use_digital:
                    n = min(station.digital_count, BUTTONS_PER_STATION)
                    first = station.digital_first
                    self._digital[first : first + n] = record.digital[:n]
                if station.use_analog:
                    n = min(station.analog_count, ANALOG_PER_STATION)
                    first = station.analog_first
                    self._analog[first : first + n] = record.analog[:n]
        stamp = self.now()
        self.add_position_sample(self._matrices, stamp)
        if len(self._digital):
            self.add_digital_sample(self._digital.tolist(), stamp)
        if len(self._analog):
            self.add_analog_sample(self._analog.tolist(), stamp)
