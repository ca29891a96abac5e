"""Linux joydev protocol: decode ``struct js_event`` records from a joystick device file.

Knows nothing of gadgetctl. The device file may be a real ``/dev/input/jsN`` node or any
byte stream with the same records (a FIFO, a pipe): the joystick ioctls are optional.

Record layout (``linux/joystick.h``), in the host's byte order (little-endian on x86)::

    u32 time (ms)   s16 value   u8 type   u8 number

``type`` is ``JS_EVENT_BUTTON`` (0x01) or ``JS_EVENT_AXIS`` (0x02), with ``JS_EVENT_INIT``
(0x80) OR-ed in for the burst of current states the kernel sends when the file is opened
(every button first, then every axis).

Differences from Gadgeteer's C++ driver, on purpose:

* The ioctl results are checked (upstream ignored them). When the ioctls fail, as they do on a
  FIFO (``ENOTTY``), the counts come from the configuration or grow with the initial burst.
* End of file and read errors are handled from the read's own result. Upstream looked at a stale
  ``errno`` after a 0-byte read and then dropped the whole sample. Here the events read before
  the end are kept, and the end is reported separately with :class:`JoystickDisconnected`.
* The stream is checked record by record. Implausible records are counted and skipped, and the
  decoder moves forward one byte at a time until it finds a record boundary again.
"""

from __future__ import annotations

import errno
import fcntl
import os
import re
import select
import struct
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol

JS_EVENT_BUTTON = 0x01
JS_EVENT_AXIS = 0x02
JS_EVENT_INIT = 0x80

EVENT_FORMAT = "=IhBB"  # native byte order, standard sizes, no padding
EVENT_SIZE = struct.calcsize(EVENT_FORMAT)  # 8

JSIOCGVERSION = 0x80046A01
JSIOCGAXES = 0x80016A11
JSIOCGBUTTONS = 0x80016A12
NAME_LENGTH = 128
JSIOCGNAME = 0x80006A13 | (NAME_LENGTH << 16)

AXIS_MIN = -32767
AXIS_MAX = 32767

_VALID_TYPES = frozenset(
    {JS_EVENT_BUTTON, JS_EVENT_AXIS, JS_EVENT_BUTTON | JS_EVENT_INIT, JS_EVENT_AXIS | JS_EVENT_INIT}
)


class JoystickError(OSError):
    """The device cannot be used (for example a joydev API that is too old)."""


class JoystickDisconnected(ConnectionError):
    """The device went away: end of file, or a read error such as ``ENODEV``.

    Close the driver and open it again to reconnect.
    """


class _HasFileno(Protocol):
    def fileno(self) -> int: ...


@dataclass(frozen=True)
class JoystickEvent:
    """One decoded ``js_event`` record."""

    time_ms: int
    value: int
    type: int
    number: int

    @property
    def is_init(self) -> bool:
        return bool(self.type & JS_EVENT_INIT)

    @property
    def is_button(self) -> bool:
        return (self.type & ~JS_EVENT_INIT) == JS_EVENT_BUTTON

    @property
    def is_axis(self) -> bool:
        return (self.type & ~JS_EVENT_INIT) == JS_EVENT_AXIS

    def pack(self) -> bytes:
        """The 8 bytes of this record."""
        return struct.pack(
            EVENT_FORMAT, self.time_ms & 0xFFFFFFFF, self.value, self.type, self.number
        )


@dataclass(frozen=True)
class JoystickSample:
    """The joystick state after one :meth:`LinuxJoydevStandalone.sample` call.

    ``buttons`` holds the device's buttons as 0/1, ``virtual_buttons`` the (low, high) pairs made
    from the axes listed in ``axis_buttons``, flattened, and ``axes`` the raw axis values.
    ``events`` lists every record decoded during the call, so quick press/release pairs that
    leave no trace in the state can still be seen.
    """

    time_ms: int
    buttons: tuple[int, ...]
    virtual_buttons: tuple[int, ...]
    axes: tuple[int, ...]
    events: tuple[JoystickEvent, ...]

    @property
    def digital(self) -> tuple[int, ...]:
        """Digital units as Gadgeteer numbers them: buttons, then the virtual axis buttons."""
        return self.buttons + self.virtual_buttons

    def normalized(self, minimum: float = AXIS_MIN, maximum: float = AXIS_MAX) -> tuple[float, ...]:
        """All axes mapped to [0, 1] (see :func:`normalize_axis`)."""
        return tuple(normalize_axis(v, minimum, maximum) for v in self.axes)


