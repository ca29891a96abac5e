"""SDL joystick driver plug-in (element type ``sdl_joystick``, as VR Juggler names it).

Reads any joystick or gamepad SDL2 knows (USB, Bluetooth, and SDL's virtual joysticks)
through PySDL2: buttons as digital units, axes as analog units (raw -32768..32767, which
analog proxies normalise over -32767..32767 as Gadgeteer does), hat switches as hat units,
and rumble where SDL offers it. Needs PySDL2 and an SDL2 library (``pysdl2-dll``): without
them the plug-in fails to load with a one-line reason. ``standalone.py`` holds the reader,
``wrapper.py`` the input-manager device and ``emulator.py`` SDL virtual joysticks, which
exist only inside the process that makes them.
"""

import warnings

GADGETCTL_API_VERSION = 1
PLUGIN_NAME = "SdlJoystick_drv"
ELEMENT_TYPES = {"sdl_joystick": ("digital", "analog", "hat", "rumble")}
# "sdl": a joystick index into SDL's list of the joysticks it sees (doctor lists them).
TRANSPORTS = {"sdl_joystick": {"kind": "sdl", "index": "device"}}
REQUIRES = {"sdl2": "pip install PySDL2 pysdl2-dll (or gadgetctl[sdl])"}

try:  # checked here, so a missing binding fails the load in one line (DRV003)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # PySDL2 notes which SDL2 library it found
        import sdl2  # noqa: F401
except ImportError:
    raise ImportError(
        "SdlJoystick_drv needs the PySDL2 package: pip install PySDL2 pysdl2-dll (or gadgetctl[sdl])"
    ) from None
except Exception:  # PySDL2 raises RuntimeError when it finds no SDL2 library
    raise ImportError(
        "SdlJoystick_drv: PySDL2 found no SDL2 library: pip install pysdl2-dll (or gadgetctl[sdl])"
    ) from None


def register(registry):
    from .wrapper import SdlJoystickDevice

    registry.register_device(SdlJoystickDevice)
