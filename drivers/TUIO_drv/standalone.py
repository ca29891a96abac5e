"""The TUIO 1.1 cursor protocol (``/tuio/2Dcur`` over OSC over UDP): touch slots from
``source``/``alive``/``set``/``fseq`` messages, and a UDP receiver. OSC is decoded by
:mod:`.osc`, with bounds. Knows nothing of gadgetctl's input manager.

A TUIO frame is a bundle: ``source NAME@ADDRESS`` (TUIO 1.1, optional) says who sends it,
``alive s1 s2 ...`` lists the sessions (fingers) of that source down now, ``set s x y X Y m``
moves session ``s`` to x, y (0 to 1), and ``fseq n`` ends the frame. The frame is applied at
its ``fseq`` (or, without one, at the end of the datagram): a new session takes the lowest free
slot, a session the source no longer lists frees its slot. Other addresses are counted and
ignored.

As the reference TuioClient (TUIO11_JAVA and TUIO11_CPP ``TuioClient``): a frame whose
``fseq`` is positive and lower than the source's last one, by at most 100, is late (UDP
reordered it) and dropped whole (``late_frames``); a larger step back is a restarted sender
and is applied; ``fseq`` 0 or below is applied unordered. Unlike the reference, whose frame
counter is one for all sources, every source keeps its own sessions and frame counter, so two
sources on one port neither lift each other's fingers nor make each other's frames late. A
bundle without ``source`` belongs to the source its sender last named (TUIO 1.0 senders: one
source per sender address). A source that sends no frame for ``SOURCE_TIMEOUT`` seconds
while others send ``SOURCE_FRAMES`` frames is gone: its fingers lift (``forgotten_sources``).

Upstream fixes (Gadgeteer's ``TuioStandalone``): a ``set`` for a session never announced in
``alive`` is counted (``unknown_sessions``) and ignored, where upstream dereferenced a null
pointer; a datagram that is a bare OSC message rather than a bundle is a frame of one message,
where upstream's bundle parser threw. A datagram that is not OSC (:mod:`.osc`: bundles nested
deeper than 8, sizes that do not fit, unknown type tags...) is a bad datagram, and so is one
whose cursor messages are all malformed; a malformed message among good ones (wrong argument
types, more sessions than ``MAX_ALIVE``) is a bad record. Sources beyond ``MAX_SOURCES`` are
counted (``overflow_sources``) and ignored.
"""

from __future__ import annotations

import math
import select
import socket
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from gadgetctl.transport.udp import DatagramLedger, bind_udp

from .osc import OscError, OscMessage, decode_packet

CURSOR_ADDRESS = "/tuio/2Dcur"
DEFAULT_PORT = 3333
#: Most sessions an ``alive`` message may list (a larger list is a bad record).
MAX_ALIVE = 1024
#: Most sources (named ones and sender addresses) one receiver keeps apart.
MAX_SOURCES = 64
#: A frame number this much lower than the last one is a restarted sender, not a late frame.
LATE_WINDOW = 100
#: A source is gone once it sent no frame for this many seconds while the other sources sent
#: ``SOURCE_FRAMES`` frames: its fingers lift and it is forgotten (TUIO senders repeat their
#: frames while nothing moves; a sender restarted from another port is another source). The
#: count keeps a reader that stalled, then reads a backlog, from forgetting everyone.
SOURCE_TIMEOUT = 3.0
SOURCE_FRAMES = 30
MAX_DATAGRAM = 65_535
_INT_LIMIT = 2**31


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


@dataclass
class _Source:
    """What one source has down: session -> slot, and its last frame number."""

    slots: dict[int, int] = field(default_factory=dict)
    last_fseq: int = -1
    seen: float = 0.0  # time.monotonic() of its last frame
    seen_frame: int = 0  # the receiver's frame count at its last frame


@dataclass
class _Frame:
    """The messages of one source's frame, applied together at its ``fseq``."""

    alive: list[int] | None = None
    sets: list[tuple[int, float, float]] = field(default_factory=list)

    @property
    def empty(self) -> bool:
        return self.alive is None and not self.sets


