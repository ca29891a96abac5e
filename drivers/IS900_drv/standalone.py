"""InterSense IS-900 serial protocol, independent of gadgetctl's input manager.

The tracker speaks the Fastrak-style command set of InterSense's ISD library. This driver
uses the part Gadgeteer needs:

* ``c`` stops continuous output (polled mode); ``MS\\r\\n`` answers a ``3`` record
  (``31S``, product id hex digit at offset 3, then text); ``f`` selects binary output;
  ``S`` answers a ``2`` record whose flags (3 hex digits at offsets 3..5) say binary
  (bit 0) and centimetres (bit 1, else inches), followed by the firmware text;
* ``l<st>,1\\r\\n`` switches a station on; ``O<st>,2,4,40,22,23,1\\r\\n`` sets its output
  list: position, Euler angles, tracking status, buttons, analog, CR LF;
* ``P`` polls: one data record per station that is on. A binary record is
  ``'0'``, station char, status char, 3 x float32 little-endian position, 3 x float32
  azimuth, elevation, roll (degrees), tracking status byte, button byte, 2 analog bytes
  (0..255), CR LF: :data:`RECORD_SIZE` bytes.

Stations are numbered from 1 on the wire (``'1'..'9'`` then ``'a'..``); gadgetctl's
``station_index`` counts from 0, as the ISD library's station arrays do.

Only the standard library, pyserial, numpy and the shared serial line
(:mod:`gadgetctl.transport.serialline`, which knows nothing of the input manager) are used.
"""

from __future__ import annotations

import math
import struct
import time
from dataclasses import dataclass

import numpy as np
import serial

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineDriver, LineSettings, SerialLine

RECORD_HEAD = ord("0")
CRLF = b"\r\n"
OUTPUT_LIST = "2,4,40,22,23,1"
#: '0', station, status; position 12; Euler 12; tracking 1; buttons 1; analog 2; CR LF.
RECORD_SIZE = 3 + 12 + 12 + 1 + 1 + 2 + 2
_BODY = struct.Struct("<6fBBBB")
#: Stations an IS-900 addresses at most (``'1'..'9'`` then ``'a'..'v'``).
MAX_STATIONS = 31
STATION_CHARS = "123456789abcdefghijklmnopqrstuv"
BUTTONS_PER_STATION = 8
ANALOG_PER_STATION = 2
#: |coordinate| above this (in the tracker's unit) is no measurement: an IS-900 room is tens
#: of metres at most, so 100,000 inches or centimetres is junk that happened to parse.
MAX_COORDINATE = 1e5
#: Euler angles are within +-360 degrees.
MAX_ANGLE = 360.0
INCH, CENTIMETRE = 0.0254, 0.01
#: Bytes of a reply line at most (the ``S`` record is 55 bytes).
MAX_LINE = 256
#: Bytes read while waiting for a reply line at most (data records may come first).
MAX_REPLY_SCAN = 8192
#: Bytes kept while looking for a record, at most (a junk run beyond is dropped at once).
MAX_BUFFER = 64 * 1024


class IS900Error(Exception):
    """Base class of the driver's errors."""


class IS900Timeout(IS900Error, TimeoutError):
    """The tracker did not answer in time."""


class IS900ProtocolError(IS900Error):
    """The tracker answered, but not as the protocol says."""


class IS900Disconnected(IS900Error):
    """The serial line is gone (EOF, hang-up, unplugged adapter); reopen to recover."""


def station_char(index: int) -> str:
    """The wire character of 0-based station ``index``."""
    if not 0 <= index < MAX_STATIONS:
        raise ValueError(f"station index {index} is outside 0..{MAX_STATIONS - 1}")
    return STATION_CHARS[index]


