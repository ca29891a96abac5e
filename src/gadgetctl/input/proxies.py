"""Proxies: what applications (and `gadgetctl monitor`) read, one unit of one device each.

A proxy names its device and unit; it binds to the device when the device is configured
and is *stupefied* otherwise (device missing, of the wrong type, or unit out of range):
it then returns the neutral value of its type and :attr:`Proxy.reason` says why. Proxies
re-bind whenever devices come and go, so a device added back revives them.

A proxy shows its device's newest sample. Most proxies read it when they are read (their
value attributes are :class:`NewestValue` descriptors), so a frame costs nothing for the
proxies nobody looks at (10,000 position proxies were half of a frame). Proxies that must
see every frame (:attr:`Proxy.EVERY_FRAME`) read it once per frame: the digital proxy looks
at every sample of the frame so that a press and release between two frames is not lost,
and the keyboard/mouse proxy takes the newest of that frame.
"""

from __future__ import annotations

from enum import Enum, StrEnum
from typing import Any, ClassVar

import numpy as np

from gadgetctl.diagnostics import Diagnostic
from gadgetctl.input.device import Input
from gadgetctl.input.devicetypes import (
    GLOVE_SHAPE,
    Analog,
    DigitalState,
    Gesture,
    Glove,
    HatState,
    KeyboardMouse,
    Rumble,
)
from gadgetctl.input.errors import DeviceConfigError
from gadgetctl.input.filters import FILTERS_PROPERTY, NO_FILTERS, build_chain
from gadgetctl.input.keys import Key, Modifier
from gadgetctl.input.kinds import DeviceKind
from gadgetctl.input.samples import EMPTY_FRAME, FrameSamples, Sample
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.wording import counted


class ProxyState(StrEnum):
    ACTIVE = "active"
    STUPEFIED = "stupefied"


class LengthUnit(float, Enum):
    """Factors from meters: a translation in meters times the factor."""

    METERS = 1.0
    CENTIMETERS = 100.0
    FEET = 1 / 0.3048
    INCHES = 1 / 0.0254


class NewestValue:
    """A proxy attribute that shows its device's newest sample: reading it first brings the
    proxy up to date (:meth:`Proxy.catch_up`); setting it sets the value read next."""

    __slots__ = ("_key",)

    def __set_name__(self, owner: type, name: str) -> None:
        self._key = "_" + name

    def __get__(self, proxy: Proxy | None, owner: type | None = None) -> Any:
        if proxy is None:
            return self
        proxy.catch_up()
        return proxy.__dict__[self._key]

    def __set__(self, proxy: Proxy, value: Any) -> None:
        proxy.__dict__[self._key] = value


class UnitReason:
    """A proxy's reason: reading it first looks at whether its unit is within its device's
    newest sample (:meth:`Proxy.check_unit`), without reading the value."""

    __slots__ = ()

    def __get__(self, proxy: Proxy | None, owner: type | None = None) -> Any:
        if proxy is None:
            return self
        proxy.check_unit()
        return proxy.__dict__["_reason"]

    def __set__(self, proxy: Proxy, value: str | None) -> None:
        proxy.__dict__["_reason"] = value


