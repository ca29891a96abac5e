"""Writing a user's file without losing what was there.

:func:`replace_file` is how gadgetctl rewrites a file it read (``upgrade --in-place``) and
writes an output file (``upgrade -o``); :func:`create_new` opens a file it creates without
following a symbolic link (``--record``). The rules:

* a symbolic link is never replaced: the file it points to is rewritten, and the caller is
  told so (:attr:`Replaced.via_link`);
* the backup ``FILE.bak`` is made next to the resolved file, in a temporary file created
  exclusively and renamed over the old backup only once complete, so a ``.bak`` that is a
  symbolic link is replaced, never followed, and a full disk leaves the previous backup;
* owner, group and mode are kept on both the new file and the backup;
* when the file no longer holds what was read at the start, nothing is written
  (:class:`FileChangedError`, exit status 1);
* every OS error (read-only file system, full disk, permissions) becomes one
  :class:`WriteError` line, and no temporary file is left behind;
* a process killed outright (SIGKILL, a power cut) cannot remove its temporary files, so each
  is named ``.NAME.XXXXXXXX.gadgetctl.tmp`` and locked (``flock``) by its writer until it is
  renamed or removed: the kernel drops the lock with the process. The next write of the same
  file (and every file ``upgrade --in-place`` reads) removes the ones beside it that are
  provably abandoned (:func:`remove_stale_temporaries`): of that naming, regular, owned by
  the same user, unchanged for :data:`STALE_AFTER` seconds, and lockable.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import stat
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from gadgetctl.boundedread import InputRefused, read_limited
from gadgetctl.errors import GadgetctlError


class WriteError(GadgetctlError):
    """A file could not be written; nothing of the user's was changed."""


class FileChangedError(WriteError):
    """The file changed on disk while gadgetctl worked on it; it was left as it is."""

    exit_code = 1


@dataclass(frozen=True)
class Replaced:
    path: Path  # as the user named it
    target: Path  # the file actually written: ``path`` with symbolic links resolved
    backup: Path | None
    #: abandoned temporary files of earlier, killed writes removed first
    removed: tuple[Path, ...] = ()

    @property
    def via_link(self) -> bool:
        """Whether ``path`` itself is a symbolic link (links among its directories do not count)."""
        return os.path.islink(self.path)


#: How a temporary file of :func:`replace_file` ends (after ``.NAME.`` and random letters).
TEMPORARY_SUFFIX = ".gadgetctl.tmp"
#: Seconds a temporary file must be unchanged before another run may call it abandoned (its
#: writer locks it at once, so this only covers the moment between creating and locking).
STALE_AFTER = 60.0


def current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _why(err: OSError) -> str:
    return err.strerror or str(err)


class _Temporary:
    """A temporary file being written, locked by this process until :meth:`close`."""

    def __init__(self, path: Path, fd: int) -> None:
        self.path, self.fd = path, fd

    def close(self, remove: bool) -> None:
        """Release the lock (after removing the file, with ``remove``)."""
        if remove:
            with contextlib.suppress(OSError):
                self.path.unlink()
        with contextlib.suppress(OSError):
            os.close(self.fd)


def _write_temporary(
    directory: Path, prefix: str, data: bytes, like: os.stat_result | None
) -> _Temporary:
    """A complete, synced temporary file in ``directory`` holding ``data``, with the owner,
    group and mode of ``like`` (or the default mode of a new file), locked until closed."""
    handle, name = tempfile.mkstemp(
        prefix=prefix, suffix=TEMPORARY_SUFFIX, dir=directory
    )  # O_EXCL: never a link
    temporary = _Temporary(Path(name), handle)
    try:
        fcntl.flock(handle, fcntl.LOCK_EX)  # held while it lives: see remove_stale_temporaries
        with os.fdopen(handle, "wb", closefd=False) as out:
            out.write(data)
            out.flush()
            if like is not None:
                _keep_owner(handle, like)
                os.fchmod(handle, stat.S_IMODE(like.st_mode))
            else:
                os.fchmod(handle, 0o666 & ~current_umask())
            os.fsync(handle)
    except BaseException:
        temporary.close(remove=True)
        raise
    return temporary


def _abandoned(path: Path, now: float) -> bool:
    """Whether ``path`` (named as our temporaries are) is one whose writer is gone: a regular
    file of this user, unchanged for STALE_AFTER seconds, that no process holds locked."""
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        return False
    try:
        found = os.fstat(fd)
        if (
            not stat.S_ISREG(found.st_mode)
            or found.st_uid != os.geteuid()
            or now - found.st_mtime < STALE_AFTER
        ):
            return False
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return False  # its writer is alive
        current = os.lstat(path)  # still the file opened, not a new one of the same name
        return (current.st_ino, current.st_dev) == (found.st_ino, found.st_dev)
    except OSError:
        return False
    finally:
        os.close(fd)


