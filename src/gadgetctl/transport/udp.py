"""UDP receiving with the kernel's count of the datagrams it dropped for the socket.

When a socket's receive buffer is full, the kernel drops what arrives and counts it. Linux
hands that count to the reader with each datagram (``SO_RXQ_OVFL`` ancillary data, the
socket's drops since it was made); where that option is missing, the ``drops`` column of
``/proc/net/udp`` for the socket's inode gives the same number. :class:`DropCountingReceiver`
reads datagrams and keeps the count, so a driver can show overflows with its other drops.
"""

from __future__ import annotations

import os
import socket
import sys
import time
from pathlib import Path

#: ``SO_RXQ_OVFL`` (Linux 2.6.33 and later); Python names it only on some builds.
SO_RXQ_OVFL: int | None = getattr(
    socket, "SO_RXQ_OVFL", 40 if sys.platform.startswith("linux") else None
)
_COUNTER_SPACE = socket.CMSG_SPACE(4) if hasattr(socket, "CMSG_SPACE") else 0


def proc_udp_drops(sock: socket.socket, proc: Path = Path("/proc/net")) -> int | None:
    """The kernel's drop count of ``sock`` from ``/proc/net/udp`` (or ``udp6``); None where
    the file or the socket's line is missing (not Linux, or the socket is closed)."""
    try:
        inode = str(os.fstat(sock.fileno()).st_ino)
    except (OSError, ValueError):
        return None
    for name in ("udp", "udp6"):
        try:
            lines = (proc / name).read_text(encoding="ascii", errors="replace").splitlines()
        except OSError:
            continue
        for line in lines[1:]:
            fields = line.split()
            # sl local rem st tx:rx tr:when retrnsmt uid timeout inode ref pointer drops
            if len(fields) >= 13 and fields[9] == inode:
                try:
                    return int(fields[12])
                except ValueError:
                    return None
    return None


def bind_udp(sock: socket.socket, host: str, port: int) -> None:
    """``sock.bind((host, port))``; an error names the port (and the address, unless it is
    every interface): ``cannot bind UDP port 5000: Address already in use``."""
    bind_named(sock, host, port)


def bind_named(sock: socket.socket, host: str, port: int) -> None:
    """``sock.bind((host, port))`` for a TCP or UDP socket; an error names the protocol, the
    port and the address (unless it is every interface): ``cannot bind TCP port 6000 on
    127.0.0.1: Address already in use``."""
    try:
        sock.bind((host, port))
    except OSError as err:
        kind = "TCP" if sock.type == socket.SOCK_STREAM else "UDP"
        where = f"{kind} port {port}" + (f" on {host}" if host not in ("", "0.0.0.0") else "")
        raise OSError(err.errno, f"cannot bind {where}: {err.strerror or err}") from err


class DropCountingReceiver:
    """Reads datagrams from a UDP socket and keeps the kernel's count of those it dropped.

    ``dropped`` is the total over every socket given to :meth:`attach` (a reconnection makes
    a new socket, whose count starts at 0). ``method`` says where the count comes from:
    ``"ancillary"`` (with every datagram), ``"proc"`` (read by :meth:`refresh`) or ``None``
    (the OS offers none; ``dropped`` stays 0). A datagram carries the drops before it was
    queued, so drops after the last one read are learnt from ``/proc`` by :meth:`refresh`,
    at most every ``proc_interval`` seconds (reading it costs more than a datagram).
    """

    def __init__(self, proc_interval: float = 0.25) -> None:
        self.proc_interval = proc_interval
        self.method: str | None = None
        self._proc_read_at = -float("inf")
        self._sock: socket.socket | None = None
        self._before = 0  # drops of the sockets detached earlier
        self._current = 0  # drops of the attached socket so far

    @property
    def dropped(self) -> int:
        return self._before + self._current

    def attach(self, sock: socket.socket) -> None:
        """Start counting for ``sock`` (asks for the per-datagram count where it can)."""
        self.detach()
        self._sock = sock
        self._current = 0
        self.method = None
        if SO_RXQ_OVFL is not None and _COUNTER_SPACE and hasattr(sock, "recvmsg"):
            try:
                sock.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
            except OSError:
                pass
            else:
                self.method = "ancillary"
                return
        if proc_udp_drops(sock) is not None:
            self.method = "proc"

    def detach(self) -> None:
        """Stop counting for the attached socket, keeping what it counted."""
        if self._sock is not None:
            self.refresh(force=True)
            self._before += self._current
            self._current = 0
            self._sock = None

    def refresh(self, *, force: bool = False) -> None:
        """Read ``/proc`` for the count, if ``proc_interval`` has passed since the last time
        (or with ``force``)."""
        if self.method is None or self._sock is None:
            return
        moment = time.monotonic()
        if not force and moment - self._proc_read_at < self.proc_interval:
            return
        self._proc_read_at = moment
        count = proc_udp_drops(self._sock)
        if count is not None:
            self._current = max(self._current, count)

    def receive(self, size: int) -> bytes:
        """One datagram of at most ``size`` bytes; raises as ``socket.recv`` does."""
        return self.receive_from(size)[0]

    def receive_from(self, size: int) -> tuple[bytes, tuple[str, int]]:
        """One datagram of at most ``size`` bytes and its sender's address; raises as
        ``socket.recvfrom`` does."""
        sock = self._sock
        if sock is None:
            raise OSError("no socket attached")
        if self.method != "ancillary":
            return sock.recvfrom(size)
        data, ancillary, _flags, address = sock.recvmsg(size, _COUNTER_SPACE)
        for level, kind, payload in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_RXQ_OVFL and len(payload) >= 4:
                self._current = max(self._current, int.from_bytes(payload[:4], sys.byteorder))
        return data, address


