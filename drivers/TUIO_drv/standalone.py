"""The TUIO 1.x cursor protocol (``/tuio/2Dcur`` over OSC over UDP): touch slots from
``alive``/``set`` messages, and a UDP receiver. OSC itself is decoded by ``python-osc``.
Knows nothing of gadgetctl's input manager.

``alive s1 s2 ...`` lists the sessions (fingers) down now: a new session takes the lowest free
slot, a session no longer listed frees its slot. ``set s x y X Y m`` moves session ``s`` to
x, y (0 to 1). ``fseq n`` ends a frame (ignored here). Other addresses are counted and ignored.

Upstream fixes (Gadgeteer's ``TuioStandalone``): a ``set`` for a session never announced in
``alive`` is counted (``unknown_sessions``) and ignored, where upstream dereferenced a null
pointer; a datagram that is a bare OSC message rather than a bundle is decoded like a bundle
of one message, where upstream's bundle parser threw. A datagram that is not OSC at all is a
counted bad datagram; a message with wrong argument types, or more sessions than
``MAX_ALIVE``, is a counted bad record.
"""

from __future__ import annotations

import math
import select
import socket
import struct
import time

from pythonosc.osc_packet import OscPacket, ParseError

from gadgetctl.transport.udp import DatagramLedger, bind_udp

CURSOR_ADDRESS = "/tuio/2Dcur"
DEFAULT_PORT = 3333
#: Most sessions an ``alive`` message may list (a larger list is a bad record).
MAX_ALIVE = 1024
MAX_DATAGRAM = 65_535
_INT_LIMIT = 2**31

#: What python-osc may raise on a datagram that is not OSC.
DECODE_ERRORS = (ParseError, ValueError, IndexError, struct.error, UnicodeError, TypeError)


class TuioDisconnected(ConnectionError):
    """No TUIO datagram arrived for longer than the receiver's peer timeout."""


def _session(value: object) -> int | None:
    if isinstance(value, int) and not isinstance(value, bool) and -_INT_LIMIT <= value < _INT_LIMIT:
        return value
    return None


def _coordinate(value: object) -> float | None:
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


class TouchSlots:
    """``points`` slots: ``down[i]`` is 1 while a session holds slot i, ``xy[i]`` its position.
    Counters: ``bad_records``, ``unknown_sessions``, ``overflow_sessions`` (more fingers than
    slots), ``other_messages``."""

    def __init__(self, points: int) -> None:
        self.points = points
        self.down = [0] * points
        self.xy = [[0.0, 0.0] for _ in range(points)]
        self._slot: dict[int, int] = {}  # session -> slot
        self.bad_records = 0
        self.unknown_sessions = 0
        self.overflow_sessions = 0
        self.other_messages = 0

    def apply(self, address: str, params: list[object]) -> bool:
        """Apply one OSC message; whether it was a TUIO cursor message."""
        if address != CURSOR_ADDRESS:
            self.other_messages += 1
            return False
        if not params or not isinstance(params[0], str):
            self.bad_records += 1
            return True
        command = params[0]
        if command == "alive":
            self._alive(params[1:])
        elif command == "set":
            self._set(params[1:])
        elif command != "fseq":
            self.bad_records += 1
        return True

    def _alive(self, values: list[object]) -> None:
        sessions = [_session(v) for v in values]
        if len(sessions) > MAX_ALIVE or None in sessions:
            self.bad_records += 1
            return
        alive = set(sessions)
        for session in [s for s in self._slot if s not in alive]:
            slot = self._slot.pop(session)
            self.down[slot] = 0
            self.xy[slot] = [0.0, 0.0]
        for session in sessions:
            if session in self._slot:
                continue
            free = next((i for i in range(self.points) if not self.down[i]), None)
            if free is None:
                self.overflow_sessions += 1
                continue
            self._slot[session] = free  # type: ignore[index]
            self.down[free] = 1

    def _set(self, values: list[object]) -> None:
        if len(values) < 3:
            self.bad_records += 1
            return
        session, x, y = _session(values[0]), _coordinate(values[1]), _coordinate(values[2])
        if session is None or x is None or y is None:
            self.bad_records += 1
            return
        slot = self._slot.get(session)
        if slot is None:  # upstream crashed here
            self.unknown_sessions += 1
            return
        self.xy[slot] = [x, y]

    def digital(self) -> list[int]:
        return list(self.down)

    def analog(self) -> list[float]:
        return [v for pair in self.xy for v in pair]


