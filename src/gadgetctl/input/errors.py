"""Exceptions of the input manager. Each carries the reason a user is shown."""

from __future__ import annotations


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


def describe(error: BaseException) -> str:
    """``Type: message`` of an exception, for statuses and reports."""
    text = str(error)
    return f"{type(error).__name__}: {text}" if text else type(error).__name__
