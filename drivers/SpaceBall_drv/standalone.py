"""3Dconnexion SpaceMouse (Magellan) and SpaceBall 4000 FLX / 2003B protocols, independent of
gadgetctl's input manager (it uses only :mod:`gadgetctl.transport.serialline`).

Both talk 9600 baud, 8 data bits, 2 stop bits, in records ended by a carriage return:

* SpaceMouse: every 4-bit value travels as one printable "nibble" character (``0x30 | v``
  when v has an even number of set bits, ``0x40 | v`` otherwise). ``d`` + 24 nibbles is six
  axes of four nibbles each, most significant first, minus 32768; ``k`` + 3 nibbles is
  buttons 1..12 (low nibble first); ``e`` reports an error; other letters echo commands.
* SpaceBall 4000 FLX: binary records. ``D`` + 2 timer bytes + six big-endian signed 16-bit
  axes (z and roll sign-flipped so both dialects turn the same way); ``.`` + 2 bytes is
  buttons 1..12 and the left-handed flag; ``K`` + 6 bytes is the older button record with
  the button bytes at 4 and 5.
* SpaceBall 2003B: the same analog record, ``K`` + 2 bytes for buttons 1..8 and the pick
  button (9).
* Both SpaceBalls escape control characters inside a record as ``^`` and a letter (``^Q``,
  ``^S``, ``^M`` for XON, XOFF, CR), ``^^`` being ``^`` itself. VRPN ``vrpn_Spaceball.C``
  unescapes whatever the model, and so does VR Juggler's ``puck_device.cpp`` (its
  ``processBuffer`` always calls ``checkControlChars``; the 2003B's flag that says otherwise is
  never read); an earlier gadgetctl did not for the 2003B and dropped every record holding
  one of those four bytes.

Axes are ``tx, ty, tz, rx, ry, rz`` in raw counts; buttons are 0/1, button N at index N-1.
Decoding is bounded: a record longer than any the protocol has, a nibble character the
encoding cannot produce or a record of the wrong length is a counted bad record, and
whatever follows is skipped up to the next carriage return (never a fault, never a resize).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from gadgetctl.transport.serialline import LineSettings, SerialLine, SerialLineLost

SPACEMOUSE = "SpaceMouse"
SPACEMOUSE_PLUS = "SpaceMouse Plus XT"
SPACEBALL_4000 = "SpaceBall 4000 FLX"
SPACEBALL_2003B = "SpaceBall 2003B"
MODELS = (SPACEMOUSE, SPACEMOUSE_PLUS, SPACEBALL_2003B, SPACEBALL_4000)

BAUD = 9600  # the only speed the pucks talk
LINE = LineSettings(baud=BAUD, bytesize=8, parity="none", stopbits=2)
CR = 0x0D
AXES = 6
BUTTONS = 12
#: The longest record either dialect sends: a SpaceBall analog record with every byte
#: escaped (1 + 2 * 14), or a SpaceMouse version reply (text). Longer is junk.
MAX_RECORD = 80

#: Raw counts the C++ driver maps onto [0, 1], whatever the element's min/max say
#: (``PuckDevice::config``: setMin/setMax -500/500 for the SpaceMouse dialects, -2000/2000 for
#: both SpaceBalls).
AXIS_RANGE = {
    SPACEMOUSE: 500.0,
    SPACEMOUSE_PLUS: 500.0,
    SPACEBALL_4000: 2000.0,
    SPACEBALL_2003B: 2000.0,
}

_EVEN_PARITY = {0, 3, 5, 6, 9, 10, 12, 15}


def nibble_char(value: int) -> int:
    """The character a SpaceMouse sends for the 4-bit ``value``."""
    return (0x30 if value in _EVEN_PARITY else 0x40) | value


_NIBBLE_VALUE = {nibble_char(v): v for v in range(16)}


class SpaceBallError(Exception):
    """Base class of the driver's errors."""


class SpaceBallDisconnected(SpaceBallError, SerialLineLost):
    """The serial line is gone; reopen to recover."""


@dataclass(frozen=True)
class PuckSample:
    """One decoded record: six raw axes, or twelve 0/1 buttons (the other field is None)."""

    axes: tuple[int, ...] | None = None
    buttons: tuple[int, ...] | None = None
    left_handed: bool | None = None


def bits_to_buttons(bits: int, count: int = BUTTONS) -> tuple[int, ...]:
    """Bit N-1 of ``bits`` is button N. Upstream quirk fixed: the C++ stored the masked bit
    (2048 for button 12) as the digital value; here every value is 0 or 1."""
    return tuple(bits >> k & 1 for k in range(count))


