"""Exceptions of the input manager. Each carries the reason a user is shown."""

from __future__ import annotations

import re


class InputError(Exception):
    """Base class of input-manager errors."""


class DeviceConfigError(InputError):
    """A device or proxy cannot be configured from its element; the message says why."""


class ElementVersionError(DeviceConfigError):
    """The element was written for an older definition version than the device accepts."""


class DeviceStartError(InputError):
    """A device's ``start_sampling`` failed; the message carries the driver's error."""


class RegistrationError(InputError):
    """A device class cannot be registered (not a device class, no element type)."""


class PluginError(InputError):
    """A driver plug-in cannot be used. ``code`` is the DRV diagnostic code of the reason."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


_ERRNO = re.compile(r"\[Errno -?\d+\] ")
#: How deep :func:`describe` follows an exception's causes (a chain is written by our
#: drivers, but a cycle or a very long one must not cost more than this).
CHAIN_LIMIT = 16


def describe(error: BaseException) -> str:
    """The reason an exception gives, in one line for statuses and reports: ``Type:
    message``; or, when an operating-system error caused it, one cause naming the resource
    once (``cannot open /dev/ttyUSB0: No such file or directory``, not the wrapped messages of
    each layer with their ``[Errno N]``)."""
    root = os_cause(error)
    if root is not None:
        return _one_cause(str(error), root)
    text = str(error)
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def os_cause(error: BaseException) -> OSError | None:
    """The innermost operating-system error (one with an errno) behind ``error``, itself
    included; None if there is none."""
    found: OSError | None = None
    seen: set[int] = set()
    current: BaseException | None = error
    while current is not None and id(current) not in seen and len(seen) < CHAIN_LIMIT:
        seen.add(id(current))
        if isinstance(current, OSError) and current.errno is not None and current.strerror:
            found = current
        cause = current.__cause__
        if cause is None and not current.__suppress_context__:
            cause = current.__context__
        current = cause
    return found


def _one_cause(text: str, root: OSError) -> str:
    text = _ERRNO.sub("", text) or str(root.strerror)
    resource = root.filename if isinstance(root.filename, str) else None
    if resource:
        quoted = f": {resource!r}"
        if text == f"{root.strerror}{quoted}":
            return f"{resource}: {root.strerror}"
        if text.endswith(quoted) and resource in text[: -len(quoted)]:
            text = text[: -len(quoted)]
        parts = text.split(": ")
        kept: list[str] = []
        named = False
        for index, part in enumerate(parts):
            if resource in part:
                if named and index < len(parts) - 1:
                    continue  # another layer naming the same port or file
                named = True
            kept.append(part)
        text = ": ".join(kept)
    return text
