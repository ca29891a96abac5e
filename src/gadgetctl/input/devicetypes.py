"""The device types a driver's class combines: analog, digital, position, glove, gesture,
command, string, hat and keyboard/mouse.

Each type is a subclass of :class:`Input` with its own sample buffer, its own
``config`` part (called through ``super()``) and ``add_*_sample`` methods. Python's
multiple inheritance plays the part of Gadgeteer's Input Mixer::

    class Joystick(Digital, Analog):
        ELEMENT_TYPE = "linux_joydev"

Single samples get the current time unless a timestamp is given; batches (``add_*_samples``)
carry one timestamp per sample and values of shape (samples, units, ...).
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import IntEnum, IntFlag
from typing import Any

import numpy as np

from gadgetctl.input.device import Input
from gadgetctl.input.events import (
    SCROLL_KEYS,
    Event,
    KeyEvent,
    MouseMoveEvent,
    ScrollDirection,
    ScrollEvent,
)
from gadgetctl.input.filters import FILTERS_PROPERTY, NO_FILTERS, build_chain
from gadgetctl.input.keys import MODIFIER_KEYS, Key, Modifier
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.transforms import as_matrices
from gadgetctl.jccl.access import ElementAccess


class DigitalState(IntEnum):
    OFF = 0
    ON = 1
    TOGGLE_ON = 2
    TOGGLE_OFF = 3


class HatState(IntFlag):
    CENTERED = 0
    UP = 1
    RIGHT = 2
    DOWN = 4
    LEFT = 8


class Finger(IntEnum):
    """Rows of a glove datum: five fingers and the wrist."""

    THUMB = 0
    INDEX = 1
    MIDDLE = 2
    RING = 3
    PINKY = 4
    WRIST = 5


GLOVE_SHAPE = (6, 4)  # components x joints (MPJ, PIJ, DIJ, ABDUCT; wrist: YAW, PITCH)


def _stamp(timestamp: float | None) -> float:
    return Input.now() if timestamp is None else float(timestamp)


class Analog(Input):
    """Continuous values. Devices store raw values; proxies normalise them with min and max."""

    KIND = DeviceKind.ANALOG
    analog_min = 0.0
    analog_max = 1.0

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.analog_min = access.float("min") if access.has("min") else 0.0
        self.analog_max = access.float("max") if access.has("max") else 1.0
        if self.analog_max <= self.analog_min:
            self.warn(
                "DRV020",
                f"analog range is {'empty' if self.analog_max == self.analog_min else 'inverted'}: "
                f"min {self.analog_min:g}, max {self.analog_max:g}; analog proxies read 0.0",
                hint="set max greater than min",
            )

    def normalize(self, raw: float) -> float:
        """``raw`` clamped into [min, max] and mapped onto [0, 1]; 0.0 when the range is empty."""
        low, high = self.analog_min, self.analog_max
        if high <= low:
            return 0.0
        value = high if raw > high else low if raw < low else raw
        return (value - low) / (high - low)

    def add_analog_sample(self, values: Sequence[float], timestamp: float | None = None) -> None:
        self.store.add(DeviceKind.ANALOG, _stamp(timestamp), tuple(float(v) for v in values))

    def add_analog_samples(self, timestamps: Any, values: Any) -> None:
        self.store.add_batch(
            DeviceKind.ANALOG,
            np.asarray(timestamps, dtype=np.float64),
            np.asarray(values, dtype=np.float64),
        )


class Digital(Input):
    """Buttons: each unit is OFF (0) or ON (1); proxies compute the toggles."""

    KIND = DeviceKind.DIGITAL

    def add_digital_sample(
        self, values: Sequence[int | bool], timestamp: float | None = None
    ) -> None:
        self.store.add(DeviceKind.DIGITAL, _stamp(timestamp), tuple(int(v) for v in values))

    def add_digital_samples(self, timestamps: Any, values: Any) -> None:
        self.store.add_batch(
            DeviceKind.DIGITAL,
            np.asarray(timestamps, dtype=np.float64),
            np.asarray(values, dtype=np.int8),
        )


class Position(Input):
    """4x4 matrices, one per unit. Device-level ``position_filters`` are applied as samples
    are added (once)."""

    KIND = DeviceKind.POSITION

    def __init__(self) -> None:
        super().__init__()
        self.position_filters = NO_FILTERS

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        if access.has(FILTERS_PROPERTY):
            self.position_filters = build_chain(access, FILTERS_PROPERTY)
            self.diagnostics.extend(self.position_filters.diagnostics)

    def add_position_sample(self, matrices: Any, timestamp: float | None = None) -> None:
        """``matrices``: one 4x4 matrix per unit, shape (units, 4, 4) or a list of 4x4."""
        # A copy: drivers may reuse their buffer for the next sample.
        data = np.array(as_matrices(matrices), dtype=np.float64).reshape(-1, 4, 4)
        self.store.add(DeviceKind.POSITION, _stamp(timestamp), self.position_filters.apply(data))

    def add_position_samples(self, timestamps: Any, matrices: Any) -> None:
        """``matrices`` of shape (samples, units, 4, 4)."""
        data = as_matrices(matrices)
        if data.ndim != 4:
            raise ValueError(f"expected shape (samples, units, 4, 4), got {data.shape}")
        self.store.add_batch(
            DeviceKind.POSITION,
            np.asarray(timestamps, dtype=np.float64),
            self.position_filters.apply(data),
        )


class Glove(Input):
    """Joint angles (radians), a (6, 4) array per glove, and each glove's position proxy."""

    KIND = DeviceKind.GLOVE
    POSITION_PROPERTIES = (("left_glove_position", "right_glove_position"), ("glove_position",))

    def __init__(self) -> None:
        super().__init__()
        self.glove_position_proxies: list[str] = []

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        for props in self.POSITION_PROPERTIES:
            if all(access.has(p) for p in props):
                self.glove_position_proxies = [access.string(p) for p in props]
                break

    def glove_position(self, unit: int) -> np.ndarray:
        """The position of glove ``unit`` from its position proxy (identity if none)."""
        if unit < len(self.glove_position_proxies) and self.context is not None:
            proxy = self.context.proxy(self.glove_position_proxies[unit])
            matrix = getattr(proxy, "matrix", None)
            if matrix is not None:
                return matrix
        return np.eye(4)

    def add_glove_sample(self, angles: Any, timestamp: float | None = None) -> None:
        data = np.asarray(angles, dtype=np.float64).reshape(-1, *GLOVE_SHAPE)
        self.store.add(DeviceKind.GLOVE, _stamp(timestamp), data)

    def add_glove_samples(self, timestamps: Any, angles: Any) -> None:
        self.store.add_batch(
            DeviceKind.GLOVE,
            np.asarray(timestamps, dtype=np.float64),
            np.asarray(angles, dtype=np.float64),
        )


