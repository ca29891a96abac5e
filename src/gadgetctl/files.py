"""Turning the paths a user names into the JCCL files to check."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from gadgetctl.errors import GadgetctlError

JCCL_SUFFIXES = (".jdef", ".jconf")


def expand_paths(paths: Iterable[Path]) -> list[Path]:
    """Files as given, directories searched recursively for .jdef and .jconf files.

    Missing or unreadable paths raise :class:`GadgetctlError`. The result is sorted per
    argument and free of duplicates.
    """
    found: list[Path] = []
    seen: set[Path] = set()
    for path in paths:
        if not path.exists():
            raise GadgetctlError(f"{path}: no such file or directory")
        if path.is_dir():
            if not os.access(path, os.R_OK | os.X_OK):
                raise GadgetctlError(f"{path}: directory is not readable")
            candidates = sorted(
                p for p in path.rglob("*")
                if p.suffix in JCCL_SUFFIXES and p.is_file() and not _hidden(p.relative_to(path))
            )
        else:
            if not os.access(path, os.R_OK):
                raise GadgetctlError(f"{path}: file is not readable")
            candidates = [path]
        for candidate in candidates:
            key = candidate.resolve()
            if key not in seen:
                seen.add(key)
                found.append(candidate)
    return found


def _hidden(relative: Path) -> bool:
    return any(part.startswith(".") for part in relative.parts)


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
