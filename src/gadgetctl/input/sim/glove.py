"""Simulated gloves: finger bends from key presses, and gestures."""

from __future__ import annotations

import math

import numpy as np

from gadgetctl.input.devicetypes import GLOVE_SHAPE, Digital, DigitalState, Gesture, Glove
from gadgetctl.input.sim.bindings import KeyBinding, SimInput, read_bindings
from gadgetctl.jccl.access import ElementAccess

FINGERS_PER_GLOVE = 5
GLOVES = 2
BENT = math.pi / 2


class SimDigitalGlove(SimInput, Glove, Digital):
    """``simulated_digital_glove``: digital units 0-9 as a simulated digital device; glove
    0 bends thumb..pinky for units 0-4, glove 1 for units 5-9 (all four joints π/2)."""

    ELEMENT_TYPE = "simulated_digital_glove"
    UNITS = FINGERS_PER_GLOVE * GLOVES

    def __init__(self) -> None:
        super().__init__()
        self.bindings: list[KeyBinding | None] = []

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        bindings = read_bindings(access, "key_pair")
        if len(bindings) > self.UNITS:
            self.warn(
                "DRV023",
                f"{len(bindings)} key_pair bindings; only the first {self.UNITS} "
                "(five fingers of two gloves) are used",
            )
        self.bindings = (bindings + [None] * self.UNITS)[: self.UNITS]

    def update_data(self) -> None:
        keyboard = self.keyboard()
        states = [
            DigitalState.ON if b is not None and b.count(keyboard) > 0 else DigitalState.OFF
            for b in self.bindings
        ]
        angles = np.zeros((GLOVES, *GLOVE_SHAPE))
        for unit, state in enumerate(states):
            if state:
                angles[unit // FINGERS_PER_GLOVE, unit % FINGERS_PER_GLOVE, :] = BENT
        stamp = self.now()
        self.add_digital_sample(states, stamp)
        self.add_glove_sample(angles, stamp)
        super().update_data()


class SimGloveGesture(SimInput, Glove, Gesture):
    """``simulated_glove_gesture``: pressing the n-th ``key_presses`` binding makes gesture n
    current (it stays until another binding is pressed); gestures are named after the
    binding elements. Unlike Gadgeteer (which reads a misnamed property and never updates)
    the bindings work. Trained gesture files are not read, so glove angles stay open."""

    ELEMENT_TYPE = "simulated_glove_gesture"

    def __init__(self) -> None:
        super().__init__()
        self.bindings: list[KeyBinding | None] = []
        self.gesture = 0

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.bindings = read_bindings(access, "key_presses")
        self.gesture_names = [
            b.name if b is not None and b.name else f"gesture {i}"
            for i, b in enumerate(self.bindings)
        ]

    def update_data(self) -> None:
        keyboard = self.keyboard()
        for index, binding in enumerate(self.bindings):
            if binding is not None and binding.count(keyboard) > 0:
                self.gesture = index
                break
        stamp = self.now()
        self.add_gesture_sample([self.gesture], stamp)
        self.add_glove_sample(np.zeros(GLOVE_SHAPE), stamp)
        super().update_data()
