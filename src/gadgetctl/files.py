"""Turning the paths a user names into the JCCL files to check."""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from functools import lru_cache
from pathlib import Path

from gadgetctl.errors import GadgetctlError

JCCL_SUFFIXES = (".jdef", ".jconf")


def expand_paths(paths: Iterable[Path]) -> list[Path]:
    """Files as given, directories searched recursively for .jdef and .jconf files.

    Missing or unreadable paths, and directories without such files (a check that checks
    nothing must not pass), raise :class:`GadgetctlError`. The result is sorted per
    argument and free of duplicates.
    """
    return [path for path, _ in resolved_paths(paths)]


def resolved_paths(paths: Iterable[Path]) -> list[tuple[Path, str]]:
    """:func:`expand_paths`, each file with its real path (:func:`real_path_text`), which
    tells duplicates apart: a caller that needs it again need not look it up again."""
    found: list[tuple[Path, str]] = []
    seen: set[str] = set()
    for path in paths:
        try:
            directory = stat.S_ISDIR(path.stat().st_mode)
        except (FileNotFoundError, NotADirectoryError):
            raise GadgetctlError(
                f"{path}: no such file or directory{_nearby(path, JCCL_SUFFIXES)}"
            ) from None
        except OSError as err:  # a directory on the way that may not be searched, a loop
            raise GadgetctlError(f"{path}: cannot look it up: {err.strerror or err}") from None
        if directory:
            if not os.access(path, os.R_OK | os.X_OK):
                raise GadgetctlError(f"{path}: directory is not readable")
            candidates = _jccl_entries(path)
            if not candidates:
                raise GadgetctlError(
                    f"{path}: no .jconf or .jdef files in this directory or below "
                    "(hidden ones are skipped): nothing to check"
                )
        else:
            if not os.access(path, os.R_OK):
                raise GadgetctlError(f"{path}: file is not readable")
            candidates = [(path, None)]
        for candidate, link in candidates:
            key = real_path_text(str(candidate), link=link)
            if key not in seen:
                seen.add(key)
                found.append((candidate, key))
    return found


@lru_cache(maxsize=4096)
def _real_directory(directory: str) -> str:
    return os.path.realpath(directory)


def real_path_text(path: str, *, link: bool | None = None) -> str:
    """``str(Path(path).resolve())``, with the directory part resolved once per directory
    (a path through ``..``, which abspath would take lexically, is resolved whole).
    ``link``: whether ``path`` itself is a symbolic link, when the caller knows (None:
    looked up)."""
    if link is None:
        link = os.path.islink(path)
    if link or os.pardir in path.split(os.sep):
        return str(Path(path).resolve())
    directory, name = os.path.split(os.path.abspath(path))
    return os.path.join(_real_directory(directory), name)


def real_path(path: str) -> Path:
    """``Path(path).resolve()``, with the directory part resolved once per directory."""
    return Path(real_path_text(path))


def _jccl_files(directory: Path) -> list[Path]:
    """The .jdef and .jconf files in ``directory`` and below, sorted, hidden ones (and hidden
    directories) left out, symbolic links to directories not followed. A directory below that
    cannot be read is an error: its files would pass unchecked; one that is gone by the time
    it is read (a build's temporary folder) had none."""
    return [path for path, _ in _jccl_entries(directory)]


def _jccl_entries(directory: Path) -> list[tuple[Path, bool]]:
    """:func:`_jccl_files`, each with whether it is a symbolic link.

    Walked as :func:`os.walk` walks (top down, each directory's entries in listing order),
    with the kinds the listing gives, so that a plain file or directory costs no stat."""
    found: list[tuple[str, bool]] = []
    root = os.fspath(directory)
    pending = [root]
    while pending:
        top = pending.pop()
        try:
            with os.scandir(top) as listing:
                entries = list(listing)
        except OSError as err:
            if top is not root and isinstance(err, (FileNotFoundError, NotADirectoryError)):
                continue  # removed (or replaced by a file) since its parent was listed
            raise GadgetctlError(
                f"{err.filename}: directory is not readable ({err.strerror or err}); "
                "the files in it cannot be checked"
            ) from None
        below = []
        for entry in entries:
            name = entry.name
            if name.startswith("."):
                continue
            if entry_is_dir(entry):
                if not entry.is_symlink():
                    below.append(entry.path)
            elif name.endswith(JCCL_SUFFIXES) and entry_is_file(entry):
                found.append((entry.path, entry.is_symlink()))
        pending.extend(reversed(below))
    # in the order of Path objects: by their parts (every path here starts alike)
    found.sort(key=lambda pair: pair[0].split(os.sep))
    return [(Path(path), link) for path, link in found]


def entry_is_dir(entry: os.DirEntry) -> bool:
    """``entry.is_dir()`` of a directory listing's entry, False when the OS refuses."""
    try:
        return entry.is_dir()
    except OSError:
        return False


def entry_is_file(entry: os.DirEntry) -> bool:
    """``entry.is_file()`` of a directory listing's entry, False when the OS refuses."""
    try:
        return entry.is_file()
    except OSError:
        return False


def is_file(path: Path) -> bool:
    """``path.is_file()``, False instead of an error for a path the OS refuses to look up
    (a name over 255 bytes, a permission denied on the way)."""
    try:
        return path.is_file()
    except OSError:
        return False


def is_dir(path: Path) -> bool:
    """``path.is_dir()``, False instead of an error for a path the OS refuses to look up."""
    try:
        return path.is_dir()
    except OSError:
        return False


def require_file(
    path: Path, what: str = "configuration file", suffixes: tuple[str, ...] = (".jconf",)
) -> None:
    """Raise :class:`GadgetctlError` unless ``path`` is a readable file, saying what it is
    instead (a directory, nothing: with the closest ``suffixes`` files beside it)."""
    from gadgetctl.boundedread import check_readable_file

    if is_dir(path):
        raise GadgetctlError(f"{path}: is a directory, not a {what}")
    problem = check_readable_file(path)
    if problem == "no such file":
        raise GadgetctlError(f"{path}: no such {what}{_nearby(path, suffixes)}")
    if problem is not None:
        raise GadgetctlError(f"{path}: {problem}")
    if not os.access(path, os.R_OK):
        raise GadgetctlError(f"{path}: file is not readable")


def _nearby(path: Path, suffixes: tuple[str, ...]) -> str:
    """`` (did you mean 'dir/name.jconf'?)`` for files of the same directory named alike."""
    from gadgetctl.suggest import close_names

    parent = path.parent
    try:
        names = (
            [p.name for p in parent.iterdir() if p.suffix in suffixes and p.is_file()]
            if parent.is_dir()
            else []
        )
    except OSError:
        return ""
    close = close_names(path.name, names)
    if not close:
        return ""
    shown = [
        str(parent / name) if str(parent) != "." or str(path).startswith("./") else name
        for name in close
    ]
    return f" (did you mean {' or '.join(shown)}?)"
