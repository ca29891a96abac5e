"""Fakespace PinchGlove protocol, independent of gadgetctl.

The glove box sends nothing until a contact between fingers changes. Each touch
frame lists the contact groups that are closed: one ``(left, right)`` byte pair
per group, a bit per finger of that hand: 0x10 thumb, 0x08 index, 0x04 middle,
0x02 ring, 0x01 pinky (as two implementations independent of VR Juggler read it:
Vrui's FakespacePinchGlove and VESS's vsPinchGloveBox). Frames
start with ``0x80`` (no timestamp) or ``0x81`` (two 7-bit timestamp bytes before
the end) and end with ``0x8F``. Commands are two bytes; replies are ``0x82 text
0x8F`` info frames.

Only the standard library, pyserial and this module's own dataclasses are used.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from types import TracebackType

import serial

try:
    import termios
except ImportError:  # not a POSIX system: no IGNBRK to set
    termios = None  # type: ignore[assignment]

START_DATA = 0x80
START_DATA_TS = 0x81
START_INFO = 0x82
END = 0x8F
DATA_STARTS = (START_DATA, START_DATA_TS)

CMD_QUERY = ord("C")
CMD_TIMESTAMPS = ord("T")
CMD_FORMAT_VERSION = ord("V")
QUERIES = {
    "left_version": ord("L"),
    "right_version": ord("R"),
    "processor": ord("P"),
    "tick_length": ord("T"),
}
CONFUSED = b"?"

HANDS = ("left", "right")
#: Gadgeteer's glove components, in their order (the rows of the glove angles).
FINGERS = ("thumb", "index", "middle", "ring", "pinky")
#: The bit of each finger in a contact byte. Fix: VR Juggler's ``PinchGloveStandalone`` turns
#: bit k into digital unit k and ``Glove::getGloveDataFromDigitalData`` then takes unit k as
#: glove component k, so its glove angles show the pinky as the thumb. The digital units keep
#: VR Juggler's numbering (unit k is bit k, so configurations read the same switches); the
#: glove rows follow the fingers the device names.
FINGER_BITS = {"thumb": 0x10, "index": 0x08, "middle": 0x04, "ring": 0x02, "pinky": 0x01}
#: The finger of each digital unit of one hand (unit k is bit k).
UNIT_FINGERS = ("pinky", "ring", "middle", "index", "thumb")
JOINTS_PER_FINGER = 4
DIGITAL_UNITS = len(HANDS) * len(FINGERS)
FINGER_MASK = (1 << len(FINGERS)) - 1
TOUCHING_ANGLE = math.pi / 2
#: Bytes between a data start byte and 0x8F at most: ten contact groups (a frame has at most
#: five, each pairing two of the ten fingers) and the two timestamp bytes. A longer body is
#: a bad frame, so a line that never sends 0x8F cannot grow a frame without limit.
MAX_FRAME_BODY = 2 * 10 + 2
#: Bytes of an info reply's text at most (the glove's version strings are short).
MAX_REPLY = 256
#: Bytes read while waiting for a reply to start, at most (touch frames may come first).
MAX_REPLY_SCAN = 4096


class PinchGloveError(Exception):
    """Base class of the driver's errors."""


class PinchGloveTimeout(PinchGloveError, TimeoutError):
    """The glove box did not answer a command in time."""


class PinchGloveProtocolError(PinchGloveError):
    """The glove box answered, but not as the protocol says."""


class PinchGloveDisconnected(PinchGloveError):
    """The serial line is gone (EOF, hang-up, unplugged adapter); reopen to recover."""


@dataclass(frozen=True)
class HandSample:
    """One hand: contact flags per finger and the matching joint angles."""

    hand: str
    contacts: tuple[bool, ...]
    angles: tuple[tuple[float, ...], ...]

    @classmethod
    def from_bits(cls, hand: str, bits: int) -> HandSample:
        """Build a hand from a contact byte (see :data:`FINGER_BITS`)."""
        contacts = tuple(bool(bits & FINGER_BITS[finger]) for finger in FINGERS)
        angles = tuple((TOUCHING_ANGLE if c else 0.0,) * JOINTS_PER_FINGER for c in contacts)
        return cls(hand, contacts, angles)

    def finger(self, name: str) -> bool:
        """Contact flag of a finger by name (``"thumb"`` .. ``"pinky"``)."""
        return self.contacts[FINGERS.index(name)]


