"""A serial line for the standalone drivers: one buffered reader over pyserial.

All port settings go into the one open call (a Linux pseudo-terminal ignores a later change of
data bits or parity, and refuses a change of parity alone). A line that cannot do what was
asked (a pty has no parity, RTS or CTS) is still used: :attr:`SerialLine.degraded` lists what
was left out, so a driver can say so instead of failing. Reads wait until a deadline; end of
file, a hang-up or an unplugged adapter raise :class:`SerialLineLost` (reopen to recover).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import serial

try:
    from termios import error as TermiosError
except ImportError:  # not a POSIX system

    class TermiosError(Exception):  # type: ignore[no-redef]
        """Stands in for termios.error where there is no termios."""


#: What a port raises when its line is gone. pyserial reconfigures the port (tcsetattr) when
#: its timeout changes, and a hung-up pty answers that with termios.error, not an OSError.
LOST = (serial.SerialException, OSError, TermiosError)

PARITIES = {"none": serial.PARITY_NONE, "even": serial.PARITY_EVEN, "odd": serial.PARITY_ODD}


def _is_pseudo_terminal(spec: str) -> bool:
    """Whether ``spec`` names a Unix98 pseudo-terminal (directly or through a link)."""
    return os.path.realpath(spec).startswith("/dev/pts/")


class SerialLineLost(ConnectionError):
    """The serial line is gone (cannot open, EOF, hang-up, unplugged adapter)."""


@dataclass(frozen=True)
class LineSettings:
    """Line speed and character format (8N1 unless a protocol says otherwise)."""

    baud: int = 9600
    bytesize: int = 8
    parity: str = "none"
    stopbits: int = 1

    def describe(self) -> str:
        return f"{self.baud} {self.bytesize}{self.parity[0].upper()}{self.stopbits}"


class SerialLine:
    """A byte stream over a serial port with deadline-based reads.

    ``port`` is a device path, a pyserial URL (``loop://``) or an open ``serial.Serial``-like
    object (used, never closed). ``poll_interval`` bounds how long one read call blocks.
    """

    def __init__(
        self,
        port: str | serial.SerialBase,
        settings: LineSettings | None = None,
        *,
        poll_interval: float = 0.01,
    ) -> None:
        self.spec = port
        self.settings = settings or LineSettings()
        self.poll_interval = poll_interval
        self.degraded: list[str] = []
        self.bytes_read = 0
        self._port: serial.SerialBase | None = None
        self._owns = False

    # -- life cycle -----------------------------------------------------------------------

    def open(self) -> SerialLine:
        if self._port is not None:
            return self
        if not isinstance(self.spec, str):
            self._port, self._owns = self.spec, False
            self._port.timeout = self.poll_interval
            return self
        s = self.settings
        try:
            try:
                if (s.bytesize, s.parity) != (8, "none") and _is_pseudo_terminal(self.spec):
                    # Known at once: no second open (each open discards what waits in the line)
                    raise ValueError("a pseudo-terminal carries 8 data bits without parity only")
                port = serial.serial_for_url(
                    self.spec,
                    baudrate=s.baud,
                    bytesize=s.bytesize,
                    parity=PARITIES[s.parity],
                    stopbits=s.stopbits,
                    timeout=self.poll_interval,
                )
                if (s.bytesize, s.parity, s.stopbits) != (8, "none", 1):
                    # A Linux pty ignores CS7 or parity in the opening call, then refuses every
                    # later reconfiguration (each read's timeout change): find out now.
                    try:
                        port.timeout = self.poll_interval / 2 or 0.001
                        port.timeout = self.poll_interval
                    except (ValueError, serial.SerialException, TermiosError):
                        port.close()
                        raise
            except (ValueError, serial.SerialException, TermiosError):
                if (s.bytesize, s.parity, s.stopbits) == (8, "none", 1):
                    raise
                # A pty (and some adapters) refuse the character format: 8N1 still carries
                # every protocol here.
                port = serial.serial_for_url(self.spec, baudrate=s.baud, timeout=self.poll_interval)
                self.degraded.append(f"character format {s.describe()} (line stays 8N1)")
        except (serial.SerialException, OSError, ValueError, TermiosError) as exc:
            raise SerialLineLost(f"cannot open {self.spec}: {exc}") from exc
        self._port, self._owns = port, True
        return self

    def open_with(self, setup: Callable[[], object], lost: type[Exception]) -> None:
        """Open the line unless it is open, then ``setup()`` the device on it; if either fails
        the line is closed again, and a lost line is raised as ``lost``."""
        if self.is_open:
            return
        try:
            self.open()
            setup()
        except SerialLineLost as exc:
            self.close()
            raise lost(str(exc)) from exc
        except BaseException:
            self.close()
            raise

    def close(self, farewell: bytes = b"") -> None:
        """Close the port, writing ``farewell`` first if it is open (to stop a stream for
        whoever opens the port next; a line lost by then is no error)."""
        if farewell and self._port is not None:
            try:
                self.write(farewell)
            except SerialLineLost:
                pass
        port, self._port = self._port, None
        if port is not None and self._owns:
            try:
                port.close()
            except (serial.SerialException, OSError):
                pass

    @property
    def is_open(self) -> bool:
        return self._port is not None

    def __enter__(self) -> SerialLine:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- control lines ----------------------------------------------------------------------

    def set_lines(self, *, rts: bool | None = None, dtr: bool | None = None) -> bool:
        """Drive RTS/DTR; False (and noted in ``degraded``) when the line cannot."""
        port = self._require()
        try:
            if dtr is not None:
                port.dtr = dtr
            if rts is not None:
                port.rts = rts
        except (serial.SerialException, OSError, ValueError):
            note = "control lines (RTS/DTR)"
            if note not in self.degraded:
                self.degraded.append(note)
            return False
        return True

    # -- data ---------------------------------------------------------------------------------

    def read(self, timeout: float) -> bytes:
        """What has arrived, waiting up to ``timeout`` seconds for the first byte; b'' if none."""
        port = self._require()
        deadline = time.monotonic() + timeout
        while True:
            try:
                waiting = port.in_waiting
                if waiting:
                    chunk = port.read(waiting)
                elif time.monotonic() >= deadline:
                    return b""
                else:
                    port.timeout = max(0.0, min(self.poll_interval, deadline - time.monotonic()))
                    chunk = port.read(1)
            except (*LOST, TypeError) as exc:
                raise SerialLineLost(f"serial line lost: {exc}") from exc
            if chunk:
                self.bytes_read += len(chunk)
                return bytes(chunk)

    def write(self, data: bytes) -> None:
        port = self._require()
        try:
            port.write(data)
            port.flush()
        except LOST as exc:
            raise SerialLineLost(f"serial line lost: {exc}") from exc

    def discard_input(self) -> None:
        try:
            self._require().reset_input_buffer()
        except LOST as exc:
            raise SerialLineLost(f"serial line lost: {exc}") from exc

    def _require(self) -> serial.SerialBase:
        if self._port is None:
            raise SerialLineLost("the serial line is not open")
        return self._port


class LineDriver:
    """For a standalone driver that holds its :class:`SerialLine` in ``_line`` (None while
    closed): opening it and starting the device (:meth:`_open_line`), closing it
    (:meth:`close`, :attr:`is_open`), and reads, writes and flushes that turn a lost line into
    the driver's own :attr:`LOST` exception, and a closed one into :attr:`CLOSED` with
    :attr:`CLOSED_TEXT`."""

    LOST: type[Exception] = SerialLineLost
    CLOSED: type[Exception] = SerialLineLost
    CLOSED_TEXT = "the device is not open"
    #: Written just before the line closes (see :meth:`SerialLine.close`).
    FAREWELL = b""

    _line: SerialLine | None = None
    poll_interval: float = 0.01

    def _open_line(
        self, port: str | serial.SerialBase, settings: LineSettings, start: Callable[[], object]
    ) -> None:
        """Open ``port`` with ``settings`` into ``_line`` unless it is open already (a port that
        cannot be opened raises :attr:`LOST`), then ``start()`` the device, closing the line
        again if that fails."""
        if self._line is not None:
            return
        line = SerialLine(port, settings, poll_interval=self.poll_interval)
        try:
            self._line = line.open()
        except SerialLineLost as exc:
            raise self.LOST(str(exc)) from exc
        try:
            start()
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        line, self._line = self._line, None
        if line is not None:
            line.close(self.FAREWELL)

    @property
    def is_open(self) -> bool:
        return self._line is not None

    def _line_or_fail(self) -> SerialLine:
        if self._line is None:
            raise self.CLOSED(self.CLOSED_TEXT)
        return self._line

    def _read_some(self) -> bytes:
        """What has arrived, waiting up to ``poll_interval`` for it."""
        try:
            return self._line_or_fail().read(self.poll_interval)
        except SerialLineLost as exc:
            raise self.LOST(str(exc)) from exc

    def _write(self, data: bytes) -> None:
        try:
            self._line_or_fail().write(data)
        except SerialLineLost as exc:
            raise self.LOST(str(exc)) from exc

    def _flush_input(self) -> None:
        """Drop what came before (only ever before a command, never right after one)."""
        try:
            self._line_or_fail().discard_input()
        except SerialLineLost as exc:
            raise self.LOST(str(exc)) from exc
