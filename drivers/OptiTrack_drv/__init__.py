"""NaturalPoint OptiTrack driver plug-in (element types ``optitrack``, ``optitrack_rigid_body``,
``optitrack_marker``).

Receives NatNet frame-of-data packets over UDP (joining the NatNet multicast group, 224.0.0.1
unless configured otherwise; unicast to the port arrives too) and offers the configured rigid
bodies and markers as position units. ``standalone.py`` holds the protocol, ``wrapper.py`` the
input-manager device and ``emulator.py`` a loopback NatNet sender.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "OptiTrack_drv"
ELEMENT_TYPES = {"optitrack": ("position",)}
# The driver binds port and joins the NatNet multicast group (224.0.0.1).
TRANSPORTS = {"optitrack": {"kind": "udp", "port": "port", "group": "224.0.0.1"}}


def register(registry):
    from .wrapper import OptiTrackDevice

    registry.register_device(OptiTrackDevice)
