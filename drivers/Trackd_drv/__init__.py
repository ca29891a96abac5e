"""CAVELib trackd driver plug-in (element types ``trackd_sensor`` and ``trackd_controller``).

Reads the tracker and controller segments the trackd daemon publishes in System V shared
memory: sensor positions, buttons and valuators. ``standalone.py`` holds the layout and the
reader, ``wrapper.py`` the input-manager devices and ``emulator.py`` a stand-in trackd that
creates, writes and removes the segments. Needs the ``sysv_ipc`` package.
"""

try:
    import sysv_ipc  # noqa: F401  (checked here, so a missing package fails the load in one line)
except ImportError:
    raise ImportError("Trackd_drv needs the sysv_ipc package (pip install sysv_ipc)") from None

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "Trackd_drv"
ELEMENT_TYPES = {
    "trackd_sensor": ("position",),
    "trackd_controller": ("digital", "analog"),
}
TRANSPORTS = {
    "trackd_sensor": {"kind": "shm", "key": "shared_memory_key"},
    "trackd_controller": {"kind": "shm", "key": "shared_memory_key"},
}


def register(registry):
    from .wrapper import TrackdControllerDevice, TrackdSensorDevice

    registry.register_device(TrackdSensorDevice)
    registry.register_device(TrackdControllerDevice)
