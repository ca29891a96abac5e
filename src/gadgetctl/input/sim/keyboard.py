"""The keyboard/mouse device and the input window that routes events to it."""

from __future__ import annotations

from gadgetctl.input.device import Input, SamplingMode
from gadgetctl.input.devicetypes import KeyboardMouse
from gadgetctl.input.errors import DeviceConfigError, DeviceStartError, ElementVersionError
from gadgetctl.input.events import EventQueue, ScrollDirection
from gadgetctl.input.keys import Key
from gadgetctl.jccl.access import ElementAccess

MIN_KEYBOARD_VERSION = 2
DEFAULT_SENSITIVITY = 0.5  # replaces a mouse_sensitivity of 0, as Gadgeteer does
_SCROLL_PROPERTIES = {
    ScrollDirection.UP: "scroll_up_button",
    ScrollDirection.DOWN: "scroll_down_button",
    ScrollDirection.LEFT: "scroll_left_button",
    ScrollDirection.RIGHT: "scroll_right_button",
}


class KeyboardMouseDevice(KeyboardMouse):
    """``keyboard_mouse_device``: key and mouse events from the manager's event source."""

    ELEMENT_TYPE = "keyboard_mouse_device"
    SAMPLING = SamplingMode.FRAME

    def __init__(self) -> None:
        super().__init__()
        self._queue: EventQueue | None = None

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        version = access.element.version
        if version is None or version < MIN_KEYBOARD_VERSION:
            raise ElementVersionError(
                f"element version {access.element.version_text} is too old: "
                f"keyboard_mouse_device needs version {MIN_KEYBOARD_VERSION} (gadgetctl upgrade)"
            )
        if access.has("mouse_sensitivity"):
            self.mouse_sensitivity = access.float("mouse_sensitivity") or DEFAULT_SENSITIVITY
        if access.has("scroll_as_buttons"):
            self.scroll_as_buttons = access.boolean("scroll_as_buttons")
        for direction, prop in _SCROLL_PROPERTIES.items():
            if access.has(prop):
                code = access.integer(prop)
                if code in Key._value2member_map_:
                    self.scroll_buttons[direction] = Key(code)

    def start_sampling(self) -> None:
        if self.context is None:
            raise DeviceStartError("no event source: the device runs outside an input manager")
        self._queue = self.context.events.subscribe(self.name)

    def stop_sampling(self) -> None:
        if self.context is not None and self._queue is not None:
            self.context.events.unsubscribe(self.name)
        self._queue = None

    def update_data(self) -> None:
        if self._queue is not None:
            self.process_events(self._queue.drain())
        self.end_frame()
        self.store.swap()


class InputWindow(Input):
    """``input_window``: in VR Juggler a window whose key presses feed a keyboard/mouse
    device. Here events pushed with this window's name as target reach that device."""

    ELEMENT_TYPE = "input_window"
    SAMPLING = SamplingMode.FRAME
    KEYBOARD_DEVICE_PROPERTY = "keyboard_mouse_device_name"

    def __init__(self) -> None:
        super().__init__()
        self.keyboard_device = ""

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.keyboard_device = access.string(self.KEYBOARD_DEVICE_PROPERTY)
        if not self.keyboard_device:
            raise DeviceConfigError(
                f"{self.KEYBOARD_DEVICE_PROPERTY} is empty: the window's events would go nowhere"
            )

    def start_sampling(self) -> None:
        if self.context is None:
            raise DeviceStartError("no event source: the window runs outside an input manager")
        self.context.events.route(self.name, self.keyboard_device)

    def stop_sampling(self) -> None:
        if self.context is not None:
            self.context.events.unroute(self.name)
