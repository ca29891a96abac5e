"""Whether SDL sees a joystick at the index an element names (``sdl_joystick``): SDL's
joystick subsystem is started in this process for the check (through the process's SDL hub)
and stopped again; no joystick is opened."""

from __future__ import annotations

from gadgetctl.doctor.model import PortCheck, Status
from gadgetctl.wording import counted


def sdl_joysticks() -> list[tuple[int, str]] | str:
    """(index, name) of every joystick SDL sees, or why SDL cannot be asked (one line)."""
    from gadgetctl.transport.sdl import SdlError, SdlUnavailable, hub

    sdl_hub = hub()
    try:
        sdl_hub.acquire()
    except (SdlUnavailable, SdlError) as err:
        return str(err)
    try:
        return [(j.index, j.name) for j in sdl_hub.call(sdl_hub.joysticks)]
    except SdlError as err:
        return str(err)
    finally:
        sdl_hub.release()


def check_sdl(index: int, *, emulator: str | None = None) -> PortCheck:
    """One check: SDL has a joystick at ``index``."""
    target = f"SDL joystick {index}"
    if index < 0:
        return PortCheck(
            "sdl", target, Status.PROBLEM, f"{index} is not a joystick index (0 or more)", "DRV106"
        )
    found = sdl_joysticks()
    if isinstance(found, str):
        return PortCheck("sdl", target, Status.UNCHECKED, f"cannot ask SDL: {found}", "DRV105")
    names = dict(found)
    if index in names:
        return PortCheck(
            "sdl",
            target,
            Status.OK,
            f"SDL sees {names[index] or 'an unnamed joystick'}"
            f" at index {index} ({counted(len(found), 'joystick')} in all)",
        )
    seen = ", ".join(f"{i}: {n}" for i, n in found)
    hint = (
        f"SDL sees {seen}"
        if found
        else "SDL sees no joystick: plug one in (and check /dev/input permissions)"
    )
    if emulator:
        hint += (
            f"; SDL virtual joysticks ({emulator}'s emulator) exist only in the process that "
            "makes them, so they cannot stand in for a device here"
        )
    return PortCheck(
        "sdl",
        target,
        Status.PROBLEM,
        f"SDL sees {counted(len(found), 'joystick')}, none at index {index}",
        "DRV100",
        hint,
    )