@dataclass(frozen=True)
class PinchSample:
    """One decoded touch frame (or the all-open state after start-up).

    ``digital`` has 10 values of 0/1: unit k is bit k of the left byte (0 pinky .. 4 thumb),
    5 + k bit k of the right byte (5 pinky .. 9 thumb), as VR Juggler numbers them. ``hands`` are glove units 0 (left) and 1 (right).
    ``groups`` keeps the raw ``(left bits, right bits)`` contact groups, and
    ``timestamp`` the 14-bit tick count (None for frames without one).
    """

    digital: tuple[int, ...]
    hands: tuple[HandSample, HandSample]
    groups: tuple[tuple[int, int], ...]
    timestamp: int | None

    @classmethod
    def from_groups(
        cls, groups: tuple[tuple[int, int], ...], timestamp: int | None = None
    ) -> PinchSample:
        """OR all contact groups of a frame into per-finger contacts."""
        left = right = 0
        for lbits, rbits in groups:
            left |= lbits
            right |= rbits
        digital = tuple(left >> k & 1 for k in range(len(FINGERS))) + tuple(
            right >> k & 1 for k in range(len(FINGERS))
        )
        hands = (HandSample.from_bits("left", left), HandSample.from_bits("right", right))
        return cls(digital, hands, groups, timestamp)

    @classmethod
    def open_hands(cls) -> PinchSample:
        """The state before any frame arrives: no finger touches another."""
        return cls.from_groups(())

    @property
    def left(self) -> HandSample:
        return self.hands[0]

    @property
    def right(self) -> HandSample:
        return self.hands[1]


def decode_frame(start: int, body: bytes) -> PinchSample | None:
    """Decode the bytes between a data start byte and ``0x8F``; None if malformed."""
    timestamp = None
    if start == START_DATA_TS:
        if len(body) < 2:
            return None
        # The two bytes before 0x8F are the timestamp, low 7 bits first, as FreeVR's
        # vr_input.pinch.c reads it (first + 128 * second). Fix: VR Juggler's C++ reads
        # one byte past the end here (it never uses the value).
        timestamp = body[-2] | body[-1] << 7
        body = body[:-2]
    if len(body) % 2:
        return None
    if any(b & ~FINGER_MASK for b in body):
        return None  # a hand has five contacts; higher bits mean corruption
    groups = tuple((body[i], body[i + 1]) for i in range(0, len(body), 2))
    return PinchSample.from_groups(groups, timestamp)


def _ignore_break(port: serial.SerialBase) -> None:
    """Set IGNBRK as the C++ driver does; only real POSIX ports have it."""
    if termios is None:
        return
    try:
        fd = port.fileno()
        attrs = termios.tcgetattr(fd)
        attrs[0] |= termios.IGNBRK
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
    except (AttributeError, NotImplementedError, OSError, termios.error, serial.SerialException):
        pass  # URL ports have no file descriptor


class _SerialLink:
    """Buffered byte reader over a pyserial port with deadline-based reads."""

    def __init__(self, port: serial.SerialBase, poll_interval: float) -> None:
        self.port = port
        self.buffer = bytearray()
        port.timeout = poll_interval

    def fill(self, deadline: float) -> bool:
        """Read whatever is available, waiting until ``deadline``; True if bytes came."""
        while True:
            try:
                waiting = self.port.in_waiting
                if not waiting and time.monotonic() >= deadline:
                    return False
                # read(1) returns at the first byte or after ``poll_interval``.
                chunk = self.port.read(waiting or 1)
            except (serial.SerialException, OSError) as exc:
                raise PinchGloveDisconnected(f"serial line lost: {exc}") from exc
            if chunk:
                self.buffer += chunk
                return True

    def read_byte(self, timeout: float) -> int | None:
        """Next byte, or None when nothing arrives within ``timeout`` seconds."""
        if not self.buffer and not self.fill(time.monotonic() + timeout):
            return None
        value = self.buffer[0]
        del self.buffer[0]
        return value

    def unread(self, value: int) -> None:
        self.buffer.insert(0, value)

    def write(self, data: bytes) -> None:
        try:
            self.port.write(data)
            self.port.flush()
        except (serial.SerialException, OSError) as exc:
            raise PinchGloveDisconnected(f"serial line lost: {exc}") from exc

    def flush_queues(self) -> None:
        """Drop pending input and output, as the glove's command procedure asks."""
        self.buffer.clear()
        try:
            self.port.reset_input_buffer()
            self.port.reset_output_buffer()
        except (serial.SerialException, OSError) as exc:
            raise PinchGloveDisconnected(f"serial line lost: {exc}") from exc


