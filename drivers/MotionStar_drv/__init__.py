"""Ascension MotionStar driver plug-in (element type ``motion_star``).

The MotionStar chassis speaks BIRDNET over TCP: 16-byte headers, status and
setup blocks, then a stream of data packets with one record per sensor.
``standalone.py`` holds the protocol, ``wrapper.py`` feeds the input manager,
``emulator.py`` plays a chassis on a loopback TCP server.

Position units are the sensors in FBB address order; positions are in inches,
so configurations pair the driver with a position_transform_filter whose
``device_units`` is 0.0254. BIRDNET over UDP (server_port 5000) is not
implemented.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "MotionStar_drv"
ELEMENT_TYPES = {"motion_star": ("position",)}
TRANSPORTS = {"motion_star": {"kind": "tcp", "host": "address", "port": "server_port"}}


def register(registry):
    from .wrapper import MotionStarDevice

    registry.register_device(MotionStarDevice)
