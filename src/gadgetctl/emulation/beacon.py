"""Telling others that a live emulator holds a path it made (a pty link, a FIFO, a socket).

An emulator that creates a path also binds a Linux abstract-namespace Unix socket whose
name is derived from the path's own identity (device and inode, from ``lstat``). The
kernel drops the name when the process ends, however it ends (even SIGKILL), so
:func:`is_held` tells a live emulator's path from a stale one left behind, without any
file to clean up. (A path removed and made again at once may get the same inode number
on some file systems; the beacon then vouches for it while its emulator lives.) Where
abstract sockets do not exist (not Linux) beacons are silently absent.
"""

from __future__ import annotations

import contextlib
import os
import socket
import sys

PREFIX = b"\0gadgetctl-emulation:"


def beacon_name(path: str | os.PathLike[str]) -> bytes | None:
    """The abstract socket name for ``path`` as it is now (None if it does not exist)."""
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return PREFIX + f"{st.st_dev}:{st.st_ino}".encode()


class Beacon:
    """Holds the abstract name of ``path`` while open; :meth:`close` lets it go."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = os.fspath(path)
        self._sock: socket.socket | None = None
        name = beacon_name(path)
        if name is None or not sys.platform.startswith("linux"):
            return
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            sock.bind(name)
            sock.listen(1)
        except OSError:
            sock.close()  # another process vouches for it already, or no abstract sockets
            return
        self._sock = sock

    @property
    def held(self) -> bool:
        return self._sock is not None

    def close(self) -> None:
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.close()


def is_held(path: str | os.PathLike[str]) -> bool | None:
    """Whether a live emulator vouches for ``path``; None when this cannot be known here."""
    if not sys.platform.startswith("linux"):
        return None
    name = beacon_name(path)
    if name is None:
        return False
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        probe.bind(name)  # free: nobody holds it
    except OSError:
        return True
    finally:
        probe.close()
    return False
