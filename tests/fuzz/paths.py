"""Cross-layer fuzz targets: whole paths driven by a hostile peer, with memory and time caps.

The parser targets (:mod:`fuzz.targets`) feed one input to one decoder in the worker. A path
target instead runs a whole path for a set time: a real ``gadgetctl serve`` process with a
hostile VRPN client, ``gadgetctl monitor vrpn:`` against a hostile server, an input manager
whose UDP driver is flooded with mutated datagrams, a serial driver reading mutated bytes
from its emulator's pty. Each has caps, checked while it runs:

- a memory cap: the resident memory (``VmRSS`` of ``/proc/PID/status``) of the process under
  test, against a baseline measured in the same run before the hostile part starts;
- a time cap: how long one step may take (a frame of the input manager, an answer of serve
  to a well-behaved client, the exit of ``monitor`` after its ``--duration``), and how long
  the whole target may overrun its time (the campaign kills it then);

and the checks of its path (nothing faults with an internal error, every datagram counted,
no traceback on stderr, the exit status). The caps of each target are in its ``caps`` text
(``campaign.py --list`` prints them). The campaign runs each path target in a process of its
own (:func:`run_path`), so one target's memory is not another's; a failure is saved as a
JSON file (target, seed, seconds, error) with the last inputs sent beside it, and
``campaign.py --replay FILE.json`` runs the target again with the same seed.

A new path target is a function of a :class:`Run` registered with :func:`path_target`
(``hidden=True`` keeps it out of the default list: it runs only when named).
"""

from __future__ import annotations

import collections
import random
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field

from fuzz.memory import MB


class PathFailure(AssertionError):
    """A path target found a defect (a check of the path failed)."""


class CapExceeded(PathFailure):
    """A memory or time cap was exceeded."""


@dataclass
class Run:
    """One run of a path target: its random source, its time and what it measured."""

    rng: random.Random
    seconds: float
    started: float = field(default_factory=time.monotonic)
    #: figures the campaign prints (peak memory, baseline, inputs sent...)
    figures: dict[str, float] = field(default_factory=dict)
    #: the last inputs sent (saved beside a failure)
    recent: collections.deque[bytes] = field(default_factory=lambda: collections.deque(maxlen=64))

    @property
    def deadline(self) -> float:
        return self.started + self.seconds

    def left(self) -> float:
        return self.deadline - time.monotonic()

    def sent(self, data: bytes, count: int = 1) -> bytes:
        """Keep ``data`` among the recent inputs and count it; returns it."""
        self.recent.append(bytes(data[:70_000]))
        self.figures["inputs"] = self.figures.get("inputs", 0) + count
        return data

    def count(self, name: str, amount: float = 1) -> None:
        self.figures[name] = self.figures.get(name, 0) + amount

    def memory(self, name: str, value: int) -> None:
        """Record a memory figure (bytes) in MB."""
        self.figures[name] = round(value / MB, 1)

    def check_memory(self, what: str, peak: int, baseline: int, cap: Callable[[int], int]) -> None:
        """Fail when ``peak`` exceeds ``cap(baseline)``."""
        limit = cap(baseline)
        if peak > limit:
            raise CapExceeded(
                f"memory cap exceeded: {what} reached {peak / MB:.0f} MB, cap {limit / MB:.0f} MB "
                f"(baseline {baseline / MB:.0f} MB)"
            )

    def check_time(self, what: str, took: float, cap: float) -> None:
        if took > cap:
            raise CapExceeded(f"time cap exceeded: {what} took {took:.1f} s, cap {cap:g} s")


@dataclass(frozen=True)
class PathTarget:
    name: str
    run: Callable[[Run], None]
    #: the caps, in words (printed by --list and the README)
    caps: str
    #: seconds the target may run past its time (setting up, stopping) before it is killed
    overrun: float = 60.0
    hidden: bool = False


PATHS: dict[str, PathTarget] = {}


def path_target(
    name: str, *, caps: str, overrun: float = 60.0, hidden: bool = False
) -> Callable[[Callable[[Run], None]], Callable[[Run], None]]:
    def register(run: Callable[[Run], None]) -> Callable[[Run], None]:
        if name in PATHS:
            raise ValueError(f"path target {name!r} registered twice")
        PATHS[name] = PathTarget(name, run, caps, overrun, hidden)
        return run

    return register


def load() -> dict[str, PathTarget]:
    """Every path target (importing the modules that register them)."""
    import fuzz.path_drivers
    import fuzz.path_replay
    import fuzz.path_vrpn  # noqa: F401

    return PATHS


def run_path(name: str, seconds: float, seed: int) -> dict:
    """Run the path target ``name`` for ``seconds``; its figures, and the failure if any (with
    the trace and the recent inputs)."""
    target = load()[name]
    run = Run(random.Random(seed), seconds)
    result: dict = {"target": name, "seed": seed, "seconds": seconds}
    try:
        target.run(run)
    except Exception as exc:  # a failure of the path, or an internal error of the harness
        kind = "" if isinstance(exc, PathFailure) else "internal error: "
        result["error"] = f"{kind}{type(exc).__name__}: {exc}"[:500]
        result["trace"] = "".join(traceback.format_exception(exc))[-3000:]
        result["recent"] = list(run.recent)
    result["figures"] = dict(run.figures)
    result["elapsed"] = round(time.monotonic() - run.started, 1)
    return result


# -- a target that grows on purpose (the test that shows the memory cap fails a run) ----------


@path_target(
    "selftest.grows",
    caps="memory: 64 MB over its baseline (it allocates 8 MB every 50 ms: always exceeded)",
    overrun=10.0,
    hidden=True,
)
def _grows(run: Run) -> None:
    from fuzz.memory import PeakWatch

    hoard: list[bytearray] = []
    with PeakWatch() as watch:
        baseline = watch.sample()
        run.memory("baseline_mb", baseline)
        while run.left() > 0:
            hoard.append(bytearray(8 * MB))  # zero-filled pages, touched: resident
            hoard[-1][::4096] = b"\1" * len(hoard[-1][::4096])
            time.sleep(0.05)
            watch.sample()
            run.memory("peak_mb", watch.peak)
            run.check_memory("the target", watch.peak, baseline, lambda b: b + 64 * MB)


@path_target(
    "selftest.hangs",
    caps="time: killed 2 s past its time (it never ends by itself: always exceeded)",
    overrun=2.0,
    hidden=True,
)
def _hangs(run: Run) -> None:
    stop = time.monotonic() + 600  # bounded even if nothing kills it
    while time.monotonic() < stop:
        time.sleep(0.05)
