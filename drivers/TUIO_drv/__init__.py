"""TUIO multi-touch driver plug-in (element type ``TUIO_drv``, as VR Juggler names it).

Receives TUIO 1.1 cursor messages (``/tuio/2Dcur``, OSC over UDP, port 3333 by default) and
offers each touch slot as a digital unit (ON while a finger is down) and two analog units
(x, y from 0 to 1). ``osc.py`` decodes OSC with bounds, ``standalone.py`` holds the TUIO
protocol, ``wrapper.py`` the input-manager device and ``emulator.py`` a loopback TUIO sender.
"""

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "TUIO_drv"
ELEMENT_TYPES = {"TUIO_drv": ("digital", "analog")}
TRANSPORTS = {"TUIO_drv": {"kind": "udp", "port": "port"}}


def register(registry):
    from .wrapper import TuioDevice

    registry.register_device(TuioDevice)
