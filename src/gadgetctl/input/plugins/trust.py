"""Whose code a plug-in is: plug-in code is imported only from places no other user can
write to, unless the user accepts them (``--trust-driver-path``).

A configuration names its own ``driver_path``; if that directory (or the plug-in in it) is
writable by other users, any of them can put code there that gadgetctl would run as the
user who runs it (often root, for device access). Installed packages (entry points) and
the bundled drivers are trusted as the installation is.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from gadgetctl.input.plugins.discovery import PluginInfo, PluginSource

_accepted = False


def accept_writable_places(accept: bool = True) -> None:
    """Import plug-ins from places writable by others too (``--trust-driver-path``)."""
    global _accepted
    _accepted = accept


def writable_places_accepted() -> bool:
    return _accepted


def _open_to_others(path: Path) -> bool:
    try:
        info = path.stat()
    except OSError:
        return False
    return bool(info.st_mode & stat.S_IWOTH) or info.st_uid not in (0, os.geteuid())


def writable_by_others(info: PluginInfo) -> Path | None:
    """The first place of the plug-in (its directory, its folder or file, its modules)
    that a user other than root and the current one can write to, or None."""
    if info.module is not None or info.source is PluginSource.BUNDLED:
        return None
    places = [info.path.parent, info.path]
    if info.package:
        try:
            places += sorted(p for p in info.path.rglob("*.py"))
        except OSError:
            pass
    found = next((p for p in places if _open_to_others(p)), None)
    return None if found is None else Path(os.path.normpath(found))
