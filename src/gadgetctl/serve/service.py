"""`gadgetctl serve` as a library: the monitor session's pipeline (the embedded input
manager, frame by frame, every sample of every device gathered) with one more consumer,
the :class:`~gadgetctl.serve.feed.ServeFeed`, whose reports a VRPN server fans out.

The server's input and output run in the frame loop's waits (the session's ``sleep`` is the
server's poll), on one thread: a frame is gathered, framed and queued for each client's
bounded buffer, then written as far as each socket takes it; a client that does not read
only fills its own buffer (and loses messages, counted) while the others and the input
manager go on.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

from gadgetctl.input.clock import now
from gadgetctl.input.manager import InputManager
from gadgetctl.jccl.configuration import Configuration
from gadgetctl.monitor.session import MonitorSession
from gadgetctl.serve.address import DEFAULT_BIND, DEFAULT_PORT, allowed
from gadgetctl.serve.catalog import ServedElement, build_catalog
from gadgetctl.serve.feed import ServeFeed

WARMUP = 0.5  # seconds of frames before the catalog is read (so unit counts are known)
SOCKET_BUFFER = (
    256 * 1024
)  # kernel send buffer per client: a stalled client's backlog shows as drops
SWITCH_INTERVAL = 0.0005  # seconds: how long another thread may keep the GIL while frames run
DEFAULT_RATE = 1000.0  # frames per second: a sample waits at most a millisecond to be sent
#: A wait before the next frame up to this long (seconds) is a plain sleep, followed by one
#: pass of the server's I/O that does not wait when the last pass is :data:`POLL_INTERVAL`
#: old, much as a C++ VRPN server's main loop polls between its sleeps: at 1 kHz, waking from
#: a sleep costs less than from a ``select`` over every client's socket, and a pass over the
#: sockets every frame was a tenth of serve's work. Longer waits watch the sockets throughout.
SHORT_WAIT = 0.002
#: Seconds: how long clients may wait to be accepted, read and answered while frames run
#: back to back (the frames' own writes go out at once, every frame).
POLL_INTERVAL = 0.004


@dataclass
class ServeOptions:
    selectors: Sequence[str] = ()
    renames: Mapping[str, str] = field(default_factory=dict)
    bind: str = DEFAULT_BIND
    port: int = DEFAULT_PORT
    allow: list = field(default_factory=list)  # ipaddress networks; empty: everyone
    rate: float = DEFAULT_RATE
    client_buffer: int = 1 << 20  # bytes queued per client before messages are dropped
    statistics: bool = False  # the session's per-device statistics (needed for --record's stats)


@dataclass(frozen=True, slots=True)
class ServeEvent:
    """Something a server operator sees: a client connecting, leaving, being refused."""

    kind: str  # connected, disconnected, refused
    client: str  # host:port
    detail: str = ""
    sent: int = 0
    dropped: int = 0
    moment: float = field(default_factory=time.time)


def _address(client) -> str:
    host, port = client.address
    return f"{host}:{port}"


class ServeService:
    """Runs a configuration's devices and serves them; see the module documentation."""

    def __init__(
        self,
        manager: InputManager,
        configuration: Configuration | None,
        options: ServeOptions | None = None,
        *,
        info: Mapping[str, object] | None = None,
    ) -> None:
        self.options = options or ServeOptions()
        self.session = MonitorSession(
            manager,
            configuration,
            selectors=self.options.selectors,
            rate=self.options.rate,
            info=info,
            statistics=self.options.statistics,
        )
        self.catalog: list[ServedElement] = []
        self.server = None
        self.outlet = None
        self.feed: ServeFeed | None = None
        self.listeners: list[Callable[[ServeEvent], object]] = []
        self._closed = False
        self._polled_at = -math.inf  # when the frame loop's waits last passed over the sockets

    @property
    def manager(self) -> InputManager:
        return self.session.manager

    def prepare(self, warmup: float = WARMUP) -> list[ServedElement]:
        """Configure the manager, run frames until every device delivered (at most
        ``warmup`` seconds) and name what is served. Raises SelectionError and NamingError."""
        session = self.session
        session.start()
        deadline = now() + warmup
        for _ in session.frames(duration=warmup):
            if session.warm() or now() >= deadline:
                break
        self.catalog = build_catalog(self.manager, session.selected, self.options.renames)
        return self.catalog

    def listen(self) -> int:
        """Bind the server (TCP and UDP, the same port) and start feeding it; returns the port.
        Raises :class:`OSError` when the port cannot be bound."""
        from gadgetctl.serve.outlet import VrpnOutlet
        from gadgetctl.vrpn.server import VrpnServer

        options = self.options
        networks = list(options.allow)
        server = VrpnServer(
            options.bind,
            options.port,
            client_buffer=options.client_buffer,
            socket_buffer=SOCKET_BUFFER,
            allow=lambda ip: allowed(ip, networks),
        )
        server.start()
        self.server = server
        self.outlet = VrpnOutlet(server, self.catalog)
        server.on_connect = self._connected
        server.on_disconnect = self._disconnected
        server.on_ping = self._pinged
        self.feed = ServeFeed(self.catalog, self.outlet)
        self.session.add_consumer(self.feed)
        self.session.add_consumer(self._flush)
        return server.port

    def _flush(self, session: MonitorSession, moment: float) -> None:
        self.outlet.end_frame()  # the frame's writes
        if session.has_slack():
            # rows the coming frames will need; the wait before the next frame then polls
            self.outlet.prepare()
        else:
            # a full pass (accept, read, write), not only a flush: when frames fall behind,
            # the frame loop has no waits left, and clients must still be accepted and heard
            self.server.poll(0.0)

    def _wait(self, delay: float) -> None:
        """The frame loop's sleep: the server's I/O until the next frame is due."""
        if delay <= SHORT_WAIT:
            time.sleep(delay)
            moment = now()
            if moment - self._polled_at >= POLL_INTERVAL:
                self._polled_at = moment
                self.server.poll(0.0)
            return
        end = now() + delay
        while True:
            self.server.poll(max(0.0, end - now()))
            moment = now()
            if moment >= end:
                self._polled_at = moment
                return

    def _connected(self, client) -> None:
        self.outlet.audience = True
        self.outlet.send_states(client)  # as a C++ button server does
        self._tell(ServeEvent("connected", _address(client), client.mode))

    def _pinged(self, client, sender: str) -> None:
        self.outlet.send_states(client, sender)

    def _disconnected(self, client, reason: str) -> None:
        self._tell(
            ServeEvent("disconnected", _address(client), reason, client.sent, client.dropped)
        )

    def _tell(self, event: ServeEvent) -> None:
        for listener in self.listeners:
            listener(event)

    def totals(self) -> dict[str, object]:
        """Clients served, messages framed, messages dropped for full client buffers, and
        the server's counters of refused and malformed traffic."""
        server = self.server
        if server is None:
            return {"clients": 0, "connected": 0, "messages": 0, "dropped": 0, "counters": {}}
        return {
            "clients": server.counters["connections"],
            "connected": len(server.clients),
            "messages": self.outlet.messages,
            "dropped": server.dropped,
            "counters": {k: v for k, v in sorted(server.counters.items()) if v},
        }

    def frames(self, duration: float | None = None) -> Iterator[object]:
        """Run until ``duration`` seconds or :meth:`stop`; the server works between frames.

        Meanwhile the interpreter's thread switch interval is at most :data:`SWITCH_INTERVAL`:
        the frame thread lets go of the GIL at each write to a client, and must not then wait
        the default 5 ms for a busy sampling or driver thread to hand it back."""
        previous = sys.getswitchinterval()
        sys.setswitchinterval(min(previous, SWITCH_INTERVAL))
        try:
            yield from self.session.frames(duration=duration, sleep=self._wait)
        finally:
            sys.setswitchinterval(previous)

    def stop(self) -> None:
        self.session.stop()

    def close(self, reason: str = "closed") -> None:
        """Close the clients, the recordings (``reason`` in their end record) and the manager;
        may be called again."""
        if self._closed:
            return
        self._closed = True
        try:
            if self.server is not None:
                self.server.close()
            self.session.close_sinks(reason)
        finally:
            self.manager.shutdown()
