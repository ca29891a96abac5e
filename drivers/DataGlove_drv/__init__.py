"""5DT DataGlove driver plug-in (element type ``data_glove``).

The glove streams 10-byte packets over a serial line (38400 baud by default): five finger
flexures, pitch, roll, a checksum and the hand. ``standalone.py`` holds the protocol,
``wrapper.py`` feeds the input manager, ``emulator.py`` plays the glove on a pseudo-terminal.

Analog units 0..8 are the thumb..pinky flexures (0..1), pitch and roll (degrees, 0..180),
the gesture number (0..16) and the capability byte (0 right glove, 6 left); glove unit 0 is
the hand's joint angles.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "DataGlove_drv"
ELEMENT_TYPES = {"data_glove": ("glove", "analog")}
TRANSPORTS = {"data_glove": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import DataGloveDevice

    registry.register_device(DataGloveDevice)