class TouchSlots:
    """``points`` slots: ``down[i]`` is 1 while a session holds slot i, ``xy[i]`` its position.
    Counters: ``bad_records``, ``unknown_sessions``, ``overflow_sessions`` (more fingers than
    slots), ``other_messages``, ``late_frames``, ``overflow_sources``, ``forgotten_sources``
    (silent for ``SOURCE_TIMEOUT`` seconds: their fingers lifted)."""

    def __init__(self, points: int) -> None:
        self.points = points
        self.down = [0] * points
        self.xy = [[0.0, 0.0] for _ in range(points)]
        self.sources: dict[str, _Source] = {}
        self._named: dict[str, str] = {}  # sender address -> the source it last named
        self.bad_records = 0
        self.unknown_sessions = 0
        self.overflow_sessions = 0
        self.other_messages = 0
        self.late_frames = 0
        self.overflow_sources = 0
        self.forgotten_sources = 0
        self._now = 0.0
        self._frames = 0  # frames committed, over every source
        self._pruned_at = -SOURCE_TIMEOUT

    @property
    def sessions(self) -> int:
        """Sessions holding a slot, over every source."""
        return sum(len(s.slots) for s in self.sources.values())

    def apply(self, address: str, params: Sequence[object]) -> bool:
        """One OSC message as a frame of its own; whether it was a good cursor message."""
        return self.frame([OscMessage(address, tuple(params))])[0] > 0

    def frame(
        self, messages: Sequence[OscMessage], sender: str = "", now: float | None = None
    ) -> tuple[int, int, bool]:
        """Apply the messages of one datagram from ``sender`` arriving at ``now``
        (``time.monotonic()``; default: now): (good cursor messages, bad ones, whether a frame
        with cursor data was applied). Sources silent for ``SOURCE_TIMEOUT`` go first."""
        self._now = time.monotonic() if now is None else now
        self._forget_silent_sources()
        source = self._named.get(sender, sender)
        pending = _Frame()
        good = bad = 0
        applied = False
        for message in messages:
            if message.address != CURSOR_ADDRESS:
                self.other_messages += 1
                continue
            args = message.arguments
            command = args[0] if args and isinstance(args[0], str) else None
            ok = True
            if command == "source" and len(args) >= 2 and isinstance(args[1], str):
                if not pending.empty:  # a frame without fseq ends where the next source begins
                    applied |= self._commit(source, pending, None)
                    pending = _Frame()
                source = args[1]
                self._remember(sender, source)
            elif command == "fseq" and len(args) >= 2 and _session(args[1]) is not None:
                applied |= self._commit(source, pending, _session(args[1]))
                pending = _Frame()
            elif command == "alive":
                ok = self._alive(args[1:], pending)
            elif command == "set":
                ok = self._set(args[1:], pending)
            else:
                ok = False
            good += ok
            bad += not ok
        if not pending.empty:  # no fseq after them: applied as a frame (a bare message)
            applied |= self._commit(source, pending, None)
        self.bad_records += bad
        return good, bad, applied

    def _alive(self, values: Sequence[object], pending: _Frame) -> bool:
        sessions = [_session(v) for v in values]
        if len(sessions) > MAX_ALIVE or None in sessions:
            return False
        pending.alive = sessions  # type: ignore[assignment]
        return True

    def _set(self, values: Sequence[object], pending: _Frame) -> bool:
        if len(values) < 3:
            return False
        session, x, y = _session(values[0]), _coordinate(values[1]), _coordinate(values[2])
        if session is None or x is None or y is None:
            return False
        pending.sets.append((session, x, y))
        return True

    def _remember(self, sender: str, source: str) -> None:
        if sender in self._named or len(self._named) < MAX_SOURCES:
            self._named[sender] = source

    def _source(self, name: str) -> _Source | None:
        state = self.sources.get(name)
        if state is None:
            if len(self.sources) >= MAX_SOURCES:
                self.overflow_sources += 1
                return None
            state = self.sources[name] = _Source()
        self._frames += 1
        state.seen, state.seen_frame = self._now, self._frames
        return state

    def _forget_silent_sources(self) -> None:
        if self._now - self._pruned_at < SOURCE_TIMEOUT / 4:
            return
        self._pruned_at = self._now
        gone = [
            name
            for name, s in self.sources.items()
            if self._now - s.seen > SOURCE_TIMEOUT and self._frames - s.seen_frame > SOURCE_FRAMES
        ]
        for name in gone:
            for slot in self.sources.pop(name).slots.values():
                self.down[slot] = 0
                self.xy[slot] = [0.0, 0.0]
            self.forgotten_sources += 1
        for sender in [k for k, v in self._named.items() if v not in self.sources]:
            del self._named[sender]

    def _commit(self, name: str, frame: _Frame, fseq: int | None) -> bool:
        """Apply ``frame`` to source ``name`` unless it is late; whether cursor data changed
        hands (a frame with alive or set messages was applied)."""
        state = self._source(name)
        if state is None:
            return False
        if fseq is not None and fseq > 0:
            if fseq >= state.last_fseq or state.last_fseq - fseq > LATE_WINDOW:
                state.last_fseq = fseq
            else:
                self.late_frames += 1
                return False
        if frame.alive is not None:
            self._alive_now(state, frame.alive)
        for session, x, y in frame.sets:
            slot = state.slots.get(session)
            if slot is None:  # upstream crashed here
                self.unknown_sessions += 1
                continue
            self.xy[slot] = [x, y]
        return not frame.empty

    def _alive_now(self, state: _Source, sessions: list[int]) -> None:
        alive = set(sessions)
        for session in [s for s in state.slots if s not in alive]:
            slot = state.slots.pop(session)
            self.down[slot] = 0
            self.xy[slot] = [0.0, 0.0]
        for session in sessions:
            if session in state.slots:
                continue
            free = next((i for i in range(self.points) if not self.down[i]), None)
            if free is None:
                self.overflow_sessions += 1
                continue
            state.slots[session] = free
            self.down[free] = 1

    def digital(self) -> list[int]:
        return list(self.down)

    def analog(self) -> list[float]:
        return [v for pair in self.xy for v in pair]


