"""``simulated_digital_device``: buttons that are ON in a frame where their key was pressed."""

from __future__ import annotations

from gadgetctl.input.devicetypes import Digital, DigitalState
from gadgetctl.input.sim.bindings import KeyBinding, SimInput, read_bindings
from gadgetctl.jccl.access import ElementAccess


class SimDigital(SimInput, Digital):
    """One unit per ``key_pair`` binding. A key tapped between two frames gives one ON
    sample (counts include every press since the previous frame)."""

    ELEMENT_TYPE = "simulated_digital_device"

    def __init__(self) -> None:
        super().__init__()
        self.bindings: list[KeyBinding | None] = []

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.bindings = read_bindings(access, "key_pair")

    def states(self) -> list[int]:
        keyboard = self.keyboard()
        return [
            DigitalState.ON if b is not None and b.count(keyboard) > 0 else DigitalState.OFF
            for b in self.bindings
        ]

    def update_data(self) -> None:
        self.add_digital_sample(self.states())
        super().update_data()