@dataclass(frozen=True)
class StationRecord:
    """One decoded data record: station (0-based), position in metres, Euler angles in
    degrees (azimuth about z, elevation about y, roll about x), buttons (bit k = button k),
    the two analog bytes (raw 0..255) and the tracking status byte."""

    station: int
    position: tuple[float, float, float]
    euler: tuple[float, float, float]
    buttons: int
    analog: tuple[int, int]
    tracking: int

    @property
    def digital(self) -> tuple[int, ...]:
        """Button ``k`` as 0/1 (not the raw bit value)."""
        return tuple(self.buttons >> k & 1 for k in range(BUTTONS_PER_STATION))

    def matrix(self) -> np.ndarray:
        """The 4x4 pose: rotation Rz(azimuth) Ry(elevation) Rx(roll), translation in metres."""
        return pose_matrix(self.position, self.euler)


def pose_matrix(
    position: tuple[float, float, float], euler: tuple[float, float, float]
) -> np.ndarray:
    """A 4x4 matrix from a translation and ZYX Euler angles in degrees (z first)."""
    az, el, roll = (math.radians(a) for a in euler)
    cz, sz, cy, sy, cx, sx = (
        math.cos(az),
        math.sin(az),
        math.cos(el),
        math.sin(el),
        math.cos(roll),
        math.sin(roll),
    )
    m = np.eye(4)
    m[:3, :3] = (
        (cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx),
        (sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx),
        (-sy, cy * sx, cy * cx),
    )
    m[:3, 3] = position
    return m


def decode_record(
    record: bytes, scale: float, stations: frozenset[int] | None = None
) -> StationRecord | None:
    """Decode one :data:`RECORD_SIZE`-byte binary record; None if it is no valid record (wrong
    framing, a station outside ``stations``, numbers no tracker sends)."""
    if len(record) != RECORD_SIZE or record[0] != RECORD_HEAD or record[-2:] != CRLF:
        return None
    station = STATION_CHARS.find(chr(record[1]))
    if station < 0 or (stations is not None and station not in stations):
        return None
    x, y, z, az, el, roll, tracking, buttons, a0, a1 = _BODY.unpack_from(record, 3)
    if not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE for v in (x, y, z)):
        return None
    if not all(math.isfinite(v) and abs(v) <= MAX_ANGLE for v in (az, el, roll)):
        return None
    return StationRecord(
        station, (x * scale, y * scale, z * scale), (az, el, roll), buttons, (a0, a1), tracking
    )


@dataclass
class RecordScanner(ResyncScanner[StationRecord]):
    """Finds records in a byte stream. Junk between records is skipped a whole run at a time
    (one ``bytes.find`` to the next candidate head), counted once per run in ``bad_records``
    and byte by byte in ``skipped_bytes``."""

    HEAD = b"0"
    SIZE = RECORD_SIZE
    MAX_BUFFER = MAX_BUFFER  # cannot be reached with a record this short; a guard all the same

    scale: float = INCH
    stations: frozenset[int] | None = None

    def decode(self, record: bytes) -> StationRecord | None:
        return decode_record(record, self.scale, self.stations)


@dataclass(frozen=True)
class StationSetup:
    """A station to set up: 0-based index, and whether to switch it on."""

    index: int
    enabled: bool = True


