"""Logitech 3D mouse / head tracker driver plug-in (element type ``three_d_mouse``).

The mouse talks over a serial line (8 data bits, 2 stop bits): two-byte commands, 16-byte
reports polled with ``*d``. ``standalone.py`` holds the protocol, ``wrapper.py`` feeds the
input manager, ``emulator.py`` plays the mouse on a pseudo-terminal.

Position unit 0 is the mouse; digital units 0, 1, 2 are its left, middle and right buttons.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "ThreeDMouse_drv"
ELEMENT_TYPES = {"three_d_mouse": ("position", "digital")}
TRANSPORTS = {"three_d_mouse": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import ThreeDMouseDevice

    registry.register_device(ThreeDMouseDevice)
