"""Polhemus Fastrak serial protocol, independent of gadgetctl's input manager.

ASCII commands, binary records. The start, in this order (the port is opened first):

* ``c`` continuous output off, ``f`` binary output, ``u`` centimetres;
* per station 1..4: ``O<st>,2,11,16,1\\r`` output list: position, quaternion, stylus switch,
  CR LF; ``H<st>,x,y,z\\r`` the hemisphere vector; then ``e1,0\\r``: station 1's stylus
  switch reported in the records (not as a trigger);
* ``l1\\r`` answers ``2`` ``1`` ``l`` + four ``'0'``/``'1'`` (stations 1..4 active) CR LF;
* ``S`` answers the 55-byte status record: ``2``, station, ``S``, 3 hex flag digits (bit 0
  binary, bit 1 centimetres), 3 error bytes, 6 blanks, 6-char version, 32-char id, CR LF;
* ``C`` continuous output on: the tracker streams one record per active station per cycle.

A record is ``'0'``, station ``'1'..'4'``, a status char, 3 x float32 little-endian
position, 4 x float32 quaternion W, X, Y, Z, the stylus item (a pad byte, then ``'0'`` or
``'1'``), CR LF: :data:`RECORD_SIZE` bytes. Positions are inches or centimetres as the
status record says; this module gives metres.

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

STATIONS = 4
OUTPUT_LIST = "2,11,16,1"
CRLF = b"\r\n"
#: '0', station, status; position 12; quaternion 16; stylus 2; CR LF.
RECORD_SIZE = 3 + 12 + 16 + 2 + 2
_BODY = struct.Struct("<7fxB")
STATUS_SIZE = 55
INCH, CENTIMETRE = 0.0254, 0.01
#: |coordinate| beyond this (inches or centimetres) is no Fastrak measurement (its range is
#: a few metres), but junk that happened to parse.
MAX_COORDINATE = 1e4
#: A quaternion farther than this from unit length is no orientation.
QUATERNION_SLACK = 0.05
#: The ``hemisphere`` enumeration of the fastrak definition: its H command vectors.
HEMISPHERES = {
    0: (1, 0, 0),  # forward
    1: (-1, 0, 0),  # back
    2: (0, 1, 0),  # right
    3: (0, -1, 0),  # left
    4: (0, 0, 1),  # lower
    5: (0, 0, -1),  # upper
    6: (0, 0, 0),  # automatic
}
MAX_LINE = 128
MAX_REPLY_SCAN = 8192


class FastrakError(Exception):
    """Base class of the driver's errors."""


class FastrakTimeout(FastrakError, TimeoutError):
    """The tracker did not answer in time."""


class FastrakProtocolError(FastrakError):
    """The tracker answered, but not as the protocol says."""


class FastrakDisconnected(FastrakError):
    """The serial line is gone (EOF, hang-up, unplugged adapter) or silent; reopen to recover."""


def quaternion_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The 3x3 rotation of a quaternion (normalised first; q and -q are the same rotation)."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        (
            (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
            (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
            (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
        )
    )


@dataclass(frozen=True)
class FastrakRecord:
    """One station's record: station 1..4, position in metres, quaternion (w, x, y, z) and
    the stylus switch (0/1)."""

    station: int
    position: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]
    stylus: int

    def matrix(self) -> np.ndarray:
        m = np.eye(4)
        m[:3, :3] = quaternion_matrix(*self.quaternion)
        m[:3, 3] = self.position
        return m


def decode_record(record: bytes, scale: float) -> FastrakRecord | None:
    """Decode one :data:`RECORD_SIZE`-byte record; None if it is none (framing, a station
    beyond 4, a stylus byte other than '0'/'1', numbers no tracker sends)."""
    if len(record) != RECORD_SIZE or record[0] != ord("0") or record[-2:] != CRLF:
        return None
    station = record[1] - ord("0")
    if not 1 <= station <= STATIONS:
        return None
    *values, stylus = _BODY.unpack_from(record, 3)
    if stylus not in (ord("0"), ord("1")):
        return None
    if not all(math.isfinite(v) for v in values):
        return None
    x, y, z, qw, qx, qy, qz = values
    if max(abs(x), abs(y), abs(z)) > MAX_COORDINATE:
        return None
    if abs(math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz) - 1.0) > QUATERNION_SLACK:
        return None
    return FastrakRecord(
        station, (x * scale, y * scale, z * scale), (qw, qx, qy, qz), stylus - ord("0")
    )


@dataclass
class RecordScanner(ResyncScanner[FastrakRecord]):
    """Finds records in the stream; junk is skipped a whole run at a time (one ``find`` to the
    next candidate), counted once per run in ``bad_records`` and per byte in ``skipped_bytes``."""

    HEAD = b"0"
    SIZE = RECORD_SIZE

    scale: float = INCH

    def decode(self, record: bytes) -> FastrakRecord | None:
        return decode_record(record, self.scale)


