"""US Digital serial encoder driver plug-in (element type ``serial_encoder``).

Two encoders on an SEI bus (9600 baud) give a table's tilt (address 1, degrees) and height
(address 2, inches); position unit 0 is T(height) . R_x(tilt) in meters. ``standalone.py``
holds the bus protocol, ``wrapper.py`` feeds the input manager, ``emulator.py`` plays the
encoders on a pseudo-terminal.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "SerialEncoder_drv"
ELEMENT_TYPES = {"serial_encoder": ("position",)}
TRANSPORTS = {"serial_encoder": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import SerialEncoderDevice

    registry.register_device(SerialEncoderDevice)
