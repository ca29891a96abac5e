"""5DT Data Glove Ultra Wireless driver plug-in (element type ``data_glove_ultra_wireless``).

One serial receiver (115200 baud by default) carries two gloves, on ports A and B.
``standalone.py`` holds the protocol, ``wrapper.py`` feeds the input manager, ``emulator.py``
plays the receiver on a pseudo-terminal.

Analog units 0..13 are glove A's fourteen sensors, 14..27 glove B's, auto-ranged to 0..1;
command units 0 and 1 are the gestures of gloves A and B (0..15, -1 for none).
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "DataGloveUltraWireless_drv"
ELEMENT_TYPES = {"data_glove_ultra_wireless": ("analog", "command")}
TRANSPORTS = {"data_glove_ultra_wireless": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import UltraGloveDevice

    registry.register_device(UltraGloveDevice)
