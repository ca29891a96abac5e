"""Keyboard and mouse events, and the source keyboard/mouse devices receive them from.

In VR Juggler an input window delivers key presses to a ``keyboard_mouse_device``. In
gadgetctl an :class:`EventSource` does: tests push events, and an interactive monitor
pushes the terminal's key presses. An event may name its target, a keyboard/mouse device
or an ``input_window`` routed to one; an event without a target reaches every
keyboard/mouse device. Pushing is thread-safe; devices drain their queue once per frame.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import StrEnum

from gadgetctl.input.clock import now
from gadgetctl.input.keys import MODIFIER_KEYS, Key, Modifier


@dataclass(frozen=True, slots=True)
class KeyEvent:
    """A key or mouse button (``Key.MOUSE_BUT1``...) pressed or released."""

    key: Key
    pressed: bool
    timestamp: float = field(default_factory=now)
    target: str | None = None


@dataclass(frozen=True, slots=True)
class MouseMoveEvent:
    """Relative mouse motion in pixels; positive ``dy`` is downwards (MOUSE_POSY)."""

    dx: float
    dy: float
    timestamp: float = field(default_factory=now)
    target: str | None = None


class ScrollDirection(StrEnum):
    UP = "up"
    DOWN = "down"
    LEFT = "left"
    RIGHT = "right"


SCROLL_KEYS: dict[ScrollDirection, Key] = {
    ScrollDirection.UP: Key.MOUSE_SCROLL_UP,
    ScrollDirection.DOWN: Key.MOUSE_SCROLL_DOWN,
    ScrollDirection.LEFT: Key.MOUSE_SCROLL_LEFT,
    ScrollDirection.RIGHT: Key.MOUSE_SCROLL_RIGHT,
}


@dataclass(frozen=True, slots=True)
class ScrollEvent:
    direction: ScrollDirection
    timestamp: float = field(default_factory=now)
    target: str | None = None


Event = KeyEvent | MouseMoveEvent | ScrollEvent

_MODIFIER_KEY = {
    Modifier.SHIFT: Key.KEY_SHIFT,
    Modifier.CTRL: Key.KEY_CTRL,
    Modifier.ALT: Key.KEY_ALT,
    Modifier.COMMAND: Key.KEY_COMMAND,
}


def modifier_key(modifier: Modifier | Key) -> Key:
    """The key of a modifier (``Modifier.CTRL`` or ``Key.KEY_CTRL`` -> ``Key.KEY_CTRL``)."""
    if isinstance(modifier, Key):
        if modifier not in MODIFIER_KEYS:
            raise ValueError(f"{modifier.name} is not a modifier key")
        return modifier
    try:
        return _MODIFIER_KEY[Modifier(modifier)]
    except KeyError:
        raise ValueError(f"{Modifier(modifier).name} is not a modifier that can be held") from None


class EventQueue:
    """The events waiting for one keyboard/mouse device."""

    def __init__(self) -> None:
        self._events: deque[Event] = deque()

    def put(self, event: Event) -> None:
        self._events.append(event)

    def drain(self) -> list[Event]:
        events = []
        pop = self._events.popleft
        while self._events:
            events.append(pop())
        return events


class EventSource:
    """Where keyboard/mouse devices get their events from."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._queues: dict[str, EventQueue] = {}
        self._routes: dict[str, str] = {}  # input window name -> device name

    # -- devices ------------------------------------------------------------------------

    def subscribe(self, device: str) -> EventQueue:
        with self._lock:
            queue = self._queues[device] = EventQueue()
            return queue

    def unsubscribe(self, device: str) -> None:
        with self._lock:
            self._queues.pop(device, None)

    def route(self, window: str, device: str) -> None:
        """Deliver events targeted at ``window`` to ``device``."""
        with self._lock:
            self._routes[window] = device

    def unroute(self, window: str) -> None:
        with self._lock:
            self._routes.pop(window, None)

    @property
    def targets(self) -> list[str]:
        """Names events can be targeted at: devices and routed windows."""
        with self._lock:
            return sorted({*self._queues, *self._routes})

    # -- producers ----------------------------------------------------------------------

    def push(self, event: Event) -> int:
        """Deliver ``event``; returns how many devices received it."""
        with self._lock:
            if event.target is None:
                queues = list(self._queues.values())
            else:
                device = self._routes.get(event.target, event.target)
                queue = self._queues.get(device)
                queues = [queue] if queue is not None else []
        for queue in queues:
            queue.put(event)
        return len(queues)

    def press(self, key: Key, *, target: str | None = None) -> None:
        self.push(KeyEvent(Key(key), True, now(), target))

    def release(self, key: Key, *, target: str | None = None) -> None:
        self.push(KeyEvent(Key(key), False, now(), target))

    def tap(
        self, key: Key, *, modifiers: Iterable[Modifier | Key] = (), target: str | None = None
    ) -> None:
        """Press and release ``key`` while holding ``modifiers`` (what one keystroke in a
        terminal amounts to)."""
        held = [modifier_key(m) for m in modifiers]
        for mod in held:
            self.press(mod, target=target)
        self.press(key, target=target)
        self.release(key, target=target)
        for mod in reversed(held):
            self.release(mod, target=target)

    def move(self, dx: float, dy: float, *, target: str | None = None) -> None:
        self.push(MouseMoveEvent(dx, dy, now(), target))

    def scroll(self, direction: ScrollDirection | str, *, target: str | None = None) -> None:
        self.push(ScrollEvent(ScrollDirection(direction), now(), target))
