"""Datagrams thrown at a UDP driver in tests: a flood of malformed datagrams must be counted
as bad one for one (:func:`bad_one_for_one`), and a sender that keeps sending while a
``gadgetctl monitor`` child process runs (:class:`DatagramSender`). Loopback only."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from gadgetctl.input.testing import frames_until

if TYPE_CHECKING:
    from gadgetctl.input.manager import InputManager

LOOPBACK = "127.0.0.1"


def send_datagrams(port: int, payloads: Sequence[bytes]) -> None:
    """Each payload as one datagram to ``127.0.0.1:port``."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        for payload in payloads:
            tx.sendto(payload, (LOOPBACK, port))


def bad_one_for_one(
    manager: InputManager,
    name: str,
    port: int,
    payloads: Sequence[bytes],
    *,
    timeout: float = 10.0,
    send: Callable[[Sequence[bytes]], object] | None = None,
) -> dict[str, int]:
    """Send ``payloads`` (none of them decodable) to the device ``name`` on ``port`` (or with
    ``send``, for a device that takes datagrams from one peer only), run frames until its
    ledger has accounted for every one (read or dropped by the kernel), and check that each
    read was counted bad and none decoded. Its ledger's counters after."""
    device = manager.device(name)
    assert device is not None, f"no device {name!r}"
    ledger = device.datagram_ledger()
    assert ledger is not None, f"{name} keeps no datagram ledger"
    before = ledger.counters()
    if send is None:
        send_datagrams(port, payloads)
    else:
        send(payloads)

    def accounted() -> bool:
        now = ledger.counters()
        arrived = now["datagrams"] - before["datagrams"]
        dropped = now["kernel_dropped"] - before["kernel_dropped"]
        judged = (now["decoded"] + now["bad_datagrams"]) - (
            before["decoded"] + before["bad_datagrams"]
        )
        return arrived + dropped >= len(payloads) and judged >= arrived

    frames_until(manager, accounted, timeout=timeout)
    after = ledger.counters()
    arrived = after["datagrams"] - before["datagrams"]
    dropped = after["kernel_dropped"] - before["kernel_dropped"]
    assert arrived + dropped == len(payloads), (before, after)
    assert after["bad_datagrams"] - before["bad_datagrams"] == arrived, (before, after)
    assert after["decoded"] == before["decoded"], (before, after)
    return after


class DatagramSender:
    """A thread sending ``payload(n)`` (n = 0, 1, ...) to ``127.0.0.1:port`` every
    ``interval`` seconds while the context is open (e.g. while a monitor child runs).
    ``sent`` counts what went out."""

    def __init__(
        self, port: int, payload: Callable[[int], bytes], *, interval: float = 0.01
    ) -> None:
        self.port = port
        self.payload = payload
        self.interval = interval
        self.sent = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="datagram sender", daemon=True)

    def _run(self) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            while not self._stop.is_set():
                try:
                    tx.sendto(self.payload(self.sent), (LOOPBACK, self.port))
                except ConnectionRefusedError:
                    pass  # nobody bound yet: an ICMP answer to an earlier datagram
                self.sent += 1
                self._stop.wait(self.interval)

    def __enter__(self) -> DatagramSender:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
