"""InterSense IS-900 driver plug-in (element type ``intersense`` with ``intersense_station``
children).

The tracker talks over a serial line: Fastrak-style ASCII commands, binary data records
polled with ``P``. ``standalone.py`` holds the protocol, ``wrapper.py`` feeds the input
manager, ``emulator.py`` plays the tracker on a pseudo-terminal.

Position unit i is the i-th configured station; each station's wand buttons and joystick
bytes go to the digital and analog units its ``digital_first``/``analog_first`` name.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "IS900_drv"
ELEMENT_TYPES = {"intersense": ("position", "digital", "analog")}
TRANSPORTS = {"intersense": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import IntersenseDevice

    registry.register_device(IntersenseDevice)
