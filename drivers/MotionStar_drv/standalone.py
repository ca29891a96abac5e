"""Ascension MotionStar BIRDNET protocol over TCP, independent of gadgetctl.

Every message starts with a 16-byte big-endian header (sequence, milliseconds,
time, type, xtype, protocol 3, error code, error extension, payload length).
Start-up: wake-up, general system status (with one FBB status byte per
device), optionally a new measurement rate, then per bird a status read and a
setup write, then run-continuous. Data packets carry one record per sensor:
address (bit 7 = two button bytes follow), data info (format code << 4 | word
count), big-endian int16 words, the optional buttons.

Positions are ``full_scale * word / 32767`` inches, angles ``180 * word / 32767``
degrees in the order Z, Y, X; matrix and quaternion words are fractions in
[-1, 1). Each sample gives a 4x4 float64 matrix per sensor, translation in
inches, rotation ``Rz @ Ry @ Rx``.

The quaternion is used as sent, (w, x, y, z) = (q0, q1, q2, q3), as VR Juggler's
C++ does. Ascension's manuals say the Bird extracts q0..q3 (q0 the scalar) from its
MATRIX output with Shepperd's algorithm; that matrix M is the direction-cosine
matrix from transmitter to sensor axes (M11 = cos E cos A, M12 = cos E sin A,
M13 = -sin E), whose Shepperd quaternion is, in the usual active (Hamilton) reading,
the rotation M transposed: the sensor's orientation, the same rotation as the angles
give. So no conjugation is needed; an independent driver (VESS's
``vsEthernetMotionStar``) conjugates because its own quaternion class rotates frames
the other way round.

Differences from the C++ driver, on purpose:

* matrix and quaternion words are signed fractions ``word / 32768``; the C++
  read them unsigned, so negative values came out in (-2, -1];
* button bytes are read right after each record's data words; the C++ read them
  at a fixed offset in a union sized for the largest format;
* the rotation of the matrix formats is taken from the matrix itself; the C++
  went through arcsines (losing the quadrant) and, for the plain matrix format,
  passed the X and Z angles in swapped order;
* records are stepped over by their own word count, as the C++ does, and a record
  whose format code is no data format (the feed-through record ``0xE1``, code 14
  with one word, that a chassis sends while a wand button is held) is counted in
  ``other_records`` and skipped (gadgetctl used to reject the whole packet, so
  tracking vanished while the button was held); pose records are decoded by
  their own format code (the C++ decodes every record by the format it set up,
  which gives the same poses for the records a chassis set up that way sends)
  and mapped to units by their FBB address; packets that do not add up count as
  garbage and the stream is re-synchronised on the next plausible header;
* re-synchronisation skips a whole run of junk at once (a scan for the
  protocol byte, not a header parse per byte), and takes only the message
  types it waits for: a reply-like header inside junk can no longer swallow
  the data packet that follows it; when a data packet's sequence number is
  not the expected one and a data packet with the expected number starts
  inside it, the first is junk (a packet cut short by the next one);
* a data packet whose header carries an error code (missed or repeated packets
  on the server side) is still decoded; the code is kept in the sample;
* after a failed wake-up the server is shut down and woken again, as the
  manual recommends (the C++ only shut it down).
"""

from __future__ import annotations

import contextlib
import socket
import struct
import time
from dataclasses import dataclass
from enum import IntEnum
from types import TracebackType

import numpy as np

MSG_WAKE_UP = 10
RSP_WAKE_UP = 20
MSG_SHUT_DOWN = 11
RSP_SHUT_DOWN = 21
MSG_SYNC_SEQUENCE = 30
RSP_SYNC_SEQUENCE = 31
RSP_ILLEGAL = 40
RSP_UNKNOWN = 50
MSG_GET_STATUS = 101
MSG_SEND_SETUP = 102
MSG_SINGLE_SHOT = 103
MSG_RUN_CONTINUOUS = 104
MSG_STOP_DATA = 105
RSP_GET_STATUS = 201
RSP_SEND_SETUP = 202
RSP_RUN_CONTINUOUS = 204
RSP_STOP_DATA = 205
DATA_PACKET_MULTI = 210
RESPONSE_TYPES = frozenset(
    {
        RSP_WAKE_UP,
        RSP_SHUT_DOWN,
        RSP_SYNC_SEQUENCE,
        RSP_ILLEGAL,
        RSP_UNKNOWN,
        RSP_GET_STATUS,
        RSP_SEND_SETUP,
        RSP_RUN_CONTINUOUS,
        RSP_STOP_DATA,
        DATA_PACKET_MULTI,
    }
)
BN_PROTOCOL = 3
HEADER = struct.Struct(">HH4sBBBBHH")
MAX_PAYLOAD = 2048
SYSTEM_STATUS_SIZE = 16
BIRD_STATUS_SIZE = 70
SEQUENCE_MODULO = 1 << 16