class Gesture(Input):
    """Recognised gestures: an id per unit (-1 = none) and optional names."""

    KIND = DeviceKind.GESTURE

    def __init__(self) -> None:
        super().__init__()
        self.gesture_names: list[str] = []

    def gesture_name(self, gesture: int) -> str:
        if 0 <= gesture < len(self.gesture_names):
            return self.gesture_names[gesture]
        return "none" if gesture < 0 else f"gesture {gesture}"

    def add_gesture_sample(self, gestures: Sequence[int], timestamp: float | None = None) -> None:
        self.store.add(DeviceKind.GESTURE, _stamp(timestamp), tuple(int(g) for g in gestures))


class Command(Input):
    """Integer commands (e.g. recognised speech)."""

    KIND = DeviceKind.COMMAND

    def add_command_sample(self, values: Sequence[int], timestamp: float | None = None) -> None:
        self.store.add(DeviceKind.COMMAND, _stamp(timestamp), tuple(int(v) for v in values))


class String(Input):
    """Text values."""

    KIND = DeviceKind.STRING

    def add_string_sample(self, values: Sequence[str], timestamp: float | None = None) -> None:
        self.store.add(DeviceKind.STRING, _stamp(timestamp), tuple(str(v) for v in values))


class Hat(Input):
    """Hat switches: a :class:`HatState` per unit."""

    KIND = DeviceKind.HAT

    def add_hat_sample(self, values: Sequence[int], timestamp: float | None = None) -> None:
        self.store.add(DeviceKind.HAT, _stamp(timestamp), tuple(int(v) for v in values))

    def add_hat_samples(self, timestamps: Any, values: Any) -> None:
        self.store.add_batch(
            DeviceKind.HAT,
            np.asarray(timestamps, dtype=np.float64),
            np.asarray(values, dtype=np.int8),
        )


class Rumble(Input):
    """Force-feedback output (Gadgeteer's Rumble type), in a minimal form: no samples and no
    effects objects; :meth:`rumble` runs the device's two motors (low and high frequency, 0
    to 1) for a while, where the hardware offers it. A device class overrides both members."""

    KIND = DeviceKind.RUMBLE

    @property
    def has_rumble(self) -> bool:
        """Whether the device can rumble now (opened, and the hardware has motors)."""
        return False

    def rumble(self, low: float, high: float, duration: float) -> bool:
        """Run the motors at ``low`` and ``high`` (0 to 1) for ``duration`` seconds (0, 0
        stops them). False when the device cannot rumble now."""
        return False


