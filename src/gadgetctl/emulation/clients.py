"""Knowing when a driver opens and closes an emulator's device file (a pty slave, a FIFO).

A pseudo-terminal's master is not told when someone opens the slave, but Linux inotify is:
an :class:`OpenWatch` on the path counts the opens and closes made after it was set up (so
the emulator's own, earlier, open does not count). Where inotify is missing (not Linux, no
watches left) the watch is inert: :attr:`OpenWatch.available` is False and nothing is said.

inotify merges identical events that wait unread, so two opens (or closes) in quick
succession may count as one: once a close is reported, :func:`openers` counts the
descriptors that still refer to the path (from /proc), which is exact by then.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import struct
import sys

IN_CLOSE_WRITE = 0x00000008
IN_CLOSE_NOWRITE = 0x00000010
IN_OPEN = 0x00000020
IN_NONBLOCK = os.O_NONBLOCK
IN_CLOEXEC = 0o2000000
_EVENT = struct.Struct("iIII")  # wd, mask, cookie, len (then len bytes of name)


def _libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
    except OSError:
        return None
    return libc if hasattr(libc, "inotify_init1") else None


def openers(path: str | os.PathLike[str], exclude: frozenset[tuple[int, int]] = frozenset()) -> int:
    """How many open descriptors of any process (that /proc lets us see) refer to ``path``,
    leaving out the ``(pid, fd)`` pairs in ``exclude``; -1 when /proc cannot be read."""
    target = os.fspath(path)
    try:
        pids = [name for name in os.listdir("/proc") if name.isdigit()]
    except OSError:
        return -1
    count = 0
    for pid in pids:
        folder = f"/proc/{pid}/fd"
        try:
            fds = os.listdir(folder)
        except OSError:
            continue  # gone, or not ours to see
        for fd in fds:
            if (int(pid), int(fd)) in exclude:
                continue
            try:
                if os.readlink(f"{folder}/{fd}") == target:
                    count += 1
            except OSError:
                continue
    return count


class OpenWatch:
    """Counts the opens and closes of ``path`` by anyone, from now on.

    :meth:`fileno` is readable when something happened; :meth:`poll` then returns how many
    opens and closes were reported since the last call (identical events waiting unread are
    merged by the kernel, so these are lower bounds)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = os.fspath(path)
        self._fd = -1
        libc = _libc()
        if libc is None:
            return
        fd = libc.inotify_init1(IN_NONBLOCK | IN_CLOEXEC)
        if fd < 0:
            return
        mask = IN_OPEN | IN_CLOSE_WRITE | IN_CLOSE_NOWRITE
        if libc.inotify_add_watch(fd, os.fsencode(self.path), mask) < 0:
            os.close(fd)
            return
        self._fd = fd

    @property
    def available(self) -> bool:
        return self._fd >= 0

    def fileno(self) -> int:
        return self._fd

    def poll(self) -> tuple[int, int]:
        """``(opens, closes)`` reported since the last call ((0, 0) when inert)."""
        opens = closes = 0
        while self._fd >= 0:
            try:
                data = os.read(self._fd, 4096)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                self.close()
                break
            if not data:
                break
            offset = 0
            while offset + _EVENT.size <= len(data):
                _wd, mask, _cookie, length = _EVENT.unpack_from(data, offset)
                offset += _EVENT.size + length
                if mask & IN_OPEN:
                    opens += 1
                if mask & (IN_CLOSE_WRITE | IN_CLOSE_NOWRITE):
                    closes += 1
        return opens, closes

    def close(self) -> None:
        fd, self._fd = self._fd, -1
        if fd >= 0:
            with contextlib.suppress(OSError):
                os.close(fd)