class Proxy:
    """Base of every proxy type."""

    ELEMENT_TYPE: ClassVar[str] = ""
    KIND: ClassVar[DeviceKind]
    HAS_UNIT: ClassVar[bool] = True
    #: Whether the proxy must look at every frame (the manager updates it each frame); the
    #: others read their device's newest sample when read.
    EVERY_FRAME: ClassVar[bool] = False

    timestamp = NewestValue()
    reason = UnitReason()

    def __init__(self) -> None:
        self.name = ""
        self.element_type = self.ELEMENT_TYPE
        self.device_name = ""
        self.unit = 0
        self.device: Input | None = None
        self.reason = "not configured yet"
        self.timestamp = None
        self.diagnostics: list[Diagnostic] = []  # configuration findings (e.g. skipped filters)
        self._updated_frame = -1
        self._seen: object = None  # the device store's changes() when read last
        self._unit_seen: object = None  # ... and when the unit was checked last
        self.reset()

    # -- configuration ------------------------------------------------------------------

    def config(self, access: ElementAccess) -> None:
        self.name = access.name
        self.element_type = access.element.type
        self.device_name = access.string("device")
        if self.HAS_UNIT and access.has("unit"):
            self.unit = access.integer("unit")
            if self.unit < 0:
                raise DeviceConfigError(f"unit {self.unit} is negative")

    def refresh(self, devices: dict[str, Input], why_missing: str | None = None) -> None:
        """Bind to the device called ``device_name`` in ``devices``, or stupefy."""
        device = devices.get(self.device_name)
        if not self.device_name:
            self.stupefy("its device property is empty")
        elif device is None:
            detail = f": {why_missing}" if why_missing else ""
            self.stupefy(f"device {self.device_name!r} is not configured{detail}")
        elif self.KIND not in device.kinds():
            self.stupefy(
                f"device {self.device_name!r} ({device.element_type}) provides no {self.KIND} data"
            )
        elif device is not self.device:
            self.device = device
            self.reason = None
            self.reset()
            self._updated_frame = -1
            self._seen = self._unit_seen = None

    def stupefy(self, reason: str) -> None:
        self.device = None
        self.reason = reason
        self.timestamp = None
        self.reset()

    # -- per frame ----------------------------------------------------------------------

    def update_for_frame(self, frame: int) -> None:
        if self._updated_frame == frame:
            return
        self._updated_frame = frame
        device = self.device
        if device is None:
            return
        device.update_for_frame(frame)
        if self.EVERY_FRAME:
            self.update_data(device)
        else:
            self.catch_up()

    def catch_up(self) -> None:
        """Read the device's newest sample if its frame changed since the last read (a proxy
        that looks at every frame is updated by the manager instead)."""
        if self.EVERY_FRAME:
            return
        device = self.device
        if device is None:
            return
        seen = device.store.changes()
        if seen != self._seen:
            self._seen = seen
            self.update_data(device)

    def update_data(self, device: Input) -> None:
        """Read the device's newest sample of this proxy's unit."""
        sample = device.store.latest(self.KIND)
        if sample is None:
            return
        value = self._unit_value(sample)
        if value is not None:
            self.timestamp = sample.timestamp
            self.take(value, device)

    def check_unit(self) -> None:
        """Whether the unit is within the device's newest sample, looked at again when the
        device's frame changed (the value is read only when read: :meth:`catch_up`)."""
        if self.EVERY_FRAME:
            return
        device = self.device
        if device is None:
            return
        store = device.store
        seen = store.changes()
        if seen != self._unit_seen:
            self._unit_seen = seen
            width = store.width(self.KIND)
            if width is not None:
                self._unit_within(width)

    def _unit_within(self, width: int) -> bool:
        """Set or clear the reason for a device whose newest sample has ``width`` units."""
        if self.unit < width:
            if self.__dict__["_reason"] is not None:  # (not through the descriptor: now)
                self.reason = None
            return True
        self.reason = f"unit {self.unit} is out of range: {self.device_name!r} has {counted(width, f'{self.KIND} unit')}"
        self.reset()
        return False

    def _unit_value(self, sample: Sample) -> Any:
        values = sample.values
        return values[self.unit] if self._unit_within(len(values)) else None

    # -- type-specific ------------------------------------------------------------------

    def reset(self) -> None:
        """Set the neutral value."""

    def take(self, value: Any, device: Input) -> None:
        """Store the unit's newest value."""

    @property
    def data(self) -> Any:
        raise NotImplementedError

    # -- status -------------------------------------------------------------------------

    @property
    def stupefied(self) -> bool:
        return self.device is None or self.reason is not None

    @property
    def state(self) -> ProxyState:
        return ProxyState.STUPEFIED if self.stupefied else ProxyState.ACTIVE

    def samples(self) -> FrameSamples:
        """Every sample of the device since the previous frame (all units)."""
        return self.device.store.frame(self.KIND) if self.device is not None else EMPTY_FRAME


class AnalogProxy(Proxy):
    ELEMENT_TYPE = "analog_proxy"
    KIND = DeviceKind.ANALOG
    value = NewestValue()
    raw = NewestValue()

    def reset(self) -> None:
        self.value = 0.0
        self.raw = None

    def take(self, value: Any, device: Input) -> None:
        raw = self.raw = float(value)
        self.value = device.normalize(raw) if isinstance(device, Analog) else raw

    @property
    def data(self) -> float:
        """The normalised value in [0, 1] (0.0 when stupefied)."""
        return 0.0 if self.stupefied else self.value


class DigitalProxy(Proxy):
    ELEMENT_TYPE = "digital_proxy"
    KIND = DeviceKind.DIGITAL
    EVERY_FRAME = True  # a press and release between two reads must show

    def reset(self) -> None:
        self.value = DigitalState.OFF

    def update_data(self, device: Input) -> None:
        store = device.store
        frame = store.frame(DeviceKind.DIGITAL)
        newest = store.latest(DeviceKind.DIGITAL)
        if newest is None or self._unit_value(newest) is None:
            return
        self.timestamp = newest.timestamp
        was_pressed = self.value == _ON or self.value == _TOGGLE_ON
        if frame:
            # any sample of the frame that differs from the previous state counts, so a press
            # and release between two frames is not lost
            changed = _any_sample(frame, self.unit, pressed=not was_pressed)
        else:
            changed = (newest.values[self.unit] != _OFF) != was_pressed
        if was_pressed:
            self.value = DigitalState.TOGGLE_OFF if changed else DigitalState.ON
        else:
            self.value = DigitalState.TOGGLE_ON if changed else DigitalState.OFF

    @property
    def data(self) -> DigitalState:
        return DigitalState.OFF if self.stupefied else self.value


