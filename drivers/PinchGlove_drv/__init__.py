"""Fakespace PinchGlove driver plug-in (element type ``pinch_glove``).

The glove box talks over a serial line: two-byte commands answered by
``0x82 ... 0x8F`` info frames, and asynchronous touch frames whenever a contact
between fingers opens or closes. ``standalone.py`` holds the protocol,
``wrapper.py`` feeds the input manager, ``emulator.py`` plays the glove box on a
pseudo-terminal.

Digital units 0..4 are the left pinky, ring, middle, index and thumb (bit k of the
left contact byte), 5..9 the right ones in the same order; glove units 0 and 1 are
the left and right hand.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "PinchGlove_drv"
ELEMENT_TYPES = {"pinch_glove": ("glove", "digital")}
TRANSPORTS = {"pinch_glove": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import PinchGloveDevice

    registry.register_device(PinchGloveDevice)