def normalize_axis(value: float, minimum: float = AXIS_MIN, maximum: float = AXIS_MAX) -> float:
    """Map a raw value to [0, 1] the way an analog proxy does: clamp, then scale.

    Gadgeteer's joydev driver always uses -32767..32767, whatever the configuration says.
    """
    if maximum <= minimum:
        raise ValueError(f"maximum ({maximum}) must be greater than minimum ({minimum})")
    clamped = min(max(value, minimum), maximum)
    return (clamped - minimum) / (maximum - minimum)


def axis_button_pair(
    value: float, minimum: float = AXIS_MIN, maximum: float = AXIS_MAX
) -> tuple[int, int]:
    """The (low, high) virtual buttons of one axis value.

    Above the middle of the range only "high" is on, below it only "low", exactly in the middle
    neither. There is no dead zone: raw +1 already presses "high".
    """
    n = normalize_axis(value, minimum, maximum)
    return (int(n < 0.5), int(n > 0.5))


def axis_buttons_state(
    axes: Sequence[int],
    axis_buttons: Iterable[int],
    minimum: float = AXIS_MIN,
    maximum: float = AXIS_MAX,
) -> tuple[int, ...]:
    """Virtual buttons for the ``axis_buttons`` list: entry i gives (low, high) at 2i, 2i+1.

    An axis the device does not have gives two released buttons.
    """
    states: list[int] = []
    for axis in axis_buttons:
        if 0 <= axis < len(axes):
            states.extend(axis_button_pair(axes[axis], minimum, maximum))
        else:
            states.extend((0, 0))
    return tuple(states)


_DecoderState = tuple[int, int, "int | None", float, "JoystickEvent | None", bool, int]


_TYPE_OFFSET = 6  # where the type byte sits in a record
_TYPE_BYTE = re.compile(b"[" + re.escape(bytes(sorted(_VALID_TYPES))) + b"]")


def _unpack(buf: bytes | bytearray, pos: int) -> JoystickEvent:
    return JoystickEvent(*struct.unpack_from(EVENT_FORMAT, buf, pos))


