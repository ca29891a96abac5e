"""Helpers for tests of drivers against the input manager (bundled and scaffolded drivers).

Each wait has a deadline, so a device that never delivers fails the test instead of
stalling it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from gadgetctl.input.manager import InputManager


def wait_until(predicate: Callable[[], bool], timeout: float = 3.0,
               step: Callable[[], object] | None = None, pause: float = 0.005) -> bool:
    """Call ``step`` (if any) and poll ``predicate`` until it holds or ``timeout`` passes."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if step is not None:
            step()
        if predicate():
            return True
        time.sleep(pause)
    return predicate()


def frames_until(manager: InputManager, done: Callable[[], bool], timeout: float = 3.0,
                 pause: float = 0.002) -> float:
    """Run frames until ``done()``; the seconds it took. Fails after ``timeout``."""
    start = time.monotonic()
    while True:
        manager.update()
        if done():
            return time.monotonic() - start
        if time.monotonic() - start >= timeout:
            raise AssertionError(f"timed out after {timeout} s")
        time.sleep(pause)
