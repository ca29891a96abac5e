"""A.R.T. DTrack driver plug-in (element type ``dtrack``).

Receives DTrack's ASCII UDP datagrams (frame counter, timestamp, 6DOF bodies, Flysticks,
measurement tools, markers and gloves) and offers them as position, digital and analog
data, optionally starting and stopping the tracker through its UDP command port.
``standalone.py`` holds the protocol and ``emulator.py`` a loopback DTrack sender.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "DTrack_drv"
ELEMENT_TYPES = {"dtrack": ("position", "digital", "analog")}