class IS900(LineDriver, ScannedDevice):
    """An InterSense IS-900 on a serial line, polled.

    ``port`` is a device path, a pyserial URL or an open ``serial.Serial``-like object (used,
    never closed). ``stations`` are the stations to set up and read. Delays are settings:
    ``settle`` after ``c`` (0.1 s upstream), ``read_timeout`` for a reply line,
    ``poll_timeout`` before a poll is repeated when not every station answered (0.1 s
    upstream), ``silence_timeout`` of no data at all after which the tracker counts as gone.
    """

    LOST = IS900Disconnected
    CLOSED = IS900Error
    CLOSED_TEXT = "the tracker is not open"

    def __init__(
        self,
        port: str | serial.SerialBase,
        baud: int = 115200,
        stations: tuple[StationSetup, ...] = (StationSetup(0),),
        *,
        settle: float = 0.1,
        read_timeout: float = 2.0,
        poll_timeout: float = 0.1,
        silence_timeout: float = 2.0,
        poll_interval: float = 0.05,
    ) -> None:
        self.port_spec = port
        self.baud = baud
        self.stations = stations
        self.settle = settle
        self.read_timeout = read_timeout
        self.poll_timeout = poll_timeout
        self.silence_timeout = silence_timeout
        self.poll_interval = poll_interval
        self.product = ""
        self.firmware = ""
        self.units = "inches"
        self.polls = 0
        self.scanner = RecordScanner(stations=frozenset(s.index for s in stations))
        self._line: SerialLine | None = None
        self._answered: set[int] = set()
        self._polled_at = 0.0
        self._heard_at = 0.0

    # -- life cycle -------------------------------------------------------------------

    def open(self) -> None:
        """Open the port, stop continuous output, read the system records, set up stations."""
        # One call for every setting: a pty ignores later changes (and is always 8N1).
        self._open_line(self.port_spec, LineSettings(self.baud), self._handshake)

    # -- counters -----------------------------------------------------------------------

    # -- data ---------------------------------------------------------------------------

    def read(self) -> list[StationRecord]:
        """Poll when due and return the records that arrived (possibly none).

        A poll is sent once every station answered the previous one, or ``poll_timeout``
        after it. Raises :class:`IS900Disconnected` when the line is lost or silent for
        ``silence_timeout``."""
        now = time.monotonic()
        wanted = self.scanner.stations or frozenset()
        if self._answered >= wanted or now - self._polled_at >= self.poll_timeout:
            self._answered = set()
            self._polled_at = now
            self.polls += 1
            self._write(b"P")
        records = self.scanner.feed(self._read_some())
        if records:
            self._heard_at = time.monotonic()
            self._answered.update(r.station for r in records)
        elif time.monotonic() - self._heard_at > self.silence_timeout:
            raise IS900Disconnected(f"no data from the IS-900 for {self.silence_timeout:g} s")
        return records

    # -- internals ------------------------------------------------------------------------

    def _handshake(self) -> None:
        self._write(b"c")
        if self.settle > 0:
            time.sleep(self.settle)
        self._flush_input()
        self._write(b"MS\r\n")
        system = self._reply_line(ord("3"))
        if system[1:3] != b"1S" or len(system) < 4:
            raise IS900ProtocolError(f"not an InterSense system record: {system[:40]!r}")
        self.product = system[3:4].decode("ascii", "replace")
        self._write(b"f")
        status = self._reply_line(ord("2"))
        try:
            flags = int(status[3:6].decode("ascii"), 16)
        except ValueError:
            raise IS900ProtocolError(f"status record without flags: {status[:40]!r}") from None
        if not flags & 1:
            raise IS900ProtocolError("the tracker stays in ASCII output after 'f'")
        self.units = "centimetres" if flags & 2 else "inches"
        self.scanner.scale = CENTIMETRE if flags & 2 else INCH
        self.firmware = (
            status[12:].decode("ascii", "replace").strip()
        )  # after 3 error bytes, 6 blanks
        for setup in self.stations:
            st = station_char(setup.index)
            if setup.enabled:
                self._write(f"l{st},1\r\n".encode("ascii"))
            self._write(f"O{st},{OUTPUT_LIST}\r\n".encode("ascii"))
        self._heard_at = time.monotonic()
        self._polled_at = 0.0

    def _reply_line(self, kind: int) -> bytes:
        """Ask ``S`` when ``kind`` is '2' (the caller sent the rest); return the first line
        starting with ``kind``, without CR LF. Data records before it are skipped."""
        if kind == ord("2"):
            self._write(b"S")
        deadline = time.monotonic() + self.read_timeout
        line = bytearray()
        scanned = 0
        while True:
            chunk = self._read_some()
            if not chunk:
                if time.monotonic() >= deadline:
                    raise IS900Timeout("no reply from the IS-900")
                continue
            for value in chunk:
                scanned += 1
                if scanned > MAX_REPLY_SCAN:
                    raise IS900ProtocolError(f"no reply among {MAX_REPLY_SCAN} bytes")
                if not line and value != kind:
                    continue
                line.append(value)
                if line.endswith(CRLF):
                    return bytes(line[:-2])
                if len(line) > MAX_LINE:
                    raise IS900ProtocolError(f"a reply longer than {MAX_LINE} bytes")
