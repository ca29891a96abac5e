"""TUIO multi-touch driver plug-in (element type ``TUIO_drv``, as VR Juggler names it).

Receives TUIO 1.x cursor messages (``/tuio/2Dcur``, OSC over UDP, port 3333 by default) and
offers each touch slot as a digital unit (ON while a finger is down) and two analog units
(x, y from 0 to 1). OSC is decoded by the ``python-osc`` package: without it the plug-in
fails to load with a one-line reason. ``standalone.py`` holds the protocol, ``wrapper.py`` the
input-manager device and ``emulator.py`` a loopback TUIO sender.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "TUIO_drv"
ELEMENT_TYPES = {"TUIO_drv": ("digital", "analog")}
TRANSPORTS = {"TUIO_drv": {"kind": "udp", "port": "port"}}

try:
    import pythonosc  # noqa: F401
except ImportError:  # one line for DRV003, naming what to install
    raise ImportError(
        "TUIO_drv needs the python-osc package: pip install python-osc (or gadgetctl[tuio])"
    ) from None


def register(registry):
    from .wrapper import TuioDevice

    registry.register_device(TuioDevice)
