"""The client side of a VRPN connection, with automatic reconnection.

A :class:`VrpnClient` talks to one server location. It connects as the C++ client does: by
default with the UDP connection request ("lob": it listens on an ephemeral TCP port, sends
``"<ip> <port>\\0"`` to the server's UDP port, re-sent every ``retry_interval`` until the
server calls back), or by direct TCP for ``tcp://`` locations. After the cookie exchange it
announces its UDP channel (lob mode only, so the server sends unreliable reports such as
tracker poses by UDP), describes its senders (the device names) and types, and pings every
device. When the connection drops it starts again: the first retry comes at once, later ones
back off to ``retry_interval`` (the C++ client waits about 2 s; we retry sooner so that data
resume within 2 s of a server's return).

The client runs in the caller's thread: :meth:`VrpnClient.poll` does all I/O and returns
the messages that arrived, their payloads decoded into reports (see :mod:`.codecs`).
"""

from __future__ import annotations

import errno
import os
import select
import socket
import time
from collections import Counter
from collections.abc import Iterable
from typing import Protocol

from .codecs import CLIENT_TYPES, PING, PONG, decode
from .endpoint import ConnectionDropped, Endpoint, NameTable
from .names import Location, parse_location
from .wire import (
    MAX_DATAGRAM,
    SENDER_DESCRIPTION,
    TYPE_DESCRIPTION,
    Block,
    Message,
    lob_request,
    pack_description,
    pack_message,
    pack_udp_description,
)

IDLE = "idle"  # waiting for the next attempt
CONNECTING = "connecting"  # TCP connect or lob under way
HANDSHAKE = "handshake"  # cookies being exchanged
CONNECTED = "connected"
CLOSED = "closed"
#: Seconds a new connection waits for the server's descriptions before describing its own
#: senders anyway.
SETUP_WAIT = 0.5
#: Bytes asked of the kernel for the UDP channel's receive buffer.
UDP_RECEIVE_BUFFER = 4 << 20
#: Datagrams read from the UDP channel per poll at most (the TCP side gets its turn between).
UDP_READS_PER_POLL = 256


class DatagramReceiver(Protocol):
    """What reads the UDP channel when the caller wants more than ``recv`` (for instance the
    kernel's count of the datagrams it dropped): attached to each new channel socket,
    detached when the connection ends. ``decoded()``/``bad(reason)``, when it has them, hear
    what became of each datagram."""

    def attach(self, sock: socket.socket) -> None: ...

    def detach(self) -> None: ...

    def receive(self, size: int) -> bytes: ...


