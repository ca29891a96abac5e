"""The Elexol Ether I/O 24 protocol: binary commands to UDP port 2424 and the board's
replies. Knows nothing of gadgetctl's input manager.

Ports 0, 1, 2 are A, B, C. Read a port: ``'a'+p`` -> reply ``'A'+p, value``. Write a port:
``'A'+p, value`` (no reply). Registers put a prefix before a write: ``'!'`` direction (1 =
input), ``'@'`` pull-up (0 = on), ``'#'`` threshold (0 = 2.5 V, 1 = 1.4 V), ``'$'`` Schmitt
trigger (0 = on). A reply that is not two bytes with a known port letter is a counted bad
reply, never a fault.

Discovery (``config_method`` Match MAC Address): ``IO24`` sent to port 2424, by default to
the broadcast address 255.255.255.255; each board answers ``IO24`` + its 6-byte MAC + a
2-byte firmware version. :func:`find_board` stops at the first reply with the wanted MAC
(upstream listened for a whole second, then matched); replies of another shape are counted.

Upstream fix (Gadgeteer's ``Ether24``): a line is reported as 0 or 1; upstream stored the
masked bit value (8, 16, ...), so line 3 read as 8 when on.
"""

from __future__ import annotations

import select
import socket
import time
from dataclasses import dataclass

from gadgetctl.transport.udp import DatagramLedger

BOARD_PORT = 2424
PORTS = 3
LINES = 8 * PORTS
REGISTERS = {"direction": b"!", "pullup": b"@", "threshold": b"#", "schmitt_trigger": b"$"}
IDENTIFY = b"IO24"
IDENTITY_LENGTH = len(IDENTIFY) + 6 + 2
BROADCAST = "255.255.255.255"
DISCOVERY_TIME = 1.0  # seconds upstream listens for boards


class Ether24Disconnected(ConnectionError):
    """The board did not answer for longer than the peer timeout."""


@dataclass(frozen=True)
class PortSettings:
    """One port's pins, bit-packed (bit i = pin i), as the board's registers take them."""

    initial_value: int = 0
    direction: int = 0xFF
    pullup: int = 0xFF
    threshold: int = 0xFF
    schmitt_trigger: int = 0xFF
    invert: int = 0


def parse_address(text: str) -> tuple[str, int]:
    """``host`` or ``host:port`` (the port defaults to 2424); raises ValueError."""
    host, _, port = text.strip().rpartition(":") if ":" in text else (text.strip(), "", "")
    if not host:
        raise ValueError("no IP address")
    number = int(port) if port else BOARD_PORT
    if not 1 <= number <= 65535:
        raise ValueError(f"port {number} is not between 1 and 65535")
    return host, number


def parse_mac(text: str) -> bytes:
    """Six bytes from ``00:0A:BC:12:34:56`` (``-`` or no separators also do)."""
    digits = text.strip().replace(":", "").replace("-", "")
    if len(digits) != 12:
        raise ValueError(f"{text!r} is not a MAC address (six hex bytes, e.g. 00:0A:BC:12:34:56)")
    try:
        return bytes.fromhex(digits)
    except ValueError:
        raise ValueError(f"{text!r} is not a MAC address (six hex bytes)") from None


def format_mac(raw: bytes) -> str:
    return ":".join(f"{b:02X}" for b in raw)


@dataclass(frozen=True)
class BoardIdentity:
    """A board's answer to ``IO24``: where it answered from, its MAC and firmware."""

    host: str
    port: int
    mac: bytes
    firmware: int


@dataclass
class DiscoveryCounts:
    replies: int = 0
    bad_replies: int = 0


def find_board(
    mac: bytes,
    target: tuple[str, int] = (BROADCAST, BOARD_PORT),
    *,
    listen: float = DISCOVERY_TIME,
    counts: DiscoveryCounts | None = None,
) -> BoardIdentity | None:
    """Send ``IO24`` to ``target`` and wait up to ``listen`` seconds for the board with
    ``mac``; None when it did not answer. Other boards' answers are passed over."""
    counts = counts if counts is not None else DiscoveryCounts()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
        sock.setblocking(False)
        try:
            sock.sendto(IDENTIFY, target)
        except OSError as err:
            raise Ether24Disconnected(
                f"cannot send the discovery to {target[0]}:{target[1]}: {err}"
            ) from None
        deadline = time.monotonic() + listen
        while (left := deadline - time.monotonic()) > 0:
            if not select.select([sock], [], [], left)[0]:
                break
            try:
                data, peer = sock.recvfrom(64)
            except (BlockingIOError, ConnectionRefusedError):
                continue
            if len(data) != IDENTITY_LENGTH or not data.startswith(IDENTIFY):
                counts.bad_replies += 1
                continue
            counts.replies += 1
            if data[4:10] == mac:
                return BoardIdentity(peer[0], peer[1], data[4:10], int.from_bytes(data[10:], "big"))
    return None


