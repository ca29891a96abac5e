"""Ascension Wanda driver plug-in (element type ``wanda``).

The Wanda speaks the Logitech three-button serial-mouse protocol at 1200 baud, 7N1, with its
joystick as an absolute position. ``standalone.py`` holds the protocol, ``wrapper.py`` feeds
the input manager, ``emulator.py`` plays the Wanda on a pseudo-terminal.

Digital units 0..2 are buttons 0..2 (0/1; on the Wanda the rightmost button reports as 0);
analog units 0 and 1 the joystick's X and Y, raw -34..34.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Wanda_drv"
ELEMENT_TYPES = {"wanda": ("digital", "analog")}
TRANSPORTS = {"wanda": {"kind": "serial", "port": "port"}}


def register(registry):
    from .wrapper import WandaDevice

    registry.register_device(WandaDevice)
