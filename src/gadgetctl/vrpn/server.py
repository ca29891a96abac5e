"""The server side of VRPN: one TCP listener and one UDP socket on the same port.

:class:`VrpnServer` accepts clients both ways a C++ client connects: direct TCP, and the UDP
connection request ("lob") to which the server answers by connecting back to the TCP port
named in the datagram. Each client gets the cookie, then a description of every sender and
type the server registered (names registered later are announced on the spot), then the
device messages passed to :meth:`VrpnServer.send`. Every ping is answered with a pong from
the same sender.

Sending never waits for a client: each message is framed once and queued in every client's
bounded output buffer; a client whose buffer is full loses that message (counted in
``ServerClient.dropped``), so a stalled or vanished client never delays the caller or the
other clients. Unreliable messages go by UDP to clients that announced a UDP channel.

Deviations from the C++ server, for safety: a lob is honoured only when the host it names is
the datagram's own source address (so the server cannot be made to connect to a third host),
``allow`` may restrict which addresses are served, and a client that does not complete the
cookie exchange within ``handshake_timeout`` is closed.

Input is budgeted per client and pass (:data:`READ_BUDGET` bytes, :data:`MESSAGE_BUDGET`
messages): a client that floods the server (pings at megabytes a second) is served at that
pace, its excess left waiting (in its socket, or read and handled in the next passes;
counted in ``input_deferred`` and ``messages_deferred``), so it never holds up a pass, the
frames of the thread that polls, or the other clients.

Thread use: :meth:`poll` runs the I/O (typically in a thread of its own); :meth:`send`,
:meth:`register_sender` and the others may be called from any thread.
"""

from __future__ import annotations

import errno
import ipaddress
import os
import select
import socket
import threading
import time
from collections import Counter
from collections.abc import Callable

from .codecs import BASE_TYPES, PING, PONG
from .endpoint import ConnectionDropped, Endpoint, NameTable
from .wire import (
    DEFAULT_PORT,
    MAX_SEND_MESSAGE,
    SENDER_DESCRIPTION,
    TYPE_DESCRIPTION,
    LobError,
    Message,
    pack_description,
    pack_message,
    parse_lob,
)

CONNECTING = "connecting"
HANDSHAKE = "handshake"
OPEN = "open"

#: Connections the kernel completes and holds for the server before it accepts them (capped
#: by ``net.core.somaxconn``). A burst of connects beyond it has its SYNs dropped, and each
#: such client waits a second for its retry: at 16, every 17th of a burst did.
LISTEN_BACKLOG = 1024

#: Each client's input budget per pass of :meth:`VrpnServer.poll`: at most this many bytes
#: read from its socket (what is left waits in the kernel, and TCP slows the sender down)...
READ_BUDGET = 4096
#: ...and at most this many of its messages handled (pings answered, messages passed on);
#: the rest of a read waits for the next passes, during which its socket is not read.
#: So a client flooding the server costs a pass a bounded amount of work, and the frames
#: and the other clients of the same thread wait at most that long for it.
MESSAGE_BUDGET = 32


class ServerClient:
    """One client of a :class:`VrpnServer`."""

    def __init__(self, ident: int, mode: str, address: tuple[str, int]) -> None:
        self.id = ident
        self.mode = mode  # "tcp" (direct) or "lob" (called back)
        self.address = address
        self.state = CONNECTING if mode == "lob" else HANDSHAKE
        self.since = time.monotonic()
        self.endpoint: Endpoint | None = None
        self.sock: socket.socket | None = None  # while the call-back connect is under way
        self.closed = False
        #: Messages read but over this pass's budget: handled by the next passes (at most
        #: one read's worth: the socket is not read again until they are).
        self.pending: list[Message] = []
        #: Passes in which this client used its whole input budget (more input waited).
        self.deferred = 0

    @property
    def dropped(self) -> int:
        """Messages lost because this client's output buffer was full."""
        return self.endpoint.dropped if self.endpoint is not None else 0

    @property
    def sent(self) -> int:
        return self.endpoint.sent_messages if self.endpoint is not None else 0

    @property
    def queued_bytes(self) -> int:
        return len(self.endpoint.out) if self.endpoint is not None else 0

    @property
    def version(self) -> str | None:
        return self.endpoint.peer_version if self.endpoint is not None else None

    @property
    def udp(self) -> bool:
        return self.endpoint is not None and self.endpoint.udp is not None

    def __repr__(self) -> str:
        return (
            f"<ServerClient {self.id} {self.mode} {self.address[0]}:{self.address[1]} {self.state}>"
        )


