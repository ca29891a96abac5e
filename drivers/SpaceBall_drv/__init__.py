"""3Dconnexion SpaceMouse / SpaceBall driver plug-in (element type ``puck_device``).

The puck talks over a serial line at 9600 baud in carriage-return-ended records: the
SpaceMouse (Magellan, also the SpaceBall 5000 and the SpaceMouse Plus XT) in printable
"nibble" characters, the SpaceBall 4000 FLX and 2003B in binary. ``standalone.py`` holds
the protocols, ``wrapper.py`` feeds the input manager, ``emulator.py`` plays the puck on a
pseudo-terminal.

Analog units 0..5 are the raw axes tx, ty, tz, rx, ry, rz; digital units 0..11 are
buttons 1..12 (0/1).
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "SpaceBall_drv"
ELEMENT_TYPES = {"puck_device": ("digital", "analog")}
TRANSPORTS = {"puck_device": {"kind": "serial", "port": "port", "baud": "baud"}}


def register(registry):
    from .wrapper import PuckDevice

    registry.register_device(PuckDevice)
