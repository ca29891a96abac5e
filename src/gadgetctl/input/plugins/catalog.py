"""Which driver plug-in handles which element type, without importing any plug-in.

Bundled plug-ins declare it in ``drivers/<name>/__init__.py`` as a literal
``ELEMENT_TYPES = {"dtrack": ("position", ...)}`` (read without importing, see
:mod:`gadgetctl.input.plugins.metadata`). Upstream
Gadgeteer drivers that gadgetctl does not bundle are listed too, so that configurations
written for VR Juggler show where their devices come from.
"""

from __future__ import annotations

from functools import cache, lru_cache
from pathlib import Path

from gadgetctl.input.plugins.metadata import read_metadata


@cache
def built_in_types() -> frozenset[str]:
    """Element types the input manager handles without a plug-in (simulated devices etc.)."""
    from gadgetctl.input.builtin import BUILTIN_DEVICES

    return frozenset(cls.ELEMENT_TYPE for cls in BUILTIN_DEVICES)


# Upstream driver plug-ins (Gadgeteer 2.x) and the element types they handle.
UPSTREAM_DRIVERS: dict[str, tuple[str, ...]] = {
    "SpaceBall_drv": ("puck_device",),
    "DataGlove_drv": ("data_glove",),
    "DataGloveUltraWireless_drv": ("data_glove_ultra_wireless",),
    "DTrack_drv": ("dtrack",),
    "Flock_drv": ("flock",),
    "MotionStar_drv": ("motion_star",),
    "Wanda_drv": ("wanda",),
    "ElexolEther24_drv": ("elexol_ether24",),
    "P5Glove_drv": ("p5_glove",),
    "PinchGlove_drv": ("pinch_glove",),
    "IBox_drv": ("ibox",),
    "IS900_drv": ("intersense",),
    "IntersenseAPI_drv": ("intersense_api",),
    "ThreeDMouse_drv": ("three_d_mouse",),
    "DirectXJoystick_drv": ("directx_joystick",),
    "MSFTSpeechRecog_drv": ("msft_speech_recog_digital", "msft_speech_recog_string"),
    "MotionNode_drv": ("motionnode",),
    "OptiTrack_drv": ("optitrack",),
    "DTK_drv": ("dtk",),
    "LinuxJoydev_drv": ("linux_joydev",),
    "SdlJoystick_drv": ("sdl_joystick",),
    "TUIO_drv": ("TUIO_drv",),
    "Trackd_drv": ("trackd_controller", "trackd_sensor"),
    "VRPN_drv": ("vrpn",),
    "Fastrak_drv": ("fastrak",),
    "SerialEncoder_drv": ("serial_encoder",),
    "TrackdAPI_drv": ("trackd_api_controller", "trackd_api_sensor"),
    "CyberGlove_drv": ("cyber_glove",),
    "X-IST_drv": ("x_ist_glove",),
}


@lru_cache(maxsize=8)  # keyed by folder: the bundled one, and any a caller names
def bundled_plugins(drivers_dir: Path) -> dict[str, tuple[str, ...]]:
    """Plug-in name -> element types, for every plug-in folder under ``drivers_dir``."""
    plugins: dict[str, tuple[str, ...]] = {}
    if not drivers_dir.is_dir():
        return plugins
    for init_file in sorted(drivers_dir.glob("*/__init__.py")):
        meta = read_metadata(init_file)
        if meta.element_types:
            plugins[meta.plugin_name or init_file.parent.name] = tuple(meta.element_types)
    return plugins


def plugin_for_type(drivers_dir: Path | None = None) -> dict[str, str]:
    """Element type -> plug-in name; bundled plug-ins win over the upstream table."""
    from gadgetctl.resources import drivers_dir as bundled_dir

    mapping: dict[str, str] = {}
    for name, types in UPSTREAM_DRIVERS.items():
        for type_name in types:
            mapping[type_name] = name
    for name, types in bundled_plugins(drivers_dir or bundled_dir()).items():
        for type_name in types:
            mapping[type_name] = name
    return mapping