# FBB device status bits (one byte per device after the system status)
FBB_ACCESSIBLE = 0x80
FBB_RUNNING = 0x40
FBB_SENSOR = 0x20
FBB_ERC = 0x10

APPEND_BUTTON_DATA = 0x08  # bird setup bit
ERROR_FORMAT = 15  # record format code meaning "sampling failed"
WORD_DIVISOR = 32767.0  # positions and angles
FRACTION_DIVISOR = 32768.0  # matrix and quaternion words: -1 .. 0.99997
ANGLE_SCALE = 180.0
MIN_RATE, MAX_RATE = 20.0, 144.0
UNITS = {0: "inches"}


class DataFormat(IntEnum):
    """The ``data_format`` values of the motion_star definition."""

    NO_DATA = 0
    POSITION = 1
    ANGLES = 2
    MATRIX = 3
    POSITION_ANGLES = 4
    POSITION_MATRIX = 5
    QUATERNION = 7
    POSITION_QUATERNION = 8


#: Data words per format; the setup byte is ``words << 4 | code`` (e.g. 0x64).
FORMAT_WORDS = {
    DataFormat.NO_DATA: 0,
    DataFormat.POSITION: 3,
    DataFormat.ANGLES: 3,
    DataFormat.MATRIX: 9,
    DataFormat.POSITION_ANGLES: 6,
    DataFormat.POSITION_MATRIX: 12,
    DataFormat.QUATERNION: 4,
    DataFormat.POSITION_QUATERNION: 7,
}


class Hemisphere(IntEnum):
    FRONT = 0
    AFT = 1
    UPPER = 2
    LOWER = 3
    LEFT = 4
    RIGHT = 5


class RunMode(IntEnum):
    """The ``mode`` values of the motion_star definition."""

    RUN_CONTINUOUS = 0
    SAMPLE_INDIVIDUALLY = 1


class MotionStarError(Exception):
    """Base class of the driver's errors."""


class MotionStarTimeout(MotionStarError, TimeoutError):
    """The server did not answer a command in time."""


class MotionStarCommandError(MotionStarError):
    """The server refused a command (illegal, unknown, or an error code)."""


class MotionStarDisconnected(MotionStarError):
    """The connection is gone (EOF, reset); reconnect with a new ``open()``."""


class MotionStarNoData(MotionStarError):
    """No data packet for too long although the connection stands (silence or only junk)."""


@dataclass(frozen=True)
class Header:
    """A BIRDNET header; ``time`` is seconds since 1970, ``length`` the payload size."""

    sequence: int
    type: int
    xtype: int = 0
    length: int = 0
    milliseconds: int = 0
    time: int = 0
    protocol: int = BN_PROTOCOL
    error_code: int = 0
    error_extension: int = 0

    def pack(self) -> bytes:
        return HEADER.pack(
            self.sequence % SEQUENCE_MODULO,
            self.milliseconds,
            self.time.to_bytes(4, "big"),
            self.type,
            self.xtype,
            self.protocol,
            self.error_code,
            self.error_extension,
            self.length,
        )

    @classmethod
    def unpack(cls, data: bytes) -> Header:
        seq, ms, stamp, kind, xtype, proto, err, ext, length = HEADER.unpack(data[: HEADER.size])
        return cls(seq, kind, xtype, length, ms, int.from_bytes(stamp, "big"), proto, err, ext)

    def plausible(self) -> bool:
        """Whether this can start a server message (used to re-synchronise)."""
        return (
            self.protocol == BN_PROTOCOL
            and self.type in RESPONSE_TYPES
            and self.length <= MAX_PAYLOAD
        )


