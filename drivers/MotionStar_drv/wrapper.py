"""The input-manager side of the Ascension MotionStar (element type ``motion_star``).

Units, as Gadgeteer's MotionStar driver gives them: position unit i is the i-th sensor in
FBB address order (ERCs and addresses without a sensor are skipped). Each sample is a 4x4
matrix per sensor with the translation in **inches**, as the chassis reports it, and the
rotation ``Rz·Ry·Rx`` of the Z, Y, X angles it sends. The element's device-level
``position_transform_filter`` turns that into meters: its ``device_units`` must be 0.0254
(Inches), as in VR Juggler's example configurations.

Kept from the C++ wrapper: ``is_master`` is read and ignored (every chassis is read alike);
``server_port`` selects the transport, 5000 meaning UDP and anything else TCP; version 1
elements are refused (they need an upgrade).

Differences, on purpose:

* BIRDNET over UDP is not implemented: ``server_port`` 5000 is a configuration error with
  that reason, instead of a driver that would not work;
* the units check happens at configuration, for every unit value: device_units other than
  0.0254 is a warning saying how far off the positions are (the C++ refused values other
  than 0.0254, 0.3048 and 1.0, required a filter, and warned about a mismatch only at
  start-up, in its log);
* a sensor whose record is missing or failed keeps its last pose (the C++ reset it);
* a lost connection raises from ``sample`` and the input manager restarts the device with
  back-off (the C++ sample loop only logged the failure);
* no data packet for ``data_timeout`` seconds (silence, or only junk on the stream) is a
  fault too, whose reason says how much junk was skipped; a (re)start counts as done only
  when the first data packet has arrived, so the device never reads "running" while only
  junk arrives;
* the standalone driver fixes the decoding defects (signed matrix and quaternion words,
  button bytes after each record, rotations of the matrix formats); see its docstring.
"""

from __future__ import annotations

import math
import time
from enum import IntEnum

import numpy as np

from gadgetctl.input import DeviceConfigError, ElementVersionError, Position
from gadgetctl.input.filters import FILTERS_PROPERTY, TRANSFORM_FILTER
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.transport.records import CarriedCounts

from .standalone import (
    MAX_RATE,
    MIN_RATE,
    SEQUENCE_MODULO,
    DataFormat,
    Hemisphere,
    MotionStar,
    MotionStarError,
    MotionStarNoData,
    MotionStarSample,
    RunMode,
)

MIN_VERSION = 2
UDP_PORT = 5000
INCH = 0.0254  # meters; the chassis reports positions in inches


def read_choice(access: ElementAccess, prop: str, choices: type[IntEnum]) -> int:
    """An enumerated property's value (labels arrive resolved); a config error if unknown."""
    value = access.integer(prop)
    try:
        return int(choices(value))
    except ValueError:
        known = ", ".join(f"{m.value} ({m.name.replace('_', ' ').title()})" for m in choices)
        raise DeviceConfigError(f"{prop} {value} is not one of {known}") from None