def decode_spacemouse(record: bytes) -> PuckSample | str | None:
    """A SpaceMouse record without its CR: a sample, ``"reply"`` for a command echo or
    error report, or None when it is malformed."""
    code, body = record[:1], record[1:]
    if code == b"d":
        if len(body) != 4 * AXES:
            return None
        values = [_NIBBLE_VALUE.get(c) for c in body]
        if None in values:
            return None
        axes = tuple(
            (
                values[4 * i] << 12
                | values[4 * i + 1] << 8
                | values[4 * i + 2] << 4
                | values[4 * i + 3]
            )
            - 32768
            for i in range(AXES)
        )
        return PuckSample(axes=axes)
    if code == b"k":
        if len(body) != 3:
            return None
        values = [_NIBBLE_VALUE.get(c) for c in body]
        if None in values:
            return None
        return PuckSample(buttons=bits_to_buttons(values[0] | values[1] << 4 | values[2] << 8))
    if code in (b"v", b"m", b"c", b"q", b"n", b"z", b"b", b"e"):
        return "reply"
    return None


def unescape(record: bytes) -> bytes | None:
    """Undo a SpaceBall's escapes; None for an escape the protocol does not have.

    (The C++ driver masks any escaped character with 31, which turns ``^^`` into 0x1E.)"""
    if b"^" not in record:
        return record
    out = bytearray()
    escaped = False
    for c in record:
        if escaped:
            if c == 0x5E:
                out.append(c)
            elif c in b"QSM":
                out.append(c & 0x1F)
            else:
                return None
            escaped = False
        elif c == 0x5E:
            escaped = True
        else:
            out.append(c)
    return None if escaped else bytes(out)


def _axes_from_words(body: bytes) -> tuple[int, ...]:
    axes = [int.from_bytes(body[2 + 2 * i : 4 + 2 * i], "big", signed=True) for i in range(AXES)]
    axes[2], axes[5] = -axes[2], -axes[5]  # z and roll point the SpaceMouse's way
    return tuple(axes)


def decode_spaceball(record: bytes, model: str = SPACEBALL_4000) -> PuckSample | str | None:
    """A SpaceBall record without its CR (escapes still in): a sample, ``"reply"`` for a
    command echo, version or error line, or None when it is malformed."""
    plain = unescape(record)  # every SpaceBall escapes (the 2003B too)
    if plain is None:
        return None
    record = plain
    code, body = record[:1], record[1:]
    if code == b"D":
        return PuckSample(axes=_axes_from_words(body)) if len(body) == 14 else None
    if code == b"." and model == SPACEBALL_4000:
        return _buttons_4000(body) if len(body) == 2 else None
    if code == b"K":
        if model == SPACEBALL_2003B:
            if len(body) != 2 or body[0] & 0xE0 != 0x40 or body[1] & 0xF0 != 0x40:
                return None
            return PuckSample(buttons=bits_to_buttons((body[1] & 0x0F) | (body[0] & 0x1F) << 4))
        return _buttons_4000(body[4:6]) if len(body) == 6 else None
    if code in (b"@", b"C", b"P", b"M", b"F", b"N", b"Z", b"B", b"E"):
        return "reply"
    return None


def _buttons_4000(body: bytes) -> PuckSample | None:
    first, second = body
    if first & 0xC0 != 0x40 or second & 0x40 != 0x40:
        return None  # the fixed bits are 01 in the first byte and 1 in the second
    bits = (second & 0x3F) | (second & 0x80) >> 1 | (first & 0x3F) << 7
    return PuckSample(buttons=bits_to_buttons(bits), left_handed=bool(bits >> 12 & 1))


@dataclass
class RecordSplitter:
    """Cuts a byte stream into CR-ended records and decodes them, bounded.

    ``records`` counts samples decoded, ``replies`` command echoes and error reports,
    ``bad_records`` malformed or overlong records, ``skipped_bytes`` the bytes of those.
    """

    model: str = SPACEMOUSE
    records: int = 0
    replies: int = 0
    bad_records: int = 0
    skipped_bytes: int = 0
    reply_lines: list[bytes] = field(default_factory=list)
    _partial: bytearray = field(default_factory=bytearray)
    _overlong: bool = False

    def feed(self, data: bytes) -> list[PuckSample]:
        out: list[PuckSample] = []
        start = 0
        while True:
            end = data.find(b"\r", start)
            if end < 0:
                self._keep(data[start:])
                return out
            chunk = data[start:end]
            start = end + 1
            if self._overlong:
                self.skipped_bytes += len(chunk) + 1
                self._overlong = False
                continue
            record = bytes(self._partial) + chunk if self._partial else chunk
            self._partial.clear()
            self._decode(record, out)

    def _keep(self, tail: bytes) -> None:
        if self._overlong:
            self.skipped_bytes += len(tail)
            return
        self._partial += tail
        if len(self._partial) > MAX_RECORD:
            # No record is this long: count it once and skip the whole run to the next CR.
            self.bad_records += 1
            self.skipped_bytes += len(self._partial)
            self._partial.clear()
            self._overlong = True

    def _decode(self, record: bytes, out: list[PuckSample]) -> None:
        if not record:
            return
        if len(record) > MAX_RECORD:
            self.bad_records += 1
            self.skipped_bytes += len(record) + 1
            return
        if self.model in (SPACEMOUSE, SPACEMOUSE_PLUS):
            result = decode_spacemouse(record)
        else:
            result = decode_spaceball(record, self.model)
        if result is None:
            self.bad_records += 1
            self.skipped_bytes += len(record) + 1
        elif result == "reply":
            self.replies += 1
            if len(self.reply_lines) < 32:
                self.reply_lines.append(record)
        else:
            self.records += 1
            out.append(result)  # type: ignore[arg-type]


