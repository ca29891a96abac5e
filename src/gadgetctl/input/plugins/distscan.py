"""Whether any installed distribution may declare an entry point group, answered from the
metadata folders on ``sys.path`` without importing :mod:`importlib.metadata`.

Importing importlib.metadata (and the email package it reads metadata with) costs more than
a command such as ``gadgetctl validate`` spends on most files, and usually no distribution
declares a driver plug-in at all. :func:`may_declare` is a conservative test: it is False only
when no ``entry_points.txt`` of a ``*.dist-info`` or ``*.egg-info`` folder on ``sys.path``
mentions the group and nothing else could hold distributions (a zip file or an ``.egg`` on
``sys.path``, a meta path finder of another kind that finds distributions); otherwise the
caller asks importlib.metadata, which stays the authority on what is declared.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable

#: The suffixes of the folders importlib.metadata reads distributions from.
METADATA_SUFFIXES = (".dist-info", ".egg-info")
#: More than any entry_points.txt holds; a longer one is read that far.
_LIMIT = 1 << 20


def may_declare(group: str, path: Iterable[str] | None = None) -> bool:
    """False when no distribution on ``path`` (default ``sys.path``) can declare ``group``."""
    if _other_distribution_finders():
        return True
    needle = group.encode("utf-8")
    for entry in sys.path if path is None else path:
        base = entry or "."
        if base.lower().endswith(".egg"):
            return True  # an egg keeps its metadata in EGG-INFO (or inside a zip)
        try:
            listing = os.scandir(base)
        except NotADirectoryError:
            return True  # a zip file on sys.path
        except OSError:
            continue  # missing or unreadable: importlib.metadata finds nothing there either
        with listing:
            folders = [e.path for e in listing if e.name.lower().endswith(METADATA_SUFFIXES)]
        for folder in folders:
            if needle in _entry_points_text(folder):
                return True
    return False


def _entry_points_text(folder: str) -> bytes:
    try:
        with open(os.path.join(folder, "entry_points.txt"), "rb") as f:
            return f.read(_LIMIT)
    except OSError:  # none (most distributions), or the folder is a file (a PKG-INFO egg-info)
        return b""


def _other_distribution_finders() -> bool:
    """Whether a meta path finder other than the standard path finder finds distributions
    (importlib.metadata asks every finder that has ``find_distributions``)."""
    from importlib.machinery import PathFinder

    return any(
        finder is not PathFinder and getattr(finder, "find_distributions", None) is not None
        for finder in sys.meta_path
    )
