"""Memory of a process as Linux reports it (``/proc/PID/status``; psutil is not needed).

``VmRSS`` is the resident set now, ``VmHWM`` its high-water mark since the process began.
:class:`PeakWatch` samples a process's ``VmRSS`` on a thread of its own, so a peak between two
checks of a fuzz target is seen too (``VmHWM`` would include the start-up, which a baseline
must not).
"""

from __future__ import annotations

import os
import threading
from pathlib import Path

MB = 1 << 20


def status_kb(pid: int | None, field: str) -> int | None:
    """A ``kB`` field (``VmRSS``, ``VmHWM``) of ``/proc/PID/status`` in bytes; None once the
    process is gone (or where /proc has no such file)."""
    path = Path("/proc") / (str(pid) if pid is not None else "self") / "status"
    try:
        text = path.read_text(encoding="ascii", errors="replace")
    except OSError:
        return None
    for line in text.splitlines():
        if line.startswith(field + ":"):
            parts = line.split()
            if len(parts) >= 2 and parts[1].isdigit():
                return int(parts[1]) * 1024
    return None


def rss(pid: int | None = None) -> int | None:
    """Resident memory of ``pid`` (this process when None) in bytes."""
    return status_kb(pid, "VmRSS")


def high_water(pid: int | None = None) -> int | None:
    """The largest resident memory ``pid`` ever had, in bytes."""
    return status_kb(pid, "VmHWM")


class PeakWatch:
    """Samples the ``VmRSS`` of ``pid`` every ``interval`` seconds while open; ``peak`` is the
    largest seen since the last :meth:`reset` (``last`` the newest)."""

    def __init__(self, pid: int | None = None, interval: float = 0.02) -> None:
        self.pid = pid if pid is not None else os.getpid()
        self.interval = interval
        self.peak = 0
        self.last = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="rss watch", daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            self.sample()
            self._stop.wait(self.interval)

    def sample(self) -> int:
        now = rss(self.pid)
        if now is not None:
            self.last = now
            self.peak = max(self.peak, now)
        return self.last

    def reset(self) -> None:
        self.peak = self.sample()

    def __enter__(self) -> PeakWatch:
        self.sample()
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(5)