class EventDecoder:
    """Splits a byte stream into plausible ``js_event`` records and resynchronises on garbage.

    ``js_event`` has no sync marker, so boundaries are found by plausibility. A record is accepted
    when its type is one of the four the kernel sends, a button value is 0 or 1, and its number
    names a known control. Initial (``JS_EVENT_INIT``) records must follow the kernel's order
    (a burst starts at button 0, or axis 0 without buttons, and goes on with the next button,
    the first axis or the next axis), and may add the next control, which is how the counts grow
    when no ioctl could tell them. Anything else is skipped one byte at a time. While resynchronising, a candidate must also have a believable time: kernel time
    is monotonic milliseconds, so it may not lie more than ``time_slack_ms`` before the last good
    record, nor further after it than the wall-clock time since that record was read plus the
    slack. After ``max_timed_resync`` skipped bytes the time test is dropped, so a stream whose
    clock cannot be trusted (a replayed recording) still recovers. When the bytes right after an
    accepted record make no sense and two good records start inside it, that record was a fake
    built from a cut-off record and is taken back. ``skipped_bytes`` and ``resyncs`` count the
    damage.
    """

    def __init__(
        self,
        num_buttons: int = 0,
        num_axes: int = 0,
        fixed_counts: bool = False,
        *,
        time_slack_ms: int = 1000,
        max_timed_resync: int = 8 * EVENT_SIZE,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.num_buttons = num_buttons
        self.num_axes = num_axes
        self.fixed_counts = fixed_counts
        self.time_slack_ms = time_slack_ms
        self.max_timed_resync = max_timed_resync
        self.skipped_bytes = 0
        self.resyncs = 0
        self._clock = clock
        self._buffer = bytearray()
        self._last_time: int | None = None
        # the previous record, if it was an initial one
        self._last_init: JoystickEvent | None = None
        self._last_read = 0.0
        self._skipped_in_resync = 0  # bytes skipped since the stream went out of sync
        self._in_sync = True

    @property
    def pending(self) -> int:
        """Bytes kept back because they do not yet form a whole record."""
        return len(self._buffer)

    def feed(self, data: bytes) -> list[JoystickEvent]:
        """Add bytes and return every record that became complete."""
        now = self._clock()
        self._buffer += data
        events: list[JoystickEvent] = []
        buf = self._buffer
        pos = 0
        last: tuple[int, _DecoderState] | None = None  # start of, and state before, the last record
        while len(buf) - pos >= EVENT_SIZE:
            event = _unpack(buf, pos)
            if self._plausible(event, now):
                last = (pos, self._save())
                self._accept(event, now)
                events.append(event)
                pos += EVENT_SIZE
                continue
            if last is not None and last[0] == pos - EVENT_SIZE:
                start = self._overlapping_record(buf, *last, now)
                if start is not None:
                    # The record just accepted was a fake: a cut-off record followed by the
                    # first bytes of a real one, which starts inside it. Take it back.
                    events.pop()
                    self._restore(last[1])
                    self.resyncs += 1
                    self.skipped_bytes += start - last[0]
                    pos, last = start, None
                    continue
            last = None
            if self._in_sync:
                self.resyncs += 1
                self._in_sync = False
            # Skip to the next place whose type byte is one the kernel sends: every place in
            # between would fail the type test anyway, so junk costs one search, not a test
            # per byte (/dev/zero, a flood of noise).
            following = _TYPE_BYTE.search(buf, pos + 1 + _TYPE_OFFSET)
            if following is not None:
                skip_to = following.start() - _TYPE_OFFSET
            else:  # keep the tail that may yet become a record
                skip_to = max(pos + 1, len(buf) - EVENT_SIZE + 1)
            self.skipped_bytes += skip_to - pos
            self._skipped_in_resync += skip_to - pos
            pos = skip_to
        del buf[:pos]
        return events

    def _overlapping_record(
        self, buf: bytearray, start: int, before: _DecoderState, now: float
    ) -> int | None:
        """Where a believable pair of records starts inside the record at ``start``, if anywhere.

        Called when the bytes right after an accepted record make no sense. Two plausible records
        in a row, with a believable time, starting inside it mean the accepted one was not real.
        """
        after = self._save()
        for candidate in range(start + 1, start + EVENT_SIZE):
            if len(buf) - candidate < 2 * EVENT_SIZE:
                break
            self._restore(before)
            first = _unpack(buf, candidate)
            if not (self._plausible(first, now) and self._believable_time(first.time_ms, now)):
                continue
            self._accept(first, now)
            if self._plausible(_unpack(buf, candidate + EVENT_SIZE), now):
                self._restore(after)
                return candidate
        self._restore(after)
        return None

    def _save(self) -> _DecoderState:
        return (
            self.num_buttons, self.num_axes, self._last_time, self._last_read, self._last_init,
            self._in_sync, self._skipped_in_resync,
        )  # fmt: skip

    def _restore(self, state: _DecoderState) -> None:
        (
            self.num_buttons, self.num_axes, self._last_time, self._last_read, self._last_init,
            self._in_sync, self._skipped_in_resync,
        ) = state  # fmt: skip

    def finish(self) -> int:
        """Drop an incomplete trailing record (at end of stream); returns its length."""
        dropped = len(self._buffer)
        if dropped:
            self.skipped_bytes += dropped
            if self._in_sync:
                self.resyncs += 1
            self._buffer.clear()
        self._in_sync = True
        self._skipped_in_resync = 0
        return dropped

    def _plausible(self, event: JoystickEvent, now: float) -> bool:
        if event.type not in _VALID_TYPES:
            return False
        if event.is_button and event.value not in (0, 1):
            return False
        count = self.num_buttons if event.is_button else self.num_axes
        if event.number > count or (
            event.number == count and (self.fixed_counts or not event.is_init)
        ):
            return False
        if event.is_init and not self._init_in_order(event):
            return False
        return self._in_sync or self._believable_time(event.time_ms, now)

    def _init_in_order(self, event: JoystickEvent) -> bool:
        if event.number == 0 and (event.is_button or self.num_buttons == 0):
            return True  # the start of a burst (on open, or after the kernel's queue overflowed)
        prev = self._last_init
        if prev is None:
            return False
        if event.is_axis:
            return event.number == (prev.number + 1 if prev.is_axis else 0)
        return prev.is_button and event.number == prev.number + 1

    def _believable_time(self, time_ms: int, now: float) -> bool:
        if self._last_time is None or self._skipped_in_resync > self.max_timed_resync:
            return True
        delta = (time_ms - self._last_time) & 0xFFFFFFFF
        if delta >= 1 << 31:
            delta -= 1 << 32  # 32-bit wrap: a small negative step
        ahead = (now - self._last_read) * 1000.0 + self.time_slack_ms
        return -self.time_slack_ms <= delta <= ahead

    def _accept(self, event: JoystickEvent, now: float) -> None:
        self._in_sync = True
        self._skipped_in_resync = 0
        self._last_time = event.time_ms
        self._last_read = now
        self._last_init = event if event.is_init else None
        if event.is_button:
            self.num_buttons = max(self.num_buttons, event.number + 1)
        else:
            self.num_axes = max(self.num_axes, event.number + 1)


class LinuxJoydevStandalone:
    """Reads a Linux joystick device file without blocking.

    ``port`` is a path (opened ``O_RDONLY | O_NONBLOCK``) or an already-open file object; an
    injected object is switched to non-blocking mode and is not closed by :meth:`close`.

    ``num_buttons``/``num_axes`` give the counts to use when the ``JSIOCG*`` ioctls fail (a FIFO);
    the arrays still grow if the initial burst shows more. ``poll_timeout`` is how long
    :meth:`sample` waits for the first byte. ``connect_timeout`` is how long an open stream may
    stay at end-of-file before anything arrived: a FIFO reads as EOF until its writer opens it,
    while a real device always sends its initial burst at once. ``time_slack_ms`` tunes the
    resynchronisation (see :class:`EventDecoder`). One :meth:`sample` reads at most ``max_read``
    bytes (8 KiB: a second of a busy joystick), so a file that never runs dry (``/dev/zero``,
    a flood of junk) cannot keep it, or the device's thread, from returning.
    """

    def __init__(
        self,
        port: str | os.PathLike[str] | _HasFileno = "/dev/js0",
        *,
        axis_buttons: Sequence[int] = (),
        num_buttons: int | None = None,
        num_axes: int | None = None,
        poll_timeout: float = 0.0,
        connect_timeout: float = 1.0,
        read_size: int = 64 * EVENT_SIZE,
        max_read: int = 16 * 64 * EVENT_SIZE,
        time_slack_ms: int = 1000,
    ) -> None:
        self.port = port
        self.max_read = max_read
        self.axis_buttons = tuple(axis_buttons)
        self.configured_buttons = num_buttons
        self.configured_axes = num_axes
        self.poll_timeout = poll_timeout
        self.connect_timeout = connect_timeout
        self.read_size = read_size
        self.time_slack_ms = time_slack_ms
        self.name: str | None = None
        self.version: int | None = None
        self.decoder = EventDecoder()
        self._fd: int | None = None
        self._owns_fd = False
        self._buttons: list[int] = []
        self._axes: list[int] = []
        self._time_ms = 0
        self._opened_at = 0.0
        self._seen_data = False
        self._lost: str | None = None

    # -- life cycle -------------------------------------------------------------------------

    @property
    def is_open(self) -> bool:
        return self._fd is not None

    def open(self) -> None:
        """Open the device and read its identity through the ioctls, when they work."""
        if self._fd is not None:
            return
        if isinstance(self.port, (str, os.PathLike)):
            self._fd = os.open(self.port, os.O_RDONLY | os.O_NONBLOCK)
            self._owns_fd = True
        else:
            self._fd = self.port.fileno()
            self._owns_fd = False
            os.set_blocking(self._fd, False)
        try:
            self._query_device()
        except BaseException:
            self.close()
            raise
        self._buttons = [0] * self.decoder.num_buttons
        self._axes = [0] * self.decoder.num_axes
        self._time_ms = 0
        self._opened_at = time.monotonic()
        self._seen_data = False
        self._lost = None

    def close(self) -> None:
        """Close the device (an injected file object is left open)."""
        fd, self._fd = self._fd, None
        if fd is not None and self._owns_fd:
            os.close(fd)

    def __enter__(self) -> LinuxJoydevStandalone:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- reading ----------------------------------------------------------------------------

    @property
    def skipped_bytes(self) -> int:
        """Bytes dropped as garbage or as truncated records, over all connections."""
        return self.decoder.skipped_bytes

    @property
    def resyncs(self) -> int:
        """How many times the stream lost its record boundaries, over all connections."""
        return self.decoder.resyncs

    def sample(self) -> JoystickSample:
        """Read every available record, update the state and return it.

        Raises :class:`JoystickDisconnected` when the stream has ended. Records that arrived
        just before the end are returned first; the exception comes with the next call.
        """
        if self._fd is None:
            raise RuntimeError("the joystick is not open")
        if self._lost is not None:
            raise JoystickDisconnected(self._lost)
        self._wait_readable()
        events, ended, error = self._read_available()
        for event in events:
            self._apply(event)
        if ended and not self._seen_data:
            if time.monotonic() - self._opened_at > self.connect_timeout:
                self._lost = f"{self._port_label()}: nothing to read (no writer)"
                raise JoystickDisconnected(self._lost)
            # A FIFO without a writer yet: behave as if nothing were available.
            time.sleep(min(self.poll_timeout, self.connect_timeout))
            ended = False
        if ended or error:
            self.decoder.finish()
            self._lost = f"{self._port_label()}: {error or 'end of file'}"
            if not events:
                raise JoystickDisconnected(self._lost)
        return self._snapshot(events)

    def state(self) -> JoystickSample:
        """The current state without reading."""
        return self._snapshot([])

    # -- internals ----------------------------------------------------------------------------

    def _port_label(self) -> str:
        return (
            os.fspath(self.port) if isinstance(self.port, (str, os.PathLike)) else repr(self.port)
        )

    def _query_device(self) -> None:
        """Ask the kernel for version, counts and name; a FIFO answers ENOTTY to all of them."""
        assert self._fd is not None
        self.version = _ioctl_u32(self._fd, JSIOCGVERSION)
        if self.version is not None and self.version >> 16 < 1:
            raise JoystickError(
                errno.EPROTO, f"joydev API version {self.version:#x} is older than 1.0"
            )
        axes = _ioctl_u8(self._fd, JSIOCGAXES)
        buttons = _ioctl_u8(self._fd, JSIOCGBUTTONS)
        self.name = _ioctl_name(self._fd)
        fixed = axes is not None and buttons is not None
        previous = self.decoder
        self.decoder = EventDecoder(
            num_buttons=buttons if buttons is not None else (self.configured_buttons or 0),
            num_axes=axes if axes is not None else (self.configured_axes or 0),
            fixed_counts=fixed,
            time_slack_ms=self.time_slack_ms,
        )
        # the counters survive a reconnection
        self.decoder.skipped_bytes, self.decoder.resyncs = previous.skipped_bytes, previous.resyncs

    def _wait_readable(self) -> None:
        if self.poll_timeout > 0:
            select.select([self._fd], [], [], self.poll_timeout)

    def _read_available(self) -> tuple[list[JoystickEvent], bool, str | None]:
        """Read what is there, up to ``max_read`` bytes: (events, end of file, error text)."""
        assert self._fd is not None
        events: list[JoystickEvent] = []
        budget = self.max_read
        while budget > 0:
            try:
                chunk = os.read(self._fd, min(self.read_size, budget))
            except BlockingIOError:
                return events, False, None
            except InterruptedError:
                continue
            except OSError as exc:
                return events, False, os.strerror(exc.errno) if exc.errno else str(exc)
            if not chunk:
                return events, True, None
            budget -= len(chunk)
            self._seen_data = True
            events.extend(self.decoder.feed(chunk))
        return events, False, None

    def _apply(self, event: JoystickEvent) -> None:
        self._time_ms = event.time_ms
        target = self._buttons if event.is_button else self._axes
        if event.number >= len(target):
            target.extend([0] * (event.number + 1 - len(target)))
        target[event.number] = event.value

    def _snapshot(self, events: list[JoystickEvent]) -> JoystickSample:
        # Counts may have grown in the decoder before any record touched the new slots.
        if len(self._buttons) < self.decoder.num_buttons:
            self._buttons.extend([0] * (self.decoder.num_buttons - len(self._buttons)))
        if len(self._axes) < self.decoder.num_axes:
            self._axes.extend([0] * (self.decoder.num_axes - len(self._axes)))
        return JoystickSample(
            time_ms=self._time_ms,
            buttons=tuple(self._buttons),
            virtual_buttons=axis_buttons_state(self._axes, self.axis_buttons),
            axes=tuple(self._axes),
            events=tuple(events),
        )


def _ioctl_bytes(fd: int, request: int, size: int) -> bytes | None:
    buf = bytearray(size)
    try:
        fcntl.ioctl(fd, request, buf, True)
    except OSError:
        return None
    return bytes(buf)


def _ioctl_u32(fd: int, request: int) -> int | None:
    raw = _ioctl_bytes(fd, request, 4)
    return None if raw is None else struct.unpack("=I", raw)[0]


def _ioctl_u8(fd: int, request: int) -> int | None:
    raw = _ioctl_bytes(fd, request, 1)
    return None if raw is None else raw[0]


def _ioctl_name(fd: int) -> str | None:
    raw = _ioctl_bytes(fd, JSIOCGNAME, NAME_LENGTH)
    return None if raw is None else raw.split(b"\0", 1)[0].decode("utf-8", "replace")