class VrpnClient:
    """A connection to the VRPN server at ``location`` for the named devices."""

    def __init__(
        self,
        location: Location | str,
        devices: Iterable[str] = (),
        *,
        udp_channel: bool = True,
        types: Iterable[str] = CLIENT_TYPES,
        retry_interval: float = 1.0,
        first_retry: float = 0.05,
        handshake_timeout: float = 3.0,
        ping_interval: float = 1.0,
        silence_timeout: float | None = None,
        out_limit: int = 1 << 20,
        decode_reports: bool = True,
        udp_receiver: DatagramReceiver | None = None,
        udp_receive_buffer: int = UDP_RECEIVE_BUFFER,
        bulk: Iterable[tuple[str, str]] = (),
    ) -> None:
        self.location = parse_location(location) if isinstance(location, str) else location
        self.udp_channel = udp_channel and not self.location.tcp
        self.retry_interval = retry_interval
        self.first_retry = first_retry
        self.handshake_timeout = handshake_timeout
        self.ping_interval = ping_interval
        self.silence_timeout = silence_timeout
        self.out_limit = out_limit
        self.decode_reports = decode_reports
        self.udp_receiver = udp_receiver
        self.udp_receive_buffer = udp_receive_buffer
        #: (sender, type) name pairs whose messages :meth:`poll` leaves framed, in blocks
        #: (:meth:`take_blocks`), for a caller that unpacks a whole read at once.
        self.bulk = frozenset(bulk)
        self._blocks: list[Block] = []
        self.senders = NameTable()
        self.types = NameTable()
        for name in devices:
            self.senders.register(name)
        for name in types:
            self.types.register(name)
        self.state = IDLE
        self.last_error: str | None = None
        self.connects = 0  # connections made
        self.drops = 0  # connections lost
        self.counters: Counter[str] = Counter()  # summed over every connection
        self.pongs: Counter[str] = Counter()  # pongs received per device
        self._endpoint: Endpoint | None = None
        self._tcp: socket.socket | None = None  # connecting socket (direct TCP)
        self._listener: socket.socket | None = None  # lob call-back listener
        self._lob: socket.socket | None = None
        self._udp_in: socket.socket | None = None  # our UDP channel
        self._server_ip: str | None = None
        self._local_ip = "127.0.0.1"
        self._next_attempt = 0.0
        self._delay = first_retry
        self._lob_sent = 0.0
        self._state_since = time.monotonic()
        self._last_rx = 0.0
        self._last_ping = 0.0
        self._held: list[Message] = []
        self._senders_described = False

    # -- public -------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        return self.state == CONNECTED

    @property
    def server_version(self) -> str | None:
        return self._endpoint.peer_version if self._endpoint is not None else None

    @property
    def announced(self) -> list[str]:
        """The sender (device) names the server serves: those it described in its setup,
        and those it described later that this client did not describe itself (a C++ server
        describes back, as its own, every unknown name a client describes)."""
        ep = self._endpoint
        if ep is None:
            return []
        ours = set(self.senders.names)
        return sorted(ep.setup_senders | (ep.later_senders - ours))

    @property
    def announced_types(self) -> list[str]:
        ep = self._endpoint
        return sorted(set(ep.remote_types.values())) if ep is not None else []

    def counts(self) -> Counter[str]:
        """Everything counted so far: bad frames, reports, undescribed messages, lobs..."""
        total = Counter(self.counters)
        if self._endpoint is not None:
            total.update(self._endpoint.counters)
        total["connects"], total["drops"] = self.connects, self.drops
        return total

    def add_device(self, name: str) -> None:
        """Describe one more device (sender) and ping it; effective at once when connected."""
        ident, new = self.senders.register(name)
        if (
            new
            and self.state == CONNECTED
            and self._endpoint is not None
            and self._senders_described
        ):
            self._endpoint.queue(pack_description(SENDER_DESCRIPTION, ident, name))
            self._ping(name)

    def send(
        self,
        device: str,
        type_name: str,
        payload: bytes = b"",
        *,
        reliable: bool = True,
        timestamp: float | None = None,
    ) -> bool:
        """Send a message from ``device`` (e.g. a tracker request); False when not connected."""
        ep = self._endpoint
        if self.state != CONNECTED or ep is None:
            return False
        sender, new_sender = self.senders.register(device)
        type_id, new_type = self.types.register(type_name)
        if new_sender:
            ep.queue(pack_description(SENDER_DESCRIPTION, sender, device))
        if new_type:
            ep.queue(pack_description(TYPE_DESCRIPTION, type_id, type_name))
        return ep.queue(pack_message(type_id, sender, payload, timestamp), reliable)

    def wait_connected(self, timeout: float) -> bool:
        """Poll until connected or ``timeout`` passes (messages arriving meanwhile are kept
        for the next :meth:`poll`)."""
        deadline = time.monotonic() + timeout
        while self.state != CONNECTED:
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            self._held.extend(self._poll_once(min(left, 0.05)))
        return True

    def poll(self, timeout: float = 0.0) -> list[Message]:
        """Do the I/O due; the messages that arrive within ``timeout`` (returns at the first,
        or at the first block of :attr:`bulk` messages)."""
        if self._held:
            held, self._held = self._held, []
            return held
        deadline = time.monotonic() + timeout
        while True:
            out = self._poll_once(max(0.0, deadline - time.monotonic()))
            if out or self._blocks or time.monotonic() >= deadline or self.state == CLOSED:
                return out

    def take_blocks(self) -> list[Block]:
        """The blocks of :attr:`bulk` messages read since the last call, oldest first."""
        blocks, self._blocks = self._blocks, []
        return blocks

    def close(self) -> None:
        self._teardown()
        self.state = CLOSED

    def __enter__(self) -> VrpnClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the state machine --------------------------------------------------------------------

    def _poll_once(self, timeout: float) -> list[Message]:
        now = time.monotonic()
        self._timers(now)
        if self.state == CLOSED:
            return []
        readers: list[socket.socket | Endpoint] = []
        writers: list[socket.socket | Endpoint] = []
        ep = self._endpoint
        if ep is not None:
            readers.append(ep)
            if ep.wants_write:
                writers.append(ep)
            if self._udp_in is not None:
                readers.append(self._udp_in)
        if self._listener is not None:
            readers.append(self._listener)
        if self._tcp is not None:
            writers.append(self._tcp)
        wait = max(0.0, min(timeout, self._next_timer(now) - now))
        if not readers and not writers:
            if wait > 0:
                time.sleep(wait)
            return []
        try:
            r, w, _ = select.select(readers, writers, [], wait)
        except (OSError, ValueError):
            r, w = [], []
        out: list[Message] = []
        wall = time.time()
        try:
            if self._tcp is not None and self._tcp in w:
                self._tcp_connected()
            if self._listener is not None and self._listener in r:
                self._accept()
            ep = self._endpoint
            if ep is not None:
                if self._udp_in is not None and self._udp_in in r:
                    out.extend(self._read_udp(ep, wall))
                if ep in r:
                    if self.bulk:
                        messages, blocks = ep.read_bulk(wall, self.bulk)
                        out.extend(self._handle(messages))
                        self._blocks += blocks
                    else:
                        out.extend(self._handle(ep.read(wall)))
                    if ep.opened and self.state == HANDSHAKE:
                        self._opened(ep)
                if self.state == CONNECTED and not self._senders_described:
                    self._describe_senders(ep)
                if self._endpoint is ep and (ep.wants_write or ep in w):
                    ep.flush()
        except ConnectionDropped as exc:
            self._drop(exc.reason)
        except OSError as exc:  # anything else the sockets refuse ends this connection only
            self._drop(f"socket error: {exc.strerror or exc}")
        if out or self._blocks:
            self._last_rx = time.monotonic()
        return out

    def _next_timer(self, now: float) -> float:
        if self.state == IDLE:
            return self._next_attempt
        if self.state == CONNECTING and self._listener is not None:
            return self._lob_sent + self.retry_interval
        if self.state == HANDSHAKE:
            return self._state_since + self.handshake_timeout
        if self.state == CONNECTED:
            due = max(self._last_ping, self._last_rx) + self.ping_interval  # both must be stale
            if not self._senders_described:
                due = min(due, self._state_since + SETUP_WAIT)
            if self.silence_timeout is not None:
                due = min(due, self._last_rx + self.silence_timeout)
            return due
        return now + 1.0

    def _timers(self, now: float) -> None:
        if self.state == IDLE and now >= self._next_attempt:
            self._attempt(now)
        elif self.state == CONNECTING and self._listener is not None:
            if now - self._lob_sent >= self.retry_interval:
                self._send_lob(now)
        elif self.state == HANDSHAKE and now - self._state_since >= self.handshake_timeout:
            self._drop("no VRPN cookie from the server")
        elif self.state == CONNECTED:
            if self.silence_timeout is not None and now - self._last_rx >= self.silence_timeout:
                self._drop(f"nothing from the server for {self.silence_timeout:g} s")
            elif (
                now - self._last_rx >= self.ping_interval
                and now - self._last_ping >= self.ping_interval
            ):
                for name in self.senders.names:
                    self._ping(name)
                if self._endpoint is not None:
                    try:
                        self._endpoint.flush()
                    except ConnectionDropped as exc:
                        self._drop(exc.reason)

    def _set_state(self, state: str) -> None:
        self.state = state
        self._state_since = time.monotonic()

    def _attempt(self, now: float) -> None:
        loc = self.location
        try:
            self._server_ip = socket.gethostbyname(loc.host)
        except (OSError, UnicodeError) as exc:
            self._fail(f"cannot resolve {loc.host!r}: {getattr(exc, 'strerror', None) or exc}")
            return
        addr = (self._server_ip, loc.port)
        try:
            if loc.tcp:
                sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                sock.setblocking(False)
                err = sock.connect_ex(addr)
                if err not in (0, errno.EINPROGRESS, errno.EWOULDBLOCK):
                    sock.close()
                    self._fail(f"cannot connect to {loc}: {os.strerror(err)}")
                    return
                self._tcp = sock
            else:
                lob = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                lob.setblocking(False)
                lob.connect(addr)
                self._local_ip = lob.getsockname()[0]
                listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                listener.bind((self._local_ip, 0))
                listener.listen(1)
                listener.setblocking(False)
                self._lob, self._listener = lob, listener
                self._send_lob(now)
        except OSError as exc:
            self._teardown()
            self._fail(f"cannot reach {loc}: {exc.strerror or exc}")
            return
        self._set_state(CONNECTING)

    def _send_lob(self, now: float) -> None:
        self._lob_sent = now
        if self._lob is None or self._listener is None:
            return
        port = self._listener.getsockname()[1]
        try:
            self._lob.send(lob_request(self._local_ip, port))
            self.counters["lobs_sent"] += 1
        except OSError as exc:  # e.g. ICMP port unreachable from an earlier lob
            self.last_error = f"no VRPN server at {self.location}: {exc.strerror or exc}"

    def _tcp_connected(self) -> None:
        sock, self._tcp = self._tcp, None
        assert sock is not None
        err = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
        if err:
            sock.close()
            self._fail(f"cannot connect to {self.location}: {os.strerror(err)}")
            return
        self._endpoint = self._new_endpoint(sock, tcp_only=True)
        self._set_state(HANDSHAKE)

    def _accept(self) -> None:
        assert self._listener is not None
        try:
            sock, _ = self._listener.accept()
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._fail(f"call-back failed: {exc.strerror or exc}")
            return
        for s in (self._listener, self._lob):
            if s is not None:
                s.close()
        self._listener = self._lob = None
        self._endpoint = self._new_endpoint(sock, tcp_only=False)
        self._set_state(HANDSHAKE)

    def _new_endpoint(self, sock: socket.socket, *, tcp_only: bool) -> Endpoint:
        ep = Endpoint(sock, out_limit=self.out_limit, tcp_only=tcp_only)
        ep.decode = decode if self.decode_reports else None
        return ep

    def _opened(self, ep: Endpoint) -> None:
        """The server's cookie is accepted: announce our channel, names and types; ping."""
        if self.udp_channel:
            udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                udp.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.udp_receive_buffer)
            except OSError:
                pass
            udp.bind((self._local_ip, 0))
            udp.setblocking(False)
            self._udp_in = udp
            if self.udp_receiver is not None:
                self.udp_receiver.attach(udp)
            ep.queue(pack_udp_description(self._local_ip, udp.getsockname()[1]))
        for ident, name in self.types:
            ep.queue(pack_description(TYPE_DESCRIPTION, ident, name))
        self._set_state(CONNECTED)
        self._senders_described = False
        self.connects += 1
        self.last_error = None
        self._delay = self.first_retry
        self._last_rx = time.monotonic()
        self._describe_senders(ep)

    def _describe_senders(self, ep: Endpoint) -> None:
        """Describe our devices (senders) and ping them, once the server's own descriptions
        are in (its first type description ends its senders), or after ``SETUP_WAIT``: a C++
        server describes back every unknown name a client describes, so describing first
        would make any name look served."""
        if self._senders_described:
            return
        if not ep.remote_types and time.monotonic() - self._state_since < SETUP_WAIT:
            return
        self._senders_described = True
        for ident, name in self.senders:
            ep.queue(pack_description(SENDER_DESCRIPTION, ident, name))
        for name in self.senders.names:
            self._ping(name)

    def _ping(self, name: str) -> None:
        ep = self._endpoint
        sender, ping = self.senders.id(name), self.types.id(PING)
        if ep is None or sender is None or ping is None:
            return
        ep.queue(pack_message(ping, sender))
        self._last_ping = time.monotonic()

    def _read_udp(self, ep: Endpoint, wall: float) -> list[Message]:
        """Every datagram waiting (at most :data:`UDP_READS_PER_POLL`), taken as one read."""
        assert self._udp_in is not None
        receiver = self.udp_receiver
        receive = receiver.receive if receiver is not None else self._udp_in.recv
        datagrams: list[bytes] = []
        for _ in range(UDP_READS_PER_POLL):
            try:
                datagrams.append(receive(MAX_DATAGRAM + 64))
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                break
        if not datagrams:
            return []
        messages, blocks, refused = ep.read_datagrams(datagrams, wall, self.bulk)
        self._blocks += blocks
        decoded = getattr(receiver, "decoded", None)
        bad = getattr(receiver, "bad", None)
        if bad is not None and refused:
            bad("a datagram that is not whole VRPN messages", len(refused))
        if decoded is not None and len(datagrams) > len(refused):
            decoded(len(datagrams) - len(refused))
        return self._handle(messages)

    def _handle(self, messages: list[Message]) -> list[Message]:
        """Count the pongs (the reports were decoded by the endpoint)."""
        for m in messages:
            if m.type == PONG and m.sender:
                self.pongs[m.sender] += 1
        return messages

    def _fail(self, reason: str) -> None:
        self.last_error = reason
        self.counters["failed_attempts"] += 1
        self._schedule_retry()

    def _schedule_retry(self) -> None:
        self._set_state(IDLE)
        self._next_attempt = time.monotonic() + self._delay
        self._delay = min(max(self._delay * 2, self.first_retry), self.retry_interval)

    def _drop(self, reason: str) -> None:
        was_connected = self.state == CONNECTED
        self._teardown()
        self.last_error = reason
        self.counters["ended_connections"] += 1
        if was_connected:
            self.drops += 1
        self._schedule_retry()

    def _teardown(self) -> None:
        if self.udp_receiver is not None and self._udp_in is not None:
            self.udp_receiver.detach()
        ep, self._endpoint = self._endpoint, None
        if ep is not None:
            self.counters.update(ep.counters)
            ep.close()
        for attr in ("_tcp", "_listener", "_lob", "_udp_in"):
            s = getattr(self, attr)
            if s is not None:
                try:
                    s.close()
                except OSError:
                    pass
                setattr(self, attr, None)
