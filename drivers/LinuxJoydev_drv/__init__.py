"""Linux joystick driver plug-in (element type ``linux_joydev``).

Reads the 8-byte ``js_event`` records that the kernel's joydev module delivers through
``/dev/input/jsN`` and offers them as digital (buttons, plus optional virtual buttons made
from axes) and analog (axes) data. ``standalone.py`` holds the protocol, ``wrapper.py`` the
input-manager device and ``emulator.py`` a FIFO-based stand-in for a joystick device file.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "LinuxJoydev_drv"
ELEMENT_TYPES = {"linux_joydev": ("digital", "analog")}
TRANSPORTS = {"linux_joydev": {"kind": "file", "path": "port_name"}}


def register(registry):
    from .wrapper import LinuxJoydevDevice

    registry.register_device(LinuxJoydevDevice)
