"""Ascension Wanda (serial-mouse protocol), independent of gadgetctl's input manager.

Line: 1200 baud, 7 data bits, no parity, 1 stop bit (a pseudo-terminal stays 8N1, which
carries the same 7-bit bytes). Start: RTS low, then high (100 ms each; skipped on a line
without RTS); the Wanda answers ``M3`` (a Logitech three-button mouse).

Packets: the first byte has bit 6 set (sync), the others have it clear.

* byte 0: bit 5 button 0, bit 4 button 2, bits 1..0 X bits 7..6, bits 3..2 Y bits 7..6;
* byte 1: X bits 5..0; byte 2: Y bits 5..0;
* an optional 4th byte (sync clear): the middle button, button 1 pressed when non-zero; a
  3-byte packet says button 1 is released.

The joystick is absolute: X = -int8(X bits) (the Wanda's X runs the other way), Y = int8(Y
bits), both clamped to -34..34 as Gadgeteer does.

A Wanda sends nothing while the ball is at rest and no button changes (VRPN ``vrpn_Wanda.C``,
whose comment says so and which centres the joystick after 0.2 s without a packet; VR
Juggler's ``WandaStandalone.cpp`` ignores read timeouts), so silence is not a disconnect: only
a lost line (a hang-up, an unplugged adapter) is. A pulled cable on a real RS-232 port cannot
be told from rest, by this driver or any other.

Only the standard library and pyserial (through :mod:`gadgetctl.transport.serialline`) are
used.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import serial

from gadgetctl.transport.records import ResyncScanner, ScannedDevice
from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

SYNC = 0x40
LIMIT = 34
BAUD = 1200
HELLO = b"M3"
#: Bytes read while waiting for ``M3`` at most.
MAX_HELLO_SCAN = 64


class WandaError(Exception):
    """Base class of the driver's errors."""


class WandaTimeout(WandaError, TimeoutError):
    """The Wanda did not answer in time."""


class WandaProtocolError(WandaError):
    """The Wanda answered, but not as the protocol says."""


class WandaDisconnected(WandaError):
    """The serial line is gone; reopen to recover."""


def _int8(value: int) -> int:
    return value - 256 if value & 0x80 else value


@dataclass(frozen=True)
class WandaPacket:
    """Buttons 0..2 as 0/1 and the joystick (x, y), each -34..34."""

    buttons: tuple[int, int, int]
    axes: tuple[int, int]


def decode_packet(packet: bytes) -> WandaPacket | None:
    """Decode a 3- or 4-byte packet; None when it is none (sync bits, 8-bit bytes)."""
    if len(packet) not in (3, 4) or not packet[0] & SYNC or any(b & 0x80 for b in packet):
        return None
    if any(b & SYNC for b in packet[1:]):
        return None
    b0, b1, b2 = packet[:3]
    x = _int8((b0 & 0x03) << 6 | (b1 & 0x3F))
    y = _int8((b0 & 0x0C) << 4 | (b2 & 0x3F))
    middle = int(len(packet) == 4 and packet[3] != 0)
    return WandaPacket(
        (b0 >> 5 & 1, middle, b0 >> 4 & 1),
        (max(-LIMIT, min(LIMIT, -x)), max(-LIMIT, min(LIMIT, y))),
    )


