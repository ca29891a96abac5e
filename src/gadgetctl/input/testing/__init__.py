"""Helpers for tests of drivers against the input manager (bundled and scaffolded drivers).

Waits (:func:`wait_until`, :func:`frames_until`, :func:`gather`, :func:`wait_for_fault`,
:func:`resumes_within`) each have a deadline, so a device that never delivers fails the test
instead of stalling it. :mod:`~gadgetctl.input.testing.configs` writes the configurations and
builds the managers a test runs; :mod:`~gadgetctl.input.testing.fixtures` declares a driver's
pytest fixtures.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from gadgetctl.input.kinds import DeviceKind
    from gadgetctl.input.manager import InputManager
    from gadgetctl.input.status import ElementStatus

T = TypeVar("T")


def wait_until(
    predicate: Callable[[], bool],
    timeout: float = 3.0,
    step: Callable[[], object] | None = None,
    pause: float = 0.005,
) -> bool:
    """Call ``step`` (if any) and poll ``predicate`` until it holds or ``timeout`` passes."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if step is not None:
            step()
        if predicate():
            return True
        time.sleep(pause)
    return predicate()


def frames_until(
    manager: InputManager, done: Callable[[], bool], timeout: float = 3.0, pause: float = 0.002
) -> float:
    """Run frames until ``done()``; the seconds it took. Fails after ``timeout``."""
    start = time.monotonic()
    while True:
        manager.update()
        if done():
            return time.monotonic() - start
        if time.monotonic() - start >= timeout:
            raise AssertionError(f"timed out after {timeout} s")
        time.sleep(pause)


def gather(read: Callable[[], Iterable[T]], count: int, timeout: float = 5.0) -> list[T]:
    """Call ``read`` until it has returned ``count`` items in all; fails after ``timeout``."""
    got: list[T] = []
    assert wait_until(
        lambda: len(got) >= count, timeout=timeout, step=lambda: got.extend(read())
    ), f"{len(got)} of {count} items after {timeout} s"
    return got


def frame_recorder(manager: InputManager, device: str, *kinds: DeviceKind) -> tuple:
    """``(frame, values, ...)``: a frame step (``manager.update()``) and, per kind in the order
    of ``kinds``, a list that step extends with the values of every sample ``device`` stored
    in that frame."""
    source = manager.device(device)
    kept: list[list] = [[] for _ in kinds]

    def frame() -> None:
        manager.update()
        for kind, values in zip(kinds, kept, strict=True):
            values.extend(s.values for s in source.store.frame(kind))

    return (frame, *kept)


def wait_for_fault(
    manager: InputManager,
    name: str,
    timeout: float = 5.0,
    step: Callable[[], object] | None = None,
) -> ElementStatus:
    """Run frames (``step``, ``manager.update`` by default) until device ``name`` is faulted
    or reconnecting; its status then."""
    assert wait_until(
        lambda: manager.status(name).state in ("faulted", "reconnecting"),
        timeout=timeout,
        step=step or manager.update,
    ), manager.status(name)
    status = manager.status(name)
    assert status is not None
    return status


def hangs_up(
    manager: InputManager,
    name: str,
    emulator: Any,
    timeout: float = 5.0,
    fault_timeout: float = 5.0,
    step: Callable[[], object] | None = None,
) -> ElementStatus:
    """The emulator hangs up (its ``disconnected`` event, set within ``timeout``) and device
    ``name`` faults (:func:`wait_for_fault` within ``fault_timeout``); its status then."""
    assert emulator.disconnected.wait(timeout), "the emulator never hung up"
    return wait_for_fault(manager, name, fault_timeout, step)


def reads_past_garbage(manager: InputManager, name: str, records: int, timeout: float = 5.0) -> Any:
    """Run frames until device ``name`` has read ``records`` good records among the garbage its
    emulator sends; it has neither faulted nor stopped running. The device."""
    device = manager.device(name)
    assert wait_until(lambda: device.records >= records, timeout=timeout, step=manager.update)
    assert device.faults == 0 and manager.status(name).state == "running"
    return device


def resumes_within(
    manager: InputManager,
    name: str,
    restart: Callable[[], object],
    delivered: Callable[[], int],
    within: float = 2.0,
    more: int = 1,
    step: Callable[[], object] | None = None,
) -> None:
    """``restart()`` brings device ``name`` back (an emulator started again): what it has
    ``delivered()`` grows by ``more`` within ``within`` seconds of that, running frames with
    ``step`` (``manager.update``), and the device is running again."""
    before = delivered()
    restart()
    back = time.monotonic()
    assert wait_until(
        lambda: delivered() >= before + more, timeout=within, step=step or manager.update
    )
    assert time.monotonic() - back < within
    assert manager.status(name).state == "running"


def serial_line_lost_then_resumes(
    manager: InputManager,
    name: str,
    emulator: Any,
    restart: Callable[[], object],
    records: int,
    *,
    reopened: bool = False,
) -> None:
    """The emulator hangs up after sending what makes ``records`` records: device ``name``
    faults, its reason "serial line lost" (with ``reopened``, "cannot open" too: the manager
    retried and the hung-up pty behind the link is gone), and has read every record; once
    ``restart()`` brings a new emulator up behind the same link, it :func:`resumes_within` the
    usual 2 s and counts the restart."""
    device = manager.device(name)
    hangs_up(manager, name, emulator)
    reason = manager.status(name).reason or ""
    assert "serial line lost" in reason or (reopened and "cannot open" in reason), reason
    assert device.records == records
    emulator.stop()
    resumes_within(manager, name, restart, lambda: device.records)
    assert device.restarts >= 1


def faults_then_resumes(
    manager: InputManager,
    name: str,
    emulator: Any,
    restart: Callable[[], object],
    delivered: Callable[[], int],
    *,
    step: Callable[[], object] | None = None,
    more: int = 2,
    fault_timeout: float = 3.0,
) -> None:
    """A lost line and its return: the emulator hangs up and device ``name`` faults (and
    counts the fault); once ``restart()`` brings a new emulator up behind the same link,
    :func:`resumes_within` the usual 2 s."""
    hangs_up(manager, name, emulator, fault_timeout=fault_timeout, step=step)
    assert manager.status(name).stats.faults >= 1
    emulator.stop()
    resumes_within(manager, name, restart, delivered, more=more, step=step)
