"""The SDL joystick reader: opens joystick ``index`` through the process's SDL hub
(:mod:`gadgetctl.transport.sdl`, which owns every SDL call) and turns its polls into samples.

A sample is what one poll saw: every button (0 or 1), every axis as SDL reports it (a signed
16-bit value, -32768 to 32767) and every hat switch as SDL's direction bits (up 1, right 2,
down 4, left 8; diagonals are two bits; 0 is centred), which are also Gadgeteer's HatState
values. A hat value no real hat can give (opposite directions at once, or bits above 8) is
counted in ``bad_hats`` when it appears and reads as centred; it is never a fault.

Knows nothing of gadgetctl's input manager.
"""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.transport.sdl import (
    JoystickReading,
    OpenJoystick,
    SdlError,
    SdlJoystickLost,
    SdlJoystickMissing,
    hub,
)

__all__ = [
    "AXIS_RANGE",
    "VALID_HATS",
    "HatChecker",
    "JoystickSample",
    "SdlError",
    "SdlJoystickLost",
    "SdlJoystickMissing",
    "SdlJoystickReader",
    "check_hat",
]

#: The range Gadgeteer normalises SDL axes over (its driver sets min -32767, max 32767), so
#: -32768 and -32767 both read 0.0, 0 reads 0.5 and 32767 reads 1.0.
AXIS_RANGE = (-32767.0, 32767.0)

#: The hat values a real hat switch gives: centred, four directions and four diagonals.
VALID_HATS = frozenset({0, 1, 2, 4, 8, 1 | 2, 2 | 4, 4 | 8, 8 | 1})


def check_hat(value: int) -> int | None:
    """``value`` when a hat can give it, else None."""
    return value if value in VALID_HATS else None


@dataclass(frozen=True, slots=True)
class JoystickSample:
    timestamp: float
    buttons: tuple[int, ...]
    axes: tuple[int, ...]
    hats: tuple[int, ...]


class HatChecker:
    """Hat values as polled, made ones a hat can give: an impossible value reads centred and
    is counted in ``bad`` once when it appears (not again on every poll that still sees it)."""

    def __init__(self) -> None:
        self.bad = 0
        self._raw: tuple[int, ...] | None = None
        self._checked: tuple[int, ...] = ()

    def reset(self) -> None:
        """Forget the previous poll (the joystick was opened again)."""
        self._raw = None

    def check(self, hats: tuple[int, ...]) -> tuple[int, ...]:
        if hats == self._raw:
            return self._checked
        last = self._raw
        checked = []
        for unit, value in enumerate(hats):
            good = check_hat(value)
            if good is None:
                if last is None or unit >= len(last) or last[unit] != value:
                    self.bad += 1
                good = 0
            checked.append(good)
        self._raw, self._checked = hats, tuple(checked)
        return self._checked


class SdlJoystickReader:
    """One joystick, from :meth:`open` to :meth:`close`; counters add up over reopenings."""

    def __init__(self, index: int, *, rate: float = 100.0) -> None:
        self.index = index
        self.rate = rate
        self.polls = 0
        self.overflowed = 0
        self.name = ""
        self.counts = (0, 0, 0)  # buttons, axes, hats
        self._joystick: OpenJoystick | None = None
        self._hats = HatChecker()

    def open(self) -> None:
        """Open the joystick; raises :class:`SdlJoystickMissing` when SDL has no joystick
        at the index, :class:`SdlError` when SDL refuses, ImportError without PySDL2."""
        if self._joystick is not None:
            return
        sdl_hub = hub()
        sdl_hub.acquire()
        try:
            joystick = sdl_hub.open(self.index, self.rate)
        except BaseException:
            sdl_hub.release()
            raise
        self._joystick = joystick
        self.name = joystick.name
        self.counts = (joystick.num_buttons, joystick.num_axes, joystick.num_hats)
        self._hats.reset()

    @property
    def has_rumble(self) -> bool:
        return self._joystick is not None and self._joystick.has_rumble

    def read(self, timeout: float = 0.1) -> list[JoystickSample]:
        """The samples polled since the previous call (waits up to ``timeout`` for one).
        Raises :class:`SdlJoystickLost` when the joystick went away or is closed."""
        joystick = self._joystick
        if joystick is None:
            raise SdlJoystickLost(f"SDL joystick {self.index} is not open")
        readings = joystick.read(timeout)
        self.overflowed = joystick.overflowed
        return [self._decode(r) for r in readings]

    def _decode(self, reading: JoystickReading) -> JoystickSample:
        self.polls += 1
        hats = self._hats.check(reading.hats)
        return JoystickSample(reading.timestamp, reading.buttons, reading.axes, hats)

    @property
    def bad_hats(self) -> int:
        return self._hats.bad

    def rumble(self, low: float, high: float, duration: float) -> bool:
        """Rumble (motor strengths 0 to 1, ``duration`` seconds; 0 strengths stop it).
        False when the joystick offers no rumble."""
        joystick = self._joystick
        return joystick is not None and joystick.rumble(low, high, duration)

    def close(self) -> None:
        joystick, self._joystick = self._joystick, None
        if joystick is None:
            return
        try:
            joystick.close()
        finally:
            hub().release()
