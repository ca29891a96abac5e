"""Polhemus Fastrak driver plug-in (element type ``fastrak``).

The tracker talks over a serial line: ASCII commands, binary records streamed in continuous
mode. ``standalone.py`` holds the protocol, ``wrapper.py`` feeds the input manager,
``emulator.py`` plays the tracker on a pseudo-terminal.

Position units 0..3 are stations 1..4; digital unit 0 is station 1's stylus switch.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Fastrak_drv"
ELEMENT_TYPES = {"fastrak": ("position", "digital")}
TRANSPORTS = {"fastrak": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import FastrakDevice

    registry.register_device(FastrakDevice)