def decode(data: bytes) -> list[tuple[str, list[object]]]:
    """The OSC messages of a datagram (a bundle, nested bundles or a bare message), in order;
    raises one of :data:`DECODE_ERRORS` when it is not OSC."""
    return [(t.message.address, list(t.message.params)) for t in OscPacket(data).messages]


class TuioReceiver:
    """Receives TUIO datagrams on UDP ``port`` (0: chosen by the OS) into ``slots``.
    Counters: ``datagrams``, ``bad_datagrams``, ``kernel_dropped`` (and the slots')."""

    def __init__(
        self,
        port: int = DEFAULT_PORT,
        points: int = 10,
        *,
        receive_timeout: float = 0.1,
        peer_timeout: float = 2.0,
        receive_buffer: int = 1024 * 1024,
    ) -> None:
        self.requested_port = port
        self.slots = TouchSlots(points)
        self.receive_timeout = receive_timeout
        self.peer_timeout = peer_timeout
        self.receive_buffer = receive_buffer
        #: every datagram read, counted decoded or bad, and the kernel's drops
        self.ledger = DatagramLedger()
        self._sock: socket.socket | None = None
        self._last_data = time.monotonic()

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    @property
    def port(self) -> int:
        return self.requested_port if self._sock is None else self._sock.getsockname()[1]

    @property
    def kernel_dropped(self) -> int:
        return self.ledger.kernel_dropped

    @property
    def datagrams(self) -> int:
        return self.ledger.datagrams

    @property
    def bad_datagrams(self) -> int:
        return self.ledger.bad_count

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.receive_buffer)
            bind_udp(sock, "", self.requested_port)
        except OSError:
            sock.close()
            raise
        sock.setblocking(False)
        self._sock = sock
        self.ledger.attach(sock)
        self._last_data = time.monotonic()

    def close(self) -> None:
        if self._sock is not None:
            self.ledger.detach()
            self._sock.close()
            self._sock = None

    def feed(self, data: bytes) -> bool:
        """Apply one datagram; whether it held TUIO cursor messages."""
        try:
            messages = decode(data)
        except DECODE_ERRORS as err:
            self.ledger.bad(f"not OSC: {err}")
            return False
        self.ledger.decoded()
        touched = False
        for address, params in messages:
            touched |= self.slots.apply(address, params)
        return touched

    def sample_all(self, limit: int = 100) -> list[tuple[list[int], list[float]]]:
        """(digital, analog) after each datagram with cursor messages that arrives within
        ``receive_timeout`` (at most ``limit``); raises :class:`TuioDisconnected` after
        ``peer_timeout`` seconds without a datagram."""
        sock = self._sock
        if sock is None:
            raise TuioDisconnected("the receiver is closed")
        states: list[tuple[list[int], list[float]]] = []
        ready, _, _ = select.select([sock], [], [], self.receive_timeout)
        while ready and len(states) < limit:
            try:
                data = self.ledger.receive(MAX_DATAGRAM)
            except BlockingIOError:
                break
            self._last_data = time.monotonic()
            if self.feed(data):
                states.append((self.slots.digital(), self.slots.analog()))
        if not states and time.monotonic() - self._last_data > self.peer_timeout:
            raise TuioDisconnected(
                f"no TUIO data on UDP port {self.port} for {self.peer_timeout:g} s"
            )
        return states
