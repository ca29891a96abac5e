"""Ascension Flock of Birds driver plug-in (element type ``flock``).

The birds talk over one serial line (to the master bird): single-byte commands, binary
records framed by a phasing bit. ``standalone.py`` holds the protocol, ``wrapper.py`` feeds
the input manager, ``emulator.py`` plays a flock on a pseudo-terminal.

Position unit i is the i-th bird with a sensor, lowest FBB address first; the translation
is in feet, as Gadgeteer gives it (VR Juggler's configurations convert with a device-level
``position_transform_filter`` whose ``device_units`` is 0.3048).
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Flock_drv"
ELEMENT_TYPES = {"flock": ("position",)}
TRANSPORTS = {"flock": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import FlockDevice

    registry.register_device(FlockDevice)