def startup_commands(model: str) -> list[bytes]:
    """What the driver sends after opening the line (the C++ driver's settings)."""
    if model in (SPACEMOUSE, SPACEMOUSE_PLUS):
        mode = (
            b"c" + bytes([nibble_char(3), nibble_char(2)])
            if model == SPACEMOUSE_PLUS
            else b"m" + bytes([nibble_char(3)])
        )
        return [
            b"vQ\r",  # version
            mode + b"\r",  # translation and rotation on, not dominant-only
            b"q" + bytes([nibble_char(0), nibble_char(0)]) + b"\r",  # linear sensitivity
            b"n" + bytes([nibble_char(15)]) + b"\r",  # null radius
            b"z\r",  # zero the cap
        ]
    if model == SPACEBALL_2003B:
        return [b"@\r", b"CBT\rP@r@r\rMSSVLA\r", b"FTp\rFRp\r", b"NT\r", b"Z\r"]
    return [b"@\r", b"CB\rP32\rMSSV\r", b"FTp\rFRp\r", b"NT\r", b"Z\r", b"BcCcC\r"]


class SpaceBall:
    """A SpaceMouse or SpaceBall on a serial line.

    ``model`` is one of :data:`MODELS`; ``reset_wait`` bounds the wait for the SpaceBall's
    reset banner (the C++ slept 2 s); ``sample_timeout`` bounds one :meth:`poll`.
    """

    def __init__(
        self,
        port: object,
        model: str = SPACEMOUSE,
        *,
        reset_wait: float = 2.0,
        sample_timeout: float = 0.1,
        poll_interval: float = 0.01,
    ) -> None:
        if model not in MODELS:
            raise SpaceBallError(f"unknown puck model {model!r}; one of {', '.join(MODELS)}")
        self.model = model
        self.reset_wait = reset_wait
        self.sample_timeout = sample_timeout
        self.line = SerialLine(port, LINE, poll_interval=poll_interval)  # type: ignore[arg-type]
        self.decoder = RecordSplitter(model)
        self._pending: list[PuckSample] = []

    def open(self) -> None:
        try:
            self.line.open()
            self.line.set_lines(rts=True, dtr=True)  # a pty cannot: tolerated
            commands = startup_commands(self.model)
            self.line.write(commands[0])
            self._await_reply(commands[0][:1])
            for command in commands[1:]:
                self.line.write(command)
        except SerialLineLost as exc:
            self.line.close()
            raise SpaceBallDisconnected(str(exc)) from exc

    def _await_reply(self, code: bytes) -> None:
        """Wait (at most ``reset_wait``) for the reply to the first command; samples that
        come first are kept for :meth:`poll`."""
        deadline = time.monotonic() + self.reset_wait
        while time.monotonic() < deadline:
            self._pending.extend(self.decoder.feed(self.line.read(deadline - time.monotonic())))
            if any(line[:1] == code for line in self.decoder.reply_lines):
                return

    @property
    def version(self) -> str:
        for line in self.decoder.reply_lines:
            if line[:1] in (b"v", b"@"):
                return line[1:].decode("ascii", "replace").strip()
        return ""

    def poll(self) -> list[PuckSample]:
        """The records that arrive within ``sample_timeout`` (all of them, in order)."""
        out, self._pending = self._pending, []
        try:
            out.extend(self.decoder.feed(self.line.read(0.0 if out else self.sample_timeout)))
        except SerialLineLost as exc:
            raise SpaceBallDisconnected(str(exc)) from exc
        return out

    def close(self) -> None:
        self.line.close()

    def __enter__(self) -> SpaceBall:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
