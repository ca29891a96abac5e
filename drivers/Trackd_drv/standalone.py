"""trackd's shared-memory layout: decode the tracker and controller segments CAVELib's trackd
daemon publishes under System V shared-memory keys.

Knows nothing of gadgetctl. :func:`decode_tracker` and :func:`decode_controller` work on the
bytes of a segment (so they can be tested and fuzzed without shared memory);
:class:`TrackdSegment` attaches to a segment read-only through the ``sysv_ipc`` package.

Tracker segment (native byte order, 32-bit fields)::

    header  u32 version, num_sensors, sensor_offset, sensor_size, timestamp[2], command
    sensor  f32 x, y, z, azim, elev, roll; u32 timestamp[2]; i32 calibrated, frame   (40 bytes)

sensor i sits at ``sensor_offset + i * sensor_size``.

Controller segment::

    header  u32 version, button_offset, valuator_offset, num_buttons, num_valuators,
            timestamp[2], command
    buttons i32 at button_offset; valuators f32 at valuator_offset

Differences from Gadgeteer's C++ reader, on purpose: the header is checked against the size of
the segment before anything is read. A header that claims more sensors, buttons or valuators
than the segment holds (or than :data:`MAX_UNITS`), or offsets outside it, is a bad record: it is
counted and nothing is read from it, where the C++ read whatever memory the pointers reached.

Polling reads the header and then only the blocks it names (:func:`read_tracker`,
:func:`read_controller`, :meth:`TrackdSegment.read_tracker`): at most :data:`MAX_UNITS` records
of a few bytes, however large the segment (copying a 256 MB segment per poll took 815 MB and
the frame rate down to 9 per second).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

TRACKER_HEADER = struct.Struct("=7I")
SENSOR = struct.Struct("=6f2I2i")
CONTROLLER_HEADER = struct.Struct("=8I")
SENSOR_SIZE = SENSOR.size  # 40

#: Most sensors, buttons or valuators a segment may claim; more is a bad record.
MAX_UNITS = 1024

DEFAULT_SENSOR_KEY = 4126
DEFAULT_CONTROLLER_KEY = 4127


class TrackdError(OSError):
    """A segment cannot be used."""


class TrackdDisconnected(TrackdError):
    """The segment went away (trackd stopped or removed it)."""


class BadSegment(ValueError):
    """A header that does not fit the segment it is in."""


@dataclass(frozen=True)
class SensorReading:
    x: float
    y: float
    z: float
    azim: float
    elev: float
    roll: float
    calibrated: int
    frame: int


@dataclass(frozen=True)
class TrackerState:
    version: int
    timestamp: tuple[int, int]
    sensors: tuple[SensorReading, ...]


@dataclass(frozen=True)
class ControllerState:
    version: int
    timestamp: tuple[int, int]
    buttons: tuple[int, ...]
    valuators: tuple[float, ...]


def _check_block(what: str, offset: int, count: int, stride: int, size: int, segment: int) -> None:
    if count > MAX_UNITS:
        raise BadSegment(f"header claims {count} {what} (at most {MAX_UNITS})")
    if count and stride < size:
        raise BadSegment(f"{what} are {stride} bytes apart, less than the {size} each needs")
    end = offset + (count - 1) * stride + size if count else offset
    if offset > segment or end > segment:
        raise BadSegment(
            f"header claims {count} {what} at offset {offset}, beyond the {segment}-byte segment"
        )


def decode_tracker(data: bytes | bytearray | memoryview) -> TrackerState:
    """The sensors of a tracker segment; :class:`BadSegment` when the header does not fit."""
    if len(data) < TRACKER_HEADER.size:
        raise BadSegment(f"{len(data)} bytes, shorter than the tracker header")
    version, count, offset, stride, t0, t1, _command = TRACKER_HEADER.unpack_from(data, 0)
    _check_block("sensors", offset, count, stride, SENSOR_SIZE, len(data))
    sensors = []
    for i in range(count):
        x, y, z, azim, elev, roll, _s0, _s1, calibrated, frame = SENSOR.unpack_from(
            data, offset + i * stride
        )
        sensors.append(SensorReading(x, y, z, azim, elev, roll, calibrated, frame))
    return TrackerState(version, (t0, t1), tuple(sensors))


def tracker_poses(data: bytes | bytearray | memoryview) -> np.ndarray:
    """The (sensors, 6) array of x, y, z, azim, elev, roll of a tracker segment, without a
    Python object per sensor (the polling path); :class:`BadSegment` as :func:`decode_tracker`."""
    if len(data) < TRACKER_HEADER.size:
        raise BadSegment(f"{len(data)} bytes, shorter than the tracker header")
    _version, count, offset, stride, _t0, _t1, _command = TRACKER_HEADER.unpack_from(data, 0)
    _check_block("sensors", offset, count, stride, SENSOR_SIZE, len(data))
    if not count:
        return np.zeros((0, 6))
    dtype = np.dtype(
        {"names": ["pose"], "formats": [("=f4", 6)], "offsets": [0], "itemsize": stride}
    )
    return np.frombuffer(data, dtype, count, offset)["pose"].astype(np.float64)


def pose_matrices(poses: np.ndarray) -> np.ndarray:
    """:func:`sensor_matrix` for every row of a (sensors, 6) array at once: (sensors, 4, 4)."""
    a, e, r = np.radians(poses[:, 3]), np.radians(poses[:, 4]), np.radians(poses[:, 5])
    ca, sa, ce, se, cr, sr = np.cos(a), np.sin(a), np.cos(e), np.sin(e), np.cos(r), np.sin(r)
    out = np.zeros((len(poses), 4, 4))
    # R_y(a) . R_x(e) . R_z(r), multiplied out
    out[:, 0, 0] = ca * cr + sa * se * sr
    out[:, 0, 1] = -ca * sr + sa * se * cr
    out[:, 0, 2] = sa * ce
    out[:, 1, 0] = ce * sr
    out[:, 1, 1] = ce * cr
    out[:, 1, 2] = -se
    out[:, 2, 0] = -sa * cr + ca * se * sr
    out[:, 2, 1] = sa * sr + ca * se * cr
    out[:, 2, 2] = ca * ce
    out[:, :3, 3] = poses[:, :3]
    out[:, 3, 3] = 1.0
    return out


def decode_controller(data: bytes | bytearray | memoryview) -> ControllerState:
    """The buttons and valuators of a controller segment; :class:`BadSegment` when the header
    does not fit."""
    if len(data) < CONTROLLER_HEADER.size:
        raise BadSegment(f"{len(data)} bytes, shorter than the controller header")
    version, b_off, v_off, nb, nv, t0, t1, _command = CONTROLLER_HEADER.unpack_from(data, 0)
    _check_block("buttons", b_off, nb, 4, 4, len(data))
    _check_block("valuators", v_off, nv, 4, 4, len(data))
    buttons = struct.unpack_from(f"={nb}i", data, b_off) if nb else ()
    valuators = struct.unpack_from(f"={nv}f", data, v_off) if nv else ()
    return ControllerState(version, (t0, t1), tuple(buttons), tuple(valuators))


def encode_tracker(
    sensors: list[tuple[float, ...]],
    timestamp: tuple[int, int] = (0, 0),
    *,
    version: int = 1,
    claimed: int | None = None,
) -> bytes:
    """A tracker segment holding ``sensors`` (x, y, z, azim, elev, roll each); ``claimed``
    overrides the sensor count in the header (to make a bad one)."""
    count = len(sensors) if claimed is None else claimed
    out = bytearray(
        TRACKER_HEADER.pack(version, count, TRACKER_HEADER.size, SENSOR_SIZE, *timestamp, 0)
    )
    for i, s in enumerate(sensors):
        out += SENSOR.pack(*s, *timestamp, 1, i)
    return bytes(out)


def encode_controller(
    buttons: list[int],
    valuators: list[float],
    timestamp: tuple[int, int] = (0, 0),
    *,
    version: int = 1,
    claimed_buttons: int | None = None,
) -> bytes:
    """A controller segment (buttons first, then valuators)."""
    b_off = CONTROLLER_HEADER.size
    v_off = b_off + 4 * len(buttons)
    nb = len(buttons) if claimed_buttons is None else claimed_buttons
    out = bytearray(
        CONTROLLER_HEADER.pack(version, b_off, v_off, nb, len(valuators), *timestamp, 0)
    )
    out += struct.pack(f"={len(buttons)}i", *buttons)
    out += struct.pack(f"={len(valuators)}f", *valuators)
    return bytes(out)


def sensor_matrix(reading: SensorReading) -> np.ndarray:
    """Gadgeteer's matrix of a sensor: R_y(azim) . R_x(elev) . R_z(roll) (degrees), then the
    translation as stored (trackd's units; the example's device_units says feet)."""
    a, e, r = (math.radians(v) for v in (reading.azim, reading.elev, reading.roll))
    ca, sa, ce, se, cr, sr = (
        math.cos(a),
        math.sin(a),
        math.cos(e),
        math.sin(e),
        math.cos(r),
        math.sin(r),
    )
    ry = np.array([[ca, 0, sa], [0, 1, 0], [-sa, 0, ca]])
    rx = np.array([[1, 0, 0], [0, ce, -se], [0, se, ce]])
    rz = np.array([[cr, -sr, 0], [sr, cr, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = ry @ rx @ rz
    m[:3, 3] = (reading.x, reading.y, reading.z)
    return m


#: ``read(offset, count)``: ``count`` bytes of a segment from ``offset`` (both within it).
ReadAt = Callable[[int, int], bytes]


def read_tracker(read: ReadAt, size: int) -> bytes:
    """What :func:`decode_tracker` and :func:`tracker_poses` need of a tracker segment of
    ``size`` bytes, reading through ``read`` only its header and the sensors the header names:
    a compact segment (the header with the sensors right after it, :data:`SENSOR_SIZE` apart).
    A header that does not fit the segment comes back alone, which decodes as a bad segment."""
    if size < TRACKER_HEADER.size:
        return read(0, size) if size else b""
    header = read(0, TRACKER_HEADER.size)
    version, count, offset, stride, t0, t1, command = TRACKER_HEADER.unpack(header)
    try:
        _check_block("sensors", offset, count, stride, SENSOR_SIZE, size)
    except BadSegment:
        return header
    if not count:
        block = b""
    elif stride == SENSOR_SIZE:
        block = read(offset, count * SENSOR_SIZE)
    else:
        block = b"".join(read(offset + i * stride, SENSOR_SIZE) for i in range(count))
    compact = TRACKER_HEADER.pack(version, count, TRACKER_HEADER.size, SENSOR_SIZE, t0, t1, command)
    return compact + block


def read_controller(read: ReadAt, size: int) -> bytes:
    """:func:`read_tracker` for a controller segment: the header and the buttons and
    valuators it names, laid out right after it (buttons first)."""
    if size < CONTROLLER_HEADER.size:
        return read(0, size) if size else b""
    header = read(0, CONTROLLER_HEADER.size)
    version, b_off, v_off, nb, nv, t0, t1, command = CONTROLLER_HEADER.unpack(header)
    try:
        _check_block("buttons", b_off, nb, 4, 4, size)
        _check_block("valuators", v_off, nv, 4, 4, size)
    except BadSegment:
        return header
    buttons = read(b_off, 4 * nb) if nb else b""
    valuators = read(v_off, 4 * nv) if nv else b""
    start = CONTROLLER_HEADER.size
    compact = CONTROLLER_HEADER.pack(version, start, start + len(buttons), nb, nv, t0, t1, command)
    return compact + buttons + valuators


def _sysv_ipc():
    try:
        import sysv_ipc
    except ImportError:
        raise ImportError("Trackd_drv needs the sysv_ipc package (pip install sysv_ipc)") from None
    return sysv_ipc


_libc = None


def segment_id(key: int) -> int | None:
    """The id of the segment ``key`` names now, or None (``shmget`` without creating)."""
    global _libc
    if _libc is None:
        import ctypes

        _libc = ctypes.CDLL(None, use_errno=True)
        _libc.shmget.argtypes = (ctypes.c_int, ctypes.c_size_t, ctypes.c_int)
    found = _libc.shmget(key, 0, 0)
    return None if found < 0 else found


class TrackdSegment:
    """A trackd segment attached read-only by key. :meth:`read` returns its bytes and raises
    :class:`TrackdDisconnected` once the key no longer names the segment attached (trackd
    removed it, or made a new one)."""

    def __init__(self, key: int) -> None:
        self.key = key
        self._memory = None
        self._id: int | None = None
        self._ipc = _sysv_ipc()

    def open(self) -> None:
        ipc = self._ipc
        found = segment_id(self.key)
        if found is None:
            raise TrackdDisconnected(f"no shared-memory segment with key {self.key}")
        try:
            self._memory = ipc.attach(found, None, ipc.SHM_RDONLY)
        except ipc.ExistentialError:
            raise TrackdDisconnected(f"shared-memory segment {self.key} went away") from None
        except ipc.PermissionsError as err:
            raise TrackdError(f"shared-memory key {self.key}: {err}") from None
        self._id = found

    def read(self) -> bytes:
        """The whole segment (for tests and tools; polling uses :meth:`read_tracker` and
        :meth:`read_controller`)."""
        return self._attached().read()

    def read_tracker(self) -> bytes:
        """:func:`read_tracker` of this segment: its header and the sensors it names."""
        memory = self._attached()
        return read_tracker(lambda offset, count: memory.read(count, offset), memory.size)

    def read_controller(self) -> bytes:
        """:func:`read_controller` of this segment."""
        memory = self._attached()
        return read_controller(lambda offset, count: memory.read(count, offset), memory.size)

    def _attached(self):
        memory = self._memory
        if memory is None:
            raise TrackdDisconnected(f"shared-memory key {self.key}: not attached")
        if segment_id(self.key) != self._id:
            raise TrackdDisconnected(f"shared-memory segment {self.key} was removed")
        return memory

    def close(self) -> None:
        memory, self._memory, self._id = self._memory, None, None
        if memory is not None:
            try:
                memory.detach()
            except self._ipc.Error:
                pass
