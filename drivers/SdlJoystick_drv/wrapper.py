"""The input-manager side of the SDL joystick driver: an ``sdl_joystick`` element opens SDL
joystick ``device`` (an index into the joysticks SDL sees, from 0).

Units, as Gadgeteer numbers them: digital unit i = button i (0 or 1), analog unit i = axis i
(raw, -32768 to 32767), hat unit i = hat switch i (a HatState). As in Gadgeteer the
element's ``min`` and ``max`` are not used: SDL's range is fixed, so analog proxies
normalise over -32767..32767 (0.5 when centred; -32768 reads 0.0). As many units as the
joystick has: SDL tells when it opens.

The joystick is polled :attr:`SdlJoystickDevice.poll_rate` times a second (Gadgeteer's 100)
by the process's one SDL thread; each poll is a sample of every kind. A joystick that goes
away raises from ``sample()``, so the input manager marks the device faulted and opens it
again with back-off; that succeeds once SDL sees a joystick at the index again.

Rumble: :meth:`SdlJoystickDevice.rumble` (and a ``rumble_proxy`` pointing at the device)
runs the two motors through ``SDL_JoystickRumble`` when SDL offers rumble for the joystick
(``has_rumble``). Gadgeteer used SDL's haptic effects (constant, periodic, ramp) instead;
gadgetctl's rumble is the minimal form: two strengths and a duration.

Where this differs from Gadgeteer's SdlJoystick on purpose (upstream defects fixed):

* each upstream device called ``SDL_Quit`` when its thread ended, pulling SDL from under every
  other SDL device of the application; here one SDL thread per process is shared, and SDL's
  joystick subsystem is quit when its last user closes (``gadgetctl.transport.sdl``);
* upstream never noticed a joystick going away (its last values stayed for ever); here the
  device faults and opens the joystick again when SDL sees one at the index;
* upstream named the joystick with ``SDL_JoystickName(index)``, SDL 1.2's call (SDL 2 takes a
  joystick there); here ``SDL_JoystickNameForIndex``;
* upstream cast any hat value into a HatState; here values no hat can give are counted
  (``bad_hats``) and read as centred;
* SDL's own SIGINT/SIGTERM handlers are turned off, so Ctrl-C still stops gadgetctl.
"""

from __future__ import annotations

from gadgetctl.input import Analog, DeviceConfigError, Digital, Hat, Rumble
from gadgetctl.jccl.access import ElementAccess

from .standalone import AXIS_RANGE, SdlJoystickLost, SdlJoystickReader


class SdlJoystickDevice(Digital, Analog, Hat, Rumble):
    """A joystick or gamepad through SDL (element type ``sdl_joystick``)."""

    ELEMENT_TYPE = "sdl_joystick"
    sample_interval = 0.0  # sample() waits for the SDL thread's polls
    poll_rate = 100.0  # polls a second (Gadgeteer's driver slept 10 ms between polls)
    read_timeout = 0.1

    def __init__(self) -> None:
        super().__init__()
        self.device_index = 0
        self._reader: SdlJoystickReader | None = None

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name; min and max are read, then replaced as upstream does
        self.device_index = access.integer("device")
        if self.device_index < 0:
            raise DeviceConfigError(
                f"device {self.device_index} is not a joystick index (0 or more)"
            )
        self.analog_min, self.analog_max = AXIS_RANGE

    def _driver(self) -> SdlJoystickReader:
        """One reader for the device's life, so its counters add up over reconnections."""
        if self._reader is None:
            self._reader = SdlJoystickReader(self.device_index, rate=self.poll_rate)
        self._reader.rate = self.poll_rate
        return self._reader

    def start_sampling(self) -> None:
        self._driver().open()

    def sample(self) -> None:
        reader = self._reader
        if reader is None:
            raise SdlJoystickLost(f"SDL joystick {self.device_index} is not open")
        samples = reader.read(self.read_timeout)
        if not samples:
            return
        stamps = [s.timestamp for s in samples]
        self.add_digital_samples(stamps, [s.buttons for s in samples])
        self.add_analog_samples(stamps, [s.axes for s in samples])
        self.add_hat_samples(stamps, [s.hats for s in samples])

    def stop_sampling(self) -> None:
        if self._reader is not None:
            self._reader.close()

    @property
    def has_rumble(self) -> bool:
        return self._reader is not None and self._reader.has_rumble

    def rumble(self, low: float, high: float, duration: float) -> bool:
        """Run the low- and high-frequency motors (0 to 1) for ``duration`` seconds (0, 0
        stops them). False when the joystick is not open or SDL offers no rumble for it."""
        return self._reader is not None and self._reader.rumble(low, high, duration)

    @property
    def counters(self) -> dict[str, int]:
        """Polls turned into samples, hat values no hat can give (``bad_hats``, read as
        centred) and polls lost because sampling fell behind (``overflowed``)."""
        r = self._reader
        if r is None:
            return {}
        return {"polls": r.polls, "bad_hats": r.bad_hats, "overflowed": r.overflowed}
