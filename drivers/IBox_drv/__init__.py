"""Immersion Interface Box driver plug-in (element type ``ibox``).

The box talks Immersion's HCI protocol over a serial line: a sign-on, then one packet per
query byte. ``standalone.py`` holds the protocol, ``wrapper.py`` feeds the input manager,
``emulator.py`` plays the box on a pseudo-terminal.

Digital units 0..3 are buttons 0..3 (0/1); analog units 0..3 the four analog inputs, raw
0..255 (analog proxies normalise with the element's ``min``/``max``, 0 and 255).
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "IBox_drv"
ELEMENT_TYPES = {"ibox": ("digital", "analog")}
TRANSPORTS = {"ibox": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import IBoxDevice

    registry.register_device(IBoxDevice)