@dataclass(frozen=True)
class SystemStatus:
    """General system status (device 0) and the FBB status byte of each device."""

    raw: bytes
    devices: tuple[int, ...]

    @property
    def flock_number(self) -> int:
        return self.raw[2]

    @property
    def server_number(self) -> int:
        return self.raw[3]

    @property
    def transmitter_number(self) -> int:
        return self.raw[4]

    @property
    def measurement_rate(self) -> float:
        """Chassis rate in Hz, from six ASCII digits of rate x 1000 (0.0 when they are not
        six digits: a sign, blanks or other characters are no rate)."""
        digits = bytes(self.raw[5:11])
        if len(digits) != 6 or not digits.isdigit():  # bytes.isdigit: ASCII digits only
            return 0.0
        return int(digits) / 1000.0

    @property
    def chassis_number(self) -> int:
        return self.raw[11]

    @property
    def chassis_devices(self) -> int:
        return self.raw[12]

    @property
    def first_address(self) -> int:
        return self.raw[13]

    @property
    def software_revision(self) -> tuple[int, int]:
        return self.raw[14], self.raw[15]

    def with_rate(self, rate: float) -> bytes:
        """The 16-byte block with a new measurement rate (clamped to 20..144 Hz)."""
        rate = min(max(rate, MIN_RATE), MAX_RATE)
        text = f"{rate * 1000.0:06.0f}".encode("ascii")
        return self.raw[:5] + text + self.raw[11:SYSTEM_STATUS_SIZE]

    @classmethod
    def parse(cls, payload: bytes) -> SystemStatus:
        if len(payload) < SYSTEM_STATUS_SIZE:
            raise MotionStarCommandError(f"system status of {len(payload)} bytes")
        count = payload[2]
        devices = payload[SYSTEM_STATUS_SIZE : SYSTEM_STATUS_SIZE + count]
        if len(devices) < count:
            raise MotionStarCommandError("system status lacks FBB device bytes")
        return cls(bytes(payload[:SYSTEM_STATUS_SIZE]), tuple(devices))


@dataclass(frozen=True)
class BirdStatus:
    """The 70-byte status block of one bird (single bird status + filter tables)."""

    address: int
    raw: bytes

    @property
    def setup(self) -> int:
        return self.raw[5]

    @property
    def data_format(self) -> int:
        """Format code (low nibble of the data format byte)."""
        return self.raw[6] & 0x0F

    @property
    def report_rate(self) -> int:
        return self.raw[7]

    @property
    def units(self) -> int:
        """Units code from the high nibble of scaling[0]; 0 is inches."""
        return self.raw[8] >> 4

    @property
    def full_scale(self) -> int:
        return (self.raw[8] & 0x0F) << 8 | self.raw[9]

    @property
    def hemisphere(self) -> int:
        return self.raw[10]

    @property
    def fbb_address(self) -> int:
        return self.raw[11] or self.address

    def configured(self, data_format: int, report_rate: int, hemisphere: int) -> bytes:
        """The block to send back: buttons appended, our format, rate and hemisphere."""
        block = bytearray(self.raw)
        block[5] |= APPEND_BUTTON_DATA
        block[6] = FORMAT_WORDS[DataFormat(data_format)] << 4 | data_format
        block[7] = report_rate & 0xFF
        block[10] = hemisphere
        return bytes(block)


@dataclass(frozen=True)
class Record:
    """One undecoded sensor record of a data packet."""

    address: int
    format_code: int
    words: tuple[int, ...]
    buttons: tuple[int, int] | None


@dataclass(frozen=True, eq=False)
class BirdSample:
    """One sensor of one data packet.

    ``matrix`` is 4x4 float64 with the translation in inches (``position`` as
    sent), ``angles`` are degrees in wire order (z, y, x), ``quaternion`` is
    (w, x, y, z). Fields a format does not carry are None.
    """

    unit: int
    address: int
    data_format: int
    matrix: np.ndarray
    position: tuple[float, float, float] | None = None
    angles: tuple[float, float, float] | None = None
    quaternion: tuple[float, float, float, float] | None = None
    buttons: tuple[int, int] | None = None


@dataclass(frozen=True, eq=False)
class MotionStarSample:
    """One data packet: its header fields and the decoded sensors in unit order."""

    sequence: int
    milliseconds: int
    time: int
    error_code: int
    birds: tuple[BirdSample, ...]

    def matrices(self) -> dict[int, np.ndarray]:
        """Unit number -> 4x4 matrix."""
        return {bird.unit: bird.matrix for bird in self.birds}


