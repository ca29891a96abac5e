"""Logitech 3D mouse / head tracker serial protocol, independent of gadgetctl's input manager.

Two-byte ASCII commands: ``*D`` demand reporting, ``*R`` reset, ``*\\x05`` diagnostics (the
answer is the two bytes ``0xBF 0x3F``), ``*H`` head-tracker mode, ``*G`` Euler angles,
``*d`` one report. The line is 19200 bit/s, 8 data bits, 2 stop bits, no parity.

A report is 16 bytes. Byte 0 has bit 7 set (the only byte that has): 0x40 fringe, 0x20 out
of range, 0x08 suspended, 0x04 left, 0x02 middle, 0x01 right button. Bytes 1..9 are X, Y,
Z, each 21 bits two's complement, 7 bits per byte, high part first (the sign is bit 0x40 of
the first byte), in thousandths of an inch. Bytes 10..15 are the angles about x, y and z,
each 14 bits unsigned (7 + 7), in fortieths of a degree.

Only the standard library, pyserial, numpy and the shared serial line
(:mod:`gadgetctl.transport.serialline`, which knows nothing of the input manager) are used.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass

import numpy as np
import serial

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineDriver, LineSettings, SerialLine

REPORT_SIZE = 16
FLAG = 0x80
FRINGE, OUT_OF_RANGE, SUSPENDED = 0x40, 0x20, 0x08
BUTTON_BITS = (0x04, 0x02, 0x01)  # left, middle, right: digital units 0, 1, 2
DIAGNOSTIC_OK = b"\xbf\x3f"
INCH = 0.0254
#: Angles are fortieths of a degree of a turn: a value above 360 degrees is no angle.
MAX_ANGLE_RAW = 360 * 40
BAUD = 19200
_FLAG_BYTE = re.compile(rb"[\x80-\xff]")


class ThreeDMouseError(Exception):
    """Base class of the driver's errors."""


class ThreeDMouseTimeout(ThreeDMouseError, TimeoutError):
    """The mouse did not answer in time."""


class ThreeDMouseProtocolError(ThreeDMouseError):
    """The mouse answered, but not as the protocol says."""


class ThreeDMouseDisconnected(ThreeDMouseError):
    """The serial line is gone (EOF, hang-up, unplugged adapter) or silent; reopen to recover."""


def _coordinate(b: bytes) -> int:
    value = (b[0] & 0x7F) << 14 | (b[1] & 0x7F) << 7 | (b[2] & 0x7F)
    return value - (1 << 21) if b[0] & 0x40 else value


def rotation_xyz(rx: float, ry: float, rz: float) -> np.ndarray:
    """The 3x3 rotation Rx(rx) Ry(ry) Rz(rz), angles in degrees."""
    ax, ay, az = (math.radians(a) for a in (rx, ry, rz))
    cx, sx, cy, sy, cz, sz = (
        math.cos(ax),
        math.sin(ax),
        math.cos(ay),
        math.sin(ay),
        math.cos(az),
        math.sin(az),
    )
    x = np.array(((1, 0, 0), (0, cx, -sx), (0, sx, cx)))
    y = np.array(((cy, 0, sy), (0, 1, 0), (-sy, 0, cy)))
    z = np.array(((cz, -sz, 0), (sz, cz, 0), (0, 0, 1)))
    return x @ y @ z


@dataclass(frozen=True)
class MouseReport:
    """One report: position in metres, angles about x, y, z in degrees, buttons (left,
    middle, right) as 0/1 and the status bits (fringe, out of range, suspended)."""

    position: tuple[float, float, float]
    angles: tuple[float, float, float]
    buttons: tuple[int, int, int]
    status: int

    def matrix(self) -> np.ndarray:
        """Translation and rotation both (the C++ wrote the angles over the translation)."""
        m = np.eye(4)
        m[:3, :3] = rotation_xyz(*self.angles)
        m[:3, 3] = self.position
        return m


def decode_report(report: bytes) -> MouseReport | None:
    """Decode a 16-byte report; None if it is none (flag framing, angles beyond a turn)."""
    if len(report) != REPORT_SIZE or not report[0] & FLAG or any(b & FLAG for b in report[1:]):
        return None
    raw = [report[10 + 2 * i] << 7 | report[11 + 2 * i] for i in range(3)]
    if max(raw) > MAX_ANGLE_RAW:
        return None
    position = tuple(_coordinate(report[1 + 3 * i : 4 + 3 * i]) / 1000.0 * INCH for i in range(3))
    flag = report[0]
    return MouseReport(
        position,  # type: ignore[arg-type]
        (raw[0] / 40.0, raw[1] / 40.0, raw[2] / 40.0),
        tuple(int(bool(flag & bit)) for bit in BUTTON_BITS),  # type: ignore[arg-type]
        flag & (FRINGE | OUT_OF_RANGE | SUSPENDED),
    )