class TuioReceiver:
    """Receives TUIO datagrams on UDP ``port`` (0: chosen by the OS) into ``slots``. Its
    ``ledger`` counts every datagram as decoded or bad, and the kernel's drops."""

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

    def feed(self, data: bytes, sender: str = "") -> bool:
        """Judge and apply one datagram from ``sender``; whether it applied a frame with
        cursor data."""
        try:
            packet = decode_packet(data)
        except OscError as err:
            self.ledger.bad(f"not OSC: {err}")
            return False
        good, bad, applied = self.slots.frame(packet.messages, sender)
        if bad and not good:
            self.ledger.bad(f"{bad} malformed {CURSOR_ADDRESS} message" + ("s" * (bad > 1)))
        else:
            self.ledger.decoded()
        return applied

    def sample_all(self, limit: int = 100) -> list[tuple[list[int], list[float]]]:
        """(digital, analog) after each datagram that applied cursor data, of those arriving
        within ``receive_timeout`` (at most ``limit`` datagrams read); raises :class:`TuioDisconnected` after
        ``peer_timeout`` seconds without a datagram."""
        sock = self._sock
        if sock is None:
            raise TuioDisconnected("the receiver is closed")
        states: list[tuple[list[int], list[float]]] = []
        ready, _, _ = select.select([sock], [], [], self.receive_timeout)
        for _ in range(limit if ready else 0):
            try:
                data, address = self.ledger.receive_from(MAX_DATAGRAM)
            except BlockingIOError:
                break
            self._last_data = time.monotonic()
            if self.feed(data, f"{address[0]}:{address[1]}"):
                states.append((self.slots.digital(), self.slots.analog()))
        if not states and time.monotonic() - self._last_data > self.peer_timeout:
            raise TuioDisconnected(
                f"no TUIO data on UDP port {self.port} for {self.peer_timeout:g} s"
            )
        return states
