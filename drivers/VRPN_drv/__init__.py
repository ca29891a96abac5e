"""VRPN client driver plug-in (element type ``vrpn``).

Reads a tracker, a button device and an analog device from VRPN servers (``vrpn_server``,
gadgetctl's own ``serve``, or any VRPN application) and offers them as position, digital and
analog data. ``standalone.py`` holds the element's connections (on the protocol package
``gadgetctl.vrpn``), ``wrapper.py`` the input-manager device and ``emulator.py`` a small
VRPN server on loopback.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "VRPN_drv"
ELEMENT_TYPES = {"vrpn": ("position", "digital", "analog")}
# Each *_server property names a VRPN device as Device@host[:port] (or @tcp://host:port).
TRANSPORTS = {
    "vrpn": [
        {"kind": "vrpn", "name": "tracker_server", "count": "tracker_count"},
        {"kind": "vrpn", "name": "button_server", "count": "button_count"},
        {"kind": "vrpn", "name": "analog_server", "count": "analog_count"},
        {"kind": "vrpn", "name": "text_server"},
    ]
}


def register(registry):
    from .wrapper import VrpnDevice

    registry.register_device(VrpnDevice)