def record_header_plausible(address: int, info: int) -> bool:
    """Whether an address byte and a data info byte can start a record: an FBB address
    1..126, and a word count that fits the format code when the code is a data format.
    Any other code (14 for feed-through data, 15 for a sampling error) is a record the
    driver steps over by its word count."""
    code, count = info >> 4, info & 0x0F
    if not 1 <= address & 0x7F <= 126:
        return False
    return code not in FORMAT_WORDS or FORMAT_WORDS[DataFormat(code)] == count


def carries_pose(format_code: int) -> bool:
    """Whether records of this format code hold a pose (the data formats but NO_DATA); the
    others (feed-through data, code 14; a sampling error, code 15) are stepped over."""
    return format_code in FORMAT_WORDS and format_code != DataFormat.NO_DATA


def parse_records(payload: bytes) -> list[Record] | None:
    """Split a data packet payload into records, stepping over each by its own word count
    (and its button bytes), as VR Juggler's C++ does; None if it does not add up exactly.

    A record whose format code is not a data format (a feed-through record ``0xE1``: code
    14, one word, which a chassis sends while a wand button is held; an error record) is
    kept for the caller to step over: it used to make the whole packet junk, so tracking
    vanished while the button was held. Records may come in any address order (the C++
    does not require one either)."""
    records: list[Record] = []
    offset = 0
    while offset < len(payload):
        if offset + 2 > len(payload):
            return None
        address, info = payload[offset] & 0x7F, payload[offset + 1]
        has_buttons = bool(payload[offset] & 0x80)
        code, count = info >> 4, info & 0x0F
        if not record_header_plausible(address, info):
            return None
        end = offset + 2 + 2 * count
        buttons = None
        if has_buttons:
            if end + 2 > len(payload):
                return None
            # The buttons follow this record's own words (the C++ used a fixed offset).
            buttons = (payload[end], payload[end + 1])
            end += 2
        if end > len(payload):
            return None
        words = struct.unpack_from(f">{count}h", payload, offset + 2)
        records.append(Record(address, code, words, buttons))
        offset = end
    return records


def rotation_zyx(z_deg: float, y_deg: float, x_deg: float) -> np.ndarray:
    """``Rz @ Ry @ Rx`` for angles in degrees (the Z, Y, X order of the wire)."""
    z, y, x = np.radians([z_deg, y_deg, x_deg])
    cz, sz, cy, sy, cx, sx = np.cos(z), np.sin(z), np.cos(y), np.sin(y), np.cos(x), np.sin(x)
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return rz @ ry @ rx


def rotation_from_matrix_words(words: tuple[int, ...]) -> np.ndarray:
    """Rotation from the 9 matrix words.

    The words are the Ascension matrix M in column order (M11, M21, M31, M12,
    ...), whose rows are the sensor axes in transmitter coordinates, so the
    sensor orientation M transposed is the words read row by row.
    """
    return np.array(words, dtype=np.float64).reshape(3, 3) / FRACTION_DIVISOR


def rotation_from_quaternion(w: float, x: float, y: float, z: float) -> np.ndarray:
    """Rotation of the normalised quaternion (w, x, y, z); identity if it is zero."""
    norm = float(np.sqrt(w * w + x * x + y * y + z * z))
    if norm == 0.0:
        return np.eye(3)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def decode_record(record: Record, unit: int, full_scale: float) -> BirdSample:
    """Turn a record into a sample with a 4x4 matrix (translation in inches)."""
    code = DataFormat(record.format_code)
    words = record.words
    matrix = np.eye(4)
    position = angles = quaternion = None
    rest = words
    if code in (
        DataFormat.POSITION,
        DataFormat.POSITION_ANGLES,
        DataFormat.POSITION_MATRIX,
        DataFormat.POSITION_QUATERNION,
    ):
        position = tuple(full_scale * w / WORD_DIVISOR for w in words[:3])
        matrix[:3, 3] = position
        rest = words[3:]
    if code in (DataFormat.ANGLES, DataFormat.POSITION_ANGLES):
        angles = tuple(ANGLE_SCALE * w / WORD_DIVISOR for w in rest[:3])
        matrix[:3, :3] = rotation_zyx(*angles)
    elif code in (DataFormat.MATRIX, DataFormat.POSITION_MATRIX):
        matrix[:3, :3] = rotation_from_matrix_words(rest[:9])
    elif code in (DataFormat.QUATERNION, DataFormat.POSITION_QUATERNION):
        # q0 is the scalar part; used as sent (no conjugation, unlike the Flock driver).
        quaternion = tuple(w / FRACTION_DIVISOR for w in rest[:4])
        matrix[:3, :3] = rotation_from_quaternion(*quaternion)
    return BirdSample(
        unit=unit,
        address=record.address,
        data_format=int(code),
        matrix=matrix,
        position=position,  # type: ignore[arg-type]
        angles=angles,  # type: ignore[arg-type]
        quaternion=quaternion,  # type: ignore[arg-type]
        buttons=record.buttons,
    )