def lines(values: list[int], inverts: list[int]) -> list[int]:
    """The 24 lines as 0 or 1: line ``8p + b`` is bit b of port p's value XOR its invert mask."""
    return [((values[p] ^ inverts[p]) >> b) & 1 for p in range(PORTS) for b in range(8)]


class Ether24Board:
    """A board at ``host:port``. Counters: ``requests``, ``replies``, ``bad_replies``,
    ``timeouts``; ``ledger`` counts every datagram read as decoded (a port reply) or bad, and
    the kernel's drops."""

    def __init__(
        self,
        host: str,
        port: int = BOARD_PORT,
        *,
        reply_timeout: float = 0.1,
        peer_timeout: float = 1.0,
    ) -> None:
        self.host = host
        self.port = port
        self.reply_timeout = reply_timeout
        self.peer_timeout = peer_timeout
        self.requests = 0
        self.timeouts = 0
        self.ledger = DatagramLedger()
        self._sock: socket.socket | None = None
        self._last_reply = time.monotonic()
        self._values = [0] * PORTS

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.connect((self.host, self.port))
        except OSError:
            sock.close()
            raise
        sock.setblocking(False)
        self._sock = sock
        self.ledger.attach(sock)
        self._last_reply = time.monotonic()

    def close(self) -> None:
        if self._sock is not None:
            self.ledger.detach()
            self._sock.close()
            self._sock = None

    @property
    def replies(self) -> int:
        """Port replies received."""
        return self.ledger.decoded_count

    @property
    def bad_replies(self) -> int:
        """Datagrams from the board that were not a port reply."""
        return self.ledger.bad_count

    def _send(self, data: bytes) -> None:
        if self._sock is None:
            raise Ether24Disconnected("the connection to the board is closed")
        try:
            self._sock.send(data)
        except ConnectionRefusedError:
            pass  # an ICMP refusal from an earlier datagram: the board is not there (yet)

    def configure(self, ports: list[PortSettings]) -> None:
        """Write each port's start value and registers, in upstream's order."""
        for p, settings in enumerate(ports):
            letter = bytes([ord("A") + p])
            self._send(letter + bytes([settings.initial_value & 0xFF]))
            for name, prefix in REGISTERS.items():
                self._send(prefix + letter + bytes([getattr(settings, name) & 0xFF]))

    def read_ports(self) -> list[int] | None:
        """Ask for ports A, B, C and wait up to ``reply_timeout`` for the replies: the three
        values, or None when some did not come (counted). Raises :class:`Ether24Disconnected`
        after ``peer_timeout`` seconds without any good reply."""
        sock = self._sock
        if sock is None:
            raise Ether24Disconnected("the connection to the board is closed")
        while True:  # drop replies that came too late for an earlier request
            try:
                self._classify(self.ledger.receive(64))
            except (BlockingIOError, ConnectionRefusedError):
                break
        for p in range(PORTS):
            self._send(bytes([ord("a") + p]))
            self.requests += 1
        seen: set[int] = set()
        deadline = time.monotonic() + self.reply_timeout
        while len(seen) < PORTS:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([sock], [], [], left)[0]:
                break
            try:
                data = self.ledger.receive(64)
            except BlockingIOError:
                continue
            except ConnectionRefusedError:
                break
            port = self._classify(data)
            if port is not None:
                seen.add(port)
        if len(seen) == PORTS:
            self._last_reply = time.monotonic()
            return list(self._values)
        self.timeouts += 1
        if time.monotonic() - self._last_reply > self.peer_timeout:
            raise Ether24Disconnected(
                f"the Ether I/O 24 at {self.host}:{self.port} has not answered "
                f"for {self.peer_timeout:g} s"
            )
        return None

    def _classify(self, data: bytes) -> int | None:
        """Store a port reply; the port, or None for anything else (counted bad)."""
        if len(data) == 2 and ord("A") <= data[0] < ord("A") + PORTS:
            port = data[0] - ord("A")
            self._values[port] = data[1]
            self.ledger.decoded()
            return port
        self.ledger.bad(f"not a port reply: {len(data)} bytes, first {data[:2].hex() or '-'}")
        return None