class VrpnServer:
    """A VRPN server on ``host:port`` (127.0.0.1 and 3883 unless told; port 0: any free one)."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        max_clients: int = 256,
        client_buffer: int = 1 << 20,
        allow: Callable[[str], bool] | None = None,
        handshake_timeout: float = 5.0,
        max_pending: int = 64,
        socket_buffer: int | None = None,
    ) -> None:
        self.host = host
        self.port = port
        self.max_clients = max_clients
        self.client_buffer = client_buffer
        self.allow = allow
        self.handshake_timeout = handshake_timeout
        self.max_pending = max_pending
        #: SO_SNDBUF of client sockets (None: the system's), so a stalled client's backlog
        #: stays in the bounded, counted buffer instead of the kernel's.
        self.socket_buffer = socket_buffer
        self.senders = NameTable()
        self.types = NameTable()
        for name in BASE_TYPES:
            self.types.register(name)
        self.on_connect: Callable[[ServerClient], None] | None = None
        self.on_disconnect: Callable[[ServerClient, str], None] | None = None
        self.on_ping: Callable[[ServerClient, str], None] | None = None
        self.on_message: Callable[[ServerClient, Message], None] | None = None
        self.counters: Counter[str] = Counter()
        self._clients: dict[int, ServerClient] = {}
        self._open_clients = 0  # of them, those whose handshake is done
        self._open_pairs: tuple[tuple[ServerClient, Endpoint], ...] | None = None
        #: Output was queued without being written since the last flush of every client.
        self._output_queued = False
        self._by_endpoint: dict[int, ServerClient] = {}
        self._next_id = 0
        self._closed_dropped = 0
        self._lock = threading.RLock()
        self._tcp: socket.socket | None = None
        self._udp: socket.socket | None = None
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._woken = False
        self._closed = False

    # -- life cycle ---------------------------------------------------------------------------

    def start(self) -> VrpnServer:
        """Bind the TCP and UDP sockets on one port; :class:`OSError` when it is taken."""
        for _ in range(20):
            tcp = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            tcp.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                tcp.bind((self.host, self.port))
                port = tcp.getsockname()[1]
                udp.bind((self.host, port))
            except OSError as exc:
                tcp.close()
                udp.close()
                if self.port == 0 and exc.errno == errno.EADDRINUSE:
                    continue  # the UDP port of an OS-chosen TCP port was taken: pick again
                raise
            tcp.listen(LISTEN_BACKLOG)
            tcp.setblocking(False)
            udp.setblocking(False)
            self._tcp, self._udp, self.port = tcp, udp, port
            return self
        raise OSError(errno.EADDRINUSE, "no port free for both TCP and UDP")

    @property
    def address(self) -> tuple[str, int]:
        return self.host, self.port

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            for client in list(self._clients.values()):
                self._close_client(client, "server closed")
            for s in (self._tcp, self._udp, self._wake_r, self._wake_w):
                if s is not None:
                    s.close()

    def __enter__(self) -> VrpnServer:
        return self.start() if self._tcp is None else self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- names --------------------------------------------------------------------------------

    def register_sender(self, name: str) -> int:
        """The id of sender (device) ``name``; a new one is described to every open client."""
        with self._lock:
            ident, new = self.senders.register(name)
            if new:
                self._announce(pack_description(SENDER_DESCRIPTION, ident, name))
            return ident

    def register_type(self, name: str) -> int:
        """The id of message type ``name``; a new one is described to every open client."""
        with self._lock:
            ident, new = self.types.register(name)
            if new:
                self._announce(pack_description(TYPE_DESCRIPTION, ident, name))
            return ident

    def _announce(self, data: bytes) -> None:
        for client in self._clients.values():
            if client.state == OPEN and client.endpoint is not None:
                client.endpoint.queue(data)
        self._wake()

    # -- sending ------------------------------------------------------------------------------

    @property
    def clients(self) -> list[ServerClient]:
        with self._lock:
            return list(self._clients.values())

    @property
    def audience(self) -> bool:
        """Whether some client is open (its handshake done): someone reads what is sent."""
        return self._open_clients > 0

    @property
    def dropped(self) -> int:
        """Messages lost to full client buffers, clients gone included."""
        with self._lock:
            return self._closed_dropped + sum(c.dropped for c in self._clients.values())

    def send(
        self,
        sender: int,
        type_id: int,
        payload: bytes = b"",
        *,
        timestamp: float | None = None,
        reliable: bool = True,
        flush: bool = True,
    ) -> int:
        """Queue one message for every open client; how many took it (the others dropped it).

        With ``flush=False`` the bytes are written by the next :meth:`poll` or :meth:`flush`
        (a thread blocked in :meth:`poll` is woken), which lets a caller send a batch cheaply.
        """
        data = pack_message(type_id, sender, payload, timestamp)
        if len(data) > MAX_SEND_MESSAGE:
            raise ValueError(f"a VRPN message is at most {MAX_SEND_MESSAGE} bytes")
        taken = 0
        with self._lock:
            for client in self._clients.values():
                if client.state == OPEN and client.endpoint is not None:
                    taken += client.endpoint.queue(data, reliable)
            if flush:
                self._flush_all()
            else:
                self._wake()
        return taken

    def broadcast(
        self, data: bytes, size: int, *, reliable: bool = True, flush: bool = False
    ) -> int:
        """Queue already framed messages of ``size`` bytes each (e.g. from :mod:`.batch`) for
        every open client; how many messages all clients together took. A client's full
        buffer drops whole messages, counted in its ``dropped``. Without ``flush`` nothing is
        written yet (:meth:`flush` or :meth:`poll` does); with it, each client is written at
        once what its socket takes, from ``data`` itself when nothing waits before it (one
        bytes object for every client, not a copy per client)."""
        if size <= 0 or len(data) % size or size > MAX_SEND_MESSAGE:
            raise ValueError(f"{len(data)} bytes are not whole messages of {size} bytes")
        count = len(data) // size
        if not count:
            return 0
        taken = 0
        left = not flush  # output left for a poll to write
        with self._lock:
            for client, ep in self._open_endpoints():
                try:
                    if flush and not ep.out and (reliable or ep.udp is None):
                        taken += ep.write_batch(data, size, count)  # the usual: straight out
                    else:
                        taken += ep.queue_batch(data, size, reliable, write=flush)
                except ConnectionDropped as exc:
                    self._close_client(client, exc.reason)
                    continue
                if ep.out:
                    left = True
            if left:
                self._wake()  # a poll under way must watch the output left
        return taken

    def _open_endpoints(self) -> tuple[tuple[ServerClient, Endpoint], ...]:
        """The open clients and their endpoints, kept until a client opens or closes."""
        pairs = self._open_pairs
        if pairs is None:
            pairs = self._open_pairs = tuple(
                (client, client.endpoint)
                for client in self._clients.values()
                if client.state == OPEN and client.endpoint is not None
            )
        return pairs

    def send_to(
        self,
        client: ServerClient,
        sender: int,
        type_id: int,
        payload: bytes = b"",
        *,
        timestamp: float | None = None,
        reliable: bool = True,
    ) -> bool:
        """Queue one message for one client (e.g. button states when it connects)."""
        with self._lock:
            ep = client.endpoint
            if client.state != OPEN or ep is None:
                return False
            ok = ep.queue(pack_message(type_id, sender, payload, timestamp), reliable)
            self._wake()
            return ok

    def flush(self) -> None:
        """Write queued bytes to every client as far as their sockets take them now."""
        with self._lock:
            self._flush_all()

    def _flush_all(self) -> None:
        self._output_queued = False
        for client in list(self._clients.values()):
            ep = client.endpoint
            if ep is not None and client.state == OPEN:
                try:
                    ep.flush()
                except ConnectionDropped as exc:
                    self._close_client(client, exc.reason)

    def _wake(self) -> None:
        self._output_queued = True
        if not self._woken:
            self._woken = True
            try:
                self._wake_w.send(b"x")
            except OSError:
                pass

    # -- the I/O loop -------------------------------------------------------------------------

    def poll(self, timeout: float = 0.0) -> None:
        """Accept, call back, read and write for at most ``timeout`` seconds (one pass)."""
        with self._lock:
            if self._closed or self._tcp is None or self._udp is None:
                raise RuntimeError("the server is not running")
            if self._open_clients < len(self._clients):  # some handshake is under way
                self._expire(time.monotonic())
            readers: list = [self._tcp, self._udp, self._wake_r]
            writers: list = []
            backlog: list[ServerClient] = []  # messages read in an earlier pass wait
            for client in self._clients.values():
                if client.sock is not None:
                    writers.append(client.sock)
                elif client.endpoint is not None:
                    if client.pending:
                        backlog.append(client)
                    else:
                        readers.append(client.endpoint)
                    if client.endpoint.out:  # bytes its socket did not take yet
                        writers.append(client.endpoint)
            if backlog:
                timeout = 0.0
        try:
            r, w, _ = select.select(readers, writers, [], timeout)
        except (OSError, ValueError):
            return  # a socket closed under us by another thread: next pass
        with self._lock:
            if self._closed:
                return
            wall = time.time()
            for ready in r:
                if ready is self._wake_r:
                    self._drain_wake()
                elif ready is self._tcp:
                    self._accept()
                elif ready is self._udp:
                    self._lobs()
                else:
                    self._read(ready, wall)
            for client in backlog:
                if not client.closed:
                    self._handle(client, client.pending)
            for ready in w:
                if isinstance(ready, Endpoint):
                    client = self._client_of(ready)
                    if client is not None:
                        try:
                            ready.flush()
                        except ConnectionDropped as exc:
                            self._close_client(client, exc.reason)
                else:
                    self._called_back(ready)
            # what was queued since the last pass (every queueing wakes the poll), and what
            # this pass read, accepted or answered: written as far as the sockets take it
            if self._output_queued or r or w or backlog:
                self._flush_all()

    def _drain_wake(self) -> None:
        try:
            while self._wake_r.recv(4096):
                pass
        except OSError:
            pass
        self._woken = False

    def _client_of(self, ep: Endpoint) -> ServerClient | None:
        client = self._by_endpoint.get(id(ep))
        return client if client is not None and not client.closed else None

    def _permitted(self, ip: str) -> bool:
        if self.allow is None:
            return True
        try:
            return bool(self.allow(ip))
        except Exception:
            return False

    def _new_client(self, mode: str, address: tuple[str, int], sock: socket.socket) -> ServerClient:
        if self.socket_buffer is not None:
            try:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, self.socket_buffer)
            except OSError:
                pass
        client = ServerClient(self._next_id, mode, address)
        self._next_id += 1
        self._clients[client.id] = client
        return client

    def _accept(self) -> None:
        """Accept every connection waiting (at most a full backlog) in this one pass."""
        assert self._tcp is not None
        for _ in range(LISTEN_BACKLOG):
            try:
                sock, address = self._tcp.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self.counters["accept_errors"] += 1
                return
            if not self._permitted(address[0]):
                self.counters["refused"] += 1
                sock.close()
                continue
            if len(self._clients) >= self.max_clients:
                self.counters["refused_full"] += 1
                sock.close()
                continue
            client = self._new_client("tcp", address, sock)
            client.endpoint = Endpoint(sock, out_limit=self.client_buffer, tcp_only=True)
            self._by_endpoint[id(client.endpoint)] = client
            self.counters["accepted"] += 1
            self._try_flush(client)

    def _lobs(self) -> None:
        assert self._udp is not None
        for _ in range(64):
            try:
                data, source = self._udp.recvfrom(2048)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self.counters["udp_errors"] += 1
                return
            try:
                host, port = parse_lob(data)
                if str(ipaddress.IPv4Address(host)) != source[0]:
                    raise LobError(f"names {host}, came from {source[0]}")
            except (LobError, ValueError):
                self.counters["bad_lobs"] += 1
                continue
            if not self._permitted(source[0]):
                self.counters["refused"] += 1
                continue
            if any(c.mode == "lob" and c.address == (host, port) for c in self._clients.values()):
                self.counters["duplicate_lobs"] += 1
                continue
            pending = sum(1 for c in self._clients.values() if c.state != OPEN)
            if len(self._clients) >= self.max_clients or pending >= self.max_pending:
                self.counters["refused_full"] += 1
                continue
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setblocking(False)
            err = sock.connect_ex((host, port))
            if err not in (0, errno.EINPROGRESS, errno.EWOULDBLOCK):
                sock.close()
                self.counters["callback_failures"] += 1
                continue
            client = self._new_client("lob", (host, port), sock)
            client.sock = sock
            self.counters["lobs"] += 1

    def _called_back(self, sock: socket.socket) -> None:
        client = next((c for c in self._clients.values() if c.sock is sock), None)
        if client is None:
            return
        client.sock = None
        err = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
        if err:
            sock.close()
            self.counters["callback_failures"] += 1
            self._close_client(client, f"call-back failed: {os.strerror(err)}")
            return
        client.endpoint = Endpoint(sock, out_limit=self.client_buffer, tcp_only=False)
        self._by_endpoint[id(client.endpoint)] = client
        client.state = HANDSHAKE
        client.since = time.monotonic()
        self._try_flush(client)

    def _try_flush(self, client: ServerClient) -> None:
        try:
            if client.endpoint is not None:
                client.endpoint.flush()
        except ConnectionDropped as exc:
            self._close_client(client, exc.reason)

    def _read(self, ep: Endpoint, wall: float) -> None:
        client = self._client_of(ep)
        if client is None:
            return
        before = ep.bytes_read
        try:
            messages = ep.read(wall, READ_BUDGET)
            if ep.opened and client.state == HANDSHAKE:
                self._opened(client, ep)
        except ConnectionDropped as exc:
            self._close_client(client, exc.reason)
            return
        if ep.bytes_read - before >= READ_BUDGET:  # more may wait in the socket
            client.deferred += 1
            self.counters["input_deferred"] += 1
        if len(messages) > MESSAGE_BUDGET:
            self.counters["messages_deferred"] += len(messages) - MESSAGE_BUDGET
        self._handle(client, messages)

    def _handle(self, client: ServerClient, messages: list[Message]) -> None:
        """The client's messages up to its budget; the rest wait in ``client.pending``."""
        if len(messages) > MESSAGE_BUDGET:
            client.pending = messages[MESSAGE_BUDGET:]
            messages = messages[:MESSAGE_BUDGET]
        else:
            client.pending = []
        for m in messages:
            if client.closed:
                return
            if m.type == PING:
                self._pong(client, m)
            elif self.on_message is not None:
                self._callback(self.on_message, client, m)

    def _opened(self, client: ServerClient, ep: Endpoint) -> None:
        for ident, name in self.senders:
            ep.queue(pack_description(SENDER_DESCRIPTION, ident, name))
        for ident, name in self.types:
            ep.queue(pack_description(TYPE_DESCRIPTION, ident, name))
        client.state = OPEN
        self._open_clients += 1
        self._open_pairs = None
        self.counters["connections"] += 1
        if self.on_connect is not None:
            self._callback(self.on_connect, client)

    def _pong(self, client: ServerClient, m: Message) -> None:
        sender = self.senders.id(m.sender) if m.sender is not None else None
        if sender is None or client.endpoint is None:
            self.counters["pings_unknown_sender"] += 1
            return
        pong = self.types.id(PONG)
        assert pong is not None
        client.endpoint.queue(pack_message(pong, sender))
        if self.on_ping is not None:
            self._callback(self.on_ping, client, m.sender)

    def _callback(self, fn: Callable, *args: object) -> None:
        try:
            fn(*args)
        except Exception:
            self.counters["callback_errors"] += 1

    def _expire(self, now: float) -> None:
        timeout = self.handshake_timeout
        late = [c for c in self._clients.values() if c.state != OPEN and now - c.since > timeout]
        for client in late:
            self.counters["handshake_timeouts"] += 1
            self._close_client(client, "no cookie in time")

    def _close_client(self, client: ServerClient, reason: str) -> None:
        if client.closed:
            return
        client.closed = True
        self._clients.pop(client.id, None)
        if client.sock is not None:
            client.sock.close()
            client.sock = None
        was_open = client.state == OPEN
        self._open_clients -= was_open
        self._open_pairs = None
        if client.endpoint is not None:
            self._by_endpoint.pop(id(client.endpoint), None)
            self._closed_dropped += client.endpoint.dropped
            self.counters.update(client.endpoint.counters)
            client.endpoint.close()
        self.counters["disconnects"] += 1
        if was_open and self.on_disconnect is not None:
            self._callback(self.on_disconnect, client, reason)

    def serve_forever(self, stop: threading.Event, interval: float = 0.05) -> None:
        """Poll until ``stop`` is set (for a thread of its own)."""
        while not stop.is_set():
            self.poll(interval)