_OFF, _ON, _TOGGLE_ON = int(DigitalState.OFF), int(DigitalState.ON), int(DigitalState.TOGGLE_ON)


def _any_sample(frame: FrameSamples, unit: int, *, pressed: bool) -> bool:
    """Whether any sample of ``frame`` has ``unit`` pressed (non-zero) or, for
    ``pressed=False``, released (zero)."""
    for chunk in frame.chunks:
        if isinstance(chunk, Sample):
            values = chunk.values
            if unit < len(values) and (values[unit] != _OFF) == pressed:
                return True
        else:
            values = chunk.values
            if not len(values) or unit >= len(values[0]):
                continue
            column = np.asarray(values)[:, unit]
            if column.dtype.itemsize == 1 and column.dtype.kind in "iub":
                raw = column.tobytes()  # for small byte columns much cheaper than a ufunc reduction
                if (raw.count(0) < len(raw)) if pressed else (0 in raw):
                    return True
            elif column.any() if pressed else not column.all():
                return True
    return False


_IDENTITY = np.eye(4)
_IDENTITY.flags.writeable = False


def _frozen(value: Any) -> bool:
    """Whether ``value`` is a read-only array whose memory is read-only where it is owned too
    (no one can write the numbers it shows)."""
    if type(value) is not np.ndarray or value.flags.writeable:
        return False
    base = value.base
    return base is None or (type(base) is np.ndarray and not base.flags.writeable)


class PositionProxy(Proxy):
    """4x4 float64 matrices in meters; ``matrix_in(LengthUnit.FEET)`` converts."""

    ELEMENT_TYPE = "position_proxy"
    KIND = DeviceKind.POSITION

    def __init__(self) -> None:
        self.filters = NO_FILTERS
        super().__init__()

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        if access.has(FILTERS_PROPERTY):
            self.filters = build_chain(access, FILTERS_PROPERTY)
            self.diagnostics.extend(self.filters.diagnostics)

    def reset(self) -> None:
        self._matrix = _IDENTITY  # read-only: one for every proxy not yet given a sample

    def take(self, value: Any, device: Input) -> None:
        if not self.filters and _frozen(value):
            # a view of samples nothing can change (a waveform's shared signals): kept as it
            # is, not copied (a copy each was 2.5 MB for 10,000 proxies)
            self._matrix = value
            return
        matrix = self.filters.apply(value) if self.filters else np.array(value)
        matrix.flags.writeable = False
        self._matrix = matrix

    @property
    def matrix(self) -> np.ndarray:
        """Read-only 4x4 matrix in meters (identity when stupefied)."""
        self.catch_up()
        return np.eye(4) if self.stupefied else self._matrix

    @property
    def data(self) -> np.ndarray:
        return self.matrix

    def matrix_in(self, unit: LengthUnit | float) -> np.ndarray:
        """The matrix with its translation converted from meters (rotation untouched)."""
        result = np.array(self.matrix)
        result[:3, 3] *= float(unit)
        return result

    @property
    def translation(self) -> np.ndarray:
        return self.matrix[:3, 3].copy()


class GloveProxy(Proxy):
    ELEMENT_TYPE = "glove_proxy"
    KIND = DeviceKind.GLOVE
    visible = True
    angles = NewestValue()

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.visible = access.boolean("visible") if access.has("visible") else True

    def reset(self) -> None:
        self.angles = np.zeros(GLOVE_SHAPE)

    def take(self, value: Any, device: Input) -> None:
        self.angles = np.array(value, dtype=np.float64).reshape(GLOVE_SHAPE)

    @property
    def data(self) -> np.ndarray:
        """Joint angles in radians, shape (6, 4): thumb..pinky, wrist x MPJ, PIJ, DIJ, ABDUCT."""
        return np.zeros(GLOVE_SHAPE) if self.stupefied else self.angles

    @property
    def position(self) -> np.ndarray:
        device = self.device
        if self.stupefied or not isinstance(device, Glove):
            return np.eye(4)
        return device.glove_position(self.unit)