def remove_stale_temporaries(path: Path) -> list[Path]:
    """Remove the abandoned temporary files of earlier writes of ``path`` (its target, when
    it is a symbolic link) and of its backup; the ones removed. Never raises."""
    target = Path(os.path.realpath(path))
    prefix = f".{target.name}."
    removed: list[Path] = []
    now = time.time()
    try:
        with os.scandir(target.parent) as entries:
            names = [
                e.name
                for e in entries
                if e.name.startswith(prefix) and e.name.endswith(TEMPORARY_SUFFIX)
            ]
    except OSError:
        return removed
    for name in names:
        candidate = target.parent / name
        if _abandoned(candidate, now):
            with contextlib.suppress(FileNotFoundError):
                candidate.unlink()
                removed.append(candidate)
    return removed


def _keep_owner(fd: int, like: os.stat_result) -> None:
    current = os.fstat(fd)
    if (current.st_uid, current.st_gid) == (like.st_uid, like.st_gid):
        return
    try:
        os.fchown(fd, like.st_uid, like.st_gid)
    except PermissionError:
        raise OSError(
            errno.EPERM,
            f"cannot keep its owner and group ({like.st_uid}:{like.st_gid}) "
            "without the right to change ownership",
        ) from None


def _same(before: os.stat_result, path: Path, expected: bytes) -> bool:
    try:
        now = os.stat(path)
        if (now.st_ino, now.st_dev, now.st_size) != (before.st_ino, before.st_dev, before.st_size):
            return False
        return read_limited(path, len(expected)) == expected
    except (InputRefused, FileNotFoundError):
        return False


def _sync_directory(directory: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def replace_file(
    path: Path, data: bytes, *, expected: bytes | None = None, backup: bool = False
) -> Replaced:
    """Replace the content of ``path`` (or create it) by ``data``, atomically.

    ``expected`` is the content the caller read: if the file holds anything else now, or
    when it is about to be replaced, :class:`FileChangedError` is raised and nothing is
    written. With ``backup`` the old content is kept in ``FILE.bak`` next to the resolved
    file. OS errors raise :class:`WriteError`.
    """
    path = Path(path)
    target = Path(os.path.realpath(path))
    shown = f"{path} (-> {target})" if os.path.islink(path) else str(path)
    removed = tuple(remove_stale_temporaries(target))
    temporaries: list[_Temporary] = []
    try:
        try:
            before: os.stat_result | None = os.stat(target)
        except FileNotFoundError:
            if expected is not None:
                raise FileChangedError(
                    f"{shown}: the file was removed while gadgetctl worked on it; nothing written"
                ) from None
            before = None
        if before is not None and not stat.S_ISREG(before.st_mode):
            raise WriteError(f"{shown}: not a regular file; nothing written")
        if expected is not None and not _same(before, target, expected):
            raise FileChangedError(
                f"{shown}: the file changed while gadgetctl worked on it; nothing written "
                "(run the command again)"
            )
        saved = None
        if backup and before is not None:
            old = expected if expected is not None else read_limited(target, before.st_size)
            saved = target.with_name(target.name + ".bak")
            temporaries.append(_write_temporary(target.parent, f".{saved.name}.", old, before))
        temporaries.append(_write_temporary(target.parent, f".{target.name}.", data, before))
        if expected is not None and not _same(before, target, expected):
            raise FileChangedError(
                f"{shown}: the file changed while gadgetctl worked on it; nothing written "
                "(run the command again)"
            )
        if saved is not None:
            # rename never follows a link at its destination: an old FILE.bak that is a
            # symbolic link is replaced, not written through
            os.rename(temporaries[0].path, saved)
            temporaries.pop(0).close(remove=False)
        os.replace(temporaries[-1].path, target)
        temporaries.pop().close(remove=False)
        _sync_directory(target.parent)
        return Replaced(path, target, saved, removed)
    except OSError as err:
        raise WriteError(f"{shown}: cannot write: {_why(err)}; nothing written") from None
    finally:
        for temporary in temporaries:
            temporary.close(remove=True)


def create_new(path: Path, *, overwrite: bool = False) -> int:
    """A descriptor of ``path`` opened for writing, created (exclusively unless
    ``overwrite``) and never through a symbolic link. Raises :class:`WriteError`."""
    flags = os.O_WRONLY | os.O_CREAT | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOFOLLOW", 0)
    flags |= os.O_TRUNC if overwrite else os.O_EXCL
    try:
        return os.open(path, flags, 0o666)
    except FileExistsError:
        raise WriteError(f"{path}: file exists (overwrite it explicitly)") from None
    except OSError as err:
        if err.errno == errno.ELOOP or os.path.islink(path):
            raise WriteError(
                f"{path}: is a symbolic link; not followed (remove it or name its target)"
            ) from None
        raise WriteError(f"{path}: cannot create: {_why(err)}") from None
