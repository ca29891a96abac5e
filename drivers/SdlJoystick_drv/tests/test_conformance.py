"""Conformance: the SDL joystick reader against values produced by SDL itself.

Source: libSDL2's own virtual-joystick driver (``SDL_JoystickAttachVirtualEx`` and
``SDL_JoystickSetVirtual*``, from the pysdl2-dll package): SDL, not gadgetctl, turns the set values
into joystick state, and gadgetctl reads them back through SDL's public joystick API as it reads
a real pad. The expected values come from SDL's headers (``SDL_HAT_UP`` 0x01, ``SDL_HAT_RIGHT``
0x02, ``SDL_HAT_DOWN`` 0x04, ``SDL_HAT_LEFT`` 0x08, as PySDL2 exports them; axes are signed 16-bit)
and from VR Juggler's ``Open/SdlJoystick/SdlJoystick.cpp`` (the analog range is set to
[-32767, 32767] and the analog proxy normalises over it). ``SdlJoystickEmulator`` is used here
only to attach the virtual joystick on SDL's thread; it computes none of the expected values.
"""

from __future__ import annotations

import time

import pytest
import sdl2
from SdlJoystick_drv.emulator import SdlJoystickEmulator
from SdlJoystick_drv.standalone import AXIS_RANGE, JoystickSample, SdlJoystickReader

pytestmark = pytest.mark.timeout(60)

VRJ_MIN, VRJ_MAX = -32767.0, 32767.0


def vrj_normalised(raw: int) -> float:
    clamped = min(VRJ_MAX, max(VRJ_MIN, float(raw)))
    return (clamped - VRJ_MIN) / (VRJ_MAX - VRJ_MIN)


def read_until(reader: SdlJoystickReader, done, timeout: float = 10.0) -> JoystickSample:
    deadline = time.monotonic() + timeout
    while True:
        for sample in reader.read(0.1):
            if done(sample):
                return sample
        assert time.monotonic() < deadline, "SDL never reported the values set"


def test_sdl_reports_what_was_set_and_gadgeteer_normalises_it() -> None:
    raw_axes = (-32768, -16000, 0, 12345, 32767)
    with SdlJoystickEmulator(scenario="idle", axes=5, buttons=4, hats=2) as emu:
        reader = SdlJoystickReader(emu.index)
        reader.open()
        try:
            assert reader.counts == (4, 5, 2)
            for axis, value in enumerate(raw_axes):
                assert emu.set_axis(axis, value)
            assert emu.set_button(2, 1)
            assert emu.set_hat(0, sdl2.SDL_HAT_UP | sdl2.SDL_HAT_RIGHT)
            assert emu.set_hat(1, sdl2.SDL_HAT_LEFTDOWN)
            sample = read_until(reader, lambda s: tuple(s.axes) == raw_axes and s.hats[1] != 0)
        finally:
            reader.close()
    assert tuple(sample.buttons) == (0, 0, 1, 0)
    assert tuple(sample.hats) == (
        sdl2.SDL_HAT_UP | sdl2.SDL_HAT_RIGHT,
        sdl2.SDL_HAT_LEFT | sdl2.SDL_HAT_DOWN,
    )
    # the range the wrapper gives the analog proxies is VR Juggler's
    assert tuple(AXIS_RANGE) == (VRJ_MIN, VRJ_MAX)
    assert [vrj_normalised(v) for v in sample.axes] == [
        0.0,
        pytest.approx((32767 - 16000) / 65534),
        0.5,
        pytest.approx((12345 + 32767) / 65534),
        1.0,
    ]
