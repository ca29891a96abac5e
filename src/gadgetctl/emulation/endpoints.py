"""The OS endpoints an emulator creates, and their removal: a pseudo-terminal with an
optional symlink to it, a FIFO, a Unix socket.

Each one is made on ``open()``/``create()`` and undone by ``close()``/``remove()``, which
may be called more than once and after a half-done start. Removal only takes away what is
still the emulator's own (the same inode it made; a link still pointing at its pty), so an
emulator that stops late never deletes what another one made meanwhile, and nothing the
user had is replaced: an existing path that is not a leftover of the same kind is refused.
While it exists, each path is vouched for by a :class:`~gadgetctl.emulation.beacon.Beacon`,
so `gadgetctl doctor` can tell a live emulator's path from a stale one.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import socket
import stat
import struct
import termios
import threading
import tty
from pathlib import Path

from gadgetctl.emulation.beacon import Beacon, is_held


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _target(link: Path) -> str | None:
    try:
        return os.readlink(link)
    except OSError:
        return None


class PseudoTerminal:
    """A pty pair standing in for a serial line: the emulator keeps the master (non-blocking),
    the driver opens ``address`` (the slave's path, raw mode). ``link`` optionally names a
    symlink to create pointing at the slave; an existing symlink there is replaced (a
    leftover of an earlier run), anything else is refused with :class:`FileExistsError`."""

    def __init__(self, link: str | os.PathLike[str] | None = None) -> None:
        self.link = Path(link) if link is not None else None
        self.master = -1
        self.slave = -1
        self.address = ""
        self._beacons: list[Beacon] = []
        self._link_identity: tuple[int, int] | None = None
        self._lock = threading.Lock()

    def open(self) -> PseudoTerminal:
        if self.master >= 0:
            return self
        if self.link is not None and os.path.lexists(self.link) and not self.link.is_symlink():
            raise FileExistsError(
                errno.EEXIST, "exists and is not a symlink; not replacing it", str(self.link)
            )
        if self.link is not None and is_held(self.link):  # not a leftover: a live emulator's
            raise FileExistsError(
                errno.EEXIST,
                "is the link of another emulator that is running; stop it or give this one "
                "another --port",
                str(self.link),
            )
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)  # no echo, no line editing, bytes pass untouched
        os.set_blocking(self.master, False)
        self.address = os.ttyname(self.slave)
        self._beacons.append(Beacon(self.address))
        if self.link is not None:
            with contextlib.suppress(FileNotFoundError):
                self.link.unlink()
            self.link.symlink_to(self.address)
            self._link_identity = _identity(self.link)
            self._beacons.append(Beacon(self.link))
        return self

    def hang_up(self) -> None:
        """Close both sides (the driver sees the line go); the link stays until close()."""
        with self._lock:
            for fd in (self.master, self.slave):
                if fd >= 0:
                    with contextlib.suppress(OSError):
                        os.close(fd)
            self.master = self.slave = -1

    def close(self) -> None:
        """Remove the link (if it is still ours) and close both sides."""
        if self.link is not None and self._link_identity is not None:
            if _identity(self.link) == self._link_identity and _target(self.link) == self.address:
                with contextlib.suppress(FileNotFoundError):
                    self.link.unlink()
            self._link_identity = None
        for beacon in self._beacons:
            beacon.close()
        self._beacons.clear()
        self.hang_up()

    def write(self, data: bytes) -> int:
        """Write to the driver without blocking; returns the bytes taken (0 when closed)."""
        with self._lock:
            if self.master < 0:
                return 0
            try:
                return os.write(self.master, data)
            except BlockingIOError:
                return 0

    def unread(self) -> int:
        """Bytes written to the driver that it has not read yet (0 once closed). The kernel
        moves written bytes to the reader's queue a moment later, so a write just made may
        not show yet."""
        with self._lock:
            if self.slave < 0:
                return 0
            try:
                raw = fcntl.ioctl(self.slave, termios.FIONREAD, b"\0\0\0\0")
            except OSError:
                return 0
        return struct.unpack("i", raw)[0]

    def __enter__(self) -> PseudoTerminal:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()


class Fifo:
    """A FIFO at ``path`` that a driver reads as its device file. An existing FIFO there is
    taken over (a leftover); anything else is refused with :class:`FileExistsError`."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self._identity: tuple[int, int] | None = None
        self._beacon: Beacon | None = None

    def create(self) -> Fifo:
        if self._identity is not None:
            return self
        if os.path.lexists(self.path) and not stat.S_ISFIFO(os.lstat(self.path).st_mode):
            raise FileExistsError(errno.EEXIST, "exists and is not a FIFO", str(self.path))
        if is_held(self.path):  # not a leftover: a live emulator's
            raise FileExistsError(
                errno.EEXIST,
                "is the FIFO of another emulator that is running; stop it or give this one "
                "another path",
                str(self.path),
            )
        if not os.path.lexists(self.path):
            os.mkfifo(self.path)
        self._own()
        return self

    def open_writer(self, stop: threading.Event, poll_interval: float) -> int | None:
        """Open for writing (non-blocking) once a reader has the FIFO open; None if ``stop``
        is set first. A reader is noticed within ``poll_interval`` seconds."""
        while not stop.is_set():
            try:
                return os.open(self.path, os.O_WRONLY | os.O_NONBLOCK)
            except OSError as exc:
                if exc.errno != errno.ENXIO:  # ENXIO: no reader yet
                    raise
            stop.wait(poll_interval)
        return None

    def replace(self) -> None:
        """A new FIFO at the same path: the current reader gets end of file, a new open
        finds the new one (a device unplugged and plugged in again)."""
        self.remove()
        os.mkfifo(self.path)
        self._own()

    def remove(self) -> None:
        """Remove the FIFO if it is still the one made or taken over here."""
        if self._beacon is not None:
            self._beacon.close()
            self._beacon = None
        if self._identity is not None and _identity(self.path) == self._identity:
            with contextlib.suppress(FileNotFoundError):
                self.path.unlink()
        self._identity = None

    def _own(self) -> None:
        self._identity = _identity(self.path)
        self._beacon = Beacon(self.path)


class UnixSocket:
    """A listening (stream) or bound (datagram) Unix socket at ``path``, removed on close.
    A leftover socket file there is replaced; anything else is refused."""

    def __init__(self, path: str | os.PathLike[str], kind: int = socket.SOCK_STREAM) -> None:
        self.path = Path(path)
        self.kind = kind
        self.sock: socket.socket | None = None
        self._identity: tuple[int, int] | None = None
        self._beacon: Beacon | None = None

    def open(self) -> socket.socket:
        if self.sock is not None:
            return self.sock
        if os.path.lexists(self.path):
            if not stat.S_ISSOCK(os.lstat(self.path).st_mode):
                raise FileExistsError(errno.EEXIST, "exists and is not a socket", str(self.path))
            self.path.unlink()
        sock = socket.socket(socket.AF_UNIX, self.kind)
        try:
            sock.bind(str(self.path))
            if self.kind == socket.SOCK_STREAM:
                sock.listen(4)
        except BaseException:
            sock.close()
            raise
        self.sock = sock
        self._identity = _identity(self.path)
        self._beacon = Beacon(self.path)
        return sock

    def close(self) -> None:
        if self._beacon is not None:
            self._beacon.close()
            self._beacon = None
        if self._identity is not None and _identity(self.path) == self._identity:
            with contextlib.suppress(FileNotFoundError):
                self.path.unlink()
        self._identity = None
        sock, self.sock = self.sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.close()