class GestureProxy(Proxy):
    ELEMENT_TYPE = "gesture_proxy"
    KIND = DeviceKind.GESTURE
    HAS_UNIT = False
    gesture = NewestValue()

    def reset(self) -> None:
        self.gesture = -1

    def take(self, value: Any, device: Input) -> None:
        self.gesture = int(value)

    @property
    def data(self) -> int:
        """The current gesture id; -1 when none (or stupefied)."""
        return -1 if self.stupefied else self.gesture

    @property
    def gesture_name(self) -> str:
        device = self.device
        if isinstance(device, Gesture):
            return device.gesture_name(self.data)
        return "none"


class CommandProxy(Proxy):
    ELEMENT_TYPE = "command_proxy"
    KIND = DeviceKind.COMMAND
    value = NewestValue()

    def reset(self) -> None:
        self.value = 0

    def take(self, value: Any, device: Input) -> None:
        self.value = int(value)

    @property
    def data(self) -> int:
        return 0 if self.stupefied else self.value


class StringProxy(Proxy):
    """Unlike Gadgeteer's, this string proxy does update."""

    ELEMENT_TYPE = "string_proxy"
    KIND = DeviceKind.STRING
    value = NewestValue()

    def reset(self) -> None:
        self.value = ""

    def take(self, value: Any, device: Input) -> None:
        self.value = str(value)

    @property
    def data(self) -> str:
        return "" if self.stupefied else self.value


class HatProxy(Proxy):
    ELEMENT_TYPE = "hat_proxy"
    KIND = DeviceKind.HAT
    value = NewestValue()

    def reset(self) -> None:
        self.value = HatState.CENTERED

    def take(self, value: Any, device: Input) -> None:
        self.value = HatState(int(value))

    @property
    def data(self) -> HatState:
        return HatState.CENTERED if self.stupefied else self.value


class KeyboardMouseProxy(Proxy):
    ELEMENT_TYPE = "keyboard_mouse_proxy"
    KIND = DeviceKind.KEYBOARD_MOUSE
    HAS_UNIT = False
    EVERY_FRAME = True  # the newest of each frame (a frame without keys keeps it)

    def update_data(self, device: Input) -> None:
        self.reason = None
        newest = device.store.frame(DeviceKind.KEYBOARD_MOUSE).newest
        if newest is not None:
            self.timestamp = newest.timestamp

    def key_pressed(self, key: Key | int) -> float:
        """Presses of ``key`` this frame plus one if held (0 when stupefied)."""
        device = self.device
        return device.key_pressed(key) if isinstance(device, KeyboardMouse) else 0

    def key_pressed_with(self, key: Key | int, modifier: Modifier | int) -> float:
        """Presses of ``key`` this frame typed with exactly ``modifier`` held (0 when stupefied)."""
        device = self.device
        return device.key_pressed_with(key, modifier) if isinstance(device, KeyboardMouse) else 0

    def modifier_only(self, modifier: Modifier | int) -> bool:
        device = self.device
        if isinstance(device, KeyboardMouse):
            return device.modifier_only(modifier)
        return int(modifier) == Modifier.NONE

    @property
    def data(self) -> frozenset[Key]:
        """The keys held now."""
        device = self.device
        return device.held if isinstance(device, KeyboardMouse) else frozenset()


class RumbleProxy(Proxy):
    """Force feedback through a device that can rumble (Gadgeteer's rumble_proxy, minimal:
    :meth:`rumble` passes a request on; there are no effect objects). It reads no data:
    ``data`` is whether the device can rumble now, and it never has a sample time."""

    ELEMENT_TYPE = "rumble_proxy"
    KIND = DeviceKind.RUMBLE
    HAS_UNIT = False
    EVERY_FRAME = True  # (it reads no samples: nothing to gain)

    def update_data(self, device: Input) -> None:
        self.reason = None

    def rumble(self, low: float, high: float, duration: float) -> bool:
        """Run the device's motors (0 to 1) for ``duration`` seconds; False when stupefied
        or the device cannot rumble now."""
        device = self.device
        return (
            isinstance(device, Rumble) and not self.stupefied and device.rumble(low, high, duration)
        )

    @property
    def data(self) -> bool:
        device = self.device
        return isinstance(device, Rumble) and not self.stupefied and device.has_rumble


PROXY_CLASSES: dict[str, type[Proxy]] = {
    cls.ELEMENT_TYPE: cls
    for cls in (
        AnalogProxy,
        DigitalProxy,
        PositionProxy,
        GloveProxy,
        GestureProxy,
        CommandProxy,
        StringProxy,
        HatProxy,
        KeyboardMouseProxy,
        RumbleProxy,
    )
}