class Fastrak(LineDriver, ScannedDevice):
    """A Polhemus Fastrak on a serial line, streaming.

    ``port`` is a device path, a pyserial URL or an open ``serial.Serial``-like object (used,
    never closed). ``hemisphere`` is the definition's enumeration value (3, left, by default).
    ``read_timeout`` bounds a reply during the start, ``silence_timeout`` the time without a
    record after which the tracker counts as gone."""

    LOST = FastrakDisconnected
    CLOSED = FastrakError
    CLOSED_TEXT = "the tracker is not open"
    FAREWELL = b"c"  # stop the stream for whoever opens the port next

    def __init__(
        self,
        port: str | serial.SerialBase,
        baud: int = 115200,
        hemisphere: int = 3,
        *,
        read_timeout: float = 2.0,
        silence_timeout: float = 2.0,
        poll_interval: float = 0.02,
    ) -> None:
        if hemisphere not in HEMISPHERES:
            raise ValueError(f"hemisphere {hemisphere} is not one of 0..6")
        self.port_spec = port
        self.baud = baud
        self.hemisphere = hemisphere
        self.read_timeout = read_timeout
        self.silence_timeout = silence_timeout
        self.poll_interval = poll_interval
        self.active: tuple[int, ...] = ()
        self.units = "inches"
        self.version = ""
        self.scanner = RecordScanner()
        self._line: SerialLine | None = None
        self._heard_at = 0.0

    # -- life cycle -------------------------------------------------------------------

    def open(self) -> None:
        """Open the port, then set the tracker up and start its stream.

        The C++ driver sent its set-up in config(), before startSampling() opened the port
        (and ``u`` before that), so none of it reached the tracker; here the port is opened
        first and nothing is flushed right after a command, so no reply is lost."""
        self._open_line(self.port_spec, LineSettings(self.baud), self._setup)

    # -- data ---------------------------------------------------------------------------

    def read(self) -> list[FastrakRecord]:
        """The records that arrived (waiting up to ``poll_interval``); raises
        :class:`FastrakDisconnected` on a lost line or ``silence_timeout`` without records."""
        records = self.scanner.feed(self._read_some())
        now = time.monotonic()
        if records:
            self._heard_at = now
        elif now - self._heard_at > self.silence_timeout:
            raise FastrakDisconnected(f"no data from the Fastrak for {self.silence_timeout:g} s")
        return records

    # -- internals ------------------------------------------------------------------------

    def _setup(self) -> None:
        self._write(b"c")
        self._flush_input()  # before commands only: a stream may have been running
        self._write(b"f")
        self._write(b"u")
        vector = ",".join(str(v) for v in HEMISPHERES[self.hemisphere])
        for st in range(1, STATIONS + 1):
            self._write(f"O{st},{OUTPUT_LIST}\r".encode("ascii"))
            self._write(f"H{st},{vector}\r".encode("ascii"))
        self._write(b"e1,0\r")
        self._write(b"l1\r")
        line = self._reply(b"21l")
        flags = line[3:7]
        if len(flags) != 4 or not set(flags) <= {ord("0"), ord("1")}:
            raise FastrakProtocolError(f"station status without four 0/1 flags: {line!r}")
        self.active = tuple(i + 1 for i, f in enumerate(flags) if f == ord("1"))
        self._write(b"S")
        status = self._reply(b"2", size=STATUS_SIZE - 2)
        try:
            bits = int(status[3:6].decode("ascii"), 16)
        except ValueError:
            raise FastrakProtocolError(f"status record without flags: {status[:20]!r}") from None
        if not bits & 1:
            raise FastrakProtocolError("the tracker stays in ASCII output after 'f'")
        self.units = "centimetres" if bits & 2 else "inches"
        self.scanner.scale = CENTIMETRE if bits & 2 else INCH
        self.version = status[15:21].decode("ascii", "replace").strip()
        self._write(b"C")
        self._heard_at = time.monotonic()

    def _reply(self, prefix: bytes, size: int | None = None) -> bytes:
        """The first line starting with ``prefix`` (without CR LF); with ``size``, exactly that
        many bytes before the CR LF (the status record's text may hold any byte)."""
        deadline = time.monotonic() + self.read_timeout
        line = bytearray()
        scanned = 0
        while True:
            chunk = self._read_some()
            if not chunk and time.monotonic() >= deadline:
                raise FastrakTimeout("no reply from the Fastrak")
            for value in chunk:
                scanned += 1
                if scanned > MAX_REPLY_SCAN:
                    raise FastrakProtocolError(f"no reply among {MAX_REPLY_SCAN} bytes")
                if len(line) < len(prefix) and value != prefix[len(line)]:
                    line.clear()
                    if value != prefix[0]:
                        continue
                line.append(value)
                done = len(line) == size + 2 if size is not None else line.endswith(CRLF)
                if done:
                    if not line.endswith(CRLF):
                        raise FastrakProtocolError(
                            f"a reply not ended by CR LF: {bytes(line[:20])!r}"
                        )
                    return bytes(line[:-2])
                if len(line) > MAX_LINE:
                    raise FastrakProtocolError(f"a reply longer than {MAX_LINE} bytes")