class MotionStarDevice(Position):
    """Sensor poses from one MotionStar chassis over TCP."""

    ELEMENT_TYPE = "motion_star"
    sample_interval = 0.0  # sample() waits for a data packet (at most sample_timeout)

    # Network timeouts in seconds; tests shorten them.
    connect_timeout = 5.0
    read_timeout = 5.0  # per command reply
    sample_timeout = 0.25  # one sample() call waiting for a data packet
    close_timeout = 1.0  # stop-data and shut-down replies
    data_timeout = 2.0  # no data packet for this long (silence or only junk): a fault

    def __init__(self) -> None:
        super().__init__()
        self.address = ""
        self.server_port = 6000
        self.is_master = True
        self.hemisphere = int(Hemisphere.FRONT)
        self.data_format = int(DataFormat.POSITION_ANGLES)
        self.mode = int(RunMode.RUN_CONTINUOUS)
        self.report_rate = 1
        self.measurement_rate = 0.0
        self.ms: MotionStar | None = None
        self.sequence: int | None = None  # of the newest data packet
        self.packets = 0
        self.sequence_gaps = 0  # data packets whose number did not follow the previous one
        self._next_sequence: int | None = None
        self._poses = np.zeros((0, 4, 4))
        self.counts = CarriedCounts(
            ("bad_packets", "skipped_bytes", "sensor_errors", "other_records")
        )
        self._told: set[str] = set()
        self._first: tuple[MotionStarSample, float] | None = None  # read by start_sampling
        self._last_data = 0.0  # monotonic time of the newest data packet
        self._junk_mark = 0  # skipped_bytes at that time

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, device-level position_filters
        element = access.element
        if element.version is None or element.version < MIN_VERSION:
            raise ElementVersionError(
                f"motion_star version {element.version_text} is not supported; version "
                f"{MIN_VERSION} replaced server_type by is_master and dropped number_of_birds"
            )
        self.address = access.string("address")
        self.server_port = access.integer("server_port")
        self.is_master = access.boolean("is_master")  # ignored, as by the C++ driver
        self.hemisphere = read_choice(access, "hemisphere", Hemisphere)
        self.data_format = read_choice(access, "data_format", DataFormat)
        self.mode = read_choice(access, "mode", RunMode)
        self.report_rate = access.integer("report_rate")
        self.measurement_rate = access.float("measurement_rate")
        if not self.address:
            raise DeviceConfigError("address is empty: name the MotionStar server chassis")
        if self.server_port == UDP_PORT:
            raise DeviceConfigError(
                f"server_port {UDP_PORT} selects BIRDNET over UDP, which this driver does not "
                "implement; use the chassis's TCP port (6000)"
            )
        if not 0 < self.server_port < 65536:
            raise DeviceConfigError(f"server_port {self.server_port} is not a TCP port")
        if not 1 <= self.report_rate <= 255:
            raise DeviceConfigError(f"report_rate {self.report_rate} is not in 1..255")
        self._check_rate()
        self._check_units(access)

    def start_sampling(self) -> None:
        ms = MotionStar(
            self.address,
            self.server_port,
            hemisphere=self.hemisphere,
            data_format=self.data_format,
            mode=self.mode,
            report_rate=self.report_rate,
            measurement_rate=self.measurement_rate,
            connect_timeout=self.connect_timeout,
            read_timeout=self.read_timeout,
            sample_timeout=self.sample_timeout,
            close_timeout=self.close_timeout,
        )
        ms.open()
        for warning in ms.warnings:
            self._tell(warning)
        if len(self._poses) != len(ms.sensors):
            self._poses = np.tile(np.eye(4), (len(ms.sensors), 1, 1))
        self._next_sequence = None
        self.ms = ms
        self.counts.attach(ms)
        self._last_data, self._junk_mark = time.monotonic(), ms.skipped_bytes
        try:  # started means data arrive: wait for the first packet
            first = None
            while first is None:
                first = self._next_packet(ms)
        except BaseException:
            self.stop_sampling()
            raise
        self._first = (first, self.now())

    def sample(self) -> None:
        ms = self.ms
        if ms is None:
            raise MotionStarError("the MotionStar is not open")
        if self._first is not None:
            (packet, stamp), self._first = self._first, None
        else:
            # raises MotionStarDisconnected when the connection is lost, MotionStarNoData
            # when only junk (or nothing) arrives for data_timeout seconds
            packet, stamp = self._next_packet(ms), self.now()
        if packet is None:
            return
        self._track(packet.sequence)
        poses = self._poses
        for bird in packet.birds:
            if bird.unit < len(poses):
                poses[bird.unit] = bird.matrix
        # A copy: the store keeps what it is given, and the poses change with the next packet.
        self.add_position_sample(poses.copy(), stamp)

    def _next_packet(self, ms: MotionStar) -> MotionStarSample | None:
        """One ``ms.sample()``; raises MotionStarNoData after data_timeout without data."""
        packet = ms.sample()
        now = time.monotonic()
        if packet is not None:
            self._last_data, self._junk_mark = now, ms.skipped_bytes
            return packet
        quiet = now - self._last_data
        if quiet >= self.data_timeout:
            junk = ms.skipped_bytes - self._junk_mark
            if junk:
                raise MotionStarNoData(
                    f"only junk for {quiet:.1f} s: {junk} bytes skipped, no data packet"
                )
            raise MotionStarNoData(f"no data packet for {quiet:.1f} s")
        return None

    def stop_sampling(self) -> None:
        ms, self.ms = self.ms, None
        self._first = None
        self.counts.detach()
        if ms is not None:
            ms.close()

    # -- counters over every start, for monitors and tests ------------------------------

    @property
    def bad_packets(self) -> int:
        """Runs of bytes that were not a valid server message."""
        return self.counts.get("bad_packets")

    @property
    def skipped_bytes(self) -> int:
        return self.counts.get("skipped_bytes")

    @property
    def sensor_errors(self) -> int:
        """Records in which a sensor reported a sampling error."""
        return self.counts.get("sensor_errors")

    @property
    def counters(self) -> dict[str, int]:
        """The device's health counters since it was made, reconnections included."""
        return {
            "packets": self.packets,
            "bad_packets": self.bad_packets,
            "skipped_bytes": self.skipped_bytes,
            "sensor_errors": self.sensor_errors,
            "other_records": self.counts.get("other_records"),
            "sequence_gaps": self.sequence_gaps,
        }

    # -- internals ------------------------------------------------------------------------

    def _track(self, sequence: int) -> None:
        if self._next_sequence is not None and sequence != self._next_sequence:
            self.sequence_gaps += 1
        self._next_sequence = (sequence + 1) % SEQUENCE_MODULO
        self.sequence = sequence
        self.packets += 1

    def _tell(self, message: str) -> None:
        """A warning from the chassis, once per device."""
        if message not in self._told:
            self._told.add(message)
            self.warn("DRV024", message)

    def _check_rate(self) -> None:
        rate = self.measurement_rate
        if rate > 0 and not MIN_RATE <= rate <= MAX_RATE:
            taken = min(max(rate, MIN_RATE), MAX_RATE)
            self.warn(
                "DRV024",
                f"measurement_rate {rate:g} Hz is outside {MIN_RATE:g}-{MAX_RATE:g} Hz; "
                f"the chassis is set to {taken:g} Hz",
                hint="0 keeps the chassis's own rate",
            )

    def _check_units(self, access: ElementAccess) -> None:
        """The first position_transform_filter says what units the device reports."""
        filters = access.children(FILTERS_PROPERTY)
        first = next((f for f in filters if f.type == TRANSFORM_FILTER), None)
        hint = "set device_units of the device's position_transform_filter to 0.0254 (Inches)"
        if first is None:
            if not filters:
                self.warn(
                    "DRV024",
                    "no position_transform_filter gives the device units: the "
                    "MotionStar reports inches, which proxies then read as meters",
                    hint=hint,
                )
            return
        child = ElementAccess(first, access.repo)
        units = child.float("device_units")
        scale = child.float("custom_scale") if units == 0.0 else units
        if math.isclose(scale, INCH, rel_tol=1e-4):
            return
        what = f"custom_scale {scale:g}" if units == 0.0 else f"device_units {units:g}"
        factor = scale / INCH if scale else 0.0
        self.warn(
            "DRV024",
            f"{first.name!r} has {what}, but the MotionStar reports inches: positions "
            f"come out {factor:.4g} times their size in meters",
            hint=hint,
        )
