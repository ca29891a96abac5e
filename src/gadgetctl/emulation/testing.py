"""Emulators for the length of a test: started on demand, all stopped at the end.

Like the rest of :mod:`gadgetctl.emulation` it imports nothing else from gadgetctl. A driver's
tests make their fixture from it::

    @pytest.fixture
    def emulator() -> Iterator[Callable[..., WandaEmulator]]:
        with emulators(WandaEmulator, rate=100.0) as start:
            yield start
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Protocol, TypeVar


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
