"""Key bindings (``key_modifier_pair`` elements) and the base of keyboard-driven devices."""

from __future__ import annotations

from dataclasses import dataclass

from gadgetctl.input.device import Input, SamplingMode
from gadgetctl.input.errors import DeviceConfigError, ElementVersionError
from gadgetctl.input.keys import Key, Modifier
from gadgetctl.input.proxies import KeyboardMouseProxy
from gadgetctl.jccl.access import ElementAccess
from gadgetctl.jccl.configuration import ConfigElement

KEYBOARD_PROPERTY = "keyboard_mouse_proxy"
OLD_KEYBOARD_PROPERTY = "event_window_proxy"


@dataclass(frozen=True, slots=True)
class KeyBinding:
    """A key and the modifier that must be the only one down (ANY: whatever is down)."""

    key: int
    modifier: int = Modifier.ANY
    name: str = ""

    def count(self, keyboard: KeyboardMouseProxy | None) -> float:
        """Gadgeteer's checkKeyPair: the key's press count if the modifier condition holds,
        judged per keystroke (the presses typed with exactly that modifier held), so keys of
        one frame do not lend each other their modifiers."""
        if keyboard is None:
            return 0
        return keyboard.key_pressed_with(self.key, self.modifier)

    def __str__(self) -> str:
        key = Key(self.key).name if self.key in Key._value2member_map_ else str(self.key)
        if self.modifier == Modifier.ANY:
            return key
        modifier = (
            Modifier(self.modifier).name
            if self.modifier in Modifier._value2member_map_
            else str(self.modifier)
        )
        return f"{modifier}+{key}"


def read_binding(element: ConfigElement, access: ElementAccess) -> KeyBinding:
    child = ElementAccess(element, access.repo)
    return KeyBinding(child.integer("key"), child.integer("modifier_key"), element.name)


def read_bindings(access: ElementAccess, prop: str) -> list[KeyBinding | None]:
    """The bindings of ``prop`` by slot; an empty slot is None."""
    access.definition(prop)
    return [
        None if v.element is None else read_binding(v.element, access)
        for v in access.element.values(prop)
    ]


class SimInput(Input):
    """Base of simulated devices: a keyboard/mouse proxy whose key counts drive the data,
    computed once per frame in ``update_data``."""

    SAMPLING = SamplingMode.FRAME

    def __init__(self) -> None:
        super().__init__()
        self.keyboard_proxy = ""

    def config(self, access: ElementAccess) -> None:
        super().config(access)
        self.keyboard_proxy = (
            access.string(KEYBOARD_PROPERTY) if access.has(KEYBOARD_PROPERTY) else ""
        )
        if not self.keyboard_proxy:
            if access.element.texts(OLD_KEYBOARD_PROPERTY):
                raise ElementVersionError(
                    f"version {access.element.version_text} element names an {OLD_KEYBOARD_PROPERTY}, which "
                    f"no longer exists; upgrade it (gadgetctl upgrade) to use {KEYBOARD_PROPERTY}"
                )
            raise DeviceConfigError(
                f"{KEYBOARD_PROPERTY} is empty: the device would never see a key"
            )

    def keyboard(self) -> KeyboardMouseProxy | None:
        """The keyboard/mouse proxy, updated for the current frame."""
        if self.context is None:
            return None
        proxy = self.context.proxy(self.keyboard_proxy)
        return proxy if isinstance(proxy, KeyboardMouseProxy) else None