@dataclass
class ReportScanner(ResyncScanner[MouseReport]):
    """Finds reports in the stream. A report starts at the only byte with bit 7 set, so junk is
    skipped a whole run at a time (to the next such byte), counted once per run in
    ``bad_records`` and per byte in ``skipped_bytes``."""

    SIZE = REPORT_SIZE

    def find_head(self, buffer: bytearray, start: int) -> int:
        found = _FLAG_BYTE.search(buffer, start)
        return found.start() if found else -1

    def restart_within(self, buffer: bytearray, start: int) -> int | None:
        # a flag byte inside the partial report: what comes before it is a cut report
        found = _FLAG_BYTE.search(buffer, start + 1)
        return None if found is None else found.start()

    def decode(self, record: bytes) -> MouseReport | None:
        return decode_report(record)


class ThreeDMouse(LineDriver, ScannedDevice):
    """A Logitech 3D mouse / head tracker on a serial line, polled with ``*d``.

    ``port`` is a device path, a pyserial URL or an open ``serial.Serial``-like object (used,
    never closed). ``reset_wait`` and ``diagnostic_wait`` are the protocol's 1 s pauses after
    ``*R`` and ``*\\x05`` (``demand_wait`` the 100 ms after ``*D``); ``poll_timeout`` repeats a
    poll not answered in time; ``silence_timeout`` without a report means the line is gone.
    """

    LOST = ThreeDMouseDisconnected
    CLOSED = ThreeDMouseError
    CLOSED_TEXT = "the mouse is not open"

    def __init__(
        self,
        port: str | serial.SerialBase,
        baud: int = BAUD,
        *,
        demand_wait: float = 0.1,
        reset_wait: float = 1.0,
        diagnostic_wait: float = 1.0,
        read_timeout: float = 2.0,
        poll_timeout: float = 0.1,
        silence_timeout: float = 2.0,
        poll_interval: float = 0.02,
    ) -> None:
        self.port_spec = port
        self.baud = baud
        self.demand_wait = demand_wait
        self.reset_wait = reset_wait
        self.diagnostic_wait = diagnostic_wait
        self.read_timeout = read_timeout
        self.poll_timeout = poll_timeout
        self.silence_timeout = silence_timeout
        self.poll_interval = poll_interval
        self.character_format = "8N2"
        self.scanner = ReportScanner()
        self.polls = 0
        self._line: SerialLine | None = None
        self._polled_at = 0.0
        self._answered = True
        self._heard_at = 0.0

    def open(self) -> None:
        """Open the port, reset and check the mouse, choose head-tracker and Euler modes."""
        # A line that cannot do two stop bits (a pty) still carries the reports at 8N1.
        self._open_line(self.port_spec, LineSettings(self.baud, stopbits=2), self._start)

    def read(self) -> list[MouseReport]:
        """Poll when the last poll was answered (or ``poll_timeout`` passed) and return the
        reports that arrived; raises :class:`ThreeDMouseDisconnected` on a lost or silent line."""
        now = time.monotonic()
        if self._answered or now - self._polled_at >= self.poll_timeout:
            self._answered = False
            self._polled_at = now
            self.polls += 1
            self._write(b"*d")
        reports = self.scanner.feed(self._read_some())
        if reports:
            self._answered = True
            self._heard_at = time.monotonic()
        elif time.monotonic() - self._heard_at > self.silence_timeout:
            raise ThreeDMouseDisconnected(
                f"no report from the 3D mouse for {self.silence_timeout:g} s"
            )
        return reports

    # -- internals ------------------------------------------------------------------------

    def _start(self) -> None:
        if self._line_or_fail().degraded:
            self.character_format = "8N1"
        self._write(b"*D")
        time.sleep(self.demand_wait)
        self._write(b"*R")
        time.sleep(self.reset_wait)
        self._flush_input()  # before a command only, never right after one
        self._write(b"*\x05")
        time.sleep(self.diagnostic_wait)
        answer = self._read_exactly(2)
        if answer != DIAGNOSTIC_OK:
            raise ThreeDMouseProtocolError(
                f"diagnostics answered {answer!r}, not {DIAGNOSTIC_OK!r}"
            )
        self._write(b"*H")
        self._write(b"*G")
        self._answered = True
        self._heard_at = time.monotonic()

    def _read_exactly(self, count: int) -> bytes:
        deadline = time.monotonic() + self.read_timeout
        got = bytearray()
        while len(got) < count:
            got += self._read_some()
            if len(got) < count and time.monotonic() >= deadline:
                raise ThreeDMouseTimeout("no answer from the 3D mouse")
        return bytes(got[:count])
