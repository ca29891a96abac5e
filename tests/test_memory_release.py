"""What a run of the input manager or a monitor session holds is released when it ends:
threads, file descriptors and memory return to where they were, however many runs a
long-lived process (a test suite, an application embedding gadgetctl) makes.

Memory is measured with tracemalloc (Python allocations still alive after a full
collection), never with wall-clock time or the process's RSS, which does not shrink."""

from __future__ import annotations

import gc
import os
import subprocess
import sys
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


STYLESHEETS = """
import ctypes, gc, sys
from gadgetctl.jccl.xslt import compile_transform

class MallInfo2(ctypes.Structure):  # glibc's malloc statistics: libxslt allocates with malloc
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
        "fordblks", "keepcost")]

libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = MallInfo2

def in_use():
    info = libc.mallinfo2()
    return info.uordblks + info.hblkhd

def sheet(i):
    return ('<xsl:stylesheet version="1.0" xmlns:xsl="http://www.w3.org/1999/XSL/Transform">'
            '<xsl:template match="/*"><xsl:copy><xsl:attribute name="version">%d</xsl:attribute>'
            '<xsl:copy-of select="node()"/></xsl:copy></xsl:template></xsl:stylesheet>' % i).encode()

assert compile_transform(sheet(0)) is compile_transform(sheet(0))  # reused while in use
for i in range(100):
    compile_transform(sheet(i))
gc.collect()
before = in_use()
for i in range(100, 100 + int(sys.argv[1])):
    compile_transform(sheet(i))
gc.collect()
print(in_use() - before)
"""


@pytest.mark.timeout(120)
def test_compiled_stylesheets_are_kept_within_a_bound() -> None:
    """The sandbox child compiles the stylesheet of every definition file it is given and
    lives as long as its parent; it kept every compiled stylesheet (12.6 KB each here)."""
    done = subprocess.run(
        [sys.executable, "-c", STYLESHEETS, "600"],
        capture_output=True,
        text=True,
        timeout=100,
        cwd=REPO,
    )
    assert done.returncode == 0, done.stderr
    grown = int(done.stdout)
    assert grown < 2_000_000, f"{grown} bytes of malloc still in use after 600 stylesheets"
