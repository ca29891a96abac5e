"""The input-manager side of the Linux joystick driver: a ``linux_joydev`` element becomes a
device with digital and analog units fed from :class:`~.standalone.LinuxJoydevStandalone`.

Units, as Gadgeteer's LinuxJoydev numbers them:

* digital: the joystick's buttons, then two virtual buttons per entry of ``axis_buttons``
  (entry i: "low" at ``buttons + 2i``, "high" at ``buttons + 2i + 1``);
* analog: the axes, raw (-32767 to 32767); analog proxies normalise them with the element's
  ``min`` and ``max``.

Upstream ignored ``min``/``max`` and always used -32767..32767, which are also the
definition's defaults; here the element's values are used, for the proxies and for the
middle of the range that decides the virtual buttons. Upstream also looked at a stale errno
after end of file and then dropped the sample; the standalone driver reports the end itself
(see its module documentation) and this device raises from ``sample()``, so the input manager
marks it faulted and reopens the device file with back-off.

Every event read becomes a sample (the initial burst sent on open counts as one), stamped
from the event's own millisecond clock, so a press and release between two frames both show.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from gadgetctl.input import Analog, DeviceConfigError, Digital
from gadgetctl.jccl.access import ElementAccess

from .standalone import (
    AXIS_MAX,
    AXIS_MIN,
    JoystickDisconnected,
    JoystickEvent,
    LinuxJoydevStandalone,
    axis_button_pair,
)


class LinuxJoydevDevice(Digital, Analog):
    """A joystick read through Linux joydev (element type ``linux_joydev``)."""

    ELEMENT_TYPE = "linux_joydev"
    sample_interval = 0.0  # sample() waits for data itself

    #: Seconds one sample() call waits for data.
    poll_timeout = 0.05
    #: Seconds an opened file may stay at end of file before anything came (a FIFO without
    #: writer); then the device counts as gone.
    connect_timeout = 1.0
    #: After a loss, seconds a restart waits for the device's initial burst.
    probe_timeout = 0.25

    def __init__(self) -> None:
        super().__init__()
        self.port_name = "/dev/js0"
        self.axis_buttons: tuple[int, ...] = ()
        self._driver: LinuxJoydevStandalone | None = None
        self._open = False
        self._started = False
        self._buttons: list[int] = []
        self._axes: list[int] = []
        self._virtual: list[int] = []
        self._last_stamp = -math.inf

    def config(self, access: ElementAccess) -> None:
        super().config(access)  # name, and the analog range (min, max) proxies normalise with
        self.port_name = access.string("port_name")
        if not self.port_name:
            raise DeviceConfigError("port_name is empty")
        self.axis_buttons = tuple(access.integers("axis_buttons"))
        bad = [a for a in self.axis_buttons if not 0 <= a <= 255]
        if bad:
            raise DeviceConfigError(f"axis_buttons: {bad[0]} is not an axis number (0 to 255)")

    # -- sampling ---------------------------------------------------------------------------

    def _device(self) -> LinuxJoydevStandalone:
        """One driver for the device's life, so its counters add up over reconnections."""
        if self._driver is None:
            self._driver = LinuxJoydevStandalone(
                self.port_name, poll_timeout=self.poll_timeout, connect_timeout=self.connect_timeout
            )
        return self._driver

    def start_sampling(self) -> None:
        driver = self._device()
        driver.open()
        self._open = True
        state = driver.state()  # zeros, sized by the ioctls when the file is a real device
        self._buttons, self._axes = list(state.buttons), list(state.axes)
        self._virtual = self._virtual_buttons()
        if self._started:
            self._probe(driver)
        self._started = True

    def _probe(self, driver: LinuxJoydevStandalone) -> None:
        """After a loss, succeed only when the device sends again (a real joydev sends its
        initial burst as soon as it is opened; a FIFO once its writer is back)."""
        driver.poll_timeout = self.probe_timeout
        try:
            events = driver.sample().events
            if not events:
                raise JoystickDisconnected(f"{self.port_name}: still nothing to read")
        except BaseException:
            self.stop_sampling()
            raise
        finally:
            driver.poll_timeout = self.poll_timeout
        self._add(events)

    def sample(self) -> None:
        driver = self._driver
        if driver is None or not self._open:
            raise JoystickDisconnected(f"{self.port_name}: closed")
        events = driver.sample().events  # raises at end of file
        if events:
            self._add(events)

    def stop_sampling(self) -> None:
        if self._driver is not None and self._open:
            self._open = False
            self._driver.close()

    # -- samples ----------------------------------------------------------------------------

    def _add(self, events: Sequence[JoystickEvent]) -> None:
        """One sample per event, except inside the initial burst (one for all of it)."""
        stamps, digital, analog = [], [], []
        watched = set(self.axis_buttons)
        times = self._stamps(events)
        last = len(events) - 1
        for index, event in enumerate(events):
            target = self._buttons if event.is_button else self._axes
            if event.number >= len(target):
                target.extend([0] * (event.number + 1 - len(target)))
            target[event.number] = event.value
            if event.is_axis and event.number in watched:
                self._virtual = self._virtual_buttons()
            if event.is_init and index < last and events[index + 1].is_init:
                continue
            stamps.append(times[index])
            digital.append(self._buttons + self._virtual)
            analog.append(list(self._axes))
        start = 0
        for stop in range(1, len(stamps) + 1):  # a burst may have grown the counts
            if stop < len(stamps) and (
                len(digital[stop]) == len(digital[start])
                and len(analog[stop]) == len(analog[start])
            ):
                continue
            self.add_digital_samples(stamps[start:stop], np.array(digital[start:stop], np.int8))
            self.add_analog_samples(stamps[start:stop], np.array(analog[start:stop], np.float64))
            start = stop

    def _virtual_buttons(self) -> list[int]:
        """(low, high) per ``axis_buttons`` entry, split at the middle of the analog range."""
        low, high = self.analog_min, self.analog_max
        if high <= low:
            low, high = AXIS_MIN, AXIS_MAX
        axes = self._axes
        result: list[int] = []
        for axis in self.axis_buttons:
            result += axis_button_pair(axes[axis], low, high) if axis < len(axes) else (0, 0)
        return result

    def _stamps(self, events: Sequence[JoystickEvent]) -> list[float]:
        """Sample times: the newest event now, the others earlier by their millisecond clock
        (which wraps at 2**32), never before the previous read nor out of order."""
        now = self.now()
        newest = events[-1].time_ms
        stamps = []
        floor = self._last_stamp
        for event in events:
            age = ((newest - event.time_ms) & 0xFFFFFFFF) / 1000.0
            floor = min(max(now - age, floor), now)
            stamps.append(floor)
        self._last_stamp = floor
        return stamps

    # -- diagnostics ------------------------------------------------------------------------

    @property
    def counters(self) -> dict[str, int]:
        """What the driver counted since the device was made, reconnections included."""
        driver = self._driver
        if driver is None:
            return {}
        return {"skipped_bytes": driver.skipped_bytes, "resyncs": driver.resyncs}