DATA_ONLY = frozenset({DATA_PACKET_MULTI})
PROTOCOL_OFFSET = 10  # of the protocol byte in a header
TYPE_OFFSET = 8
LENGTH_OFFSET = 14
MAX_RECORD = 2 + 2 * 15 + 2  # address, info, at most 15 words, buttons


def record_start_plausible(address: int, info: int) -> bool:
    """Whether two bytes can start a data record (see :func:`record_header_plausible`)."""
    return record_header_plausible(address, info)


Message = tuple[Header, bytes, "list[Record] | None"]


class Framer:
    """Cuts server messages out of a byte stream, skipping junk a whole run at a time.

    Bytes go in with :meth:`feed`; :meth:`next` returns the next well-formed
    message of an accepted type, or None until more bytes are needed. A run of
    bytes between two good messages counts once in ``bad_packets`` and byte by
    byte in ``skipped_bytes``. ``max_data`` bounds a data packet's length (the
    driver sets it from the number of FBB devices).
    """

    def __init__(self) -> None:
        self.buffer = bytearray()
        self.bad_packets = 0
        self.skipped_bytes = 0
        self.max_data = MAX_PAYLOAD
        self._in_junk = False

    def feed(self, data: bytes) -> None:
        self.buffer += data

    def clear(self) -> None:
        self.buffer.clear()
        self._in_junk = False

    def next(self, accept: frozenset[int], expected: int | None = None) -> Message | None:
        """The next message whose type is in ``accept``; None when more bytes are needed.

        ``expected`` is the sequence number the next message should carry: a data packet
        with another number that has a data packet with this number starting inside it is
        taken for a packet cut short by the next one, and skipped.
        """
        buf = self.buffer
        while True:
            start = self._candidate(0, accept)
            if start:
                self._skip(start)
            if len(buf) < HEADER.size:
                return None
            header = Header.unpack(bytes(buf[: HEADER.size]))
            size = HEADER.size + header.length
            if len(buf) < size:
                return None  # wait for the rest of the packet
            payload = bytes(buf[HEADER.size : size])
            records = None
            if header.type == DATA_PACKET_MULTI:
                records = parse_records(payload)
                if records is None:
                    self._skip(1)  # a false header: look for the next one after it
                    continue
                if expected is not None and header.sequence != expected:
                    inner = self._data_with_sequence(size, expected)
                    if inner is not None:
                        self._skip(inner)
                        continue
            del buf[:size]
            self._in_junk = False
            return header, payload, records

    # -- internals --------------------------------------------------------------------

    def _plausible_at(self, i: int, accept: frozenset[int]) -> bool:
        """Whether a header starting at ``i`` (entirely in the buffer) may be real."""
        buf = self.buffer
        kind = buf[i + TYPE_OFFSET]
        if kind not in accept or buf[i + PROTOCOL_OFFSET] != BN_PROTOCOL:
            return False
        length = buf[i + LENGTH_OFFSET] << 8 | buf[i + LENGTH_OFFSET + 1]
        if kind != DATA_PACKET_MULTI:
            return length <= MAX_PAYLOAD
        if length > self.max_data or length == 1:
            return False
        first = i + HEADER.size
        return (
            length == 0
            or len(buf) < first + 2
            or record_start_plausible(buf[first], buf[first + 1])
        )

    def _candidate(self, begin: int, accept: frozenset[int], end: int | None = None) -> int:
        """The first plausible header start at or after ``begin`` (before ``end``); if
        there is none, the first position whose header is not entirely buffered yet."""
        buf = self.buffer
        last = len(buf) - HEADER.size  # the last start whose header is complete
        if end is not None:
            last = min(last, end - 1)
        pos = begin
        while pos <= last:
            found = buf.find(BN_PROTOCOL, pos + PROTOCOL_OFFSET, last + PROTOCOL_OFFSET + 1)
            if found < 0:
                break
            i = found - PROTOCOL_OFFSET
            if self._plausible_at(i, accept):
                return i
            pos = i + 1
        return max(begin, last + 1)

    def _data_with_sequence(self, size: int, expected: int) -> int | None:
        """Start of a plausible data header numbered ``expected`` inside the first ``size`` bytes."""
        buf = self.buffer
        pos = 1
        while True:
            i = self._candidate(pos, DATA_ONLY, end=size)
            if i >= size or i + HEADER.size > len(buf):
                return None
            if buf[i] << 8 | buf[i + 1] == expected:
                return i
            pos = i + 1

    def _skip(self, count: int) -> None:
        if not self._in_junk:
            self.bad_packets += 1
            self._in_junk = True
        self.skipped_bytes += count
        del self.buffer[:count]


