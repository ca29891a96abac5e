"""Ascension MotionStar driver plug-in (element type ``motion_star``).

The MotionStar chassis speaks BIRDNET over TCP: 16-byte headers, status and
setup blocks, then a stream of data packets with one record per sensor.
``standalone.py`` holds the protocol, ``emulator.py`` plays a chassis on a
loopback TCP server.

Position units are the sensors in FBB address order; positions are in inches,
so configurations pair the driver with ``device_units`` 0.0254.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "MotionStar_drv"
ELEMENT_TYPES = {"motion_star": ("position",)}