_MODIFIERS = frozenset(int(k) for k in MODIFIER_KEYS)


class KeyboardMouse(Input):
    """Key and mouse state per frame, as Gadgeteer's KeyboardMouse.

    ``key_pressed(k)`` is the number of presses of ``k`` since the previous frame plus one
    if it was held then and still is (for mouse axes: the motion, scaled by the sensitivity).
    ``modifier_only(m)`` is true when exactly that modifier (none, for ``Modifier.NONE``)
    among shift, ctrl, alt and command counts as pressed this frame. ``key_pressed_with(k, m)``
    counts only the presses of ``k`` typed with exactly modifier ``m`` held, so several
    keystrokes in one frame each keep their own modifiers (``Up Up Shift+Left``: two
    unmodified Ups and one shifted Left). Each event is also kept as a sample, so monitors
    see them all.
    """

    KIND = DeviceKind.KEYBOARD_MOUSE
    mouse_sensitivity = 1.0
    scroll_as_buttons = False

    def __init__(self) -> None:
        super().__init__()
        self.scroll_buttons: dict[ScrollDirection, Key] = {
            ScrollDirection.UP: Key.MOUSE_BUT4,
            ScrollDirection.DOWN: Key.MOUSE_BUT5,
            ScrollDirection.LEFT: Key.MOUSE_BUT6,
            ScrollDirection.RIGHT: Key.MOUSE_BUT7,
        }
        self._held: set[int] = set()
        self._carried: set[int] = set()  # keys held at the previous frame
        self._counts: dict[int, float] = {}
        self._frame_counts: dict[int, float] = {}
        self._combos: dict[tuple[int, frozenset[int]], float] = {}  # (key, modifiers held) -> count
        self._frame_combos: dict[tuple[int, frozenset[int]], float] = {}

    def _count(self, key: int, amount: float) -> None:
        self._counts[key] = self._counts.get(key, 0) + amount
        combo = (key, frozenset(self._held & _MODIFIERS) - {key})
        self._combos[combo] = self._combos.get(combo, 0) + amount

    def process_events(self, events: Sequence[Event]) -> None:
        """Count ``events`` into the current frame and keep each one as a sample."""
        for event in events:
            if isinstance(event, KeyEvent):
                key = int(event.key)
                if event.pressed:
                    self._count(key, 1)
                    self._held.add(key)
                else:
                    self._held.discard(key)
            elif isinstance(event, MouseMoveEvent):
                for amount, positive, negative in (
                    (event.dx, Key.MOUSE_POSX, Key.MOUSE_NEGX),
                    (event.dy, Key.MOUSE_POSY, Key.MOUSE_NEGY),
                ):
                    if amount:
                        self._count(
                            int(positive if amount > 0 else negative),
                            abs(amount) * self.mouse_sensitivity,
                        )
            elif isinstance(event, ScrollEvent):
                keys = [SCROLL_KEYS[event.direction]]
                if self.scroll_as_buttons:
                    keys.append(self.scroll_buttons[event.direction])
                for key in keys:
                    self._count(int(key), 1)
            self.store.add(DeviceKind.KEYBOARD_MOUSE, event.timestamp, (event,))

    def end_frame(self) -> None:
        """Freeze this frame's counts: presses since the previous frame, plus one for a key
        held since then and still held. (Gadgeteer adds the one for a key held at the
        previous frame even if it was released meanwhile, so a release shows a frame late.)"""
        for key in self._carried & self._held:
            self._count(key, 1)
        self._frame_counts, self._frame_combos = self._counts, self._combos
        self._counts, self._combos = {}, {}
        self._carried = set(self._held)

    def key_pressed(self, key: Key | int) -> float:
        return self._frame_counts.get(int(key), 0)

    def key_pressed_with(self, key: Key | int, modifier: Modifier | int) -> float:
        """Presses of ``key`` this frame typed while exactly ``modifier`` (none, for
        ``Modifier.NONE``; whatever, for ``Modifier.ANY``) was held."""
        if int(modifier) == Modifier.ANY:
            return self.key_pressed(key)
        wanted = frozenset() if int(modifier) == Modifier.NONE else frozenset({int(modifier)})
        return self._frame_combos.get((int(key), wanted), 0)

    def modifier_only(self, modifier: Modifier | int) -> bool:
        down = {k for k in _MODIFIERS if self._frame_counts.get(k, 0) > 0}
        if int(modifier) == Modifier.NONE:
            return not down
        return down == {int(modifier)}

    @property
    def held(self) -> frozenset[Key]:
        return frozenset(Key(k) for k in self._held)