class _Stream:
    """Reads from a TCP socket into a :class:`Framer`, against deadlines."""

    def __init__(self, sock: socket.socket, framer: Framer) -> None:
        self.sock = sock
        self.framer = framer

    def receive(self, deadline: float) -> bool:
        """One read of whatever is there; False at the deadline."""
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return False
        self.sock.settimeout(remaining)
        try:
            chunk = self.sock.recv(65536)
        except TimeoutError:
            return False
        except OSError as exc:
            raise MotionStarDisconnected(f"connection lost: {exc}") from exc
        if not chunk:
            raise MotionStarDisconnected("the server closed the connection")
        self.framer.feed(chunk)
        return True

    def send(self, data: bytes, timeout: float) -> None:
        try:
            self.sock.settimeout(timeout)
            self.sock.sendall(data)
        except TimeoutError as exc:
            raise MotionStarTimeout("the server does not take our messages") from exc
        except OSError as exc:
            raise MotionStarDisconnected(f"connection lost: {exc}") from exc


class MotionStar:
    """Client of one MotionStar chassis.

    Give ``host``/``port`` or an already-connected TCP ``sock`` (used, never
    closed). ``hemisphere``, ``data_format``, ``mode``, ``report_rate`` and
    ``measurement_rate`` take the numeric values of the motion_star definition.
    Timeouts: ``connect_timeout``, ``read_timeout`` (per command reply),
    ``sample_timeout`` (for :meth:`sample`), ``close_timeout`` (stop/shut-down).
    """

    def __init__(
        self,
        host: str = "",
        port: int = 6000,
        *,
        sock: socket.socket | None = None,
        hemisphere: int = Hemisphere.FRONT,
        data_format: int = DataFormat.POSITION_ANGLES,
        mode: int = RunMode.RUN_CONTINUOUS,
        report_rate: int = 1,
        measurement_rate: float = 0.0,
        connect_timeout: float = 5.0,
        read_timeout: float = 5.0,
        sample_timeout: float = 1.0,
        close_timeout: float = 1.0,
    ) -> None:
        if sock is None and not host:
            raise ValueError("give a host or a connected socket")
        self.host = host
        self.port = port
        self.hemisphere = int(Hemisphere(hemisphere))
        self.data_format = int(DataFormat(data_format))
        self.mode = int(RunMode(mode))
        if not 0 <= report_rate <= 255:
            raise ValueError("report_rate is one byte (0..255)")
        self.report_rate = report_rate
        self.measurement_rate = measurement_rate
        self.connect_timeout = connect_timeout
        self.read_timeout = read_timeout
        self.sample_timeout = sample_timeout
        self.close_timeout = close_timeout
        self.sequence = 0
        self.system_status: SystemStatus | None = None
        self.birds: dict[int, BirdStatus] = {}
        self.sensors: tuple[int, ...] = ()
        self.full_scale: int | None = None
        self.units = ""
        self.warnings: list[str] = []
        self.packets = 0
        self.framer = Framer()
        self.sequence_resyncs = 0
        self.unknown_records = 0
        self.sensor_errors = 0
        #: records stepped over that carry no pose (feed-through data, format code 14, ...)
        self.other_records = 0
        self.last_error_code = 0
        self._given_sock = sock
        self._stream: _Stream | None = None
        self._running = False
        self._units_of: dict[int, int] = {}

    # -- life cycle -------------------------------------------------------------------

    def open(self) -> None:
        """Connect, wake the server, read status, configure the birds, start data."""
        if self._stream is not None:
            return
        sock = self._given_sock
        if sock is None:
            try:
                sock = socket.create_connection(
                    (self.host, self.port), timeout=self.connect_timeout
                )
            except OSError as exc:
                raise MotionStarDisconnected(
                    f"cannot connect to {self.host}:{self.port}: {exc}"
                ) from exc
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.framer.clear()
        self.framer.max_data = MAX_PAYLOAD
        self._stream = _Stream(sock, self.framer)
        self.sequence = 0
        self.full_scale = None
        self.units = ""
        try:
            self._wake_up()
            status = SystemStatus.parse(self._transact(MSG_GET_STATUS, RSP_GET_STATUS)[1])
            if self.measurement_rate > 0:
                self._send_rate(status)
                status = SystemStatus.parse(self._transact(MSG_GET_STATUS, RSP_GET_STATUS)[1])
            self.system_status = status
            self._configure_birds(status)
            if self.full_scale is None:
                raise MotionStarError("no bird reported a position scale")
            if self.mode == RunMode.RUN_CONTINUOUS:
                self._transact(MSG_RUN_CONTINUOUS, RSP_RUN_CONTINUOUS)
                self._running = True
        except BaseException:
            self._drop_connection()
            raise

    def close(self) -> None:
        """Stop the data, shut the server down, and close our own socket."""
        if self._stream is None:
            return
        try:
            if self._running:
                self._transact(MSG_STOP_DATA, RSP_STOP_DATA, timeout=self.close_timeout)
            self._transact(MSG_SHUT_DOWN, RSP_SHUT_DOWN, timeout=self.close_timeout)
        except MotionStarError:
            pass  # the server may be gone already
        finally:
            self._drop_connection()

    @property
    def is_open(self) -> bool:
        return self._stream is not None

    @property
    def bad_packets(self) -> int:
        """Runs of bytes between two good messages that were not a message we wait for."""
        return self.framer.bad_packets

    @property
    def skipped_bytes(self) -> int:
        return self.framer.skipped_bytes

    def __enter__(self) -> MotionStar:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # -- data ---------------------------------------------------------------------------

    def sample(self) -> MotionStarSample | None:
        """Read one data packet (asking for it in single-shot mode).

        Returns None if none completes within ``sample_timeout``. Garbage and
        truncated packets are counted in ``bad_packets`` (bytes in
        ``skipped_bytes``) and skipped. Raises :class:`MotionStarDisconnected`
        when the connection is lost.
        """
        if self._stream is None:
            raise MotionStarError("the MotionStar is not open")
        if self.mode == RunMode.SAMPLE_INDIVIDUALLY:
            self._send(MSG_SINGLE_SHOT)
        deadline = time.monotonic() + self.sample_timeout
        packet = self._read_packet(deadline, DATA_ONLY)
        if packet is None:
            return None
        header, _payload, records = packet
        return self._decode(header, records or [])

    # -- internals ------------------------------------------------------------------------

    def _drop_connection(self) -> None:
        stream, self._stream = self._stream, None
        self._running = False
        self.sequence = 0  # a new connection starts from 0, as the C++ does
        if stream is not None and self._given_sock is None:
            try:
                stream.sock.close()
            except OSError:
                pass

    def _send(self, kind: int, xtype: int = 0, payload: bytes = b"") -> None:
        assert self._stream is not None
        header = Header(self.sequence, kind, xtype, len(payload))
        self._stream.send(header.pack() + payload, self.read_timeout)

    def _transact(
        self,
        kind: int,
        reply: int,
        xtype: int = 0,
        payload: bytes = b"",
        timeout: float | None = None,
    ) -> tuple[Header, bytes]:
        """Send a command and wait for its reply, passing over data packets."""
        self._send(kind, xtype, payload)
        deadline = time.monotonic() + (self.read_timeout if timeout is None else timeout)
        accept = frozenset({reply, RSP_ILLEGAL, RSP_UNKNOWN, DATA_PACKET_MULTI})
        while True:
            packet = self._read_packet(deadline, accept)
            if packet is None:
                raise MotionStarTimeout(f"no reply to message {kind} (xtype {xtype})")
            header, body, _records = packet
            if header.type == reply:
                if header.error_code:
                    raise MotionStarCommandError(
                        f"message {kind} (xtype {xtype}): server error {header.error_code}"
                    )
                return header, body
            if header.type in (RSP_ILLEGAL, RSP_UNKNOWN):
                raise MotionStarCommandError(f"message {kind} refused with type {header.type}")

    def _read_packet(self, deadline: float, accept: frozenset[int]) -> Message | None:
        """Next well-formed server message of an accepted type, re-synchronising over junk;
        None at the deadline (a partial packet is kept for the next call)."""
        stream = self._stream
        assert stream is not None
        while True:
            message = self.framer.next(accept, self.sequence)
            if message is not None:
                self._track_sequence(message[0])
                return message
            if not stream.receive(deadline):
                return None

    def _track_sequence(self, header: Header) -> None:
        """Adopt the server's sequence number if it differs, then count on."""
        if header.sequence != self.sequence:
            self.sequence_resyncs += 1
            self.sequence = header.sequence
        self.sequence = (self.sequence + 1) % SEQUENCE_MODULO

    def _wake_up(self) -> None:
        try:
            self._transact(MSG_WAKE_UP, RSP_WAKE_UP)
        except MotionStarCommandError:
            # The manual's recovery: shut the server down and wake it again.
            self._transact(MSG_SHUT_DOWN, RSP_SHUT_DOWN)
            self._transact(MSG_WAKE_UP, RSP_WAKE_UP)

    def _send_rate(self, status: SystemStatus) -> None:
        try:
            self._transact(
                MSG_SEND_SETUP, RSP_SEND_SETUP, 0, status.with_rate(self.measurement_rate)
            )
        except MotionStarCommandError as exc:
            self.warnings.append(f"measurement rate not set: {exc}")

    def _configure_birds(self, status: SystemStatus) -> None:
        """Read each non-ERC bird's status, write back our setup for sensors."""
        self.birds.clear()
        sensors: list[int] = []
        for index, flags in enumerate(status.devices):
            address = index + 1
            if flags & FBB_ERC:
                continue
            _header, body = self._transact(MSG_GET_STATUS, RSP_GET_STATUS, address)
            if len(body) < BIRD_STATUS_SIZE:
                raise MotionStarCommandError(f"bird {address}: status of {len(body)} bytes")
            bird = BirdStatus(address, bytes(body[:BIRD_STATUS_SIZE]))
            if self.full_scale is None:
                self.full_scale = bird.full_scale
                self.units = UNITS.get(bird.units, f"unknown units {bird.units}")
                if bird.units not in UNITS:
                    self.warnings.append(f"bird {address} reports units code {bird.units}")
            block = bird.raw
            if flags & FBB_SENSOR:
                block = bird.configured(self.data_format, self.report_rate, self.hemisphere)
                sensors.append(bird.fbb_address)
            self._transact(MSG_SEND_SETUP, RSP_SEND_SETUP, address, block)
            self.birds[address] = BirdStatus(address, block)
        self.sensors = tuple(sensors)
        # one record per FBB device at most, each at most MAX_RECORD bytes
        self.framer.max_data = min(MAX_PAYLOAD, MAX_RECORD * max(1, len(status.devices)))
        self._units_of = {address: unit for unit, address in enumerate(self.sensors)}

    def _decode(self, header: Header, records: list[Record]) -> MotionStarSample:
        self.packets += 1
        if header.error_code:
            self.last_error_code = header.error_code
        birds = []
        for record in records:
            unit = self._units_of.get(record.address)
            if unit is None:
                self.unknown_records += 1
                continue
            if record.format_code == ERROR_FORMAT:
                self.sensor_errors += 1
                continue
            if not carries_pose(record.format_code):
                self.other_records += 1  # feed-through data and the like: no pose in it
                continue
            birds.append(decode_record(record, unit, float(self.full_scale or 0)))
        return MotionStarSample(
            sequence=header.sequence,
            milliseconds=header.milliseconds,
            time=header.time,
            error_code=header.error_code,
            birds=tuple(birds),
        )
