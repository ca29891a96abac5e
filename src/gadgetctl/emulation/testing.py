"""Emulators for the length of a test: started on demand, all stopped at the end.

Like the rest of :mod:`gadgetctl.emulation` it imports nothing else from gadgetctl. A driver's
tests make their fixture from it (:class:`FixtureLine` plays a conformance test's own bytes on
a pty instead)::

    @pytest.fixture
    def emulator() -> Iterator[Callable[..., WandaEmulator]]:
        with emulators(WandaEmulator, rate=100.0) as start:
            yield start
"""

from __future__ import annotations

import os
import select
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Protocol, TypeVar

from gadgetctl.emulation.endpoints import PseudoTerminal


class Startable(Protocol):
    def start(self) -> object: ...

    def stop(self) -> None: ...


E = TypeVar("E", bound=Startable)


@contextmanager
def emulators(
    kind: Callable[..., E], scenario: str = "motion", **defaults: object
) -> Iterator[Callable[..., E]]:
    """A ``start(scenario=..., **options)`` that makes and starts a ``kind`` emulator
    (``defaults`` under the options given), and stops every one it started on the way out."""
    started: list[E] = []

    def start(scenario: str = scenario, **options: object) -> E:
        emulator = kind(scenario, **{**defaults, **options})
        emulator.start()
        started.append(emulator)
        return emulator

    try:
        yield start
    finally:
        for emulator in started:
            emulator.stop()


class FixtureLine:
    """A serial line on a pty that plays bytes a conformance test gives (from a manual, a
    capture, another implementation's encoder), not an emulator's: the driver opens
    ``address``; :meth:`feed` sends bytes now; ``answers`` maps a command the driver writes
    (the bytes it ends with) to the reply sent at once; ``received`` keeps everything the
    driver wrote. A context manager; a daemon thread serves the line until :meth:`close`."""

    def __init__(self, answers: Mapping[bytes, bytes] | None = None) -> None:
        self.answers = dict(answers or {})
        self.received = bytearray()
        self._pty = PseudoTerminal()
        self._pending = bytearray()  # what the driver wrote since the last answer
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.address = ""

    def open(self) -> FixtureLine:
        self.address = self._pty.open().address
        self._thread = threading.Thread(target=self._serve, name="fixture-line", daemon=True)
        self._thread.start()
        return self

    def feed(self, data: bytes) -> None:
        """Send ``data`` to the driver (all of it, waiting while the pty is full)."""
        view = memoryview(data)
        deadline = time.monotonic() + 5.0
        while view and time.monotonic() < deadline:
            taken = self._pty.write(bytes(view))
            view = view[taken:]
            if view:
                time.sleep(0.001)
        if view:
            raise TimeoutError(f"the driver left {len(view)} fixture bytes unread for 5 s")

    def unread(self) -> int:
        """Bytes fed that the driver has not read yet."""
        return self._pty.unread()

    def hang_up(self) -> None:
        self._pty.hang_up()

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        self._pty.close()

    def __enter__(self) -> FixtureLine:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _serve(self) -> None:
        while not self._stop.is_set():
            master = self._pty.master
            if master < 0:
                return
            try:
                ready, _, _ = select.select([master], [], [], 0.02)
                data = os.read(master, 4096) if ready else b""
            except OSError:
                return
            if not data:
                continue
            with self._lock:
                self.received += data
                self._pending += data
                for command, reply in self.answers.items():
                    if self._pending.endswith(command):
                        self._pending.clear()
                        self.feed(reply)
                        break
