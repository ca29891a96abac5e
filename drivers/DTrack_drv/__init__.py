"""A.R.T. DTrack driver plug-in (element type ``dtrack``).

Receives DTrack's ASCII UDP datagrams (frame counter, timestamp, 6DOF bodies, Flysticks,
measurement tools, markers and gloves) and offers them as position, digital and analog
data, optionally starting and stopping the tracker through its UDP command port.
``standalone.py`` holds the protocol, ``wrapper.py`` the input-manager device and
``emulator.py`` a loopback DTrack sender.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "DTrack_drv"
ELEMENT_TYPES = {"dtrack": ("position", "digital", "analog")}
# The driver binds receive_port; with server_name set it sends commands to command_port there.
TRANSPORTS = {
    "dtrack": {
        "kind": "udp",
        "port": "receive_port",
        "host": "server_name",
        "peer_port": "command_port",
    }
}


def register(registry):
    from .wrapper import DTrackDevice

    registry.register_device(DTrackDevice)
