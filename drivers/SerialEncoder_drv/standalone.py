"""US Digital serial encoders on the SEI bus, independent of gadgetctl's input manager (it uses
only :mod:`gadgetctl.transport.serialline`).

The bus runs at 9600 baud, 8N1. Reading the position of the encoder at address ``a``
(0..15) is one command byte, ``0x10 | a``; the encoder answers five bytes: the command byte
again, then the position as a big-endian IEEE float. A table set-up has two encoders: the
tilt at address 1 (degrees, a rotation about X) and the height at address 2 (inches, a
translation along +Y); the sample is the matrix T(height) . R(tilt), in meters.

Decoding is bounded: bytes before the echo of the command are skipped (one bad record per
run), a position that is not finite or beyond :data:`MAX_POSITION` is a bad record, and an
encoder that does not answer within ``reply_timeout`` is counted in ``timeouts``; none of
them is a fault. Only a lost line is.
"""

from __future__ import annotations

import math
import struct
import time
from dataclasses import dataclass

import numpy as np

from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

BAUD = 9600
READ_POSITION = 0x10
ADDRESSES = range(16)
REPLY_SIZE = 5
TILT_ADDRESS, HEIGHT_ADDRESS = 1, 2
INCHES_PER_METER = 39.37
#: Larger than any reading an encoder of the bus gives (counts, degrees or inches); a larger
#: or non-finite number is a corrupt reply.
MAX_POSITION = 1.0e7
_FLOAT = struct.Struct(">f")


class SerialEncoderError(Exception):
    """Base class of the driver's errors."""


class SerialEncoderDisconnected(SerialEncoderError, SerialLineLost):
    """The serial line is gone; reopen to recover."""


def command(address: int) -> int:
    if address not in ADDRESSES:
        raise SerialEncoderError(f"SEI address {address} is not 0..15")
    return READ_POSITION | address


def decode_reply(address: int, reply: bytes) -> float | None:
    """The position in a 5-byte reply to a read of ``address``; None when it is not one."""
    if len(reply) != REPLY_SIZE or reply[0] != command(address):
        return None
    (value,) = _FLOAT.unpack_from(reply, 1)
    if not math.isfinite(value) or abs(value) > MAX_POSITION:
        return None
    return value


def table_matrix(tilt_degrees: float, height_inches: float) -> np.ndarray:
    """T(0, height in meters, 0) . R_x(tilt)."""
    angle = math.radians(tilt_degrees)
    c, s = math.cos(angle), math.sin(angle)
    return np.array(
        [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, c, -s, height_inches / INCHES_PER_METER],
            [0.0, s, c, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


@dataclass
class BusCounters:
    """``records`` positions read, ``bad_records`` corrupt replies and runs of junk,
    ``skipped_bytes`` the bytes of those runs, ``timeouts`` encoders that did not answer."""

    records: int = 0
    bad_records: int = 0
    skipped_bytes: int = 0
    timeouts: int = 0

    def junk(self, count: int) -> None:
        if count > 0:
            self.bad_records += 1
            self.skipped_bytes += count


class SerialEncoderBus:
    """Encoders on an SEI bus over a serial line."""

    def __init__(
        self,
        port: object,
        baud: int = BAUD,
        *,
        reply_timeout: float = 1.0,
        poll_interval: float = 0.005,
    ) -> None:
        self.line = SerialLine(port, LineSettings(baud=baud), poll_interval=poll_interval)  # type: ignore[arg-type]
        self.counters = BusCounters()
        self.reply_timeout = reply_timeout

    def open(self) -> None:
        try:
            self.line.open()
        except SerialLineLost as exc:
            raise SerialEncoderDisconnected(str(exc)) from exc

    def close(self) -> None:
        self.line.close()

    def __enter__(self) -> SerialEncoderBus:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def position(self, address: int) -> float | None:
        """Read one encoder; None when its reply is corrupt or does not come in time."""
        cmd = command(address)
        counts = self.counters
        try:
            counts.junk(len(self.line.read(0.0)))  # unasked bytes are junk (the C++ flushed them)
            self.line.write(bytes([cmd]))
            data = b""
            skipped = 0
            deadline = time.monotonic() + self.reply_timeout
            while True:
                echo = data.find(cmd)
                if echo < 0:
                    skipped += len(data)  # no echo yet: all junk, nothing kept
                    data = b""
                elif len(data) - echo >= REPLY_SIZE:
                    break
                remaining = deadline - time.monotonic()
                chunk = self.line.read(remaining) if remaining > 0 else b""
                if not chunk:
                    counts.timeouts += 1
                    counts.junk(skipped + len(data))
                    return None
                data += chunk
        except SerialLineLost as exc:
            raise SerialEncoderDisconnected(str(exc)) from exc
        # one run of junk: what came before the echo and whatever followed the reply
        counts.junk(skipped + echo + len(data) - echo - REPLY_SIZE)
        value = decode_reply(address, data[echo : echo + REPLY_SIZE])
        if value is None:
            counts.bad_records += 1
        else:
            counts.records += 1
        return value

    def table(self) -> tuple[float | None, float | None]:
        """(tilt in degrees, height in inches) from encoders 1 and 2."""
        return self.position(TILT_ADDRESS), self.position(HEIGHT_ADDRESS)
