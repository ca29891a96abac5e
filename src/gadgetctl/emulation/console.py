"""What an emulator tells the person running it: clients coming and going, and a scenario
that stops sending.

Every emulator owns a :class:`Console`; the lines are kept (``lines``, for tests and for
anyone driving an emulator from Python) and, under ``gadgetctl emulate``, printed as they
happen: :func:`~gadgetctl.emulation.command.run` points :attr:`Console.sink` at standard
output. One plain line per event, never a traceback.
"""

from __future__ import annotations

import threading
from collections.abc import Callable


def print_line(text: str) -> None:
    """Print one line at once; a closed or broken standard output is not an error here."""
    try:
        print(text, flush=True)
    except (BrokenPipeError, OSError, ValueError):
        pass


class Console:
    """The emulator's event lines: :meth:`client_connected`, :meth:`client_disconnected`,
    :meth:`stopped_sending` (and :meth:`say` for anything else)."""

    def __init__(self, sink: Callable[[str], None] | None = None) -> None:
        self.sink = sink
        self.lines: list[str] = []
        self._lock = threading.Lock()
        self._stopped = False

    def say(self, text: str) -> None:
        with self._lock:
            self.lines.append(text)
            sink = self.sink
            if sink is not None:
                sink(text)

    def client_connected(self, who: str) -> None:
        self.say(f"client connected: {who}")

    def client_disconnected(self, who: str, why: str = "") -> None:
        self.say(f"client disconnected: {who}" + (f" ({why})" if why else ""))

    def stopped_sending(self, why: str) -> None:
        """Said once: the scenario sends nothing more (hung up, paused)."""
        with self._lock:
            if self._stopped:
                return
            self._stopped = True
        self.say(f"scenario stopped sending: {why}")

    def resumed(self) -> None:
        """Sending again after a pause: a later stop is said again."""
        with self._lock:
            self._stopped = False


def attach(emulator: object, sink: Callable[[str], None] = print_line) -> Console | None:
    """Point ``emulator.console`` (when it has one) at ``sink``; returns that console."""
    console = getattr(emulator, "console", None)
    if isinstance(console, Console):
        console.sink = sink
        return console
    return None


__all__ = ["Console", "attach", "print_line"]