@dataclass
class PacketScanner(ResyncScanner[WandaPacket]):
    """Resynchronises on the sync bit: bytes before a sync byte (or with bit 7 set, which a
    7-bit line cannot carry) are skipped a whole run at a time, counted once in
    ``bad_records`` and byte by byte in ``skipped_bytes``. A 3-byte packet is held until the
    next byte says whether a 4th follows, or until the line goes quiet (``quiet``): packets
    of two sizes, so the search is the Wanda's own, the counting the shared one. ``M3``
    followed by a sync byte (or by silence) is the Wanda's hello, said again whenever it is
    powered up: counted in ``hellos``, not as junk."""

    hellos: int = 0

    def feed(self, data: bytes, *, quiet: bool = False) -> list[WandaPacket]:
        """Add bytes; ``quiet`` says no more are coming now (a held packet is complete)."""
        buf = self.buffer
        buf += data
        out: list[WandaPacket] = []
        pos = 0
        while pos < len(buf):
            if buf[pos] & 0x80 or not buf[pos] & SYNC:
                start = pos
                while pos < len(buf) and (buf[pos] & 0x80 or not buf[pos] & SYNC):
                    pos += 1
                self.skip(pos - start)
                continue
            if buf.startswith(HELLO, pos) and (
                (len(buf) - pos == 2 and quiet) or (len(buf) - pos > 2 and buf[pos + 2] & SYNC)
            ):
                self.hellos += 1  # M3 again: the Wanda was powered up (or reset) anew
                pos += len(HELLO)
                continue
            if len(buf) - pos < 3 or (len(buf) - pos == 3 and not quiet):
                break  # wait for the rest (or the byte after a 3-byte packet)
            size = 4 if len(buf) - pos > 3 and not buf[pos + 3] & (SYNC | 0x80) else 3
            packet = decode_packet(bytes(buf[pos : pos + size]))
            if packet is None:
                self.skip(1)
                pos += 1
                continue
            out.append(packet)
            self.records += 1
            self._in_junk = False
            pos += size
        del buf[:pos]
        return out


class Wanda(ScannedDevice):
    """An Ascension Wanda on a serial line.

    ``read_timeout`` (seconds; the element's ``read_timeout`` is in ms) bounds one read;
    ``hello_timeout`` the wait for ``M3``; ``reset_time`` each half of the RTS pulse.
    ``heard_at`` is the :func:`time.monotonic` time of the last byte (silence is rest).
    """

    def __init__(
        self,
        port: str | serial.SerialBase,
        *,
        read_timeout: float = 0.02,
        hello_timeout: float = 2.0,
        reset_time: float = 0.1,
    ) -> None:
        self.line = SerialLine(port, LineSettings(BAUD, bytesize=7), poll_interval=read_timeout)
        self.read_timeout = read_timeout
        self.hello_timeout = hello_timeout
        self.reset_time = reset_time
        self.scanner = PacketScanner()
        self._early: list[WandaPacket] = []  # packets that came with the hello
        self.heard_at = 0.0

    def open(self) -> None:
        self.line.open_with(self._start, WandaDisconnected)

    def _start(self) -> None:
        reset = self.line.set_lines(rts=False)
        if reset:
            time.sleep(self.reset_time)
            self.line.set_lines(rts=True)
            time.sleep(self.reset_time)
        self._hello(reset)
        self.heard_at = time.monotonic()

    def close(self) -> None:
        self.line.close()

    @property
    def degraded(self) -> list[str]:
        return self.line.degraded

    def read(self) -> list[WandaPacket]:
        """The packets that arrived within ``read_timeout`` (possibly none: a Wanda at rest
        is silent). Raises :class:`WandaDisconnected` when the line is lost."""
        try:
            data = self.line.read(self.read_timeout)
        except SerialLineLost as exc:
            raise WandaDisconnected(str(exc)) from exc
        packets = self.scanner.feed(data, quiet=not data)
        if self._early:
            packets, self._early = self._early + packets, []
        if data:
            self.heard_at = time.monotonic()
        return packets

    def _hello(self, reset: bool) -> None:
        """After a reset, wait for ``M3``; what follows it stays for the packet scanner.
        Without RTS (a pty) the Wanda was not reset: its ``M3`` may be long gone (opening a
        port can discard it) and at rest it says nothing more, so nothing is waited for; an
        ``M3`` still in the line is the scanner's to recognise."""
        if not reset:
            return
        got = bytearray()
        deadline = time.monotonic() + self.hello_timeout
        while True:
            index = got.find(HELLO)
            if index >= 0:
                self._early = self.scanner.feed(bytes(got[index + 2 :]))
                return
            if len(got) > MAX_HELLO_SCAN:
                raise WandaProtocolError(f"no M3 among {len(got)} bytes: {bytes(got[:16])!r}")
            left = deadline - time.monotonic()
            if left <= 0:
                raise WandaTimeout("the Wanda did not say M3")
            got += self.line.read(min(left, 0.05))
