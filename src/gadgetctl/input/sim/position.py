"""Simulated positions: keyboard-driven, relative (product of two proxies) and settable."""

from __future__ import annotations

import math

import numpy as np

from gadgetctl.input.device import SamplingMode
from gadgetctl.input.devicetypes import Position
from gadgetctl.input.errors import DeviceConfigError
from gadgetctl.input.proxies import PositionProxy
from gadgetctl.input.sim.bindings import KeyBinding, SimInput, read_bindings
from gadgetctl.input.transforms import euler_xyz_degrees, rotation_axis, translation
from gadgetctl.jccl.access import ElementAccess

LOCAL, GLOBAL = 0, 1

#: The 12 key_pair slots of simulated_positional_device, in Gadgeteer's order:
#: (translation direction, None) or (None, (rotation axis, sign)).
MOVES: tuple[
    tuple[tuple[float, float, float] | None, tuple[tuple[float, float, float], float] | None], ...
] = (
    ((0, 0, -1), None),  # 0 forward
    ((0, 0, 1), None),  # 1 back
    ((-1, 0, 0), None),  # 2 left
    ((1, 0, 0), None),  # 3 right
    ((0, 1, 0), None),  # 4 up
    ((0, -1, 0), None),  # 5 down
    (None, ((0, 1, 0), -1.0)),  # 6 yaw right
    (None, ((0, 1, 0), 1.0)),  # 7 yaw left
    (None, ((1, 0, 0), 1.0)),  # 8 pitch up
    (None, ((1, 0, 0), -1.0)),  # 9 pitch down
    (None, ((0, 0, -1), 1.0)),  # 10 roll counter-clockwise
    (None, ((0, 0, -1), -1.0)),  # 11 roll clockwise
)


class SimPosition(SimInput, Position):
    """``simulated_positional_device``: 12 bindings move and turn one sensor.

    Translations are ``translation_delta`` meters per press, rotations ``rotation_delta``
    degrees; local moves post-multiply, global ones pre-multiply (a global rotation turns
    about world axes in place). Device-level filters are applied once per sample
    (Gadgeteer applies them twice, a bug not reproduced here)."""

    ELEMENT_TYPE = "simulated_positional_device"
    SLOTS = len(MOVES)

    def __init__(self) -> None:
        super().__init__()
        self.bindings: list[KeyBinding | None] = []
        self.matrix = np.eye(4)
        self.translation_delta = 0.1
        self.rotation_delta = 1.0
        self.translation_system = LOCAL
        self.rotation_system = LOCAL

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.bindings = read_bindings(access, "key_pair")[: self.SLOTS]
        if len(self.bindings) < self.SLOTS:
            self.warn(
                "DRV023",
                f"only {len(self.bindings)} of {self.SLOTS} key_pair bindings; "
                "the movements of the missing slots have no key",
            )
        self.bindings += [None] * (self.SLOTS - len(self.bindings))
        position, rotation = access.floats("initial_position"), access.floats("initial_rotation")
        self.matrix = translation(*position[:3]) @ euler_xyz_degrees(*rotation[:3])
        self.translation_delta = access.float("translation_delta")
        self.rotation_delta = access.float("rotation_delta")
        self.translation_system = access.integer("translation_coordinate_system")
        self.rotation_system = access.integer("rotation_coordinate_system")

    def move(self, slot: int, amount: float) -> None:
        """Apply movement ``slot`` ``amount`` times (a press count)."""
        direction, rotation = MOVES[slot]
        m = self.matrix
        if direction is not None:
            step = amount * self.translation_delta
            t = translation(direction[0] * step, direction[1] * step, direction[2] * step)
            self.matrix = m @ t if self.translation_system == LOCAL else t @ m
        elif rotation is not None:
            axis, sign = rotation
            r = rotation_axis(axis, math.radians(sign * amount * self.rotation_delta))
            if self.rotation_system == LOCAL:
                self.matrix = m @ r
            else:
                turned = r @ m
                turned[:3, 3] = m[:3, 3]
                self.matrix = turned

    def update_data(self) -> None:
        keyboard = self.keyboard()
        for slot, binding in enumerate(self.bindings):
            if binding is not None:
                amount = binding.count(keyboard)
                if amount:
                    self.move(slot, amount)
        self.add_position_sample([self.matrix])
        super().update_data()


class SimRelativePosition(Position):
    """``simulated_relative_position``: each frame base_frame_proxy · relative_proxy."""

    ELEMENT_TYPE = "simulated_relative_position"
    SAMPLING = SamplingMode.FRAME
    PROPERTIES = ("base_frame_proxy", "relative_proxy")

    def __init__(self) -> None:
        super().__init__()
        self.base_proxy = ""
        self.relative_proxy = ""

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.base_proxy, self.relative_proxy = (access.string(p) for p in self.PROPERTIES)
        for prop, value in zip(
            self.PROPERTIES, (self.base_proxy, self.relative_proxy), strict=True
        ):
            if not value:
                raise DeviceConfigError(f"{prop} is empty")

    def _proxy(self, name: str) -> PositionProxy | None:
        proxy = self.context.proxy(name) if self.context is not None else None
        return proxy if isinstance(proxy, PositionProxy) else None

    def update_data(self) -> None:
        base, relative = self._proxy(self.base_proxy), self._proxy(self.relative_proxy)
        base_m = base.matrix if base is not None else np.eye(4)
        relative_m = relative.matrix if relative is not None else np.eye(4)
        stamp = (
            relative.timestamp if relative is not None and relative.timestamp is not None else None
        )
        self.add_position_sample([base_m @ relative_m], stamp)
        super().update_data()


class SimSetablePosition(Position):
    """``simulated_setable_position``: programs set the data with :meth:`set_data`."""

    ELEMENT_TYPE = "simulated_setable_position"
    SAMPLING = SamplingMode.FRAME

    def set_data(self, matrices: object, timestamp: float | None = None) -> None:
        """One 4x4 matrix per unit; thread-safe."""
        self.add_position_sample(matrices, timestamp)
