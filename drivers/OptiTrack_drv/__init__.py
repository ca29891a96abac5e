"""NaturalPoint OptiTrack driver plug-in (element types ``optitrack``, ``optitrack_rigid_body``,
``optitrack_marker``).

Receives NatNet frames (NatNet 1.0 to 4.1) over UDP where Motive sends them by default
(multicast group 239.255.42.99, data port 1511; command port 1510), or in unicast mode after a
connect request, and offers the configured rigid bodies and markers as position units. ``standalone.py`` holds the protocol, ``wrapper.py`` the
input-manager device and ``emulator.py`` a loopback NatNet sender.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "OptiTrack_drv"
ELEMENT_TYPES = {"optitrack": ("position",)}
# The driver binds port (Motive's 1511 when the element sets none) and joins Motive's group.
TRANSPORTS = {
    "optitrack": {"kind": "udp", "port": "port", "port_unset": "1511", "group": "239.255.42.99"}
}


def register(registry):
    from .wrapper import OptiTrackDevice

    registry.register_device(OptiTrackDevice)