#: Seconds of nothing but bad datagrams after which a receiver that decoded before is
#: undecodable again (one that never decoded is undecodable from its first bad datagram).
UNDECODABLE_AFTER = 1.0
#: Characters of a decoding error kept (the text may quote what the peer sent).
MAX_ERROR_TEXT = 200


class DatagramLedger:
    """One receiver's account of its datagrams: the kernel's drops, and each datagram read
    counted once, as decoded or as bad.

    A driver reads through :meth:`receive` (which counts ``datagrams``) and says what became
    of each one: :meth:`decoded` (it was the protocol, whether or not it carried samples) or
    :meth:`bad` with the reason (it was not). ``datagrams == decoded + bad`` once the driver
    has judged what it read. :meth:`undecodable` tells a receiver that gets data but can
    decode none of it from one that is fine, with the first error of the bad run.
    """

    def __init__(
        self, *, proc_interval: float = 0.25, undecodable_after: float = UNDECODABLE_AFTER
    ) -> None:
        self.drops = DropCountingReceiver(proc_interval)
        self.undecodable_after = undecodable_after
        self.datagrams = 0
        self.decoded_count = 0
        self.bad_count = 0
        #: The error of the first bad datagram since the last decoded one (None: no such run).
        self.first_error: str | None = None
        self._run = 0  # bad datagrams since the last decoded one
        self._run_began = 0.0
        self._run_last = 0.0

    # -- the socket -----------------------------------------------------------------------

    def attach(self, sock: socket.socket) -> None:
        self.drops.attach(sock)

    def detach(self) -> None:
        self.drops.detach()

    def receive(self, size: int) -> bytes:
        """One datagram (counted) of at most ``size`` bytes; raises as ``socket.recv`` does."""
        return self.receive_from(size)[0]

    def receive_from(self, size: int) -> tuple[bytes, tuple[str, int]]:
        """One datagram (counted) of at most ``size`` bytes and its sender's address; raises
        as ``socket.recvfrom`` does."""
        found = self.drops.receive_from(size)
        self.datagrams += 1
        return found

    @property
    def kernel_dropped(self) -> int:
        """Datagrams the kernel dropped for a full receive buffer, over every socket."""
        self.drops.refresh()
        return self.drops.dropped

    # -- what became of each datagram ---------------------------------------------------------

    def decoded(self, count: int = 1) -> None:
        """``count`` datagrams were well-formed (they may have carried nothing to sample)."""
        if count > 0:
            self.decoded_count += count
            self._run = 0
            self.first_error = None

    def bad(self, error: str, count: int = 1) -> None:
        """``count`` datagrams could not be decoded; ``error`` says why (the first of a run
        of bad datagrams is kept, cut to :data:`MAX_ERROR_TEXT` characters)."""
        if count <= 0:
            return
        moment = time.monotonic()
        if self._run == 0:
            self.first_error = error[:MAX_ERROR_TEXT]
            self._run_began = moment
        self._run += count
        self._run_last = moment
        self.bad_count += count

    def undecodable(self) -> str | None:
        """Why the receiver counts as undecodable: bad datagrams arrive and none decodes (none
        ever, or none for ``undecodable_after`` seconds of bad ones); None when it is not."""
        run, error = self._run, self.first_error
        if not run:
            return None
        if self.decoded_count and self._run_last - self._run_began < self.undecodable_after:
            return None
        what = f"{run} bad datagram" + ("" if run == 1 else "s")
        since = " since the last decoded one" if self.decoded_count else ", none decoded"
        return f"{what}{since}; first: {error or '-'}"

    def counters(self) -> dict[str, int]:
        """``datagrams``, ``decoded``, ``bad_datagrams`` and ``kernel_dropped``."""
        return {
            "datagrams": self.datagrams,
            "decoded": self.decoded_count,
            "bad_datagrams": self.bad_count,
            "kernel_dropped": self.kernel_dropped,
        }


class LedgeredReceiver:
    """For a receiver that keeps a ``ledger``: its ``datagrams``, ``bad_datagrams`` and
    ``kernel_dropped`` read from it."""

    ledger: DatagramLedger

    @property
    def datagrams(self) -> int:
        """Datagrams read."""
        return self.ledger.datagrams

    @property
    def bad_datagrams(self) -> int:
        """Datagrams that did not decode."""
        return self.ledger.bad_count

    @property
    def kernel_dropped(self) -> int:
        """Datagrams the kernel dropped for a full receive buffer (0 where the OS does not
        say)."""
        return self.ledger.kernel_dropped
