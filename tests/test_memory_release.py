"""What a run of the input manager or a monitor session holds is released when it ends:
threads, file descriptors and memory return to where they were, however many runs a
long-lived process (a test suite, an application embedding gadgetctl) makes.

Memory is measured with tracemalloc (Python allocations still alive after a full
collection), never with wall-clock time or the process's RSS, which does not shrink."""

from __future__ import annotations

import gc
import os
import threading
import tracemalloc
from collections.abc import Callable, Iterator

import pytest

from gadgetctl.input.manager import InputManager, ManagerOptions
from gadgetctl.input.testing import wait_until
from gadgetctl.jccl.configload import load_configuration
from gadgetctl.jccl.repository import default_repository
from gadgetctl.monitor.session import MonitorSession

from conftest import REPO

WAVEFORM = REPO / "examples" / "waveform.jconf"

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope="module")
def waveform():
    """The bundled definitions and the waveform example (two threaded devices, proxies)."""
    return default_repository(), load_configuration([WAVEFORM])


def open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


@pytest.fixture
def measured() -> Iterator[Callable[[Callable[[], None], int, int], None]]:
    """``repeat(action, times, limit)``: runs ``action`` twice to warm up (imports, caches),
    then ``times`` times under tracemalloc; asserts that threads and file descriptors came
    back, that less than ``limit`` bytes are still allocated after a full collection and
    that nothing was left in the collector's permanent generation (never collected)."""
    started = tracemalloc.is_tracing()

    def repeat(action: Callable[[], None], times: int, limit: int) -> None:
        action()
        action()
        gc.collect()
        threads, fds = threading.active_count(), open_fds()
        tracemalloc.start()
        before = tracemalloc.get_traced_memory()[0]
        for _ in range(times):
            action()
        gc.collect()
        grown = tracemalloc.get_traced_memory()[0] - before
        tracemalloc.stop()
        # joined by shutdown(); waited for only so that a loaded machine cannot fail this
        assert wait_until(lambda: threading.active_count() == threads, timeout=10.0), [
            t.name for t in threading.enumerate()
        ]
        assert open_fds() == fds
        assert grown < limit, f"{grown} bytes still allocated after {times} runs"
        assert gc.get_freeze_count() == 0, "objects were left in the permanent generation"

    yield repeat
    if tracemalloc.is_tracing() and not started:
        tracemalloc.stop()


def test_input_manager_run_releases_its_devices(waveform, measured) -> None:
    repo, configuration = waveform

    def run() -> None:
        with InputManager(repo, ManagerOptions(entry_points=False, retry_interval=None)) as manager:
            manager.configure(configuration)
            assert manager.run(rate=1000.0, frames=3) == 3

    # run() froze the collector's generations and never unfroze them: every manager (a
    # cycle through its device context) stayed, about 0.9 MB a run, 45 MB here.
    measured(run, 50, 2_000_000)


def test_input_manager_run_ended_by_its_callback_releases_too(waveform, measured) -> None:
    repo, configuration = waveform

    def run() -> None:
        with InputManager(repo, ManagerOptions(entry_points=False, retry_interval=None)) as manager:
            manager.configure(configuration)
            manager.run(rate=1000.0, on_frame=lambda m: m.frame < 2)

    measured(run, 50, 2_000_000)


def test_monitor_sessions_started_and_stopped_release_everything(waveform, measured) -> None:
    repo, configuration = waveform

    def session_run() -> None:
        with InputManager(repo, ManagerOptions(entry_points=False, retry_interval=None)) as manager:
            session = MonitorSession(manager, configuration, rate=1000.0)
            assert session.start()
            count = sum(1 for _ in session.frames(frames=3, sleep=lambda _: None))
            assert count == 3

    measured(session_run, 100, 3_000_000)


def test_a_monitor_session_left_mid_run_releases_everything(waveform, measured) -> None:
    repo, configuration = waveform

    def abandoned() -> None:
        with InputManager(repo, ManagerOptions(entry_points=False, retry_interval=None)) as manager:
            session = MonitorSession(manager, configuration, rate=1000.0)
            session.start()
            for _ in session.frames(sleep=lambda _: None):
                break  # the generator is dropped, not exhausted

    measured(abandoned, 50, 2_000_000)
