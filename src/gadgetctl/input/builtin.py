"""Device classes available without a plug-in, like Gadgeteer's built-in constructors."""

from __future__ import annotations

from gadgetctl.input.device import Input
from gadgetctl.input.sim.analog import SimAnalog
from gadgetctl.input.sim.digital import SimDigital
from gadgetctl.input.sim.glove import SimDigitalGlove, SimGloveGesture
from gadgetctl.input.sim.keyboard import InputWindow, KeyboardMouseDevice
from gadgetctl.input.sim.position import SimPosition, SimRelativePosition, SimSetablePosition
from gadgetctl.input.waveform import WaveformDevice

BUILTIN_DEVICES: tuple[type[Input], ...] = (
    KeyboardMouseDevice,
    InputWindow,
    SimAnalog,
    SimDigital,
    SimPosition,
    SimRelativePosition,
    SimSetablePosition,
    SimDigitalGlove,
    SimGloveGesture,
    WaveformDevice,
)
