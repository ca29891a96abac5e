"""Reading a user's input file with a size limit, whatever the path names.

Every command reads configurations, definitions and recordings through :func:`read_limited`:
a path that is not a regular file (a device such as /dev/zero, a FIFO, a socket) is refused
before anything is read, so nothing blocks or grows without bound, and a regular file is
read only up to the limit (its size as the file system reports it is not trusted: files
under /proc report 0).
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

DEFAULT_MAX_SIZE = 16 * 1024 * 1024
_CHUNK = 1 << 20


class InputRefused(OSError):
    """A path that was not read; ``strerror`` says why in words fit for a diagnostic."""


class FileTooLarge(InputRefused):
    pass


class NotRegularFile(InputRefused):
    pass


def file_kind(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def too_large_message(limit: int, size: int | None = None) -> str:
    if size is None:
        return f"file is larger than the limit of {limit} bytes; not read"
    return f"file is {size} bytes, above the limit of {limit}; not read"


def read_limited(path: str | os.PathLike[str], max_size: int = DEFAULT_MAX_SIZE) -> bytes:
    """The content of the regular file ``path``, at most ``max_size`` bytes.

    Raises :class:`NotRegularFile` or :class:`FileTooLarge` (both :class:`OSError`) instead
    of reading what could block or not end; other I/O errors propagate as they are.
    """
    # O_NONBLOCK: opening a FIFO must not wait for a writer (regular files ignore the flag).
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise NotRegularFile(
                errno.EINVAL, f"{file_kind(info.st_mode)}, not a regular file; not read", str(path)
            )
        if info.st_size > max_size:
            raise FileTooLarge(errno.EFBIG, too_large_message(max_size, info.st_size), str(path))
        chunks: list[bytes] = []
        total = 0
        while True:
            chunk = os.read(fd, min(_CHUNK, max_size + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
            if total > max_size:
                raise FileTooLarge(errno.EFBIG, too_large_message(max_size), str(path))
        return b"".join(chunks)
    finally:
        os.close(fd)


def check_readable_file(path: Path) -> str | None:
    """Why ``path`` cannot be read as an input file (missing, not regular), or None."""
    try:
        info = path.stat()
    except FileNotFoundError:
        return "no such file"
    except OSError as err:
        return err.strerror or str(err)
    if not stat.S_ISREG(info.st_mode):
        return f"{file_kind(info.st_mode)}, not a regular file"
    return None


def open_regular(path: str | os.PathLike[str]) -> BinaryIO:
    """``path`` opened for binary reading, for input read in pieces (recordings); refuses
    what is not a regular file with :class:`NotRegularFile`, without blocking on a FIFO."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise NotRegularFile(
                errno.EINVAL, f"{file_kind(info.st_mode)}, not a regular file; not read", str(path)
            )
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def bounded_lines(stream: BinaryIO, limit: int) -> Iterator[bytes | None]:
    """The lines of ``stream``; a line longer than ``limit`` bytes is consumed in pieces
    and yielded as None, so one endless line never fills memory."""
    while True:
        line = stream.readline(limit + 1)
        if not line:
            return
        if len(line) > limit and not line.endswith(b"\n"):
            while True:
                rest = stream.readline(limit)
                if not rest or rest.endswith(b"\n"):
                    break
            yield None
            continue
        yield line
