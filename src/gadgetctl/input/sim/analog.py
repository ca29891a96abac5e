"""``simulated_analog_device``: values moved up and down by key presses."""

from __future__ import annotations

from gadgetctl.input.devicetypes import Analog
from gadgetctl.input.sim.bindings import KeyBinding, SimInput, read_bindings
from gadgetctl.jccl.access import ElementAccess


class SimAnalog(SimInput, Analog):
    """One unit per ``increment_keypress`` binding; the ``decrement_keypress`` list is read in
    parallel. Each frame: value += ups·delta - downs·delta; with ``auto_return`` and no key,
    one delta back towards ``initial_value``; then clamped into [min, max]."""

    ELEMENT_TYPE = "simulated_analog_device"

    def __init__(self) -> None:
        super().__init__()
        self.increments: list[KeyBinding | None] = []
        self.decrements: list[KeyBinding | None] = []
        self.delta = 1.0
        self.initial_value = 0.0
        self.auto_return = False
        self.values: list[float] = []

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.increments = read_bindings(access, "increment_keypress")
        self.decrements = read_bindings(access, "decrement_keypress")
        if len(self.decrements) < len(self.increments):
            self.warn(
                "DRV023",
                f"{len(self.increments)} increment bindings but only {len(self.decrements)} "
                "decrement bindings; the units without one can only increase",
                hint="add a decrement_keypress for every increment_keypress",
            )
        self.delta = access.float("delta")
        self.initial_value = access.float("initial_value")
        self.auto_return = access.boolean("auto_return")
        self.values = [self._clamp(self.initial_value)] * len(self.increments)

    def _clamp(self, value: float) -> float:
        low, high = self.analog_min, self.analog_max
        return high if value > high else low if value < low else value

    def update_data(self) -> None:
        keyboard = self.keyboard()
        delta = self.delta
        for unit, up_binding in enumerate(self.increments):
            down_binding = self.decrements[unit] if unit < len(self.decrements) else None
            ups = up_binding.count(keyboard) if up_binding else 0
            downs = down_binding.count(keyboard) if down_binding else 0
            value = self.values[unit] + ups * delta - downs * delta
            if self.auto_return and not ups and not downs:
                target = self.initial_value
                if abs(value - target) <= delta:
                    value = target
                else:
                    value += delta if value < target else -delta
            self.values[unit] = self._clamp(value)
        self.add_analog_sample(self.values)
        super().update_data()