class PinchGlove:
    """Fakespace PinchGlove over a serial line.

    ``port`` is a device path, a pyserial URL (``loop://``, ``socket://host:port``,
    ``spy://...``) or an already-open ``serial.Serial``-like object (which the
    driver uses but never closes). All protocol delays are settings:
    ``command_delay`` between the two command bytes (100 ms upstream),
    ``echo_wait`` for a confused-glove ``?`` after the first byte, ``read_timeout``
    per byte of a reply or frame (5 s upstream), ``sample_timeout`` for
    :meth:`sample` to wait for a frame to start, ``setup_timeout`` for the whole of
    :meth:`open` (its queries and commands: a line that keeps sending junk or ``?`` slowly
    enough would otherwise hold it for minutes, each byte within ``read_timeout``).
    """

    def __init__(
        self,
        port: str | serial.SerialBase,
        baud: int = 9600,
        *,
        timestamps: bool = True,
        query_info: bool = True,
        command_delay: float = 0.1,
        echo_wait: float = 0.1,
        read_timeout: float = 5.0,
        sample_timeout: float = 0.5,
        poll_interval: float = 0.05,
        command_retries: int = 2,
        setup_timeout: float = 6.0,
    ) -> None:
        self.port_spec = port
        self.baud = baud
        self.timestamps = timestamps
        self.query_info = query_info
        self.command_delay = command_delay
        self.echo_wait = echo_wait
        self.read_timeout = read_timeout
        self.sample_timeout = sample_timeout
        self.poll_interval = poll_interval
        self.command_retries = command_retries
        self.setup_timeout = setup_timeout
        self._setup_deadline: float | None = None  # while open() runs
        self.info: dict[str, str] = {}
        self.last = PinchSample.open_hands()
        self.frames = 0
        self.bad_frames = 0
        self.skipped_bytes = 0
        self.control_lines = True
        self._link: _SerialLink | None = None
        self._owns_port = False

    # -- life cycle -------------------------------------------------------------------

    def open(self) -> PinchSample:
        """Open the port, query the hardware, enable timestamps; return the open-hand state."""
        if self._link is not None:
            return self.last
        try:
            port = self._open_port()
        except (serial.SerialException, OSError, ValueError) as exc:
            raise PinchGloveDisconnected(f"cannot open {self.port_spec}: {exc}") from exc
        self._link = _SerialLink(port, self.poll_interval)
        self._setup_deadline = time.monotonic() + self.setup_timeout
        try:
            _ignore_break(port)
            self._raise_control_lines(port)
            if self.query_info:
                for key, param in QUERIES.items():
                    self.info[key] = self._command(CMD_QUERY, param).decode("ascii", "replace")
            self._set_echoed(CMD_TIMESTAMPS, ord("1") if self.timestamps else ord("0"))
        except BaseException:
            self.close()
            raise
        finally:
            self._setup_deadline = None
        # The glove is silent until a contact changes, so start from open hands.
        self.last = PinchSample.open_hands()
        return self.last

    def close(self) -> None:
        """Release the port (only if this driver opened it)."""
        link, self._link = self._link, None
        if link is not None and self._owns_port:
            try:
                link.port.close()
            except (serial.SerialException, OSError):
                pass

    @property
    def is_open(self) -> bool:
        return self._link is not None

    def __enter__(self) -> PinchGlove:
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

    def sample(self) -> PinchSample | None:
        """Read one touch frame; None if no valid frame starts within ``sample_timeout``.

        Bytes outside frames are skipped (``skipped_bytes``); malformed or
        truncated frames are dropped (``bad_frames``) and reading resumes at the
        next start byte. Raises :class:`PinchGloveDisconnected` on EOF/hang-up.
        """
        link = self._require_link()
        deadline = time.monotonic() + self.sample_timeout
        while True:
            value = link.read_byte(max(0.0, deadline - time.monotonic()))
            if value is None:
                return None
            if value not in DATA_STARTS:
                self.skipped_bytes += 1
                continue
            frame = self._read_frame(value)
            if frame is not None:
                self.frames += 1
                self.last = frame
                return frame

    def set_data_format_version(self, version: int = ord("1")) -> None:
        """Send ``V`` + version (the C++ driver wrongly sends ``T`` here)."""
        self._set_echoed(CMD_FORMAT_VERSION, version)

    # -- internals ------------------------------------------------------------------------

    def _open_port(self) -> serial.SerialBase:
        if not isinstance(self.port_spec, str):
            self._owns_port = False
            return self.port_spec
        self._owns_port = True
        # Everything goes in one call: a pty ignores a later CS8/parity change.
        return serial.serial_for_url(
            self.port_spec,
            baudrate=self.baud,
            bytesize=serial.EIGHTBITS,
            parity=serial.PARITY_NONE,
            stopbits=serial.STOPBITS_ONE,
            timeout=self.poll_interval,
        )

    def _raise_control_lines(self, port: serial.SerialBase) -> None:
        """Assert DTR/RTS; a pty (and some adapters) cannot, which is fine here."""
        try:
            port.dtr = True
            port.rts = True
        except (serial.SerialException, OSError, ValueError):
            self.control_lines = False

    def _require_link(self) -> _SerialLink:
        if self._link is None:
            raise PinchGloveError("the glove is not open")
        return self._link

    def _read_frame(self, start: int) -> PinchSample | None:
        """Collect a frame body after ``start``; count and drop it if it is bad."""
        link = self._require_link()
        body = bytearray()
        while True:
            value = link.read_byte(self.read_timeout)
            if value is None:
                self.bad_frames += 1  # truncated, then silence
                return None
            if value == END:
                break
            if value & 0x80:
                self.bad_frames += 1  # truncated by the next frame: resynchronise there
                link.unread(value)
                return None
            if len(body) == MAX_FRAME_BODY:
                self.bad_frames += 1  # longer than any frame: skip the rest as junk
                link.unread(value)
                return None
            body.append(value)
        frame = decode_frame(start, bytes(body))
        if frame is None:
            self.bad_frames += 1
        return frame

    def _set_echoed(self, command: int, param: int) -> None:
        reply = self._command(command, param)
        if reply[:1] != bytes([param]):
            raise PinchGloveProtocolError(f"command {chr(command)}{chr(param)} answered {reply!r}")

    def _command(self, first: int, second: int) -> bytes:
        """Send a two-byte command and return the text of its info reply."""
        self._send_pair(first, second)
        reply = self._read_reply()
        for _attempt in range(self.command_retries):
            if reply != CONFUSED:
                return reply
            reply = self._recover(first, second)
        if reply == CONFUSED:
            raise PinchGloveProtocolError(f"glove stays confused by {chr(first)}{chr(second)}")
        return reply

    def _recover(self, first: int, second: int) -> bytes:
        """Re-send a command after a ``?`` that the echo check did not catch.

        The glove then holds our second byte as the start of a new command. A
        lone first byte completes that pair (answered by ``?``), after which the
        whole command is sent again. If no ``?`` comes, the glove was in step
        after all and the lone byte already starts the command.
        """
        link = self._require_link()
        link.flush_queues()
        link.write(bytes([first]))
        try:
            answer: bytes | None = self._read_reply()
        except PinchGloveTimeout:
            answer = None
        if answer is None:
            link.write(bytes([second]))
        else:
            self._send_pair(first, second)
        return self._read_reply()

    def _send_pair(self, first: int, second: int) -> None:
        link = self._require_link()
        link.flush_queues()
        link.write(bytes([first]))
        # A stray byte in the glove's buffer pairs with ours and the glove answers
        # '?'; if anything comes back, the first byte starts a fresh command.
        if self._drain(self.echo_wait):
            link.write(bytes([first]))
        if self.command_delay > 0:
            time.sleep(self.command_delay)
        link.write(bytes([second]))

    def _drain(self, wait: float) -> bool:
        """Read and drop up to 10 bytes arriving within ``wait``; True if any came."""
        link = self._require_link()
        deadline = time.monotonic() + wait
        got = 0
        while got < 10:
            if not link.buffer and not link.fill(deadline):
                break
            take = min(10 - got, len(link.buffer))
            del link.buffer[:take]
            got += take
        return got > 0

    def _read_reply(self) -> bytes:
        """Skip to ``0x82`` and collect bytes until ``0x8F``; a bare ``?`` counts too."""
        link = self._require_link()
        scanned = 0
        while True:
            value = self._reply_byte(link)
            scanned += 1
            if value == START_INFO:
                break
            if value in DATA_STARTS:
                # A touch frame in between: skip it whole, its timestamp may be 0x3F.
                while self._reply_byte(link) != END and scanned < MAX_REPLY_SCAN:
                    scanned += 1
            elif value == CONFUSED[0]:
                return CONFUSED
            if scanned >= MAX_REPLY_SCAN:
                raise PinchGloveProtocolError(f"no reply among {scanned} bytes from the glove")
        body = bytearray()
        while True:
            value = self._reply_byte(link)
            if value == END:
                return bytes(body)
            if value == START_INFO:
                body.clear()  # the previous reply was cut short
                continue
            if len(body) == MAX_REPLY:
                raise PinchGloveProtocolError(f"a reply longer than {MAX_REPLY} bytes")
            body.append(value)

    def _reply_byte(self, link: _SerialLink) -> int:
        timeout = self.read_timeout
        deadline = self._setup_deadline
        if deadline is not None:
            timeout = min(timeout, deadline - time.monotonic())
        value = link.read_byte(timeout) if timeout > 0 else None
        if value is None:
            if deadline is not None and time.monotonic() >= deadline:
                raise PinchGloveTimeout(
                    f"the PinchGlove did not complete its setup within {self.setup_timeout:g} s"
                )
            raise PinchGloveTimeout("no reply from the PinchGlove")
        return value
