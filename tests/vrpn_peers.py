"""Helpers for VRPN tests: a running library server, and raw-socket peers written from the
reference (they build bytes by hand, so a bug shared by our client and server cannot hide)."""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
from collections.abc import Iterator

from gadgetctl.vrpn import VrpnServer

COOKIE = bytes.fromhex("7672706e3a207665722e2030372e33382020300000000000")


def frame(type_id: int, sender: int, payload: bytes = b"") -> bytes:
    """A message built byte by byte from the reference (section 4), zero padding."""
    n = len(payload)
    return struct.pack(">IiiiiI", 24 + n, 0, 0, sender, type_id, 0) + payload + b"\0" * (-n % 8)


def describe(kind: int, ident: int, name: str) -> bytes:
    raw = name.encode()
    return frame(kind, ident, struct.pack(">I", len(raw) + 1) + raw + b"\0")


def read_messages(
    sock: socket.socket, want: int, timeout: float = 5.0
) -> list[tuple[int, int, bytes]]:
    """(type, sender, payload) of the next ``want`` messages on a raw TCP socket."""
    sock.settimeout(timeout)
    buf = b""
    out: list[tuple[int, int, bytes]] = []
    while len(out) < want:
        while len(buf) >= 24:
            length, _s, _u, sender, type_id, _q = struct.unpack_from(">IiiiiI", buf)
            body = (length - 24 + 7) & ~7
            if len(buf) < 24 + body:
                break
            out.append((type_id, sender, buf[24:length]))
            buf = buf[24 + body :]
        if len(out) >= want:
            break
        data = sock.recv(65536)
        if not data:
            break
        buf += data
    return out


@contextlib.contextmanager
def running_server(**options) -> Iterator[VrpnServer]:
    """A :class:`VrpnServer` on 127.0.0.1 (an OS-chosen port) polled by a thread of its own."""
    server = VrpnServer("127.0.0.1", options.pop("port", 0), **options).start()
    stop = threading.Event()
    thread = threading.Thread(target=server.serve_forever, args=(stop, 0.02), daemon=True)
    thread.start()
    try:
        yield server
    finally:
        stop.set()
        thread.join(5)
        server.close()


class RawServer:
    """A hand-written VRPN server on loopback (direct TCP only) whose bytes a test scripts:
    ``script(conn)`` runs for each accepted connection."""

    def __init__(self, script) -> None:
        self.script = script
        self.sock = socket.socket()
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.sock.settimeout(0.1)
        self.port = self.sock.getsockname()[1]
        self.connections = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> RawServer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(5)
        self.sock.close()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            self.connections += 1
            with conn:
                try:
                    conn.settimeout(2)
                    self.script(conn, self.connections)
                except OSError:
                    pass


class Broadcasts:
    """A server stand-in for :class:`gadgetctl.serve.outlet.VrpnOutlet`: names get ids, every
    broadcast is kept; no client listens until the test says so (the outlet's ``audience``)."""

    def __init__(self) -> None:
        self.names: dict[str, int] = {}
        self.sent: list[bytes] = []
        self.audience = False

    def register_sender(self, name: str) -> int:
        return self.names.setdefault(name, len(self.names))

    register_type = register_sender

    def broadcast(
        self, data: bytes, size: int, *, reliable: bool = True, flush: bool = False
    ) -> int:
        self.sent.append(bytes(data))
        return len(data) // size
