"""What the network emulators share: sending frames over loopback UDP at a rate, and the
run loop's end is :func:`~gadgetctl.emulation.command.ended`.

:class:`UdpFrameSender` owns the sending socket (unicast to ``127.0.0.1:port``, or a
multicast group kept on the loopback interface), a thread that sends one frame per
``1/rate`` seconds (catching up when late), the ``disconnect`` scenario (the socket closes
after ``disconnect_after`` frames), ``max_frames``, ``error`` and ``finished``, and its
console lines. A tracker emulator adds :meth:`~UdpFrameSender.send_frame` (and, to hold
frames back, :meth:`~UdpFrameSender.may_send`).
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from typing import ClassVar, TypeVar

from gadgetctl.emulation.command import STANDARD_SCENARIOS, check_settings
from gadgetctl.emulation.console import Console

LOOPBACK = "127.0.0.1"

Self = TypeVar("Self", bound="UdpFrameSender")


class UdpFrameSender:
    """Sends frames to ``127.0.0.1:port`` (or multicast ``group`` via loopback) at ``rate``
    frames per second; subclass it with :meth:`send_frame`."""

    NAME: ClassVar[str] = "udp"
    SCENARIOS: ClassVar[tuple[str, ...]] = STANDARD_SCENARIOS

    def __init__(
        self,
        port: int,
        *,
        scenario: str,
        rate: float,
        disconnect_after: int = 10,
        max_frames: int | None = None,
        first_frame: int = 1,
        group: str | None = None,
    ) -> None:
        check_settings(scenario, self.SCENARIOS, rate)
        if not 0 < port < 65536:
            raise ValueError("port must be between 1 and 65535")
        self.port = port
        self.scenario = scenario
        self.rate = rate
        self.group = group
        self.disconnect_after = disconnect_after
        self.max_frames = max_frames
        self.error: BaseException | None = None
        self.finished = threading.Event()
        self.console = Console()
        self._next_frame = first_frame
        self._sender: socket.socket | None = None
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._threads: list[threading.Thread] = []

    @property
    def address(self) -> str:
        """Where the frames go."""
        return f"{self.group or LOOPBACK}:{self.port}"

    # -- life cycle ---------------------------------------------------------------------------

    def start(self: Self) -> Self:
        if self._threads:
            return self
        self._stop.clear()
        self.finished.clear()
        self._sender = self._open_sender()
        self.open()
        targets = [(self._send_loop, f"{self.NAME}-emulator"), *self.services()]
        self._threads = [
            threading.Thread(target=target, name=name, daemon=True) for target, name in targets
        ]
        for thread in self._threads:
            thread.start()
        return self

    def stop(self, timeout: float = 2.0) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(timeout)
        self._threads.clear()
        self._close_sender()
        self.close()

    def __enter__(self: Self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def send_raw(self, data: bytes | str) -> None:
        """Send one datagram of your own (for hand-made test data)."""
        payload = data.encode("ascii") if isinstance(data, str) else data
        with self._lock:
            sock = self._sender
            if sock is None:
                raise RuntimeError("the emulator is not running")
            sock.sendto(payload, (self.group or LOOPBACK, self.port))

    # -- what a tracker emulator adds ---------------------------------------------------------

    def open(self) -> None:
        """More sockets to open at start (a command port)."""

    def close(self) -> None:
        """Close what :meth:`open` opened."""

    def services(self) -> list[tuple[Callable[[], None], str]]:
        """More threads to run beside the sending one: ``(target, name)``."""
        return []

    def may_send(self) -> bool:
        """Whether this frame is sent (False holds it back: waiting for a start command)."""
        return True

    def send_frame(self, n: int) -> None:
        """Send frame number ``n`` (and whatever the scenario adds)."""
        raise NotImplementedError

    # -- the sending thread -------------------------------------------------------------------

    def _open_sender(self) -> socket.socket:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4 * 1024 * 1024)
            if self.group:  # multicast stays on the loopback interface
                loopback = socket.inet_aton(LOOPBACK)
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, loopback)
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
                sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
            sock.bind((LOOPBACK, 0))
        except BaseException:
            sock.close()
            raise
        return sock

    def _close_sender(self) -> None:
        with self._lock:
            if self._sender is not None:
                self._sender.close()
            self._sender = None

    def _send_loop(self) -> None:
        try:
            deadline = time.monotonic()
            sent = 0
            while not self._stop.is_set():
                deadline += 1.0 / self.rate
                delay = deadline - time.monotonic()
                if delay > 0 and self._stop.wait(delay):
                    return
                if not self.may_send():
                    continue
                n = self._next_frame
                self._next_frame += 1
                self.send_frame(n)
                sent += 1
                if self.scenario == "disconnect" and sent >= self.disconnect_after:
                    self._close_sender()
                    self.console.stopped_sending(f"closed the socket after {sent} frames")
                    return
                if self.max_frames is not None and sent >= self.max_frames:
                    self.console.stopped_sending(f"sent the {sent} frames asked for")
                    return
        except BaseException as exc:  # reported through .error
            self.error = exc
        finally:
            self.finished.set()


class Peers:
    """The UDP peers heard from: the first datagram of each is a client connecting."""

    def __init__(self, console: Console) -> None:
        self.console = console
        self.seen: set[tuple[str, int]] = set()
        self._lock = threading.Lock()

    def heard(self, peer: tuple[str, int], what: str = "first datagram") -> None:
        key = (str(peer[0]), int(peer[1]))
        with self._lock:
            if key in self.seen:
                return
            self.seen.add(key)
        self.console.client_connected(f"{key[0]}:{key[1]} ({what})")
